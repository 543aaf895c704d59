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
                               const AdaptiveSteps& adaptive) {
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
  const auto finish = [&](StepperExit exit) {
    out.exit = exit;
    if (stats && stats->observer) stats->observer->on_step(t, s);
    impacts = st.impacts;
    if (stats) {
      stats->corrections.add(st.corrections);
      stats->sweeps += st.sweeps;
      stats->steps += steps;
      stats->located += st.located;
      stats->located_trials += st.located_trials;
      stats->located_capped += st.located_capped;
      stats->nudges += static_cast<std::uint64_t>(out.nudges);
      stats->max_energy_gain = std::max(stats->max_energy_gain, st.max_energy_gain);
      stats->max_step_rise = std::max(stats->max_step_rise, st.max_step_rise);
      stats->max_rise_excess = std::max(stats->max_rise_excess, st.max_rise_excess);
      stats->max_penetration = std::max(stats->max_penetration, st.max_penetration);
      stats->halved += st.halved;
      stats->curvature_capped += st.curvature_capped;
      stats->support_search_capped += st.support_search_capped;
      stats->slaps += st.slaps;
      stats->slap_no_arrival += st.slap_no_arrival;
      stats->slap_rim_below += st.slap_rim_below;
      stats->flat_landed += st.flat_landed;
      stats->face_jumped += st.face_jumped;
      stats->face_jump_declined += st.face_jump_declined;
      stats->rim_struck += st.rim_struck;
      stats->rim_strike_declined += st.rim_strike_declined;
      stats->dual_solves += st.dual_solves;
      stats->exact_fallbacks += st.exact_fallbacks;
      stats->max_held_sink = std::max(stats->max_held_sink, st.max_held_sink);
      stats->held_sinks += st.held_sinks;
      stats->sink_shortened += st.sink_shortened;
      stats->short_steps += st.short_steps;
      stats->rise_dropped += st.rise_dropped;
      // The guards of the sustained phase, reported with the corrections (kept out of the
      // stepper's own, whose totals decide its re-tried steps).
      stats->corrections.located_capped += static_cast<std::uint32_t>(st.located_capped);
      stats->corrections.support_search_capped += static_cast<std::uint32_t>(st.support_search_capped);
      stats->corrections.rise_dropped += static_cast<std::uint32_t>(st.rise_dropped);
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
    const int n = st.step(s, ke);
    ke = st.end_ke();
    ++steps;
    t += st.last_dt();
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
