// Arc tangent, the same bits on every x86-64 machine (glibc's atan and atan2 pick an FMA variant
// by CPU at run time, and the variants differ in the last bit for some arguments; see log.hpp).
// For |t| > 1, atan t = pi/2 - atan(1/t); then atan t = 2 atan(t / (1 + sqrt(1 + t^2))) halves the
// angle (at most twice) to |t| <= 0.2, where the odd Taylor series to t^29 leaves < 1e-21 out. Only IEEE
// additions, multiplications, divisions and square roots, and the build forbids FMA contraction,
// so the result is a fixed function of the argument. Accuracy, checked against long double by
// tests/test_atan.cpp: within 3.5 ulp (each halving rounds); what matters here is that every
// machine gets the same number, and that it is far below the model's other approximations.
#pragma once

#include <cmath>

namespace dicesim {

inline double atan_fixed(double x) {
  if (std::isnan(x)) return x;
  const double sign = x < 0.0 ? -1.0 : 1.0;
  double t = std::abs(x);
  // t > 1: atan t = pi/2 - atan(1/t), pi/2 in two parts.
  const bool inverted = t > 1.0;
  if (inverted) t = 1.0 / t;  // 0 for t = inf
  // At most two halvings take t <= 1 to <= tan(pi/16) = 0.199.
  double scale = 1.0;
  for (int k = 0; k < 2 && t > 0.2; ++k) {
    t = t / (1.0 + std::sqrt(1.0 + t * t));
    scale *= 2.0;
  }
  const double z = t * t;
  // t - t^3/3 + ... + t^29/29 (z <= 0.04: the first omitted term is below 1e-21 of t)
  const double p =
      -1.0 / 3 + z * (1.0 / 5 + z * (-1.0 / 7 + z * (1.0 / 9 + z * (-1.0 / 11 + z * (1.0 / 13 + z * (-1.0 / 15 + z * (1.0 / 17 + z * (-1.0 / 19 + z * (1.0 / 21 + z * (-1.0 / 23 + z * (1.0 / 25 + z * (-1.0 / 27 + z * (1.0 / 29)))))))))))));
  const double a = scale * (t + t * (z * p));
  if (!inverted) return sign * a;
  constexpr double kHalfPiHi = 0x1.921fb54442d18p+0, kHalfPiLo = 0x1.1a62633145c07p-54;
  return sign * ((kHalfPiHi - a) + kHalfPiLo);
}

}  // namespace dicesim
