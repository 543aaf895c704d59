// Interval estimates and goodness-of-fit for face counts.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace dicesim {

inline constexpr double kZ95 = 1.959963984540054;  // two-sided 95% normal quantile

struct Interval {
  double lo = 0.0;
  double hi = 0.0;
  double half_width() const { return 0.5 * (hi - lo); }
};

// Wilson score interval for a binomial proportion (the seed's Wald interval fails near 0 and
// for small n). n == 0 gives [0, 1].
Interval wilson_interval(std::uint64_t successes, std::uint64_t n, double z = kZ95);

struct ChiSquare {
  double statistic = 0.0;
  int dof = 0;
  double p_value = 1.0;
};

// P(chi2_dof > statistic); 1 for dof <= 0.
double chi2_p_value(double statistic, int dof);

// Pearson chi-square of `counts` against equal probabilities.
ChiSquare chi2_uniform(std::span<const std::uint64_t> counts);
// Pearson chi-square of `counts` against probabilities `p` (sum 1); cells with p = 0 are skipped.
ChiSquare chi2_against(std::span<const std::uint64_t> counts, std::span<const double> p);

// Tosses needed for a 95% half-width h at proportion p: z^2 p (1 - p) / h^2.
double tosses_for_halfwidth(double p, double h, double z = kZ95);

}  // namespace dicesim
