// A curved die's (a coin's, a cylinder's) sustained step in FixedStepper: drift-kick-drift, second
// order (try_step_rim), and its support solve at the step's middle (rim_support, mid_support).
//
// Why not the polyhedra's first-order step. A rim's semi-implicit Euler step (gravity's kick and
// the plastic solve at the start, free motion after) loses energy at a rate proportional to the
// step wherever the contact point accelerates: the solve stops a normal approach of order g h and
// a slip of order (tangential acceleration) h every step. On a coin standing on its band that loss
// damped the tilt's wobble and the rocking between the two rim circles by more than the physics
// does, and held coins upright until the "outcome settled" rule caught them: the dropped quarter's
// edge rate read 2.76 / 1.36 / 0.85 % at 1 / 0.2 / 0.1 ms. Here the solve sits at the step's middle,
// asks the rims' lowest points to end the step on the floor (a position target, not a velocity
// one), and a single sticking point's slip is reflected about zero rather than stopped, so a held
// contact neither gains nor loses to first order, while arrivals stay plastic.
#include <cmath>
#include <limits>

#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/contact_stepper_internal.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/rim_rest.hpp"
#include "sim/illinois.hpp"

namespace dicesim {

using stepper_detail::rim_low_z;

void FixedStepper::try_step_rim(const ContactSet& c, double d, Attempt& a, bool full) {
  const DieModel& m = *m_;
  RigidState& s = a.s;  // the step's start, after its impact
  // (1) An arrival: a point of c approaching at the start is a contact that landed slower than
  // the impact threshold (located to this instant), and such an arrival is plastic, as in the
  // first-order step. Without this impulse the middle's position target returned its approach
  // (the point, half a step below the floor, asked to end the step on it): a quarter rocking
  // between its rim circles kept all its energy at 1 ms instead of losing 1.2 um of lift in
  // 0.8 s. A held point's approach here is O(d^2) (the last step ended it on the floor, at rest
  // to first order), so this impulse costs a held contact O(d^4) a step.
  ImpactResult arrival;
  bool arrived = false;
  for (int i = 0; i < c.n; ++i) arrived = arrived || corner_velocity(m, s, c.vertex[i]).z() < 0.0;
  if (arrived) arrival = apply_friction_impact(m, s, c, /*restitution=*/false, nullptr, nullptr, &geo_);
  // (2) Free motion for d / 2, (3) gravity's whole kick, (4) the support solve there.
  const double half = 0.5 * d;
  RigidState mid = s;
  TorqueFreeRotation(moments_, s.R, Vec3(Iw_start_ * s.omega), /*bounds=*/false).state(half, mid.R, mid.omega);
  mid.position = s.position + half * s.velocity;
  mid.velocity.z() -= kick_g_ * d;
  ContactGeometry geo;  // the middle's orientation: its own set-up
  geo.Iw = world_inertia(m, mid.R);
  geo.iw_given = true;
  std::optional<TorqueFreeRotation>& slot = full ? full_rot_ : trial_rot_;
  rim_support(mid, c, half, a, slot, full, geo);
  if (arrived) {
    a.sup.corrections.add(arrival.corrections);
    a.sup.exact_fallbacks += arrival.exact_fallbacks;
    a.sup.iterations += arrival.iterations;
  }
  // (5) The free motion of the result for d / 2. The location model (model_G) and the new
  // contacts' search run on this second half, from the middle.
  rot_start_ = mid.R;
  const Vec3 p = mid.position, v = mid.velocity;
  if (full) {
    full_p_ = p;
    full_v_ = v;
    full_w_ = mid.omega;
  }
  s = mid;
  slot->state(half, s.R, s.omega);
  a.G = lowest_new(c, p, v, *slot, half);
  s.position = p + half * v;
}

void FixedStepper::rim_support(RigidState& s, const ContactSet& c, double d, Attempt& a,
                               std::optional<TorqueFreeRotation>& rot, bool full, ContactGeometry& geo) {
  mid_support(s, c, d, a, rot, geo);
  const DieModel& m = *m_;
  if (!(d > 0.0)) return;
  if (full) free_end_row_ = rot->bottom_row(d);
  if (full && !slap_located_ && !(a.sup.normal_impulse > 0.0)) {
    // Leaving (no push) and first rising, yet below the floor at the step's end: the sinking is
    // another part of the rim arriving (rims_new_), located as a new contact.
    const double eps = 1e-3 * d;
    const double z0 = s.position.z() + rim_lowest(m, s.R);
    const double z1 = s.position.z() + s.velocity.z() * eps + rim_lowest(m, rot->orientation(eps));
    const double zd = s.position.z() + s.velocity.z() * d + rim_lowest(m, rot->orientation(d));
    rims_new_ = z1 > z0 && zd < -touch_tol_;
  }
}

void FixedStepper::mid_support(RigidState& s, const ContactSet& c, double d, Attempt& a,
                               std::optional<TorqueFreeRotation>& rot, ContactGeometry& geo) {
  // The plastic solve at the step's middle (s: gravity's whole kick already in it; d: what is
  // left of the step), with rolling and pivoting resistance, asked to leave the touching rims'
  // lowest points on the floor at the step's end: v_n >= b (the same solve on the velocity
  // shifted by -b e_z, then restored; tangential velocities and friction unchanged by the shift),
  // b found by a bracketed root search on the end gap. b > 0 where the plain solve leaves them
  // sinking (a rim's lowest point is not a material point: with the touching point stopped it
  // runs along the rim and sinks like -k t^2 / 2), b < 0 where it pushes harder than they need
  // (the contact point's centripetal acceleration lifts it): the push eased until they end on
  // the floor, or none (the die leaves). The end gap is the exact free motion's, so the target
  // holds to rounding; the step's energy is checked below.
  const DieModel& m = *m_;
  const RigidState base = s;
  bool rim_in[2] = {false, false};
  for (int i = 0; i < c.n; ++i) rim_in[c.vertex[i] < 3 ? 0 : 1] = true;
  // A single rim point: its slip is reflected, not stopped. Its slip changes by about (its
  // tangential acceleration) d between two solves; stopping it every step lost that, m_eff
  // (a_t d)^2 / 2 a step, first order in all (Euler's disk precessed 1.4 % slow at 0.2 ms, a
  // wobbling disk with mu 2 lost 0.6 % of its energy a second). The solve asks for the slip
  // -(its change since the last solve) / 2, so the slip is zero on average over the step; if
  // friction cannot give that much, it slides, and the next step's change is measured from
  // wherever it ended. A slip that friction merely stops (a coin coming to rest) goes to -v / 2,
  // then 0: a stop one step later.
  Eigen::Vector2d bt = Eigen::Vector2d::Zero();
  const auto slip_of = [&](const RigidState& q) {
    return Eigen::Vector2d((q.velocity + q.omega.cross(contact_point(m, q.R, c.vertex[0]))).head<2>());
  };
  if (c.n == 1) {
    const Eigen::Vector2d before = rim_slip_vertex_ == c.vertex[0] ? rim_slip_ : Eigen::Vector2d::Zero();
    bt = -0.5 * (slip_of(base) - before);
  }
  int sweeps = 0;
  const auto solve = [&](double b) {
    s = base;
    s.velocity.z() -= b;
    s.velocity.head<2>() -= bt;
    a.sup = apply_friction_impact(m, s, c, /*restitution=*/false, &warm_, &a.next, &geo);
    s.velocity.z() += b;
    s.velocity.head<2>() += bt;
    sweeps += a.sup.iterations;
    apply_rolling_resistance(m, s, c, a.sup.normal_impulse);
    apply_pivoting_resistance(m, s, c, a.sup.normal_impulse);
    // The end's bottom row only; the rotation itself is built once, for the solve that stands.
    const Vec3 z_row = TorqueFreeRotation::bottom_row_at(moments_, s.R, geo.Iw * s.omega, d);
    double gap = std::numeric_limits<double>::infinity();
    for (int r = 0; r < 2; ++r)
      if (rim_in[r]) gap = std::min(gap, s.position.z() + s.velocity.z() * d + rim_low_z(m, z_row, r));
    return gap;
  };
  // The step may not gain energy beyond the leapfrog's split bound (split_gain, m (g h)^2 / 8 for
  // the whole step h = 2 d: the kick at the middle lifts the COM through the second half): the
  // rest rules rely on it (rest.hpp). Kinetic energy after the solve plus m g (the COM's height at
  // the end), against the step's start (after its impact).
  const double e_allow = e_start_ + split_gain(2.0 * d);
  const auto gains = [&] {
    return kinetic_energy(m, s) + m.mass * m.gravity * (s.position.z() + s.velocity.z() * d) > e_allow;
  };
  // The largest |b| towards `b` that does not gain (bisection towards the plain solve).
  const auto cap = [&](double b) {
    double ok = 0.0, bad = b;
    for (int k = 0; k < 20; ++k) {
      const double x = 0.5 * (ok + bad);
      solve(x);
      (gains() ? bad : ok) = x;
    }
    ++curvature_capped;
    return solve(ok);
  };
  const auto done = [&] {
    a.sup.iterations = sweeps;
    a.slip_vertex = c.n == 1 ? c.vertex[0] : -1;
    if (c.n == 1) a.slip = slip_of(s);
    // (A curved die's rotations need no bounds: only model_root's search for a polyhedron reads them.)
    rot.emplace(moments_, s.R, geo.Iw * s.omega, /*bounds=*/false);
  };
  const double g0 = solve(0.0);
  if (d > 0.0 && g0 < -touch_tol_) {
    // Sinking: pushed until the rims end within [0, touch_tol] of the floor.
    double lo = 0.0, g_lo = g0, hi = -g0 / d, g_hi = solve(hi);
    for (int k = 0; k < 8 && g_hi < 0.0; ++k) {
      lo = hi, g_lo = g_hi;
      hi *= 2.0;
      g_hi = solve(hi);
    }
    Illinois br{lo, g_lo, hi, g_hi};
    double b = hi, g = g_hi;
    for (int k = 0; k < 20 && !(g >= 0.0 && g <= touch_tol_) && br.f_hi > 0.0; ++k) {
      b = br.next();
      g = solve(b);
      br.update(b, g, /*lo_side=*/g < 0.0);
    }
    if (!(g >= 0.0 && g <= touch_tol_) && b != br.hi) {  // out of iterations: the bracket's end above the floor, counted
      ++support_search_capped;
      b = br.hi;
      g = solve(b);
    }
    if (gains()) {
      // Capped: a clamp, and the step halved while the cap leaves the rims below (step()). In the
      // cases examined a coin within milliradians of flat whose lowest point runs round the rim
      // faster than the step resolves (kind B, docs/fidelity.md).
      const double gc = cap(b);
      a.clamped = true;
      a.capped = gc < -touch_tol_;
    }
    done();
    return;
  }
  if (!(d > 0.0) || g0 <= touch_tol_ || !(a.sup.normal_impulse > 0.0)) {
    // The plain solve, checked like the searches' results: a plastic solve at the middle keeps
    // within the bound, but the reflected slip's impulse may not. Where it gains, the slip is
    // stopped instead (no bias), counted as an energy clamp.
    if (!bt.isZero() && gains()) {
      bt.setZero();
      solve(0.0);
      ++a.sup.corrections.energy_clamps;
    }
    done();
    return;
  }
  // Rising: the push eased (b < 0) until the rims end on the floor.
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
  // Easing a push takes energy out (b times the normal impulse, b < 0): a gain here is rounding
  // or the split bound's edge, capped and counted as an energy clamp.
  if (gains()) {
    cap(b);
    ++a.sup.corrections.energy_clamps;
  }
  done();
}

}  // namespace dicesim
