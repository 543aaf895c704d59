#include "sim/models/world_windows.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/dynamics/contact.hpp"

namespace dicesim::world_detail {

Reach reach_of(ImpulseRun& r, TossProbe* probe) {
  Reach out;
  // A flight's start checks for rest first (as the run's own would, at once).
  if (r.state == RunState::Running && !r.sustained && !r.flight && !r.settles_now(probe)) {
    const PhaseTimer timer(probe, Phase::Search);
    r.start_flight(probe);
  }
  if (r.state != RunState::Running) return out;
  const DieModel& d = *r.m;
  const RigidState& s = r.s;
  const double z_rest = *std::min_element(d.face_height.begin(), d.face_height.end());
  const Vec3 w_body = s.R.transpose() * s.omega;  // (kinetic_energy's terms, the spin's kept apart)
  const double k_rot = 0.5 * w_body.dot(d.principal_moments.cwiseProduct(w_body));
  const double e = 0.5 * d.mass * s.velocity.squaredNorm() + k_rot +
                   d.mass * d.gravity * std::max(0.0, s.position.z() - z_rest);
  const double i_min = d.principal_moments.minCoeff();
  out.com = 1.05 * std::sqrt(2.0 * e / d.mass) + 1e-12;
  out.any = out.com + 1.05 * d.bounding_radius * std::sqrt(2.0 * e / i_min);
  if (!r.sustained) {
    // Until its next floor contact (its own flight's, searched once at the flight's start) it only
    // flies. (A search that ended without a contact found none before it ended.)
    out.flying = true;
    out.free_for = r.flight->t0 + r.flight->contact.t - r.t;
    out.v = s.velocity;
    out.spin = 1.0000001 * d.bounding_radius * std::sqrt(2.0 * k_rot / i_min);
  }
  return out;
}

double window_for(double gap, double closing, double accel) {
  if (accel <= 0.0) return closing > 0.0 ? gap / closing : std::numeric_limits<double>::infinity();
  // The first root of gap - closing t - accel t^2 / 2, each form free of cancellation.
  const double root = std::sqrt(closing * closing + 2.0 * accel * gap);
  return closing >= 0.0 ? 2.0 * gap / (closing + root) : (root - closing) / accel;
}

double spheres_window(const Reach& a, const Reach& b, const Vec3& d, double R) {
  const double gap = d.norm() - R;
  const double both = a.com + b.com;
  double dt = gap / both;
  if (!(a.flying && b.flying)) return dt;
  const double f = std::min(a.free_for, b.free_for);
  const Vec3 v = b.v - a.v;
  const double qa = v.squaredNorm(), qb = d.dot(v), qc = d.squaredNorm() - R * R;
  const double disc = qb * qb - qa * qc;
  if (qa > 0.0 && qb < 0.0 && disc >= 0.0) {
    const double hit = qc / (-qb + std::sqrt(disc));  // the smaller root of qa t^2 + 2 qb t + qc
    if (hit < f) return std::max(dt, hit);
  }
  return std::max(dt, f + std::max(0.0, (d + v * f).norm() - R) / both);
}

double sphere_fixed_window(const Reach& a, double gap, const Vec3& n, double g) {
  double dt = gap / a.com;
  if (!a.flying) return dt;
  const bool known = n.squaredNorm() > 0.5;
  const double v_in = known ? std::max(0.0, -a.v.dot(n)) : a.v.norm();
  const double g_in = known ? std::max(0.0, g * n.z()) : g;
  const double flown = window_for(gap, v_in, g_in);
  if (flown < a.free_for) return std::max(dt, flown);
  const double closed = v_in * a.free_for + 0.5 * g_in * a.free_for * a.free_for;
  return std::max(dt, a.free_for + std::max(0.0, gap - closed) / a.com);
}

double closing_time(const DieModel& d, std::span<const Vec3> corners, const RigidState& s, const Vec3& n, double level,
                    const RigidState* other) {
  double soonest = std::numeric_limits<double>::infinity();
  for (const Vec3& c : corners) {
    const Vec3 r = c - s.position;
    Vec3 rel = s.velocity + s.omega.cross(r);
    if (other) rel -= other->velocity + other->omega.cross(c - other->position);
    const double approach = -rel.dot(n);
    if (approach <= 0.0) continue;
    const double height = std::max(0.0, n.dot(c) - d.rounding - level);
    soonest = std::min(soonest, height / approach);
  }
  return soonest;
}

}  // namespace dicesim::world_detail
