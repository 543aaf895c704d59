// FixedStepper's trial steps: one step of a given length from a start with its contact set
// (try_step, try_step_with: a flat die's held corners asked to rise), and the held corners'
// bookkeeping around it (predicted_step, held_sink, held_energy).
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/contact_stepper_internal.hpp"

#include <cmath>
#include <limits>

#include <Eigen/QR>

#include "sim/dynamics/friction_impact.hpp"

namespace dicesim {

using stepper_detail::mechanical_energy;

namespace {

// Leapfrog: the velocity (m/s, world) at which the solve at the step's middle holds c's corners
// (its bias). A corner moves with the free rotation except for the solve: acceleration a = w x
// (w x r) + dw/dt x r, dw/dt = -I_w^-1 (w x L), taken at the middle before the solve. Held at B
// there, it ends the step a half^2 + B half from where it started, moving at B + a half: B = -a
// half returns it to its start, at rest, to first order. The whole vector, not only its normal
// part: on a die rocking about a held edge, a is the pivot's centripetal acceleration, along the
// line to the COM. With B = 0 the pivot ended every step a half^2 above the floor and ahead of
// where it was: it left the contact set, fell and landed again plastically, losing energy, a loss
// that moved with the tolerance. Holding only the normal part put the centripetal impulse off the
// line through the COM, a torque that changed the spin by O(h) (the landing speed 0.2-0.5 % low).
// The normal part also corrects the corner's start height z and normal velocity v: above the
// floor - k (z / d + v / 2), which takes (z, v d) to (z (1 - k / 2) + v d (1 - k / 2) / 2, -k z -
// k v d / 2), eigenvalues 0 and 1 - k: back to the floor without oscillation (closing the
// middle's gap alone reflects v every step, a period-2 oscillation that never decays); below it
// - k v / 2 and its depth over span (a single corner: the depth term is try_step's, shallow). k =
// d / span: over the ceiling's length, as the depth (with k = 1 the bias varied as 1 / d across a
// located step's trials, and a Die 1 toss took 2.56 trials per located step instead of 2.29).
// Two or more corners (an edge, a face) are each asked for their own rise: the solve's target is
// shifted by a rigid motion, a rise b at the COM plus a horizontal spin W (tilt), which matches
// affine asks exactly, as every ask is across one edge or face. With one rise for all (the most
// any corner asked) a face that landed tilted stayed tilted, its corners 0.2-3 um apart for the
// rest of the contact: never "lying flat" (rest.cpp, 1e-6 r), so a Die 1 toss took ~6 four-corner
// steps (each a Gauss-Seidel solve) before the energy rule ended it. The tangential part is the
// most-asking corner's acceleration term, less what W moves the corners sideways. (The spin the
// solve makes is not in a: predicted from the last step's impulses it sank held corners 50 um,
// after a sub-threshold landing whose impulse was no force.)
struct LeapfrogBias {
  Vec3 B;     // the shift of the solve's target velocity at the COM: tangential slip, normal rise b
  Vec3 tilt;  // W, horizontal (rad/s, world): the shift of its spin
};
LeapfrogBias leapfrog_bias(const DieModel& m, const RigidState& s0, const ContactSet& c, const Mat3& R_mid,
                           const Vec3& w, double d, double k, double shallow_term, double span, double touch_tol) {
  const double half = 0.5 * d;
  const Vec3 wb = R_mid.transpose() * w;
  const Vec3 alpha = R_mid * (-(wb.cross(Vec3(m.principal_moments.cwiseProduct(wb)))).cwiseQuotient(m.principal_moments));
  LeapfrogBias out{Vec3(0.0, 0.0, -std::numeric_limits<double>::infinity()), Vec3::Zero()};
  double ask[kMaxContacts];
  Vec3 rm[kMaxContacts];
  for (int i = 0; i < c.n; ++i) {
    const Vec3 r = contact_point(m, R_mid, c.vertex[i]);
    const Vec3 r0 = contact_point(m, s0.R, c.vertex[i]);
    const double z = s0.position.z() + r0.z();
    const double v = (s0.velocity + s0.omega.cross(r0)).z();
    const Vec3 a = w.cross(w.cross(r)) + alpha.cross(r);
    const double bn = z > 0.0 ? -a.z() * half - k * (z / d + 0.5 * v) : -a.z() * half - 0.5 * k * v;
    if (bn > out.B.z()) out.B = Vec3(-a.x() * half, -a.y() * half, bn);
    rm[i] = r;
    ask[i] = std::min(bn + (z < -touch_tol ? -z / span : 0.0), m.gravity * d);
  }
  if (c.n < 2) {
    out.B.z() += shallow_term;
    return out;
  }
  // The asks as b0 + (W x r_i)_z: along an edge W is normal to it; on a face, least squares (exact:
  // depth, acceleration and velocity are affine across a rigid face).
  Vec3 W = Vec3::Zero();
  if (c.n == 2) {
    const Vec3 e = rm[1] - rm[0];
    const double e2 = e.x() * e.x() + e.y() * e.y();
    if (e2 > 0.0) {
      const double s = (ask[1] - ask[0]) / e2;
      W = Vec3(s * e.y(), -s * e.x(), 0.0);  // (W x e)_z = W_x e_y - W_y e_x
    }
  } else {
    // Dynamic sizes with fixed maxima: on the stack, no allocation in a toss.
    Eigen::Matrix<double, Eigen::Dynamic, 3, 0, kMaxContacts, 3> A(c.n, 3);
    Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxContacts, 1> b(c.n);
    for (int i = 0; i < c.n; ++i) {
      A(i, 0) = 1.0;
      A(i, 1) = rm[i].y() / m.bounding_radius;
      A(i, 2) = -rm[i].x() / m.bounding_radius;
      b(i) = ask[i];
    }
    const Eigen::Vector3d x = A.colPivHouseholderQr().solve(b);
    W = Vec3(x(1) / m.bounding_radius, x(2) / m.bounding_radius, 0.0);
  }
  // The rise at the COM: every corner at least its ask.
  double b0 = -std::numeric_limits<double>::infinity();
  double rz = 0.0;
  for (int i = 0; i < c.n; ++i) {
    b0 = std::max(b0, ask[i] - W.cross(rm[i]).z());
    rz += rm[i].z();
  }
  rz /= c.n;
  out.B.z() = b0;
  // The spin shift moves the corners horizontally by rz (W_y, -W_x): taken out of the slip's.
  out.B.x() -= rz * W.y();
  out.B.y() += rz * W.x();
  out.tilt = W;
  return out;
}

}  // namespace

void FixedStepper::try_step(const RigidState& s0, const ContactSet& c, double d, Attempt& a, bool full) {
  const DieModel& m = *m_;
  // `impulse` (hold_): a flat die's held corners are asked to end the step on the floor, v_n >= b
  // at every one of them after the solve (the solve on the velocity shifted by -b e_z, then
  // restored), b = depth / d + a_n d / 2: the shallowest one's depth at the start (what earlier
  // steps left) and what the free rotation's downward acceleration a_n < 0 of the corners would
  // sink them within the step (predicted_step). Without it a corner held while the die spins
  // over it sank a micrometre a step, and kept sinking: up to 0.3 mm in 10^4 Die 1 tosses.
  // b is at most gravity's kick g d, and the step may not gain energy as the rest rules count
  // it, kinetic + m g (COM height + the deepest corner's depth) (rest.hpp): the rise lifts the
  // COM by what the depth falls. At a resting corner, dE = m_eff b^2 / 2 - (m - m_eff)(b g d +
  // g^2 d^2 / 2) (m_eff = 1 / W_nn), so b = g d costs energy only where m_eff > 3 m / 4 (a corner
  // nearly under the COM). Checked at the step's end: if it gains, b / 4, then none: the plain
  // step, which never gains kinetic + m g z (counted, rise_dropped; its corners' depth stays).
  if (full) full_bias_ = 0.0;
  slip_bias_ = Eigen::Vector2d::Zero();
  tilt_bias_ = Vec3::Zero();
  mid_d_ = -1.0;
  if (!hold_ || m.curved() || c.n == 0) {
    try_step_with(s0, c, d, a, full, 0.0);
    return;
  }
  // Adaptive steps: the depth is taken out over the ceiling's length at least (a short step asked
  // to close it alone would rise fast, and gain energy).
  const double span = adaptive_.tol > 0.0 ? std::max(d, h_max_) : d;
  double b;
  if (leapfrog() && d > 0.0) {
    // The leapfrog's solve is at the step's middle: what the held corners ask there, a vector
    // (leapfrog_bias), replaces a_down_'s term; negative where the pivot's acceleration lifts it.
    start_rot_->state(0.5 * d, mid_R_, mid_w_);
    mid_d_ = d;
    const LeapfrogBias lb =
        leapfrog_bias(m, s0, c, mid_R_, mid_w_, d, d / span, start_shallow_ / span, span, touch_tol_);
    slip_bias_ = lb.B.head<2>();
    tilt_bias_ = lb.tilt;
    b = std::min(lb.B.z(), m.gravity * d);
  } else {
    b = std::min(start_shallow_ / span + 0.5 * a_down_ * d, m.gravity * d);
  }
  // (The leapfrog's whole bias, normal and tangential, is checked and scaled down alike.)
  if (try_step_with(s0, c, d, a, full, b)) {
    if (full) full_bias_ = b;
    return;
  }
  slip_bias_ *= 0.25;
  tilt_bias_ *= 0.25;
  if (try_step_with(s0, c, d, a, full, 0.25 * b)) {
    if (full) full_bias_ = 0.25 * b;
    return;
  }
  slip_bias_.setZero();
  tilt_bias_.setZero();
  try_step_with(s0, c, d, a, full, 0.0);
  a.rise_dropped = true;
}

bool FixedStepper::try_step_with(const RigidState& s0, const ContactSet& c, double d, Attempt& a, bool full,
                                 double bias) {
  // The impact (solved once per step in step(): it does not depend on d) is already in s0.
  a.s = s0;
  a.impact = impact_;
  if (impact_) a.imp = imp_;
  a.next.n = 0;
  a.capped = a.clamped = false;
  a.slip_vertex = -1;
  a.risen = bias != 0.0 || !slip_bias_.isZero() || !tilt_bias_.isZero();  // (fixed steps: bias >= 0, no slip)
  a.rise_dropped = false;
  if (leapfrog()) {
    try_step_dkd(s0, c, d, a, full, bias);
  } else {
    try_step_fixed(s0, c, d, a, full, bias);
  }
  if (!a.risen) return true;
  // (New corners below the floor are the located step's business.)
  a.held_e = held_energy(a.s, c);
  return a.held_e <= e_start_ + m_->mass * m_->gravity * start_depth_max_ + split_gain(d);
}

void FixedStepper::try_step_fixed(const RigidState& s0, const ContactSet& c, double d, Attempt& a, bool full,
                                  double bias) {
  const DieModel& m = *m_;
  RigidState& s = a.s;  // (s0 until the kick)
  if (m.curved() && c.n > 0) {  // a rim's step is drift-kick-drift (rim_step.cpp)
    try_step_rim(c, d, a, full);
    return;
  }
  s.velocity.z() -= kick_g_ * d;
  // Built in place (the full step's is kept for model_G; the object is large, so no copies).
  std::optional<TorqueFreeRotation>& slot = full ? full_rot_ : trial_rot_;
  if (c.n > 0) {
    s.velocity.z() -= bias;
    a.sup = apply_friction_impact(m, s, c, /*restitution=*/false, &warm_, &a.next, &geo_);
    s.velocity.z() += bias;
  }
  // Free motion for d: straight COM, exact torque-free rotation (kinetic energy exact). A trial of
  // a step without contact has the full step's rotation exactly (the same s0.R and, with no
  // impulse, the same angular momentum): it is reused.
  const TorqueFreeRotation& rot = !full && c.n == 0 && full_rot_ ? *full_rot_
                                                                    : slot.emplace(moments_, s.R,
                                                                                   Vec3(Iw_start_ * s.omega), full);
  rot_start_ = s.R;
  const Vec3 p = s.position, v = s.velocity;
  // Every body point lies within the bounding radius of the COM (|bottom row| = 1 to rounding, far
  // inside the relative 1e-9): a full step that ends with the COM that far above the floor cannot
  // bring a corner below it, and its G is only compared with -touch_tol (the shortened steps'
  // search, which needs G's value, never starts from such a step). Most of `stepped`'s steps are
  // in the air: this skips their corner heights (and the rotation's evaluation for them).
  const double clear = p.z() + v.z() * d - (1.0 + 1e-9) * m.bounding_radius;
  // The step's end orientation is evaluated once: its bottom row is bit for bit the one
  // bottom_row(d) returns (the same operations on the same row), so a flat die's corner heights
  // come from it (a curved die's rim, and d = 0, keep lowest_new's own evaluation).
  // (Written straight into s: rot holds its own copy of the start.)
  if (full) {
    full_p_ = p;
    full_v_ = v;
    full_w_ = s.omega;
  }
  rot.state(d, s.R, s.omega);
  if (full && clear > 0.0)
    a.G = clear;
  else if (m.curved() || d == 0.0)
    a.G = lowest_new(c, p, v, rot, d);
  else
    a.G = lowest_flat(c, p, v, s.R.row(2).transpose(), d);
  // The COM's horizontal path with the step's mean velocity, not its end velocity: the solve at
  // the start stands for a force over the whole step (friction decelerating a sliding face), under
  // which the mean velocity is exact; the end velocity put a block sliding to rest short by
  // mu g h^2 / 2 a step, v h / 2 in all (-0.88 % at 3 ms). Horizontally only: nothing in the
  // model depends on where the die is on the floor (so no outcome changes), and the height, which
  // the energy argument and the contact search use, keeps the end velocity. (A curved die in
  // contact takes try_step_rim's drift-kick-drift instead.)
  Vec3 path = v;
  path.head<2>() = 0.5 * (s0.velocity.head<2>() + v.head<2>());
  s.position = p + d * path;
}

void FixedStepper::try_step_dkd(const RigidState& s0, const ContactSet& c, double d, Attempt& a, bool full,
                                double bias) {
  const DieModel& m = *m_;
  RigidState& s = a.s;
  const double half = 0.5 * d;
  std::optional<TorqueFreeRotation>& slot = full ? full_rot_ : trial_rot_;
  if (c.n == 0) {
    // No solve: the whole step is free motion, gravity's parabola exactly.
    start_rot_->state(d, s.R, s.omega);
    s.position = s0.position + d * s0.velocity;
    s.position.z() -= 0.5 * kick_g_ * d * d;
    s.velocity.z() -= kick_g_ * d;
    if (full) {
      full_p_ = s0.position;
      full_v_ = s.velocity;
      full_w_ = s0.omega;
      slot = start_rot_;  // the model's free motion is this motion
    }
  } else {
    if (mid_d_ == d) {  // try_step's evaluation for the bias, of the same trial
      s.R = mid_R_;
      s.omega = mid_w_;
    } else {
      start_rot_->state(half, s.R, s.omega);
    }
    s.position = s0.position + half * s0.velocity;
    s.velocity.z() -= kick_g_ * d;
    s.velocity.z() -= bias;
    s.velocity.head<2>() -= slip_bias_;
    s.omega -= tilt_bias_;
    a.sup = apply_friction_impact(m, s, c, /*restitution=*/false, &warm_, &a.next);
    s.velocity.z() += bias;
    s.velocity.head<2>() += slip_bias_;
    s.omega += tilt_bias_;
    const Vec3 L = world_inertia(m, s.R) * s.omega;  // the solve's angular momentum, kept by the second half
    if (full) {
      full_p_ = s0.position;
      full_v_ = s.velocity;
      full_w_ = s.omega;
      // The location model: s0's free motion with the solve's momenta (the trials correct it).
      slot.emplace(moments_, s0.R, L, true);
    }
    const TorqueFreeRotation second(moments_, s.R, L, false);
    second.state(half, s.R, s.omega);
    s.position += half * s.velocity;
  }
  rot_start_ = s0.R;
  a.G = lowest_flat(c, s.position, Vec3::Zero(), s.R.row(2).transpose(), 0.0);
  if (full) {
    model_slope_ = 0.0;
    if (d > 0.0) model_slope_ = (a.G - model_G(c, d)) / d;
  }
}

double FixedStepper::predicted_step(const RigidState& s0, const ContactSet& c) {
  // A held corner r (from the COM) leaves the start's solve with normal velocity >= 0 and then
  // moves with the free rotation: its height gains a_n d^2 / 2, a_n = e_z . (w x (w x r) + dw/dt x r)
  // with dw/dt = -I_w^-1 (w x L) (torque-free, L = I_w w). (The solve changes w a little; the
  // accepted step is checked, step().)
  const DieModel& m = *m_;
  const Vec3& w = s0.omega;
  const Vec3 L = Iw_start_ * w;
  const Vec3 wb = s0.R.transpose() * (w.cross(L));
  const Vec3 alpha = -(s0.R * wb.cwiseQuotient(m.principal_moments));
  double a_min = 0.0;
  for (int i = 0; i < c.n; ++i) {
    const Vec3 r = s0.R * m.vertices[static_cast<std::size_t>(c.vertex[i])];
    a_min = std::min(a_min, (w.cross(w.cross(r)) + alpha.cross(r)).z());
  }
  a_down_ = -a_min;
  if (!(a_min < 0.0)) return h_ctrl_;
  const double d = std::sqrt(2.0 * max_sink_ / -a_min);
  return std::clamp(d, std::min(h_ctrl_, h_max_ / kMinStepDivisor), h_ctrl_);
}

double FixedStepper::held_energy(const RigidState& s, const ContactSet& c) const {
  const DieModel& m = *m_;
  const Vec3 z_row = s.R.row(2).transpose();
  double depth = 0.0;
  for (int i = 0; i < c.n; ++i)
    depth = std::max(depth, -(s.position.z() + z_row.dot(m.vertices[static_cast<std::size_t>(c.vertex[i])]) - m.rounding));
  return mechanical_energy(m, s) + m.mass * m.gravity * depth;
}

double FixedStepper::held_sink(const RigidState& s0, const RigidState& s, const ContactSet& c, double& depth) const {
  const DieModel& m = *m_;
  const Vec3 z0 = s0.R.row(2).transpose(), z1 = s.R.row(2).transpose();
  double sink = -std::numeric_limits<double>::infinity();
  depth = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < c.n; ++i) {
    const Vec3& v = m.vertices[static_cast<std::size_t>(c.vertex[i])];
    const double d0 = -(s0.position.z() + z0.dot(v) - m.rounding), d1 = -(s.position.z() + z1.dot(v) - m.rounding);
    sink = std::max(sink, d1 - std::max(0.0, d0));
    depth = std::max(depth, d1);
  }
  return sink;
}

}  // namespace dicesim
