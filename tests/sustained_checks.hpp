// Deterministic checks of the sustained-contact phase against closed-form mechanics (issue 39,
// point 2): a block sliding to rest, Euler's disk in steady precession, a die rocking about a
// sticking edge onto its face. Each returns the measured error for one integrator setting, so that
// any sustained-contact integrator can be measured the same way: pass a factory that builds its
// step function for a die (fixed_steps() wraps today's FixedStepper as `impulse` and `stepped` use
// it). tests/test_sustained_checks.cpp asserts the tolerances and prints the error-vs-step tables.
#pragma once

#include <cmath>
#include <functional>
#include <memory>
#include <string>

#include "scenes_for_tests.hpp"
#include "sim/body/die_model.hpp"
#include "sim/body/rim.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim::testing {

// One step of a sustained-contact integrator: advances s, returns the time it advanced (s).
using SustainedStep = std::function<double(RigidState&)>;
// Builds a fresh integrator (its own state) for a die.
using SustainedFactory = std::function<SustainedStep(const DieModel&)>;

// Today's FixedStepper with step h (<= 0: the die's contact_step). impulse = true: as `impulse`'s
// sustained phase runs it (gravity threshold, held corners sinking at most held_corner_sink);
// false: as `stepped` runs it (contact threshold, no sink bound).
inline SustainedFactory fixed_steps(double h, bool impulse = true) {
  return [h, impulse](const DieModel& m) -> SustainedStep {
    const double step = h > 0.0 ? h : m.contact_step;
    auto st = impulse ? std::make_shared<FixedStepper>(m, step, ImpactThreshold::Gravity, held_corner_sink(m))
                      : std::make_shared<FixedStepper>(m, step, ImpactThreshold::Contact);
    return [st](RigidState& s) {
      st->step(s);
      return st->last_dt();
    };
  };
}

// `impulse`'s sustained phase on a polyhedron: leapfrog steps of error-controlled length (tol,
// AdaptiveSteps), ceiling h (<= 0: the die's contact_step), as impulse_model.cpp sets it up.
inline SustainedFactory adaptive_steps(double tol, double h = 0.0) {
  return [tol, h](const DieModel& m) -> SustainedStep {
    const double step = h > 0.0 ? h : m.contact_step;
    const AdaptiveSteps a{.tol = tol, .floor = std::min(kContactStepFloor, step), .threshold_step = m.sustained_step};
    auto st = std::make_shared<FixedStepper>(m, step, ImpactThreshold::Gravity, held_corner_sink(m), a);
    return [st](RigidState& s) {
      st->step(s);
      return st->last_dt();
    };
  };
}

// The height of s's lowest contact point relative to its COM (< 0).
inline double lowest_offset(const DieModel& m, const Mat3& R) {
  double low = 0.0;
  for (int i = 0; i < m.vertex_count(); ++i) low = std::min(low, contact_point(m, R, i).z());
  return low;
}

struct CheckResult {
  double measured = 0.0;
  double expected = 0.0;
  double rel_error = 0.0;  // (measured - expected) / expected
  long steps = 0;
};

// a. A 3 cm cube (fair_scene, friction mu) lying flat on its -z face, sliding along x at v with no
// spin: Coulomb friction decelerates it at mu g, so it stops after v^2 / (2 mu g). measured: the
// distance its COM travelled until it stopped (speed below 1e-9 v).
inline CheckResult sliding_block(const SustainedFactory& make, double v = 1.0, double mu = 0.3) {
  SceneDef def = fair_scene();
  def.materials["plastic"].friction = mu;
  const DieModel m = compile(def);
  RigidState s;
  s.R = m.geo_to_body.transpose();
  s.position = Vec3(0.0, 0.0, -lowest_offset(m, s.R));
  s.velocity = Vec3(v, 0.0, 0.0);
  const Vec3 start = s.position;
  SustainedStep step = make(m);
  CheckResult r;
  r.expected = v * v / (2.0 * mu * m.gravity);
  const double t_stop = v / (mu * m.gravity);
  double t = 0.0;
  while (t < 3.0 * t_stop && s.velocity.norm() + s.omega.norm() * m.bounding_radius > 1e-9 * v) {
    t += step(s);
    ++r.steps;
  }
  r.measured = (s.position - start).head<2>().norm();
  r.rel_error = (r.measured - r.expected) / r.expected;
  return r;
}

// b. Euler's disk: the quarter (scenes/coins/quarter.toml: a cylinder 24.26 mm across, 1.75 mm
// thick, rims rounded 0.2 mm) with high friction and no rolling or pivoting resistance, rolling
// without slipping with its centre at rest, its axis n at angle alpha from the vertical (the
// face alpha from the floor), n precessing about the vertical at Omega.
// Steady motion (world frame, n = (sin a, 0, cos a) at t = 0, the contact point P at r = P - COM,
// fixed in the frame turning at Omega e_z):
//  - the centre at rest and no slip at P: v_P = omega x r = 0, so omega = lambda r; with
//    omega = Omega e_z + s n (precession and spin) this fixes omega = Omega w~ (w~ in the x-z plane,
//    linear in r: its x and z components solve s n_x = lambda r_x, 1 + s n_z = lambda r_z);
//  - the COM at rest: the floor's force is m g e_z (no friction);
//  - L = I_world omega = Omega L~ turns with the frame: dL/dt = Omega^2 e_z x L~ = r x m g e_z.
//  Its y component: Omega^2 = m g (r x e_z)_y / (e_z x L~)_y. (A thin disk of radius a, r = a u,
//  I = m a^2 / 4 about a diameter: Omega^2 = 4 g / (a sin alpha), the textbook result.)
// r: the lower rim's lowest point, a' u - h' n - rho e_z (u = (cos a, 0, -sin a) down the face,
// a' and h' the core's radius and half-height, rho the rounding).
// (tests/test_cylinder.cpp's EulersDiskPrecessesAtTheSteadyRate puts the contact at the corner of
// the cylinder enlarged by the rounding; here it is the rounded rim's lowest point, the model's.)
// measured: the azimuth of n advanced over `duration` (default 0.5 s, 6.5 turns at 30 deg: the
// steady motion must be kept, not only started) divided by the time (unwrapped): euler_disk below.

// The quarter (scenes/coins/quarter.toml), its rolling and pivoting resistance kept or removed.
inline SceneDef quarter_scene(bool resistances) {
  SceneDef def = load_scene(std::string(DICESIM_SOURCE_DIR) + "/scenes/coins/quarter.toml");
  if (!resistances)
    for (auto& [name, mat] : def.materials) mat.rolling_resistance = mat.pivoting_resistance = 0.0;
  return def;
}
// The quarter as Euler's disk uses it: friction mu, no rolling or pivoting resistance.
inline DieModel euler_disk_model(double mu = 2.0) {
  SceneDef def = quarter_scene(false);
  for (auto& [name, mat] : def.materials) mat.friction = mu;
  return compile(def);
}

// Euler's disk's steady state at alpha (above) for m; returns Omega, the steady precession rate
// (0 if the model's lowest point is not the one the derivation holds: not the other rim).
inline double euler_disk_state(const DieModel& m, double alpha, RigidState& s) {
  const Vec3 n(std::sin(alpha), 0.0, std::cos(alpha));
  const Vec3 u(std::cos(alpha), 0.0, -std::sin(alpha));
  const Vec3 ez = Vec3::UnitZ();
  s = RigidState{};
  s.R = Quat::FromTwoVectors(m.rims.axis, n).toRotationMatrix();
  const Vec3 r = s.R * m.rims.centre + m.rims.radius * u - m.rims.half * n - m.rounding * ez;
  const double lambda = 1.0 / (r.z() - r.x() * n.z() / n.x());
  const Vec3 w = lambda * r;  // for Omega = 1
  const Mat3 I = s.R * m.principal_moments.asDiagonal() * s.R.transpose();
  const Vec3 L = I * w;
  const double omega = std::sqrt(m.mass * m.gravity * r.cross(ez).y() / ez.cross(L).y());
  s.position = Vec3(0.0, 0.0, -r.z());
  s.omega = omega * w;
  if (std::abs(lowest_offset(m, s.R) - r.z()) > 1e-12) return 0.0;
  return omega;
}

inline CheckResult euler_disk(const SustainedFactory& make, double alpha = 30.0 * kPi / 180.0,
                              double duration = 0.5) {
  const DieModel m = euler_disk_model();
  RigidState s;
  CheckResult res;
  res.expected = euler_disk_state(m, alpha, s);
  if (res.expected == 0.0) return {0.0, 0.0, 1.0, 0};
  const Vec3 n = s.R * m.rims.axis;
  SustainedStep step = make(m);
  double t = 0.0, phi = 0.0;
  Vec3 prev = n;
  while (t < duration) {
    t += step(s);
    ++res.steps;
    const Vec3 a = s.R * m.rims.axis;
    phi += std::atan2(prev.x() * a.y() - prev.y() * a.x(), prev.x() * a.x() + prev.y() * a.y());
    prev = a;
  }
  res.measured = phi / t;
  res.rel_error = (res.measured - res.expected) / res.expected;
  return res;
}

// d. Euler's disk wobbling: the steady state above (alpha 60 deg) with `spin` rad/s more about
// the coin's axis, so the tilt nutates (about 49-60 deg at mu 2, 45-60 deg at mu 0) while the
// rim rolls (mu 2, sticking throughout) or slides (mu 0) on the floor without leaving it. With
// no restitution at stake, no resistance and no slip that friction resists, the motion keeps its
// energy E = kinetic + m g z_COM. measured: the relative energy change per second, (E(t) - E(0)) /
// (E(0) t) over `duration`; expected 0 (rel_error = measured). This is the damping of a coin's
// wobble that the sustained step itself adds.
inline CheckResult wobbling_disk(const SustainedFactory& make, double mu, double spin = 5.0, double duration = 0.3) {
  const DieModel m = euler_disk_model(mu);
  RigidState s;
  CheckResult res;
  if (euler_disk_state(m, 60.0 * kPi / 180.0, s) == 0.0) return {1.0, 0.0, 1.0, 0};
  s.omega += spin * (s.R * m.rims.axis);
  Vec3 r = contact_point(m, s.R, 0);  // the lower rim's lowest point (the state's contact) ...
  if (const Vec3 r1 = contact_point(m, s.R, 3); r1.z() < r.z()) r = r1;
  s.velocity = -s.omega.cross(r);  // ... at rest on the floor
  const auto energy = [&] { return kinetic_energy(m, s) + m.mass * m.gravity * s.position.z(); };
  const double e0 = energy();
  SustainedStep step = make(m);
  double t = 0.0;
  while (t < duration) {
    t += step(s);
    ++res.steps;
  }
  res.measured = (energy() - e0) / (e0 * t);
  res.rel_error = res.measured;
  return res;
}

// c. A 3 cm cube (fair_scene, friction mu: the edge sticks) balanced on an edge of its -z face and
// tipped back by theta0 toward that face, released at rest: it turns about the edge and lands on
// the face. Energy (no slip, no loss before the landing): omega^2 = 2 m g (h_start - h_land) / I_edge,
// I_edge the moment about the edge (I_com about its direction + m d^2). measured: |omega| of the
// last state before the landing impact (the step after which |omega| drops by more than half);
// the test checks that state's face is within 1e-3 rad of flat.
struct RockingResult : CheckResult {
  double tilt_at_landing = 0.0;  // angle of the landing face to the floor in that state (rad)
};
inline RockingResult rocking_die(const SustainedFactory& make, double theta0 = 0.1, double mu = 1.0) {
  SceneDef def = fair_scene();
  def.materials["plastic"].friction = mu;
  def.materials["plastic"].restitution = 0.0;  // the landing stops it (|omega| drops to ~0)
  const DieModel m = compile(def);
  const double beta = 0.25 * kPi - theta0;
  RigidState s;
  s.R = Eigen::AngleAxisd(beta, Vec3::UnitX()).toRotationMatrix() * m.geo_to_body.transpose();
  s.position = Vec3(0.0, 0.0, -lowest_offset(m, s.R));
  // The edge: the -z face's corners with geometric y = -edge/2 (the two lowest); its direction x.
  const Vec3 face_n = m.geo_to_body * Vec3(0.0, 0.0, -1.0);  // the landing face's normal, body frame
  Vec3 edge_point = Vec3::Zero();
  int on_edge = 0;
  for (int i = 0; i < m.vertex_count(); ++i) {
    const Vec3 p = contact_point(m, s.R, i);
    if (p.z() < lowest_offset(m, s.R) + 1e-12) {
      edge_point += p;
      ++on_edge;
    }
  }
  edge_point /= on_edge;
  const Vec3 e = Vec3::UnitX();
  const Vec3 d = -edge_point - (-edge_point).dot(e) * e;  // COM relative to the edge, perpendicular
  const Mat3 I = s.R * m.principal_moments.asDiagonal() * s.R.transpose();
  const double I_edge = e.dot(I * e) + m.mass * d.squaredNorm();
  const int landing_face = 5;  // -z in the shape's face order (+x, -x, +y, -y, +z, -z)
  const double h_start = s.position.z(), h_land = m.face_height[landing_face];
  RockingResult res;
  res.expected = std::sqrt(2.0 * m.mass * m.gravity * (h_start - h_land) / I_edge);
  SustainedStep step = make(m);
  double t = 0.0;
  while (t < 2.0) {
    const RigidState before = s;
    t += step(s);
    ++res.steps;
    if (s.omega.norm() < 0.5 * before.omega.norm() && before.omega.norm() > 0.5 * res.expected) {
      res.measured = before.omega.norm();
      res.tilt_at_landing = std::acos(std::min(1.0, -(before.R * face_n).z()));
      break;
    }
  }
  res.rel_error = (res.measured - res.expected) / res.expected;
  if (on_edge != 2) res.rel_error = 1.0;  // not the edge balance the check means
  return res;
}

// e, f. The quarter upright on its band, where a dropped quarter's edge outcomes come from (issue
// 39): the edge basin is the coin tilted less than atan(b' / a') ~ 3.24 deg (b', a': the core's
// half-height and radius), its barrier only ~19 um of COM lift above standing straight up, and an
// edge outcome is a coin whose energy fell below that barrier while it stayed in the band. The
// quarter (scenes/coins/quarter.toml) starts with its axis horizontal but tilted up by `tilt`,
// standing on the lower rim circle's lowest point, that point at rest on the floor.
inline RigidState upright_quarter(const DieModel& m, double tilt, const Vec3& omega) {
  RigidState s;
  const Vec3 K(std::cos(tilt), 0.0, std::sin(tilt));  // the coin's axis, world
  s.R = Quat::FromTwoVectors(m.rims.axis, K).toRotationMatrix();
  s.position = Vec3(0.0, 0.0, -rim_lowest(m, s.R));
  Vec3 r = contact_point(m, s.R, 0);
  if (const Vec3 r3 = contact_point(m, s.R, 3); r3.z() < r.z()) r = r3;
  s.omega = omega;
  s.velocity = -s.omega.cross(r);
  return s;
}

// E / (m g) as the "outcome settled" rule counts it (rim_rest.cpp): kinetic energy over m g plus
// the COM height, a rim below the floor counted at the floor (m).
inline double lift_energy(const DieModel& m, const RigidState& s) {
  const double low = s.position.z() + rim_lowest(m, s.R);
  return kinetic_energy(m, s) / (m.mass * m.gravity) + s.position.z() + std::max(0.0, -low);
}

// e. A wobbling roller: the quarter rolling like a wheel on its band (`roll` rad/s about its axis,
// ~0.36 m/s at 30) with a tilt wobble (`tilt_rate` rad/s about the horizontal in its plane, so
// the tilt swings across the band, ~+-3 deg, and its lowest point changes rim circle ~17 times a
// second), no rolling or pivoting resistance. Then E = kinetic + m g z_COM only falls at the
// rim changes (the other rim circle landing, a plastic contact below the impact threshold): a
// step that starts on one rim circle should keep E. measured: E's change per second (lift units,
// m/s) over `duration`, split by the steps' start: one rim circle on the floor (step error only),
// both (the changes), neither; and the tilt's amplitude over the first and last tenth.
struct RollerResult {
  double one_rim = 0.0, two_rims = 0.0, none = 0.0;  // dE / (m g) per second (m/s)
  double amp_start = 0.0, amp_end = 0.0;             // largest tilt in the first / last 10 % (rad)
  long steps = 0;
};
inline DieModel upright_quarter_model(bool resistances) { return compile(quarter_scene(resistances)); }
inline RollerResult wobbling_roller(const SustainedFactory& make, double roll = 30.0, double tilt = 1.0 * kPi / 180.0,
                                    double tilt_rate = 2.0, double duration = 1.0) {
  const DieModel m = upright_quarter_model(false);
  const Vec3 K(std::cos(tilt), 0.0, std::sin(tilt));
  RigidState s = upright_quarter(m, tilt, roll * K + tilt_rate * Vec3::UnitZ().cross(K).normalized());
  const auto on_floor = [&](const RigidState& q) {
    const RimFeatures rf(m, q.R);
    const double tol = 1e-6;  // m: a rim circle's lowest point this close touches
    return (q.position.z() + rf.point(0).z() < tol ? 1 : 0) + (q.position.z() + rf.point(3).z() < tol ? 1 : 0);
  };
  const auto tilt_of = [&](const RigidState& q) { return std::asin(std::min(1.0, std::abs((q.R * m.rims.axis).z()))); };
  SustainedStep step = make(m);
  RollerResult res;
  double t = 0.0, de[3] = {0.0, 0.0, 0.0};
  while (t < duration) {
    const int k = on_floor(s);
    const double e0 = lift_energy(m, s);
    t += step(s);
    ++res.steps;
    de[k] += lift_energy(m, s) - e0;
    if (t < 0.1 * duration) res.amp_start = std::max(res.amp_start, tilt_of(s));
    if (t > 0.9 * duration) res.amp_end = std::max(res.amp_end, tilt_of(s));
  }
  res.none = de[0] / t;
  res.one_rim = de[1] / t;
  res.two_rims = de[2] / t;
  return res;
}

// g. A rocking coin: the quarter standing on its band, no resistances, tilted `tilt` and released
// at rest. It rocks between its two rim circles (the other circle landing slower than any impact
// threshold: plastic), losing a little at each landing. measured: the lift it lost in `duration`,
// E / (m g) at the start less at the end (m).
inline double rocking_coin(const SustainedFactory& make, double tilt, double duration = 0.8) {
  const DieModel m = upright_quarter_model(false);
  RigidState s = upright_quarter(m, tilt, Vec3::Zero());
  const double e0 = lift_energy(m, s);
  SustainedStep step = make(m);
  double t = 0.0;
  while (t < duration) t += step(s);
  return e0 - lift_energy(m, s);
}

// f. A spinning coin: the quarter (its own materials: rolling and pivoting resistance on) spinning
// at `spin` rad/s about the vertical through its contact point, tilted `tilt`. It spins down
// (pivoting resistance, the rim changes) and, below a spin of ~14 rad/s, tips out of the band and
// falls flat, with its spin's energy still ~20x the barrier: it can end `edge` only if something
// holds it in the band until the spin's energy, m a^2 w^2 / 8, falls below the barrier (w ~3 rad/s).
// measured: the spin about the vertical (rad/s) when it fell (tilt past 30 deg) or was captured.
struct SpinResult {
  bool captured = false;  // the rest rule read `edge` (the side, face 2) before it fell
  double spin = 0.0;      // |w_z| at the fall or the capture (rad/s)
  double spin_4s = 0.0;   // |w_z| at the first step's end at or after t = 4 s, still upright (0: fallen before)
  double t = 0.0;
  long steps = 0;
};
inline SpinResult spinning_upright(const SustainedFactory& make, double spin = 30.0, double tilt = 1.0 * kPi / 180.0,
                                   double max_time = 40.0) {
  const DieModel m = upright_quarter_model(true);
  RigidState s = upright_quarter(m, tilt, Vec3(0.0, 0.0, spin));
  SustainedStep step = make(m);
  SpinResult res;
  while (res.t < max_time) {
    res.t += step(s);
    ++res.steps;
    if (res.spin_4s == 0.0 && res.t >= 4.0) res.spin_4s = std::abs(s.omega.z());
    const int f = rest_face_down(m, s, 0.5, kinetic_energy(m, s));
    if (f >= 0 || std::abs((s.R * m.rims.axis).z()) > 0.5) {
      res.captured = f == 2;
      break;
    }
  }
  res.spin = std::abs(s.omega.z());
  return res;
}

}  // namespace dicesim::testing
