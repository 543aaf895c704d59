// Accuracy of the hand-written elementary functions (test_sincos, test_log, test_atan).
#pragma once

#include <cmath>
#include <limits>

namespace dicesim::testing {

// |got - exact| in units of the last place of the exact value rounded to double.
inline double ulps(double got, long double exact) {
  const double e = static_cast<double>(exact);
  const double a = std::abs(e);
  const double ulp = a == 0.0 ? std::numeric_limits<double>::denorm_min()
                              : std::nextafter(a, std::numeric_limits<double>::infinity()) - a;
  return static_cast<double>(std::fabs(static_cast<long double>(got) - exact)) / ulp;
}

}  // namespace dicesim::testing
