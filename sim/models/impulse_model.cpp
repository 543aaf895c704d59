// `impulse`: event-driven. Exact flight to the next contact, the friction impact law on every
// corner that touches, and fixed steps only while the die is in sustained contact (a rebound
// shorter than one contact step); the toss ends when the die must come to rest (sim/rest.hpp).
#include <cmath>

#include "sim/dynamics/contact_stepper.hpp"
#include "sim/models/fidelity_models.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/rest.hpp"

namespace dicesim {

TossResult run_impulse(const DieModel& m, RigidState s, double tiebreak, TossProbe* probe) {
  TossResult r;
  double t = 0.0;
  const double set_tol = 1e-6 * m.bounding_radius;  // corners this close strike together
  bool sustained = false;
  bool after_impact = false;  // the state is right after an impact (sustained contact is possible)
  const auto settle = [&](int down) {
    if (probe && probe->final_state) *probe->final_state = s;
    r.status = TossStatus::Settled;
    set_result_face(m, result_face(m, down), r);
    r.t_end = t;
    return r;
  };
  for (;;) {
    if (sustained) {
      const StepperOutcome o = run_fixed_steps(m, s, t, r.bounces, m.contact_step, tiebreak, /*allow_liftoff=*/true);
      if (o.exit == StepperExit::Settled) return settle(o.face_down);
      if (o.exit == StepperExit::Unresolved) break;
      sustained = false;  // lift-off: back to exact flight
      s.R = Quat(s.R).normalized().toRotationMatrix();
    }
    const int down = rest_face_down(m, s, tiebreak);
    if (down >= 0) return settle(down);

    const Flight flight(m, s);
    const ContactSearch c = flight.next_contact(m.max_time - t);
    if (probe) {
      probe->search_iterations += static_cast<std::uint64_t>(c.iterations);
      ++probe->flights;
    }
    // A rebound that lands again within one contact step is sustained contact. (The one search
    // from the state after the impact both decides that and, if not, is the next flight's.)
    if (after_impact && c.outcome == ContactSearch::Outcome::Contact && c.t <= m.contact_step) {
      sustained = true;
      after_impact = false;
      continue;
    }
    after_impact = false;
    if (c.outcome != ContactSearch::Outcome::Contact) {
      t += c.t;
      break;
    }
    t += c.t;
    s = flight.state(c.t);
    s.R = Quat(s.R).normalized().toRotationMatrix();
    const ContactSet set = touching_corners(m, s, set_tol);
    const RigidState before = s;
    const ImpactResult imp = apply_friction_impact(m, s, set, /*restitution=*/true);
    ++r.bounces;
    if (probe && probe->trace)
      probe->trace->push_back({r.bounces, t, before, s, set.n > 0 ? set.vertex[0] : -1, imp.normal_impulse});
    if (r.bounces >= m.max_bounces) break;
    after_impact = true;
  }
  r.status = TossStatus::Unresolved;
  r.t_end = t;
  if (probe && probe->final_state) *probe->final_state = s;
  return r;
}

}  // namespace dicesim
