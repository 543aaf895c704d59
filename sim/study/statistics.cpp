#include "sim/study/statistics.hpp"

#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <numeric>

namespace dicesim {

Interval wilson_interval(std::uint64_t successes, std::uint64_t n, double z) {
  if (n == 0) return {0.0, 1.0};
  const double nn = static_cast<double>(n);
  const double p = static_cast<double>(successes) / nn;
  const double z2 = z * z;
  const double denom = 1.0 + z2 / nn;
  const double centre = (p + z2 / (2.0 * nn)) / denom;
  const double half = z * std::sqrt(p * (1.0 - p) / nn + z2 / (4.0 * nn * nn)) / denom;
  // Clamp: rounding can put the bounds a hair outside [0, 1] at p = 0 or 1.
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

double chi2_p_value(double statistic, int dof) {
  if (dof <= 0) return 1.0;
  boost::math::chi_squared dist(dof);
  return boost::math::cdf(boost::math::complement(dist, statistic));
}

ChiSquare chi2_against(std::span<const std::uint64_t> counts, std::span<const double> p) {
  const double n = static_cast<double>(std::accumulate(counts.begin(), counts.end(), std::uint64_t{0}));
  ChiSquare r;
  if (n == 0) return r;
  int cells = 0;
  for (std::size_t i = 0; i < counts.size(); ++i) {
    if (p[i] <= 0.0) continue;
    const double expected = n * p[i];
    const double d = static_cast<double>(counts[i]) - expected;
    r.statistic += d * d / expected;
    ++cells;
  }
  r.dof = cells - 1;
  r.p_value = chi2_p_value(r.statistic, r.dof);
  return r;
}

ChiSquare chi2_uniform(std::span<const std::uint64_t> counts) {
  std::vector<double> p(counts.size(), counts.empty() ? 0.0 : 1.0 / static_cast<double>(counts.size()));
  return chi2_against(counts, p);
}

double tosses_for_halfwidth(double p, double h, double z) { return z * z * p * (1.0 - p) / (h * h); }

}  // namespace dicesim
