// How far apart two face distributions are, and whether the difference is more than noise:
// what `dicesim bench tradeoff` and the fidelity tests compare models with.
#pragma once

#include <array>
#include <cstdint>

namespace dicesim {

struct Agreement {
  double tv = 0.0;        // total-variation distance  1/2 sum |p_a - p_b|
  double tv_noise = 0.0;  // its expected value from sampling alone (both samples, pooled p)
  double chi2 = 0.0;      // Pearson chi-square of homogeneity (2 x 6 table)
  int dof = 0;
  double chi2_p = 1.0;    // p-value: small means the two distributions differ
};

// a, b: settled counts per face index.
Agreement agreement_of(const std::array<std::uint64_t, 6>& a, const std::array<std::uint64_t, 6>& b);

}  // namespace dicesim
