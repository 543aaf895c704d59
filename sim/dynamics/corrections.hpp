// Guards, clamps and fallbacks inside a toss, counted (never silent). Each should read 0: a
// non-zero count says the physics was repaired somewhere, and the reports print it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace dicesim {

// Count: uint32 per toss (Corrections), uint64 totals over a run (RunCorrections). Every kind
// travels everywhere a report goes (table, --json, the wire, the checkpoint, Python) in the order
// of for_each; docs/fidelity.md ("Corrections") says when each can fire.
template <class Count>
struct CorrectionCounts {
  Count energy_clamps = 0;    // an impact would have gained energy and was scaled back
  Count pgs_unconverged = 0;  // a multi-contact solve converged neither by Gauss-Seidel nor by its Newton finish;
                              // a world toss: an instant's strikes (Gauss-Seidel sweeps over its contacts)
                              // capped with slow contacts still approaching
  Count overlap_fixes = 0;    // the stepper lifted the die out of the floor
  Count fallbacks = 0;        // a frictionless rescue pass ran (a corner still approaching after the
                              // frictional solve), or corners beyond kMaxContacts got no impulse; an exact
                              // solve's jam is not one (ImpactResult::exact_fallbacks, reported by bench);
                              // a world toss: a touch whose contact patch came out empty, struck at its
                              // nearest point alone
  // The sustained phase's guards (contact_stepper.cpp):
  Count located_capped = 0;          // a new contact not located within the touch tolerance in the trials allowed
  Count support_search_capped = 0;   // curved dice: a support search out of iterations (its end above the floor taken)
  Count rise_dropped = 0;            // flat dice: held corners' rise dropped (it would gain energy), the plain step taken
  // A world toss (several dice, obstacles): two bodies found overlapping after a window deeper than
  // 1e-4 of the bounding radius (the floor's bound on a held corner's sink), struck and lifted out.
  // (Its slot held the retired first-order rim step's depth_held, always 0.)
  Count contact_overlaps = 0;
  Count nudges = 0;                  // an exact balance at rest broken by the toss's tiebreak (a spin of 1e-4 sqrt(g/r))

  static constexpr std::size_t kKinds = 9;
  // f(name, count&) for every kind, in the wire's and the checkpoint's order.
  template <class F>
  void for_each(F&& f) {
    f("energy_clamps", energy_clamps);
    f("pgs_unconverged", pgs_unconverged);
    f("overlap_fixes", overlap_fixes);
    f("fallbacks", fallbacks);
    f("located_capped", located_capped);
    f("support_search_capped", support_search_capped);
    f("rise_dropped", rise_dropped);
    f("contact_overlaps", contact_overlaps);
    f("nudges", nudges);
  }
  template <class F>
  void for_each(F&& f) const {
    const_cast<CorrectionCounts*>(this)->for_each([&](const char* name, Count& c) { f(name, static_cast<const Count&>(c)); });
  }

  bool any() const { return total() != 0; }
  Count total() const {
    Count t = 0;
    for_each([&](const char*, const Count& c) { t += c; });
    return t;
  }
  template <class Other>
  void add(const CorrectionCounts<Other>& o) {
    energy_clamps += o.energy_clamps;
    pgs_unconverged += o.pgs_unconverged;
    overlap_fixes += o.overlap_fixes;
    fallbacks += o.fallbacks;
    located_capped += o.located_capped;
    support_search_capped += o.support_search_capped;
    rise_dropped += o.rise_dropped;
    contact_overlaps += o.contact_overlaps;
    nudges += o.nudges;
  }
  bool operator==(const CorrectionCounts&) const = default;
};

using Corrections = CorrectionCounts<std::uint32_t>;
using RunCorrections = CorrectionCounts<std::uint64_t>;

}  // namespace dicesim
