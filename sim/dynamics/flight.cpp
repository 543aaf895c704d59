#include "sim/dynamics/flight.hpp"

#include <cmath>
#include <limits>

namespace dicesim {

Flight::Flight(const DieModel& model, const RigidState& s)
    : model_(&model),
      p0_(s.position),
      v0_(s.velocity),
      rotation_(model.principal_moments, s.R, world_inertia(model, s.R) * s.omega) {
  const double r = model.bounding_radius;
  // z_i'' = -g + (alpha x p + omega x (omega x p))_z, so |z_i'' + g| <= r (|omega|^2 + |alpha|).
  const double w = rotation_.max_omega();
  accel_bound_ = model.gravity + r * (w * w + rotation_.max_alpha());
  contact_tol_ = 1e-9 * r;
}

RigidState Flight::state_with(double t, const Mat3& R, const Vec3& omega) const {
  RigidState s;
  s.position = p0_ + v0_ * t;
  s.position.z() -= 0.5 * model_->gravity * t * t;
  s.velocity = v0_;
  s.velocity.z() -= model_->gravity * t;
  s.R = R;
  s.omega = omega;
  return s;
}

RigidState Flight::state(double t) const {
  Mat3 R;
  Vec3 w;
  rotation_.state(t, R, w);
  return state_with(t, R, w);
}

ContactSearch Flight::next_contact(double t_limit) const {
  const double g = model_->gravity;
  const double A = accel_bound_;
  ContactSearch out;

  // No vertex can touch while the COM is higher than the bounding radius: whenever it is, jump
  // in closed form to the time it comes back down to that height (the whole free fall of a high
  // throw, or the rise and fall after a strong bounce, costs one square root).
  // sphere_time: the later root of z_com(t) = bounding radius, when the COM is on its way down.
  const double clear = p0_.z() - model_->bounding_radius;
  const double disc = v0_.z() * v0_.z() + 2.0 * g * clear;
  const double sphere_time = disc >= 0.0 ? (v0_.z() + std::sqrt(disc)) / g : 0.0;
  double t = clear > 0.0 ? sphere_time : 0.0;

  // Second-order conservative advancement: vertex i satisfies
  //   z_i(t + s) >= z_i + zdot_i s - A s^2 / 2,
  // so the smallest root of that bound over all vertices is a step that cannot pass a contact.
  // Near a contact it converges quadratically (like Newton's method from the safe side).
  constexpr int kMaxIterations = 100000;
  const double min_step = 1e-15;
  for (int it = 0; it < kMaxIterations; ++it) {
    out.iterations = it + 1;
    if (t > t_limit) {
      out.outcome = ContactSearch::Outcome::TimeLimit;
      out.t = t_limit;
      return out;
    }
    // Above the bounding sphere no corner can touch: jump before evaluating the rotation.
    const double zc = p0_.z() + v0_.z() * t - 0.5 * g * t * t;
    if (zc > model_->bounding_radius && sphere_time > t) {
      t = sphere_time;
      continue;
    }
    Mat3 R;
    Vec3 w;
    rotation_.state(t, R, w);
    const double vz = v0_.z() - g * t;

    // The step is min_i (zdot_i + sqrt(zdot_i^2 + 2 A z_i)) / A; division by A > 0 is monotone
    // under rounding, so dividing the smallest numerator once gives the same number.
    double numerator = std::numeric_limits<double>::infinity();
    int touching = -1;
    double touching_z = std::numeric_limits<double>::infinity();
    const int n = model_->vertex_count();
    const double rounding = model_->rounding;
    for (int i = 0; i < n; ++i) {
      const Vec3 p = R * model_->vertices[static_cast<std::size_t>(i)];
      const double z = zc + p.z() - rounding;  // the lowest point of the corner's ball
      const double zdot = vz + (w.x() * p.y() - w.y() * p.x());
      if (z <= contact_tol_ && zdot < 0.0) {
        if (z < touching_z) {
          touching = i;
          touching_z = z;
        }
        continue;
      }
      const double zp = std::max(z, 0.0);
      numerator = std::min(numerator, zdot + std::sqrt(zdot * zdot + 2.0 * A * zp));
    }
    if (touching >= 0) {
      out.outcome = ContactSearch::Outcome::Contact;
      out.t = t;
      out.vertex = touching;
      out.at = state_with(t, R, w);
      return out;
    }
    t += std::max(numerator / A, min_step * (1.0 + t));
  }
  out.outcome = ContactSearch::Outcome::IterationLimit;
  out.t = t;
  return out;
}

}  // namespace dicesim
