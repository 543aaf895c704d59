// `fidelity = "auto"` resolved for one run: the cheapest model shown adequate for this scene at
// this run's precision, else `impulse`. Shown adequate = measured by a pilot of paired tosses:
// the same throws (toss indices 0, 1, ... of the pilot's own seed kPilotSeed) in a cheaper model
// and in `impulse`. If a fraction d of the pairs land differently, every outcome's probability
// differs by at most P(outcomes differ) between the two models, so the upper 95% limit of d
// bounds the bias the cheaper model adds. The rule:
//   * candidates, cheapest first: static, paper;
//   * threshold = kAutoFraction x the run's 95% half-width (a fair die's face at the run's N, or
//     --target-halfwidth);
//   * the pilot's full size: 1.1 x the pairs whose zero differences would just pass, at most
//     kPilotCapShare of the run's tosses (its impulse tosses: at most 5% of the run in `impulse`;
//     a run too small for any pilot to pass takes impulse without one);
//   * sequential: pairs in growing blocks; a candidate is rejected as soon as its differences
//     exceed those the full size allows (exact: no more pairs could bring it under), so a clearly
//     inadequate model costs a few dozen pairs; it is taken only after the full size, when its
//     bound (one-sided Clopper-Pearson, 95%) is below the threshold.
// The pilot's seed is fixed and apart from the run's, so the choice is a function of (scene,
// precision) only and the run's counts of (scene, seed, N) only, on any number of threads.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/body/die_model.hpp"

namespace dicesim {

inline constexpr double kAutoFraction = 0.5;       // bias bound < this x the run's half-width
inline constexpr double kPilotCapShare = 0.05;      // pairs (one impulse toss each) <= this x the run's tosses
inline constexpr std::uint64_t kPilotSeed = 0x70696c6f74ULL;  // "pilot": the pilot's own stream

// The pilot's numbers, for the reports. If a fraction d of `pairs` land differently, the cheaper
// model's bias is at most the upper 95% limit of d (`bound`).
struct PilotCandidate {
  Fidelity model = Fidelity::Static;  // the cheaper model tried
  std::uint64_t pairs = 0;            // pairs tossed before the decision
  std::uint64_t differing = 0;        // of them with different outcomes
  double bound = 1.0;                 // upper 95% (one-sided Clopper-Pearson) limit of P(outcomes differ)
  bool adequate = false;              // bound < threshold after the pilot's full size
};
struct FidelityPilot {
  bool ran = false;              // a pilot was tossed
  double halfwidth = 0.0;        // the run's 95% half-width it was judged against
  std::string precision;         // where that half-width comes from, in words
  double fraction = 0.0;         // the bound must be below fraction * halfwidth
  double threshold = 0.0;        // fraction * halfwidth
  std::uint64_t max_pairs = 0;   // the pilot's full size (a candidate is taken only after all of them)
  std::uint64_t cap = 0;         // the most pairs the run's size allows (max_pairs <= cap)
  std::uint64_t seed = 0;        // the pilot's own seed (toss indices 0 .. max_pairs-1)
  std::uint64_t tosses = 0;      // tosses the pilot made, every model (impulse tosses shared by the candidates)
  double seconds = 0.0;          // wall time of the pilot (reported only; never decides anything)
  std::vector<PilotCandidate> candidates;  // in the order tried (cheapest first)
};

struct AutoPrecision {
  double halfwidth = 0.0;       // the run's 95% half-width
  std::uint64_t tosses = 0;     // the run's tosses (expected, for a target)
  std::string what;             // in words, for the reports
};

// A run of `tosses`: the half-width of a fair die's face (p = 1/outcomes) after that many.
AutoPrecision precision_of_run(const DieModel& m, std::uint64_t tosses);
// A run to --target-halfwidth h: h, and the tosses a fair die's face needs to reach it.
AutoPrecision precision_of_target(const DieModel& m, double halfwidth);

// When m.fidelity_requested is Auto, runs the pilot, sets m.fidelity and m.fidelity_reason and
// returns the pilot's numbers; otherwise does nothing (and returns ran = false). `threads` only
// splits the work (the same answer on any count).
FidelityPilot resolve_auto(DieModel& m, const AutoPrecision& precision, int threads = 1);

// Auto where no pilot applies (a fit: one model for every point of its box): `impulse`, `why` as
// the reason. Does nothing unless m.fidelity_requested is Auto.
void resolve_auto_unmeasured(DieModel& m, const std::string& why);

}  // namespace dicesim
