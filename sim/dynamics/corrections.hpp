// Guards, clamps and fallbacks inside a toss, counted (never silent). Each should read 0: a
// non-zero count says the physics was repaired somewhere, and the reports print it.
#pragma once

#include <cstdint>

namespace dicesim {

// Count: uint32 per toss (Corrections), uint64 totals over a run (RunCorrections).
template <class Count>
struct CorrectionCounts {
  Count energy_clamps = 0;    // an impact would have gained energy and was scaled back
  Count pgs_unconverged = 0;  // a multi-contact solve converged neither by Gauss-Seidel nor by its Newton finish
  Count overlap_fixes = 0;    // the stepper lifted the die out of the floor
  Count fallbacks = 0;        // an exact solve failed (jam) or a frictionless rescue ran

  bool any() const { return energy_clamps || pgs_unconverged || overlap_fixes || fallbacks; }
  Count total() const { return energy_clamps + pgs_unconverged + overlap_fixes + fallbacks; }
  template <class Other>
  void add(const CorrectionCounts<Other>& o) {
    energy_clamps += o.energy_clamps;
    pgs_unconverged += o.pgs_unconverged;
    overlap_fixes += o.overlap_fixes;
    fallbacks += o.fallbacks;
  }
  bool operator==(const CorrectionCounts&) const = default;
};

using Corrections = CorrectionCounts<std::uint32_t>;
using RunCorrections = CorrectionCounts<std::uint64_t>;

}  // namespace dicesim
