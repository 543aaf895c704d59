// The fidelity ladder's models behind sim::toss (sim/toss.cpp dispatches on DieModel::fidelity).
// Each takes a valid initial state and a tiebreak in [0, 1) derived from the toss index, which
// decides exact balances (PHYSICS.md, erratum 9: no hidden randomness).
#pragma once

#include <algorithm>
#include <vector>

#include "sim/body/die_model.hpp"
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/flight.hpp"
#include "sim/models/toss.hpp"

namespace dicesim {

// The stepper's statistics added to a probe (`impulse`'s sustained phases, `stepped`'s toss).
inline void add_stepper_stats(TossProbe& probe, const StepperStats& stats) {
  probe.pgs_sweeps += stats.sweeps;
  probe.steps += stats.steps;
  probe.located_steps += stats.located;
  probe.located_trials += stats.located_trials;
  probe.located_capped += stats.located_capped;
  probe.nudges += stats.nudges;
  probe.max_energy_gain = std::max(probe.max_energy_gain, stats.max_energy_gain);
  probe.max_step_rise = std::max(probe.max_step_rise, stats.max_step_rise);
  probe.max_rise_excess = std::max(probe.max_rise_excess, stats.max_rise_excess);
  probe.max_penetration = std::max(probe.max_penetration, stats.max_penetration);
  probe.halved += stats.halved;
  probe.max_held_sink = std::max(probe.max_held_sink, stats.max_held_sink);
  probe.held_sinks += stats.held_sinks;
  probe.sink_shortened += stats.sink_shortened;
  probe.short_steps += stats.short_steps;
  probe.rise_dropped += stats.rise_dropped;
  probe.curvature_capped += stats.curvature_capped;
  probe.support_search_capped += stats.support_search_capped;
  probe.slaps += stats.slaps;
  probe.slap_no_arrival += stats.slap_no_arrival;
  probe.slap_rim_below += stats.slap_rim_below;
  probe.flat_landed += stats.flat_landed;
  probe.face_jumped += stats.face_jumped;
  probe.face_jump_declined += stats.face_jump_declined;
  probe.rim_struck += stats.rim_struck;
  probe.rim_strike_declined += stats.rim_strike_declined;
  probe.dual_solves += stats.dual_solves;
  probe.exact_fallbacks += stats.exact_fallbacks;
}

// `static`: the initial orientation, then the quasi-static roll (sim/rest.hpp). No dynamics.
TossResult run_static(const DieModel& m, const RigidState& s, double tiebreak);

// `static` over a uniform orientation, deterministically: the share of `directions` down
// directions on a Fibonacci lattice of the sphere that roll to each face, as the probability of
// each face (index) being the one read. For a uniform orientation each face's basin area on the
// Gauss map over 4 pi; the lattice's error is about 1 / directions (a basin boundary's length
// times the spacing).
std::vector<double> static_face_probabilities(const DieModel& m, int directions);

// `impulse`: exact flight (sim/flight.hpp) between impacts with the friction impact law
// (sim/friction_impact.hpp); sustained contact by fixed steps of m.contact_step
// (sim/contact_stepper.hpp); ends when the die must rest (sim/rest.hpp).
TossResult run_impulse(const DieModel& m, RigidState s, double tiebreak, TossProbe* probe);

// `stepped`: the whole toss by fixed steps of m.step.
TossResult run_stepped(const DieModel& m, RigidState s, double tiebreak, TossProbe* probe);

}  // namespace dicesim
