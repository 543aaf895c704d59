// run_fixed_steps: the stepper's driver loop, from a start to rest, lift-off or a cap, with the
// rest checks, the tiebreak's nudges and the statistics handed back to the toss.
#include "sim/dynamics/contact_stepper.hpp"

#include <cmath>

#include "sim/body/rim.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/dynamics/rim_rest.hpp"
#include "sim/sincos.hpp"

namespace dicesim {

StepperOutcome run_fixed_steps(const DieModel& m, RigidState& s, double& t, int& impacts, double h, double tiebreak,
                               bool allow_liftoff, ImpactThreshold threshold, StepperStats* stats, double max_sink,
                               const AdaptiveSteps& adaptive, double t_pause) {
  StepperOutcome out;
  FixedStepper st(m, h, threshold, max_sink, adaptive);
  st.impacts = impacts;
  const double g = m.gravity, r = m.bounding_radius;
  const double ke_rest = 1e-14 * m.mass * g * r;
  const double nudge = 1e-4 * std::sqrt(g / r);
  // Steps shortened to a new contact make more steps than (max_time - t) / h: a generous cap on
  // the count as well, so that nothing can loop forever.
  double h_min = max_sink > 0.0 ? h / FixedStepper::kMinStepDivisor : h;
  if (adaptive.tol > 0.0 && adaptive.floor > 0.0) h_min = std::min(h_min, adaptive.floor);
  const auto max_steps = 4 * static_cast<long long>(std::ceil((m.max_time - t) / h_min)) + 1000;
  std::uint64_t steps = 0;
  // A stepper's counters into the statistics (the main stepper at the end, a pause's tail stepper
  // as soon as it has stepped).
  const auto absorb = [&](const FixedStepper& x) {
    if (!stats) return;
    stats->corrections.add(x.corrections);
    stats->sweeps += x.sweeps;
    stats->located += x.located;
    stats->located_trials += x.located_trials;
    stats->located_capped += x.located_capped;
    stats->max_energy_gain = std::max(stats->max_energy_gain, x.max_energy_gain);
    stats->max_step_rise = std::max(stats->max_step_rise, x.max_step_rise);
    stats->max_rise_excess = std::max(stats->max_rise_excess, x.max_rise_excess);
    stats->max_penetration = std::max(stats->max_penetration, x.max_penetration);
    stats->halved += x.halved;
    stats->curvature_capped += x.curvature_capped;
    stats->support_search_capped += x.support_search_capped;
    stats->slaps += x.slaps;
    stats->slap_no_arrival += x.slap_no_arrival;
    stats->slap_rim_below += x.slap_rim_below;
    stats->flat_landed += x.flat_landed;
    stats->face_jumped += x.face_jumped;
    stats->face_jump_declined += x.face_jump_declined;
    stats->rim_struck += x.rim_struck;
    stats->rim_strike_declined += x.rim_strike_declined;
    stats->dual_solves += x.dual_solves;
    stats->exact_fallbacks += x.exact_fallbacks;
    stats->max_held_sink = std::max(stats->max_held_sink, x.max_held_sink);
    stats->held_sinks += x.held_sinks;
    stats->sink_shortened += x.sink_shortened;
    stats->short_steps += x.short_steps;
    stats->rise_dropped += x.rise_dropped;
    // The guards of the sustained phase, reported with the corrections (kept out of the
    // stepper's own, whose totals decide its re-tried steps).
    stats->corrections.located_capped += static_cast<std::uint32_t>(x.located_capped);
    stats->corrections.support_search_capped += static_cast<std::uint32_t>(x.support_search_capped);
    stats->corrections.rise_dropped += static_cast<std::uint32_t>(x.rise_dropped);
  };
  const auto finish = [&](StepperExit exit) {
    out.exit = exit;
    if (stats && stats->observer) stats->observer->on_step(t, s);
    impacts = st.impacts;
    absorb(st);
    if (stats) {
      stats->steps += steps;
      stats->nudges += static_cast<std::uint64_t>(out.nudges);
      stats->corrections.nudges += static_cast<std::uint32_t>(out.nudges);
    }
    return out;
  };
  // The kinetic energy of s, kept up to date (the rest check, the step and the balance test below
  // all read it; each step hands back its end's).
  double ke = kinetic_energy(m, s);
  for (long long k = 0; k < max_steps && t < m.max_time; ++k) {
    const int f = rest_face_down(m, s, tiebreak, ke);
    if (f >= 0) {
      out.face_down = f;
      return finish(StepperExit::Settled);
    }
    if (!allow_liftoff) {  // `stepped`: a flight high above the floor in closed form
      const long long coasted = st.coast(s, t, m.max_time, max_steps - k - 1);
      if (coasted > 0) {
        ke = kinetic_energy(m, s);
        k += coasted;
        steps += static_cast<std::uint64_t>(coasted);
        if (stats && stats->observer) stats->observer->on_step(t, s);
        if (!(k < max_steps && t < m.max_time)) break;
      }
    }
    int n;
    if (t_pause - t <= kPauseSlack * h) return finish(StepperExit::Paused);
    if (t + st.h() > t_pause) {
      // The window ends inside the next step: a step of exactly what is left (its impact threshold
      // still the full step's), so that every die of a world toss stands at the window's end.
      AdaptiveSteps tail_steps = adaptive;
      tail_steps.tol = 0.0;
      if (!(tail_steps.threshold_step > 0.0)) tail_steps.threshold_step = st.h();
      FixedStepper tail(m, t_pause - t, threshold, max_sink, tail_steps);
      tail.impacts = st.impacts;
      n = tail.step(s, ke);
      ke = tail.end_ke();
      st.impacts = tail.impacts;
      t += tail.last_dt();
      absorb(tail);
    } else {
      n = st.step(s, ke);
      ke = st.end_ke();
      t += st.last_dt();
    }
    ++steps;
    if (stats && stats->observer) stats->observer->on_step(t, s);
    if (st.impacts >= m.max_bounces) break;
    if (n == 0) {
      if (!allow_liftoff) continue;
      bool clear = true;
      const int nv = m.vertex_count();
      for (int i = 0; i < nv && clear; ++i) {
        const Vec3 ri = contact_point(m, s.R, i);
        const double z = s.position.z() + ri.z();
        const double vz = (s.velocity + s.omega.cross(ri)).z();
        clear = z + 2.0 * h * std::min(0.0, vz) - 2.0 * g * h * h > 1e-9 * r;
        if (!clear) break;
      }
      if (clear) return finish(StepperExit::LiftOff);
      continue;
    }
    // At rest but undecided: an exact balance on an edge or a corner. Break it the toss's way.
    if (ke < ke_rest && out.nudges < 4) {
      const ContactSet c = touching_corners(m, s, 1e-6 * r);
      Vec3 axis;
      if (c.n == 2) {
        axis = m.curved() ? (contact_point(m, s.R, c.vertex[1]) - contact_point(m, s.R, c.vertex[0])).normalized()
                          : (s.R * (m.vertices[c.vertex[1]] - m.vertices[c.vertex[0]])).normalized();
        if (std::fmod(tiebreak * 4096.0, 1.0) < 0.5) axis = -axis;
      } else {
        const SinCos a = sincos_turns(tiebreak);  // the angle 2 pi tiebreak
        axis = Vec3(a.cos, a.sin, 0.0);
      }
      s.omega += nudge * axis;
      ke = kinetic_energy(m, s);
      ++out.nudges;
    }
  }
  return finish(StepperExit::Unresolved);
}

}  // namespace dicesim
