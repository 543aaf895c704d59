// `impulse`'s sustained phase as leapfrog steps of error-controlled length (AdaptiveSteps in
// contact_stepper.hpp): the next step's length from how much the contact's mean force and torque
// changed over the last step.
#include <algorithm>
#include <cmath>

#include "sim/dynamics/contact_stepper.hpp"

namespace dicesim {

void FixedStepper::adapt(const RigidState& s0, const RigidState& s, double dt) {
  const DieModel& m = *m_;
  if (!(dt > 0.0)) return;
  // What changed the momenta over the step besides gravity's kick: the contact.
  const Vec3 F = m.mass * ((s.velocity - s0.velocity) / dt + Vec3(0.0, 0.0, m.gravity));
  const Vec3 T = (world_inertia(m, s.R) * s.omega - Iw_start_ * s0.omega) / dt;
  if (have_force_) {
    const double r = m.bounding_radius;
    const double jump = (F - force_).norm() / m.mass + r * (T - torque_).norm() / m.principal_moments.minCoeff();
    // A step of length h errs by about h^2 jump / 2 at a body point where the force changes so.
    const double want = jump > 0.0 ? 0.9 * std::sqrt(2.0 * adaptive_.tol * r / jump) : h_max_;
    const double next = std::clamp(want, std::max(adaptive_.floor, 0.25 * h_ctrl_), std::min(h_max_, 2.0 * h_ctrl_));
    h_ctrl_ = next;
  }
  force_ = F;
  torque_ = T;
  have_force_ = true;
}

}  // namespace dicesim
