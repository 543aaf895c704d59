#include "sim/dynamics/contact_stepper.hpp"

#include <cmath>

#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/rest.hpp"

namespace dicesim {

FixedStepper::FixedStepper(const DieModel& m, double h, ImpactThreshold threshold)
    : m_(&m),
      h_(h),
      v_impact_(4.0 * m.gravity * h),
      touch_tol_(1e-9 * m.bounding_radius) {
  if (threshold == ImpactThreshold::Contact) {
    // Gravity keeps its safety factor 4; contact forces of order m g (normal plus friction) at
    // lever r add at most (1 + mu) g m r^2 / I_min per unit time; the spin adds |w|^2 r (factor 4).
    const double r = m.bounding_radius;
    const double lever = m.mass * r * r / m.principal_moments.minCoeff();
    v_impact_ += h * m.gravity * (1.0 + m.max_friction) * lever;
    v_spin_ = 4.0 * h * r;
  }
}

int FixedStepper::step(RigidState& s) {
  const DieModel& m = *m_;
  s.velocity.z() -= m.gravity * h_;

  int n = 0;
  if (s.position.z() <= m.bounding_radius + touch_tol_) {
    const ContactSet c = touching_corners(m, s, touch_tol_);
    n = c.n;
    if (n > 0) {
      double un = 0.0;
      for (int i = 0; i < n; ++i) un = std::min(un, corner_velocity(m, s, c.vertex[i]).z());
      const bool impact = un < -(v_impact_ + v_spin_ * s.omega.squaredNorm());
      const ImpactResult r = apply_friction_impact(m, s, c, impact);
      if (impact) ++impacts;
      if (r.energy_clamped) ++energy_clamps;
    }
  }

  // Positions: COM with the new velocity, rotation by exp(h omega) with L held.
  const Vec3 L = s.R * m.principal_moments.cwiseProduct(s.R.transpose() * s.omega);
  s.position += h_ * s.velocity;
  const Vec3 half = 0.5 * h_ * s.omega;
  const double a = half.norm();
  if (a > 0.0) {
    const double k = std::sin(a) / a;
    const Quat dq(std::cos(a), k * half.x(), k * half.y(), k * half.z());
    s.R = (dq * Quat(s.R)).normalized().toRotationMatrix();
    s.omega = s.R * (s.R.transpose() * L).cwiseQuotient(m.principal_moments);
  }

  // Penetration is projected out (the energy test counts it, so it cannot hide energy).
  if (s.position.z() <= m.bounding_radius) {
    double low = 0.0;
    for (const Vec3& v : m.vertices) low = std::min(low, s.position.z() + s.R.row(2).dot(v) - m.rounding);
    s.position.z() -= low;
  }
  return n;
}

StepperOutcome run_fixed_steps(const DieModel& m, RigidState& s, double& t, int& impacts, double h, double tiebreak,
                               bool allow_liftoff, ImpactThreshold threshold) {
  StepperOutcome out;
  FixedStepper st(m, h, threshold);
  st.impacts = impacts;
  const double g = m.gravity, r = m.bounding_radius;
  const double ke_rest = 1e-14 * m.mass * g * r;
  const double nudge = 1e-4 * std::sqrt(g / r);
  const auto max_steps = static_cast<long long>(std::ceil((m.max_time - t) / h));
  for (long long k = 0; k < max_steps; ++k) {
    const int f = rest_face_down(m, s, tiebreak);
    if (f >= 0) {
      out.exit = StepperExit::Settled;
      out.face_down = f;
      impacts = st.impacts;
      return out;
    }
    const int n = st.step(s);
    t += h;
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
      }
      if (clear) {
        out.exit = StepperExit::LiftOff;
        impacts = st.impacts;
        return out;
      }
      continue;
    }
    // At rest but undecided: an exact balance on an edge or a corner. Break it the toss's way.
    const Vec3 wb = s.R.transpose() * s.omega;
    const double ke = 0.5 * m.mass * s.velocity.squaredNorm() + 0.5 * wb.dot(m.principal_moments.cwiseProduct(wb));
    if (ke < ke_rest && out.nudges < 4) {
      const ContactSet c = touching_corners(m, s, 1e-6 * r);
      Vec3 axis;
      if (c.n == 2) {
        axis = (s.R * (m.vertices[c.vertex[1]] - m.vertices[c.vertex[0]])).normalized();
        if (std::fmod(tiebreak * 4096.0, 1.0) < 0.5) axis = -axis;
      } else {
        const double a = 2.0 * kPi * tiebreak;
        axis = Vec3(std::cos(a), std::sin(a), 0.0);
      }
      s.omega += nudge * axis;
      ++out.nudges;
    }
  }
  impacts = st.impacts;
  out.exit = StepperExit::Unresolved;
  return out;
}

}  // namespace dicesim
