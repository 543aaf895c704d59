// FixedStepper::coast: `stepped`'s flights in closed form, K whole steps at once.
#include "sim/dynamics/contact_stepper.hpp"

#include <cmath>

namespace dicesim {

long long FixedStepper::coast(RigidState& s, double& t, double max_time, long long max_k) const {
  const DieModel& m = *m_;
  // High: COM above z_min. The margin (1e-6 of the radius, far above the rounding of the closed
  // form against step by step) keeps every coasted step clear of the floor by construction.
  const double z_min = (1.0 + 1e-6) * m.bounding_radius + touch_tol_;
  const double z0 = s.position.z(), vz = s.velocity.z(), g = m.gravity, h = h_max_;
  // (No rest: energy >= m g z > m g r >= m g max_escape, the rest criteria's bound; a die with
  // one basin only, max_escape infinite, rests at once and never coasts.)
  if (!(z0 > z_min) || max_k < 2 || !(m.max_escape <= m.bounding_radius)) return 0;
  // z_j = z0 + j h vz - g h^2 j (j + 1) / 2 is concave in j: the steps that stay high are j <= the
  // positive root of z_j = z_min.
  const double a = 0.5 * g * h * h, b = 0.5 * g * h * h - h * vz, c = z_min - z0;  // a j^2 + b j + c = 0, c < 0
  const double disc = b * b - 4.0 * a * c;
  const double root = b > 0.0 ? -2.0 * c / (b + std::sqrt(disc)) : (std::sqrt(disc) - b) / (2.0 * a);
  const auto z_at = [&](double j) { return z0 + j * h * vz - a * j * (j + 1.0); };
  double k = std::floor(std::min(root, static_cast<double>(max_k)));
  while (k > 0.0 && !(z_at(k) > z_min)) k -= 1.0;  // rounding of the root: the largest j that is high
  // Step j ends at z_{j+1}: the K steps' ends are z_1..z_K, all high (concavity: between z_0 and z_K
  // every z_j is at least min(z_0, z_K)).
  // The time cap as the steps would meet it: step j runs only if t (after j steps' additions of
  // h, in that order) is still below max_time.
  double t_end = t;
  long long steps = 0;
  while (static_cast<double>(steps) < k && t_end < max_time) {
    t_end += h;
    ++steps;
  }
  k = static_cast<double>(steps);
  if (k < 2.0) return 0;
  t = t_end;
  const double T = k * h;
  const Vec3 L = world_inertia(m, s.R) * s.omega;
  const TorqueFreeRotation rot(m.principal_moments, s.R, L);
  Vec3 w;
  rot.state(T, s.R, w);
  s.omega = w;
  s.position += T * s.velocity;
  s.position.z() -= a * k * (k + 1.0);
  s.velocity.z() -= k * g * h;
  return static_cast<long long>(k);
}

}  // namespace dicesim
