// Guards, clamps and fallbacks inside a toss, counted (never silent). Each should read 0: a
// non-zero count says the physics was repaired somewhere, and the reports print it.
#pragma once

#include <cstdint>

namespace dicesim {

struct Corrections {
  std::uint32_t energy_clamps = 0;    // an impact would have gained energy and was scaled back
  std::uint32_t pgs_unconverged = 0;  // a multi-contact solve hit its sweep cap before converging
  std::uint32_t overlap_fixes = 0;    // the stepper lifted the die out of the floor
  std::uint32_t fallbacks = 0;        // an exact solve failed (jam) or a frictionless rescue ran

  bool any() const { return energy_clamps || pgs_unconverged || overlap_fixes || fallbacks; }
  void add(const Corrections& o) {
    energy_clamps += o.energy_clamps;
    pgs_unconverged += o.pgs_unconverged;
    overlap_fixes += o.overlap_fixes;
    fallbacks += o.fallbacks;
  }
  bool operator==(const Corrections&) const = default;
};

}  // namespace dicesim
