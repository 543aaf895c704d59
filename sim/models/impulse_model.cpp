// `impulse`: event-driven. Exact flight to the next contact, the friction impact law on every
// corner that touches, at the exact instant; fixed steps only for sustained contact: a rebound
// that lands again within one contact step *and* arrives slower than the stepper's impact
// threshold (4 g contact_step, what gravity adds in a step: a contact that slow gets no
// restitution in the stepper either). A faster re-strike, however soon, stays an exact event.
// The toss ends when the die must come to rest (sim/rest.hpp).
#include <algorithm>
#include <cmath>

#include "sim/dynamics/contact_stepper.hpp"
#include "sim/models/fidelity_models.hpp"
#include "sim/models/impulse_run.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

void ImpulseRun::advance(double t_stop, TossProbe* probe) {
  const DieModel& md = *m;
  const double set_tol = 1e-6 * md.bounding_radius;  // corners this close strike together
  // A polyhedron's sustained contact: leapfrog steps of error-controlled length (contact_tol), the
  // contact step their ceiling, and the impact threshold a fixed speed (the shape's default step),
  // whatever the ceiling. A curved die's steps are drift-kick-drift at the fixed contact_step
  // (FixedStepper, rim_step.cpp: second order without error control), its threshold 4 g
  // contact_step.
  const bool adaptive_steps = !md.curved() && md.contact_tol > 0.0;
  const double v_sustained = sustained_contact_speed(md, adaptive_steps ? md.sustained_step : md.contact_step);
  const AdaptiveSteps adaptive{.tol = adaptive_steps ? md.contact_tol : 0.0,
                               .floor = std::min(kContactStepFloor, md.contact_step),
                               .threshold_step = adaptive_steps ? md.sustained_step : 0.0};
  if (probe) stats.observer = probe->steps_observer;
  const auto settle = [&](int down) {
    face_down = down;
    state = RunState::Settled;
  };
  const auto unresolved = [&] { state = RunState::Unresolved; };
  if (state != RunState::Running) return;
  for (;;) {
    if (sustained) {
      const PhaseTimer timer(probe, Phase::Steps);
      const StepperOutcome o = run_fixed_steps(md, s, t, bounces, md.contact_step, tiebreak, /*allow_liftoff=*/true,
                                               ImpactThreshold::Gravity, &stats, held_corner_sink(md), adaptive, t_stop);
      if (o.exit == StepperExit::Settled) return settle(o.face_down);
      if (o.exit == StepperExit::Unresolved) return unresolved();
      if (o.exit == StepperExit::Paused) return;
      sustained = false;  // lift-off: back to exact flight
      s.R = Quat(s.R).normalized().toRotationMatrix();
    }
    if (!flight && settles_now(probe)) return;
    if (t >= t_stop) return;
    PhaseTimer search_timer(probe, Phase::Search);  // flight, contact search and contact set
    if (!flight) start_flight(probe);
    const ContactSearch& c = flight->contact;
    if (flight->t0 + c.t > t_stop) {
      // The window ends in flight: the exact state there; the flight goes on from its own start.
      s = flight->path.state(t_stop - flight->t0);
      t = t_stop;
      return;
    }
    if (c.outcome != ContactSearch::Outcome::Contact) {
      t = flight->t0 + c.t;
      return unresolved();
    }
    RigidState at = c.at;  // = flight.state(c.t): the search evaluated the rotation there already
    at.R = Quat(at.R).normalized().toRotationMatrix();
    const double t_contact = flight->t0 + c.t, flown = c.t;
    flight.reset();
    const ContactSet set = touching_corners(md, at, set_tol);
    // A slow re-landing within one contact step is sustained contact: the stepper takes over from
    // the state after the impact. (The one search from that state decides it and, if not, is the
    // next flight's.)
    if (after_impact && since_impact + flown <= md.contact_step) {
      double approach = 0.0;
      for (int i = 0; i < set.n; ++i) approach = std::min(approach, corner_velocity(md, at, set.vertex[i]).z());
      if (-approach <= v_sustained) {
        sustained = true;
        after_impact = false;
        continue;
      }
    }
    search_timer.stop();
    const PhaseTimer impact_timer(probe, Phase::Impact);
    after_impact = false;
    since_impact = 0.0;
    t = t_contact;
    s = at;
    const RigidState before = s;
    const ImpactResult imp = apply_friction_impact(md, s, set, /*restitution=*/true);
    corrections.add(imp.corrections);
    ++bounces;
    if (probe) {
      probe->pgs_sweeps += static_cast<std::uint64_t>(imp.iterations);
      probe->dual_solves += static_cast<std::uint64_t>(imp.dual_solves);
      probe->exact_fallbacks += static_cast<std::uint64_t>(imp.exact_fallbacks);
      if (imp.energy_before > 0.0)
        probe->max_energy_gain =
            std::max(probe->max_energy_gain, (imp.energy_after - imp.energy_before) / imp.energy_before);
      if (probe->trace)
        probe->trace->push_back({bounces, t, before, s, set.n > 0 ? set.vertex[0] : -1, imp.normal_impulse});
    }
    if (bounces >= md.max_bounces) return unresolved();
    after_impact = true;
  }
}

bool ImpulseRun::settles_now(TossProbe* probe) {
  int down;
  {
    const PhaseTimer timer(probe, Phase::Rest);
    down = rest_face_down(*m, s, tiebreak);
  }
  if (down < 0) return false;
  face_down = down;
  state = RunState::Settled;
  return true;
}

void ImpulseRun::start_flight(TossProbe* probe) {
  flight.emplace(FlightAhead{Flight(*m, s), t, {}});
  flight->contact = flight->path.next_contact(m->max_time - t);
  if (probe) {
    probe->search_iterations += static_cast<std::uint64_t>(flight->contact.iterations);
    ++probe->flights;
  }
}

TossResult ImpulseRun::result(TossProbe* probe) {
  TossResult r;
  if (probe && probe->final_state) *probe->final_state = s;
  r.status = state == RunState::Settled ? TossStatus::Settled : TossStatus::Unresolved;
  r.t_end = t;
  r.bounces = bounces;
  r.corrections = corrections;
  r.corrections.add(stats.corrections);
  if (probe) add_stepper_stats(*probe, stats);
  if (state == RunState::Settled) set_result_face(*m, result_face(*m, face_down), r);
  return r;
}

TossResult run_impulse(const DieModel& m, RigidState s, double tiebreak, TossProbe* probe) {
  ImpulseRun run(m, s, tiebreak);
  run.advance(kRunForever, probe);
  return run.result(probe);
}

}  // namespace dicesim
