// How far apart two face distributions are, and whether the difference is more than noise:
// what `dicesim bench tradeoff` and the fidelity tests compare models with.
#pragma once

#include <cstdint>
#include <span>

namespace dicesim {

struct Agreement {
  double tv = 0.0;        // total-variation distance  1/2 sum |p_a - p_b|
  double tv_noise = 0.0;  // its expected value from sampling alone (both samples, pooled p)
  double chi2 = 0.0;      // Pearson chi-square of homogeneity (2 x N table)
  int dof = 0;
  double chi2_p = 1.0;    // p-value: small means the two distributions differ
};

// a, b: settled counts per outcome (the same outcomes in the same order; throws
// std::invalid_argument if the lengths differ).
Agreement agreement_of(std::span<const std::uint64_t> a, std::span<const std::uint64_t> b);

}  // namespace dicesim
