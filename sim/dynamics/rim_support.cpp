// A curved die's (a coin's, a cylinder's) contact in FixedStepper: its lowest point over what
// counts as new contact (curved_low, slap_low), the support solve that holds its rims' lowest
// points on the floor (rim_support, start_support, curvature_support), and the impacts that strike
// its face's tripod or its rim's most approaching arc (add_face_tripod, rim_most_approaching,
// strike_rim).
#include "sim/dynamics/contact_stepper.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include "sim/body/rim.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/rim_rest.hpp"
#include "sim/illinois.hpp"

namespace dicesim {

double FixedStepper::curved_low(const ContactSet& c, const Mat3& R) const {
  if (rims_new_) return rim_lowest(*m_, R);
  double low = rim_lowest_excluding(*m_, R, c);
  if (slap_rims_ != 0) {
    const Vec3 z_row = R.row(2).transpose();
    for (int r = 0; r < 2; ++r)
      if (slap_rims_ & (1 << r)) low = std::min(low, slap_low(z_row, r));
  }
  return low;
}

double FixedStepper::slap_low(const Vec3& z_row, int rim) const {
  // A rim point at body angle phi (from perp towards axis x perp) is at height
  // z_row.centre_rim + radius (a cos phi + b sin phi) about the COM, a and b the world heights of
  // the two basis directions; the lowest point of the whole circle is at -(a, b). The far half,
  // (cos phi, sin phi).u0 <= 0: that point if it lies there, else the lower end of the half,
  // +-(u0 turned by 90 deg), at radius (a, b).w, w = (-u0_y, u0_x). Continuous across the two.
  // The near half (rim < 0) the same way with u0 reversed.
  const DieModel& m = *m_;
  const Vec3& k = m.rims.axis;
  const Vec3& e1 = m.rims.perp;
  const Vec3 e2 = k.cross(e1);
  const double a = z_row.dot(e1), b = z_row.dot(e2), kz = z_row.dot(k);
  const int ri = rim >= 0 ? rim : -rim - 1;
  const double u0 = slap_u_[ri][0], u1 = slap_u_[ri][1];
  const double base = z_row.dot(m.rims.centre) + (ri == 0 ? m.rims.half : -m.rims.half) * kz - m.rounding;
  const bool far = rim >= 0;
  const double dot = a * u0 + b * u1;
  const double drop = (far ? dot >= 0.0 : dot <= 0.0) ? std::sqrt(a * a + b * b) : std::abs(b * u0 - a * u1);
  return base - m.rims.radius * drop;
}

namespace {

// World height, relative to the COM, of the lowest point of rim `rim` (0: the +axis rim, 1: the
// other) from the orientation's bottom row (rim.hpp's rim_point for feature 3 rim, in closed form).
double rim_low_z(const DieModel& m, const Vec3& z_row, int rim) {
  const double kz = z_row.dot(m.rims.axis);
  return z_row.dot(m.rims.centre) + (rim == 0 ? m.rims.half : -m.rims.half) * kz -
         m.rims.radius * std::sqrt(std::max(0.0, 1.0 - kz * kz)) - m.rounding;
}

}  // namespace

double FixedStepper::support_low(const Vec3& z_row, int rim) const {
  return (slap_rims_ & (1 << rim)) ? slap_low(z_row, -rim - 1) : rim_low_z(*m_, z_row, rim);
}

void FixedStepper::rim_support(RigidState& s, const ContactSet& c, double d, double e_start, Attempt& a,
                               std::optional<TorqueFreeRotation>& rot, bool full) {
  start_support(s, c, d, e_start, a, rot);
  const DieModel& m = *m_;
  if (!(d > 0.0)) return;
  if (full) free_end_row_ = rot->bottom_row(d);
  if (full && !slap_located_ && !(a.sup.normal_impulse > 0.0)) {
    // Leaving (no push) and first rising, yet below the floor at the step's end: the sinking is
    // another part of the rim arriving (rims_new_).
    const double eps = 1e-3 * d;
    const double z0 = s.position.z() + rim_lowest(m, s.R);
    const double z1 = s.position.z() + s.velocity.z() * eps + rim_lowest(m, rot->orientation(eps));
    const double zd = s.position.z() + s.velocity.z() * d + rim_lowest(m, rot->orientation(d));
    rims_new_ = z1 > z0 && zd < -touch_tol_;
  }
  // The step being located to that arrival (its trials included) takes no curvature impulse: its
  // end is where the arriving part touches.
  if (!rims_new_) curvature_support(s, c, d, e_start, a, rot);
}

void FixedStepper::curvature_support(RigidState& s, const ContactSet& c, double d, double e_start, Attempt& a,
                                     std::optional<TorqueFreeRotation>& rot) {
  // What the start's solve leaves sinking (its touching material point leaves the floor, or the
  // bias was capped): the rim's lowest point, not a material point, goes down to second order
  // while the point that touched rises. The exact constraint is on the lowest point's height
  // phi(t), whose rate is the normal velocity of the material point there (envelope theorem) and
  // whose second derivative has the rim's curvature term on top of that point's acceleration.
  // Held at phi(0) = phi(d) = 0 by one impulse at the step's middle, tau = d / 2, at the rim's
  // lowest point there, asking v_n+ >= b with b the root of the exact end-of-step gap: with phi
  // quadratic over the step (phi'' = -k), phi(tau) = phi(0) + v0 tau - k tau^2 / 2 and the point
  // arrives at v- = v0 - k tau, so the end gap asks b = -v- - 2 phi(0) / d: the impulse reflects
  // the point's normal velocity, and its normal work P (v- + b) / 2 = -P phi(0) / d <= 0 (a
  // start on or above the floor). The constraint force of the continuous motion does no work
  // either (it acts on the material point at the lowest point, whose normal velocity phi' is 0 in
  // contact): this is its impulse, placed where its work vanishes. (At the start, tau = 0, the
  // same target pushes a point that is leaving: v- = v0 >= 0, b = k d / 2, a gain of P (v0 + b)/2.)
  // If the lowest point is above the floor at d / 2 (it first rose), tau is where it comes back,
  // phi(tau) = 0, the arriving part's instant. Not exact beyond second order, so the step's
  // energy is checked as the start's bias is (no gain; b capped, the residual lifted and counted
  // in step()).
  const DieModel& m = *m_;
  bool rim_in[2] = {false, false};
  for (int i = 0; i < c.n; ++i) rim_in[c.vertex[i] < 3 ? 0 : 1] = true;
  const Vec3 p0 = s.position, v0 = s.velocity;
  const TorqueFreeRotation& r0 = *rot;
  const auto phi = [&](double t) {  // the touching rims' lowest point at t of the start's free motion
    const Vec3 z_row = r0.bottom_row(t);
    double z = std::numeric_limits<double>::infinity();
    for (int r = 0; r < 2; ++r)
      if (rim_in[r]) z = std::min(z, p0.z() + v0.z() * t + support_low(z_row, r));
    return z;
  };
  if (!(phi(d) < 0.0)) return;
  double tau = 0.5 * d;
  const double f_mid = phi(tau);
  if (f_mid > touch_tol_) {  // it rose first: where it comes back down, in (d / 2, d)
    Illinois br{tau, f_mid, d, phi(d)};
    for (int k = 0; k < 40 && br.hi - br.lo > 1e-12 * d; ++k) {
      const double x = br.next();
      const double f = phi(x);
      if (std::abs(f) <= 1e-3 * touch_tol_) {
        br.lo = br.hi = x;
        break;
      }
      br.update(x, f, /*lo_side=*/f > 0.0);
    }
    tau = br.lo;
  }
  // The state at tau (free motion), and the lowest features of the touching rims there.
  RigidState mid = s;
  Vec3 w_tau;
  r0.state(tau, mid.R, w_tau);
  mid.omega = w_tau;
  mid.position = p0 + tau * v0;
  ContactSet cm;
  for (int r = 0; r < 2; ++r)
    if (rim_in[r]) cm.vertex[cm.n++] = 3 * r;
  const double rest = d - tau;
  const RigidState base = mid;
  ImpactResult res;
  int sweeps = 0;
  double gap_end = 0.0;  // the last solve's end gap
  // Every solve of the search is of cm at mid.R (= base.R): one set-up, one world inertia.
  ContactGeometry geo_mid;
  geo_mid.Iw = world_inertia(m, base.R);
  geo_mid.iw_given = true;
  const Mat3& Iw_mid = geo_mid.Iw;
  const auto solve = [&](double b) {
    mid = base;
    mid.velocity.z() -= b;
    res = apply_friction_impact(m, mid, cm, /*restitution=*/false, nullptr, nullptr, &geo_mid);
    mid.velocity.z() += b;
    sweeps += res.iterations;
    apply_rolling_resistance(m, mid, cm, res.normal_impulse);
    apply_pivoting_resistance(m, mid, cm, res.normal_impulse);
    const Vec3 z_row = TorqueFreeRotation::bottom_row_at(moments_, mid.R, Iw_mid * mid.omega, rest);
    double gap = std::numeric_limits<double>::infinity();
    for (int r = 0; r < 2; ++r)
      if (rim_in[r]) gap = std::min(gap, mid.position.z() + mid.velocity.z() * rest + support_low(z_row, r));
    gap_end = gap;
    return gap;
  };
  // The energy checked is the held energy, as for a flat die's held corners (held_energy) and as
  // the rest rule counts it (rim_rest_face_down): kinetic + m g (COM height + the touching rims'
  // depth below the floor). Plain mechanical energy read the rise of a rim that an earlier step
  // left below the floor (a capped step's sink, up to touch_tol from the start support) as a gain
  // m g depth, and the next step clamped again: 40 % of quarter-table's clamps (2000 `impulse`
  // tosses, seed 1: 3689 -> 2247, fewer in every clamping toss). Depth only, never a height: a rim
  // above the floor that comes down converts m g height into motion, which a projection onto the
  // floor would read as a gain.
  const double mg = m.mass * m.gravity;
  double e_allow = e_start;  // plus the start's depth, evaluated only when the check needs it
  const auto energy_end = [&] {
    return kinetic_energy(m, mid) + mg * (mid.position.z() + mid.velocity.z() * rest + std::max(0.0, -gap_end));
  };
  double b = 0.0;
  // The impulse's target b for the end gap `target` (<= 0): sets b and leaves mid, res and gap_end
  // at that solve. Accepted at the target or above it, within the touch
  // tolerance (one-sided: the next step then starts no deeper than the target, where the
  // impulse's work is <= 0).
  const auto search = [&](double target) {
    b = 0.0;
    const double g = solve(0.0);
    if (!(g < target && rest > 0.0)) return;
    double lo = 0.0, g_lo = g - target, hi = (target - g) / rest, g_hi = solve(hi) - target;
    for (int k = 0; k < 8 && g_hi < -touch_tol_; ++k) {
      lo = hi, g_lo = g_hi;
      hi *= 2.0;
      g_hi = solve(hi) - target;
    }
    Illinois br{lo, g_lo, hi, g_hi};
    b = hi;
    double x = g_hi;
    const auto accepted = [&](double y) { return y >= 0.0 && y <= touch_tol_; };
    for (int k = 0; k < 20 && !accepted(x) && br.f_hi > 0.0; ++k) {
      b = br.next();
      x = solve(b) - target;
      br.update(b, x, /*lo_side=*/x < 0.0);
    }
    if (!accepted(x) && b != br.hi) {  // out of iterations: the bracket's end above the floor, counted
      ++support_search_capped;
      b = br.hi;
      x = solve(b) - target;
    }
  };
  search(0.0);  // the floor
  const double e_end = energy_end();
  bool gains = e_end > e_allow;
  const double phi0 = gains ? phi(0.0) : 0.0;
  if (gains) gains = e_end > (e_allow += mg * std::max(0.0, -phi0));
  if (gains && phi0 < 0.0) {
    // A start below the floor (within the touch tolerance a located step or the start support
    // leaves): closing that depth within the step is work P |phi(0)| / d, which the held energy's
    // m g |phi(0)| does not cover when the step is short (a located step of 1-10 ns asked 1-2 m/s
    // of the rim, and each halving doubled the ask: three-sided coin `impulse`, 4 of its 14 clamps
    // in 10^5 tosses). Holding the start's depth instead does no work; the rims end within the
    // touch tolerance, and a later, longer step closes it. (Asked in every step, the depth
    // accumulated through the steps after and was lifted: only when closing it gains.)
    search(phi0);
    gains = energy_end() > e_allow;
    if (!gains) ++depth_held;
  }
  if (gains) {  // the largest b that gains nothing (or b = 0, the plain solve)
    // Where the gain comes from, measured: the impulse's own kinetic work, or gravity's share
    // g P_z (d - tau) (the COM it lifts in the step's second half, whose kick was at the start).
    // Positive work: its target b is above the point's reflection, the lowest point's height far
    // from quadratic over the step (a near-flat coin spinning fast, its lowest point running round
    // the rim). A shorter step makes it quadratic: the step is halved (step()), and the cap below
    // (the attempt's state if the halvings run out) is a clamp only if the accepted step has it.
    // (Capped in `impulse` tosses, seed 1: the work is -0.3 to -0.5 % of gravity's share in all
    // 1480 of quarter-table's 1000, steps whose impulses exceed m g d, the rolling coin's kind A;
    // positive, 1.3 to 10^5 times that share, in all 25 of the quarter's and the three-sided
    // coin's 5000 each. docs/fidelity.md, "Which gain: halved or clamped".) Kind A was last the
    // plain solve's own held-energy rise in a coin spinning upright on one rim point, which
    // nothing dissipated; the rim's pivoting resistance (rim_rest.hpp) removed it (quarter-table
    // `impulse`, 10^5 tosses: 112 450 clamps -> 1). What caps now is kind B (docs/fidelity.md).
    a.unreflected = kinetic_energy(m, mid) > kinetic_energy(m, base);
    double ok = 0.0, bad = b;
    for (int k = 0; k < 20; ++k) {
      const double x = 0.5 * (ok + bad);
      solve(x);
      (energy_end() > e_allow ? bad : ok) = x;
    }
    b = ok;
    const double g = solve(b);
    ++curvature_capped;
    a.clamped = true;
    a.capped = g < -touch_tol_;
  }
  ++curvature_impulses;
  a.sup.corrections.add(res.corrections);
  a.sup.exact_fallbacks += res.exact_fallbacks;
  a.sup.iterations += sweeps;
  a.sup.normal_impulse += res.normal_impulse;
  // As a state at the step's start whose free motion for d is the motion after the impulse: the
  // post-impulse motion run back by tau (time reversal: the rotation under -L), so that try_step's
  // free motion, its end state and its lowest-point searches need no second piece.
  s = mid;
  Vec3 w_back;
  TorqueFreeRotation(moments_, mid.R, -(Iw_mid * mid.omega), /*bounds=*/false).state(tau, s.R, w_back);
  s.omega = -w_back;
  s.position = mid.position - tau * mid.velocity;
  rot.emplace(moments_, s.R, world_inertia(m, s.R) * s.omega, /*bounds=*/false);
}

void FixedStepper::start_support(RigidState& s, const ContactSet& c, double d, double e_start, Attempt& a,
                                 std::optional<TorqueFreeRotation>& rot) {
  // The plastic solve at the step's start stops the touching material points' approach. A rim's
  // lowest point is not a material point: over the step it moves along the rim, and with the
  // touching point stopped it sinks (curvature_support) or rises. Rising: the plain solve pushed
  // harder than the rim needs to stay on the floor (the contact point's centripetal acceleration,
  // -w x (w x r), points up toward the COM, and over the step it lifts the point by about
  // w^2 r h^2 / 2; a rolling coin hopped off the floor every other step). Then the solve asks for
  // v_n >= b with b < 0 (the same solve on the velocity shifted by -b e_z, then restored: the
  // tangential velocities and friction are unchanged by the shift), the push reduced until the
  // rims end the step on the floor, or no push at all (then the die really leaves). Its kinetic
  // energy change is the shifted solve's (<= 0, plastic) plus b times the normal impulse (<= 0).
  // (Sinking was once treated here the same way, b > 0: that pushes a point that already leaves
  // the floor, gains energy, and had to be capped, its residual lifted; the curvature impulse
  // at the step's middle does it without work.)
  const DieModel& m = *m_;
  const RigidState base = s;
  bool rim_in[2] = {false, false};
  for (int i = 0; i < c.n; ++i) rim_in[c.vertex[i] < 3 ? 0 : 1] = true;
  int sweeps = 0;
  const auto solve = [&](double b) {
    s = base;
    s.velocity.z() -= b;
    // (s.R is the step's start s0.R and c its set: the set-up geo_ the step's impact and trials share.)
    a.sup = apply_friction_impact(m, s, c, /*restitution=*/false, &warm_, &a.next, &geo_);
    s.velocity.z() += b;
    sweeps += a.sup.iterations;
    apply_rolling_resistance(m, s, c, a.sup.normal_impulse);
    apply_pivoting_resistance(m, s, c, a.sup.normal_impulse);
    // The end's bottom row only (s.R is s0.R); the rotation itself is built once, for the solve
    // that stands (done).
    const Vec3 z_row = TorqueFreeRotation::bottom_row_at(moments_, s.R, Iw_start_ * s.omega, d);
    double gap = std::numeric_limits<double>::infinity();
    for (int r = 0; r < 2; ++r)
      if (rim_in[r]) gap = std::min(gap, s.position.z() + s.velocity.z() * d + rim_low_z(m, z_row, r));
    return gap;
  };
  const auto done = [&] {
    a.sup.iterations = sweeps;
    // (A curved die's rotations need no bounds: only model_root's search for a polyhedron reads them.)
    rot.emplace(moments_, s.R, Iw_start_ * s.omega, /*bounds=*/false);
  };
  const double g0 = solve(0.0);
  if (!(d > 0.0) || g0 <= touch_tol_ || !(a.sup.normal_impulse > 0.0)) {
    done();
    return;
  }
  double hi = 0.0, g_hi = g0, lo = -g0 / d, g_lo = solve(lo);
  for (int k = 0; k < 8 && g_lo > touch_tol_ && a.sup.normal_impulse > 0.0; ++k) {
    hi = lo, g_hi = g_lo;
    lo *= 2.0;
    g_lo = solve(lo);
  }
  double b = lo;
  if (g_lo < -touch_tol_) {
    Illinois br{lo, g_lo, hi, g_hi};
    double g = g_lo;
    for (int k = 0; k < 12 && std::abs(g) > touch_tol_; ++k) {
      b = br.next();
      g = solve(b);
      br.update(b, g, /*lo_side=*/g < 0.0);
    }
    if (g < -touch_tol_) {  // not converged: the bracket's end above the floor, counted
      ++support_search_capped;
      b = br.hi;
      solve(b);
    }
  }
  // No step may gain mechanical energy (the rest rules rely on it, rest.hpp): checked, as an
  // assertion, against the step's start, e_start (the free motion keeps the kinetic energy; the
  // COM rises by v_z d). Should rounding break the argument above, the largest b that does not
  // gain (bisection towards the plain solve), counted as an energy clamp.
  const auto gains = [&] {
    return kinetic_energy(m, s) + m.mass * m.gravity * (s.position.z() + s.velocity.z() * d) > e_start;
  };
  if (gains()) {
    double ok = 0.0, bad = b;
    for (int k = 0; k < 20; ++k) {
      const double mid = 0.5 * (ok + bad);
      solve(mid);
      (gains() ? bad : ok) = mid;
    }
    solve(ok);
    ++start_capped;
    ++a.sup.corrections.energy_clamps;
  }
  done();
}

void FixedStepper::add_face_tripod(const RigidState& s, ContactSet& c, double window, double depth,
                                   bool either) const {
  // A coin flat to within ~1e-7 rad (a slap's located end: the far half arrives as the tilt
  // passes zero) touches with its whole face, but the features 120 deg either side of the rim's
  // lowest point sit 1.5 a tilt above it, just outside the touch tolerance: the contact set was the
  // lowest point alone, the face's far side (arriving at ~w 2a) struck nothing, the curvature
  // impulse could not hold it without gaining energy (capped, halved four times) and it was
  // lifted. The face's tripod joins the set when its features are within the impulse model's
  // strike tolerance (1e-6 r, corners that close strike together), as a polyhedron's face does.
  // step() widens that where the step would clamp or lift (a coin landing nearly flat): each
  // within `depth`, or reaching the floor within `window` at its approach speed.
  const DieModel& m = *m_;
  const double face_tol = 1e-6 * m.bounding_radius;
  const RimFeatures rims(m, s.R);
  const auto joins = [&](int f) {
    const Vec3 p = rims.point(f);
    const double z = s.position.z() + p.z();  // corner_height, corner_velocity
    return z <= face_tol || z <= depth || z <= -window * (s.velocity + s.omega.cross(p)).z();
  };
  const int n0 = c.n;
  for (int r = 0; r < 2; ++r) {
    bool low = false, in1 = false, in2 = false;
    for (int i = 0; i < n0; ++i) {
      low = low || c.vertex[i] == 3 * r;
      in1 = in1 || c.vertex[i] == 3 * r + 1;
      in2 = in2 || c.vertex[i] == 3 * r + 2;
    }
    if (!low || (in1 && in2)) continue;
    if (either ? !(joins(3 * r + 1) || joins(3 * r + 2)) : !(joins(3 * r + 1) && joins(3 * r + 2))) continue;
    if (!in1 && c.n < kMaxContacts) c.vertex[c.n++] = 3 * r + 1;
    if (!in2 && c.n < kMaxContacts) c.vertex[c.n++] = 3 * r + 2;
  }
  if (c.n == n0) return;
  for (int a = 1; a < c.n; ++a)  // ascending, as touching_corners leaves it
    for (int b = a; b > 0 && c.vertex[b - 1] > c.vertex[b]; --b) std::swap(c.vertex[b - 1], c.vertex[b]);
}

bool FixedStepper::rim_most_approaching(const RigidState& s, const ContactSet& c, double window, int& rim, Vec3& r,
                                        double& vz) const {
  // A rim point's normal velocity is affine in its lever arm, so over the circle it is
  // A + a (alpha cos t + beta sin t) in the rim's basis (u, K x u): its minimum lies at
  // -(alpha, beta) / |(alpha, beta)|.
  const DieModel& m = *m_;
  const RimFeatures rims(m, s.R);
  const Vec3 &K = rims.axis(), &u = rims.down(), &w2 = rims.side();
  // (alpha, beta): the same for both rims (their points differ by a multiple of K).
  const double alpha = s.omega.cross(u).z(), beta = s.omega.cross(w2).z();
  const double n = std::sqrt(alpha * alpha + beta * beta);
  if (!(n > 0.0)) return false;
  const double face_tol = 1e-6 * m.bounding_radius;
  bool found = false;
  for (int q = 0; q < 2; ++q) {
    int in = 0;
    for (int i = 0; i < c.n; ++i) in += c.vertex[i] / 3 == q ? 1 : 0;
    if (in < 3) continue;
    Vec3 p = rims.centre() + (q == 0 ? m.rims.half : -m.rims.half) * K - (m.rims.radius / n) * (alpha * u + beta * w2);
    p.z() -= m.rounding;
    const double v = (s.velocity + s.omega.cross(p)).z();
    const double z = s.position.z() + p.z();
    if (!(z <= face_tol || z <= -window * v)) continue;
    if (!found || v < vz) rim = q, r = p, vz = v, found = true;
  }
  return found;
}

ImpactResult FixedStepper::strike_rim(RigidState& s0, const ContactSet& c) {
  // A coin landing flat with its tripod struck, spinning fast about a horizontal axis (quarter-table
  // `stepped`, 5 tosses in 1e5): restitution turns the spin over, and the arc of the rim between
  // two tripod points beyond the struck side comes down at ~1 m/s, a few nm up. The tripod holds
  // only the centres of pressure in its triangle; the disc's face holds every one in its circle.
  // Each rim point that arc brings down is struck with the rest, the impact solved again from the
  // start with it, until none approaches at an impact's speed (slower is the support's, as for
  // any contact; at most four more points: near one another they make the friction degenerate).
  const DieModel& m = *m_;
  const RigidState pre = s0;
  ContactSet cs = c;
  Vec3 r[kMaxContacts];
  const RimFeatures rims(m, pre.R);
  for (int i = 0; i < c.n; ++i) r[i] = rims.point(c.vertex[i]);
  ImpactResult res;
  for (int k = 0;; ++k) {
    s0 = pre;
    res = apply_friction_impact_at(m, s0, cs, r, /*restitution=*/true);
    int rim = 0;
    Vec3 p;
    double vz = 0.0;
    if (k == 4 || cs.n >= kMaxContacts || !rim_most_approaching(s0, c, h_, rim, p, vz) ||
        !(vz < -impact_speed(s0)))
      break;
    cs.vertex[cs.n] = 3 * rim;  // (its materials)
    r[cs.n++] = p;
  }
  return res;
}

}  // namespace dicesim
