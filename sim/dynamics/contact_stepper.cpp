#include "sim/dynamics/contact_stepper.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include "sim/body/rim.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/dynamics/rim_rest.hpp"
#include "sim/illinois.hpp"
#include "sim/sincos.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dicesim {

FixedStepper::FixedStepper(const DieModel& m, double h, ImpactThreshold threshold, double max_sink)
    : m_(&m),
      moments_(m.principal_moments),
      h_max_(h),
      h_(h),
      v_impact_(sustained_contact_speed(m, h)),
      touch_tol_(1e-7 * m.bounding_radius),
      max_sink_(m.curved() ? 0.0 : max_sink) {
  if (threshold == ImpactThreshold::Contact) {
    // Gravity keeps its safety factor 4; contact forces of order m g (normal plus friction) at
    // lever r add at most (1 + mu) g m r^2 / I_min per unit time; the spin adds |w|^2 r (factor 4).
    const double r = m.bounding_radius;
    const double lever = m.mass * r * r / m.principal_moments.minCoeff();
    v_impact_ += h * m.gravity * (1.0 + m.max_friction) * lever;
    v_spin_ = 4.0 * h * r;
  }
  const int nv = m.vertex_count();
  if (!m.curved() && nv <= kSoaVertices) {
    soa_vertices_ = nv;
    for (int i = 0; i < nv; ++i) {
      vx_[i] = m.vertices[static_cast<std::size_t>(i)].x();
      vy_[i] = m.vertices[static_cast<std::size_t>(i)].y();
      vz_[i] = m.vertices[static_cast<std::size_t>(i)].z();
    }
    if (nv % 2 == 1) vx_[nv] = vx_[nv - 1], vy_[nv] = vy_[nv - 1], vz_[nv] = vz_[nv - 1];
  }
}

namespace {

double mechanical_energy(const DieModel& m, const RigidState& s) {
  return kinetic_energy(m, s) + m.mass * m.gravity * s.position.z();
}

double relative_gain(double before, double after) {
  return before > 0.0 ? (after - before) / before : (after > 0.0 ? after : 0.0);
}

}  // namespace

double FixedStepper::lowest_new(const ContactSet& c, const Vec3& p, const Vec3& v, const TorqueFreeRotation& rot,
                                double t) const {
  // At t = 0 the step's own orientation, bit for bit as touching_corners saw it (so a corner left
  // out of the contact set is above the tolerance here too).
  if (m_->curved()) {  // a cylinder's rim points need the whole orientation
    const Mat3 R = t == 0.0 ? rot_start_ : rot.orientation(t);
    return p.z() + v.z() * t + curved_low(c, R);
  }
  return lowest_flat(c, p, v, t == 0.0 ? Vec3(rot_start_.row(2).transpose()) : rot.bottom_row(t), t);
}

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

double FixedStepper::soa_heights(const ContactSet& c, const Vec3& z_row, double* z) const {
  const int nv = soa_vertices_;
  constexpr double kInf = std::numeric_limits<double>::infinity();
#if defined(__SSE2__)
  const __m128d zx = _mm_set1_pd(z_row.x()), zy = _mm_set1_pd(z_row.y()), zz = _mm_set1_pd(z_row.z());
  for (int i = 0; i < nv; i += 2) {
    const __m128d h = _mm_add_pd(_mm_add_pd(_mm_mul_pd(zx, _mm_load_pd(vx_ + i)), _mm_mul_pd(zy, _mm_load_pd(vy_ + i))),
                                 _mm_mul_pd(zz, _mm_load_pd(vz_ + i)));
    _mm_store_pd(z + i, h);
  }
  for (int k = 0; k < c.n; ++k) z[c.vertex[k]] = kInf;
  if (nv % 2 == 1) z[nv] = z[nv - 1];  // the padding lane: the last vertex again, masked or not
  // The minimum of finite heights (never -0: a height is -0 only if all three products are) is
  // the same number in any order: two lanes, then the two (z < low ? z : low, as std::min).
  __m128d low = _mm_set1_pd(kInf);
  for (int i = 0; i < nv; i += 2) low = _mm_min_pd(_mm_load_pd(z + i), low);
  return _mm_cvtsd_f64(_mm_min_pd(_mm_unpackhi_pd(low, low), low));
#else
  const double zx = z_row.x(), zy = z_row.y(), zz = z_row.z();
  for (int i = 0; i < nv; ++i) z[i] = (zx * vx_[i] + zy * vy_[i]) + zz * vz_[i];
  for (int k = 0; k < c.n; ++k) z[c.vertex[k]] = kInf;
  double low = kInf;
  for (int i = 0; i < nv; ++i) low = std::min(low, z[i]);
  return low;
#endif
}

bool FixedStepper::soa_touching(const RigidState& s, ContactSet& c) const {
  const int nv = soa_vertices_;
  const double rounding = m_->rounding, tol = touch_tol_, pz = s.position.z();
  const double r20 = s.R(2, 0), r21 = s.R(2, 1), r22 = s.R(2, 2);
  int n = 0;
#if defined(__SSE2__)
  const __m128d x = _mm_set1_pd(r20), y = _mm_set1_pd(r21), z = _mm_set1_pd(r22);
  const __m128d p = _mm_set1_pd(pz), r = _mm_set1_pd(rounding), t = _mm_set1_pd(tol);
  for (int i = 0; i < nv; i += 2) {
    const __m128d h = _mm_sub_pd(
        _mm_add_pd(p, _mm_add_pd(_mm_mul_pd(x, _mm_load_pd(vx_ + i)),
                                 _mm_add_pd(_mm_mul_pd(y, _mm_load_pd(vy_ + i)), _mm_mul_pd(z, _mm_load_pd(vz_ + i))))),
        r);
    // touching_corners keeps a corner unless its height > tol (NaN included): not-greater-than.
    const int bits = _mm_movemask_pd(_mm_cmpngt_pd(h, t));
    if (bits == 0) continue;
    if (n + 2 > kMaxContacts) return false;
    if (bits & 1) c.vertex[n++] = i;
    if ((bits & 2) && i + 1 < nv) c.vertex[n++] = i + 1;  // (not an odd count's padding lane)
  }
#else
  for (int i = 0; i < nv; ++i) {
    const double h = (pz + (r20 * vx_[i] + (r21 * vy_[i] + r22 * vz_[i]))) - rounding;
    if (h > tol) continue;
    if (n + 1 > kMaxContacts) return false;
    c.vertex[n++] = i;
  }
#endif
  c.n = n;
  return true;
}

double FixedStepper::lowest_flat(const ContactSet& c, const Vec3& p, const Vec3& v, const Vec3& z_row, double t) const {
  if (soa_vertices_ > 0) {
    // Every corner's height two at a time (the same products and sums, in the same order, as
    // z_row.dot(vertex)), the contact set's corners masked out, and their minimum: the same
    // number as the loop below.
    alignas(16) double z[kSoaVertices];
    const double low = soa_heights(c, z_row, z);
    return p.z() + v.z() * t + low - m_->rounding;
  }
  const auto& verts = m_->vertices;
  const int nv = static_cast<int>(verts.size());
  double low = std::numeric_limits<double>::infinity();
  int j = 0;  // c.vertex is ascending
  for (int i = 0; i < nv; ++i) {
    if (j < c.n && c.vertex[j] == i) {
      ++j;
      continue;
    }
    low = std::min(low, z_row.dot(verts[i]));
  }
  return p.z() + v.z() * t + low - m_->rounding;  // a rounded corner touches with its ball
}

double FixedStepper::lowest_flat(const ContactSet& c, const Vec3& p, const Vec3& v, const Vec3& z_row,
                                 const Vec3& z_rate, double t, double& slope) const {
  if (soa_vertices_ > 0) {
    // As the loop below: the lowest corner's height, and its rate from the first corner (in vertex
    // order) at that height (the loop's strict < keeps the first).
    alignas(16) double z[kSoaVertices];
    const double low = soa_heights(c, z_row, z);
    int arg = -1;
    if (low < std::numeric_limits<double>::infinity())
      for (int i = 0; arg < 0; ++i)
        if (z[i] == low) arg = i;
    slope = v.z() + (arg >= 0 ? z_rate.dot(m_->vertices[static_cast<std::size_t>(arg)]) : 0.0);
    return p.z() + v.z() * t + low - m_->rounding;
  }
  const auto& verts = m_->vertices;
  const int nv = static_cast<int>(verts.size());
  double low = std::numeric_limits<double>::infinity();
  int arg = -1;
  int j = 0;  // c.vertex is ascending
  for (int i = 0; i < nv; ++i) {
    if (j < c.n && c.vertex[j] == i) {
      ++j;
      continue;
    }
    const double z = z_row.dot(verts[i]);
    if (z < low) low = z, arg = i;
  }
  slope = v.z() + (arg >= 0 ? z_rate.dot(verts[arg]) : 0.0);
  return p.z() + v.z() * t + low - m_->rounding;
}

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
  if (!hold_ || m.curved() || c.n == 0) {
    try_step_with(s0, c, d, a, full, 0.0);
    return;
  }
  const double b = std::min(start_shallow_ / d + 0.5 * a_down_ * d, m.gravity * d);
  if (try_step_with(s0, c, d, a, full, b)) {
    if (full) full_bias_ = b;
    return;
  }
  if (try_step_with(s0, c, d, a, full, 0.25 * b)) {
    if (full) full_bias_ = 0.25 * b;
    return;
  }
  try_step_with(s0, c, d, a, full, 0.0);
  a.rise_dropped = true;
}

bool FixedStepper::try_step_with(const RigidState& s0, const ContactSet& c, double d, Attempt& a, bool full,
                                 double bias) {
  const DieModel& m = *m_;
  // The impact (solved once per step in step(): it does not depend on d) is already in s0.
  a.s = s0;
  RigidState& s = a.s;
  a.impact = impact_;
  if (impact_) a.imp = imp_;
  a.next.n = 0;
  a.capped = false;
  a.clamped = false;
  a.unreflected = false;
  a.risen = bias > 0.0;
  a.rise_dropped = false;
  s.velocity.z() -= m.gravity * d;
  // Built in place (the full step's is kept for model_G; the object is large, so no copies). A
  // curved die's support solve builds its own (rim_support: the rotation is part of its search).
  std::optional<TorqueFreeRotation>& slot = full ? full_rot_ : trial_rot_;
  const bool built = m.curved() && c.n > 0;
  if (built) rim_support(s, c, d, e_start_, a, slot, full);
  if (!m.curved() && c.n > 0) {
    s.velocity.z() -= bias;
    a.sup = apply_friction_impact(m, s, c, /*restitution=*/false, &warm_, &a.next, &geo_);
    s.velocity.z() += bias;
  }
  // Free motion for d: straight COM, exact torque-free rotation (kinetic energy exact). A trial of
  // a step without contact has the full step's rotation exactly (the same s0.R and, with no
  // impulse, the same angular momentum): it is reused.
  const TorqueFreeRotation& rot = built                             ? *slot
                                  : !full && c.n == 0 && full_rot_ ? *full_rot_
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
  s.position = p + d * v;
  if (!(bias > 0.0)) return true;
  // (New corners below the floor are the located step's business.)
  a.held_e = held_energy(s, c);
  return a.held_e <= e_start_ + m.mass * m.gravity * start_depth_max_;
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

namespace {

Mat3 skew_of(const Vec3& r) {
  Mat3 S;
  S << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return S;
}

// The derivative in the step length of a plastic support solve's impulses at K points, the solve's
// regime fixed (FixedStepper::predicted_miss): dP (3K) from one linear system, the rows of point i
// by its regime at the solved state: no impulse (dP_i = 0), sticking (its velocity stays 0) or
// sliding (normal velocity 0; P_t = -mu P_n s/|s| linearised). The pre-solve velocities change by
// -g e_z per unit length. W_ij = I/m - [r_i]x I_w^-1 [r_j]x, the points' compliance blocks. False
// if the system has no solution to 1e-9 (a sticking edge's or face's impulses are not unique, but
// then any solution gives the same motion, and the residual accepts it).
//
// Also the second derivative (dF2, dM2): the same matrix (the regime's equations are linear in
// the impulses but for a sliding point's friction direction d = s / |s|, s its slip after the
// solve), its right side the direction's curvature along the first derivative: with x the slip's
// rate, the sliding rows P_t + mu P_n d = 0 twice differentiated give
// A P'' = -mu (2 P'_n x_perp / |s| - P_n (2 (d.x) x_perp + |x_perp|^2 d) / |s|^2), x_perp = x - (d.x) d
// (the kick is linear in the step length, so the normal rows' right side is 0).
template <int K>
bool support_derivative(const ContactPoints& pts, const Mat3& Iinv, double mass, double g, const Vec3& v,
                        const Vec3& w, const ContactImpulses& P, double speed, Vec3& dF, Vec3& dM, Vec3& dF2,
                        Vec3& dM2) {
  constexpr int N = 3 * K;
  Eigen::Matrix<double, N, N> A = Eigen::Matrix<double, N, N>::Zero();
  Eigen::Matrix<double, N, 1> b = Eigen::Matrix<double, N, 1>::Zero();
  Mat3 S[K], T[K];
  for (int j = 0; j < K; ++j) {
    S[j] = skew_of(pts.r[j]);
    T[j] = Iinv * S[j];
  }
  const Mat3 Im = Mat3::Identity() / mass;
  for (int i = 0; i < K; ++i) {
    const Vec3& Pi = P.P[i];
    const Vec3 u = v + w.cross(pts.r[i]);  // the point's velocity after the solve
    const Eigen::Vector2d slip(u.x(), u.y());
    const double sn = slip.norm();
    if (!(Pi.z() > 0.0)) {
      A.template block<3, 3>(3 * i, 3 * i).setIdentity();
      continue;
    }
    b(3 * i + 2) = g;
    if (sn <= 1e-9 * speed) {
      for (int j = 0; j < K; ++j) A.template block<3, 3>(3 * i, 3 * j) = Im - S[i] * T[j];
      continue;
    }
    const Eigen::Vector2d dir = slip / sn;
    const double cf = pts.mu[i] * Pi.z() / sn;
    const Eigen::Matrix2d Pr = cf * (Eigen::Matrix2d::Identity() - dir * dir.transpose());
    for (int j = 0; j < K; ++j) {
      const Mat3 W = Im - S[i] * T[j];
      A.template block<1, 3>(3 * i + 2, 3 * j) = W.row(2);
      A.template block<2, 3>(3 * i, 3 * j) = Pr * W.template topRows<2>();
    }
    A(3 * i, 3 * i) += 1.0;
    A(3 * i + 1, 3 * i + 1) += 1.0;
    A(3 * i, 3 * i + 2) += pts.mu[i] * dir.x();
    A(3 * i + 1, 3 * i + 2) += pts.mu[i] * dir.y();
  }
  const Eigen::PartialPivLU<Eigen::Matrix<double, N, N>> lu = A.partialPivLu();
  const Eigen::Matrix<double, N, 1> x = lu.solve(b);
  if (!x.allFinite() || !((A * x - b).norm() <= 1e-9 * b.norm())) return false;
  dF.setZero();
  dM.setZero();
  for (int j = 0; j < K; ++j) {
    const Vec3 Pj = x.template segment<3>(3 * j);
    dF += Pj;
    dM += pts.r[j].cross(Pj);
  }
  const Vec3 dw = Iinv * dM;
  Eigen::Matrix<double, N, 1> b2 = Eigen::Matrix<double, N, 1>::Zero();
  for (int i = 0; i < K; ++i) {
    const Vec3& Pi = P.P[i];
    const Vec3 u = v + w.cross(pts.r[i]);
    const Eigen::Vector2d slip(u.x(), u.y());
    const double sn = slip.norm();
    if (!(Pi.z() > 0.0) || sn <= 1e-9 * speed) continue;  // no impulse, or sticking: linear
    const Vec3 du = dF / mass + dw.cross(pts.r[i]);
    const Eigen::Vector2d dir = slip / sn, xs(du.x(), du.y());
    const double dx = dir.dot(xs);
    const Eigen::Vector2d xp = xs - dx * dir;
    const Eigen::Vector2d r2 =
        -pts.mu[i] * (2.0 * x(3 * i + 2) * xp / sn - Pi.z() * (2.0 * dx * xp + xp.squaredNorm() * dir) / (sn * sn));
    b2(3 * i) = r2.x();
    b2(3 * i + 1) = r2.y();
  }
  dF2.setZero();
  dM2.setZero();
  const Eigen::Matrix<double, N, 1> y = lu.solve(b2);
  if (!y.allFinite()) return true;
  for (int j = 0; j < K; ++j) {
    const Vec3 Pj = y.template segment<3>(3 * j);
    dF2 += Pj;
    dM2 += pts.r[j].cross(Pj);
  }
  return true;
}

}  // namespace

double FixedStepper::predicted_miss(const ContactSet& c, const Vec3& r) {
  // The model (model_G) moves the full step's free motion by what a shorter gravity kick alone
  // changes; but with corners in contact the support solve absorbs part of the kick, so the
  // shortened step's motion after its solve differs from the model's to first order in (h - d):
  // G(d) - model_G(d) = -d (h - d) [v'_z + g + (w' x r(d/2))_z] + O(d (h - d)^2), v' and w' the
  // derivatives in the step length of the velocities after the solve, r(d/2) the arriving
  // corner's lever half-way (its lever at the start turned by the full step's spin, to first
  // order: the miss's rate in t). v' and w' come from the full step's solve linearised with its
  // regime fixed (support_derivative). Only a prediction of the first trial's length: every trial
  // is still a whole step, accepted only within the touch tolerance, and the search goes on from
  // the misses it measures. 0 (the plain model) when the linearisation has no solution. r: the
  // arriving corner's lever at the step's start.
  const DieModel& m = *m_;
  const int k = c.n;
  if (m.curved() || k == 0 || k > 4 || a_.next.n != k) return 0.0;
  const double g = m.gravity;
  // The solve sees the pre-solve normal velocity shifted by the kick g d and the held corners'
  // rise b(d) (try_step): per unit step length g + b'. With no depth at the start b is linear in
  // d (b = d k min(a_n / 2, g)), so b' = b(h) / h exactly for the full step's branch k.
  const double kick_rate = g + (start_shallow_ > 0.0 ? 0.0 : full_bias_ / h_);
  const double speed = full_v_.norm() + full_w_.norm() * m.bounding_radius + 1e-2 * std::sqrt(g * m.bounding_radius);
  Vec3 dF, dM, dF2, dM2;
  bool ok = false;
  switch (k) {
    case 1: ok = support_derivative<1>(geo_.pts, geo_.inv_inertia, m.mass, kick_rate, full_v_, full_w_, a_.next, speed, dF, dM, dF2, dM2); break;
    case 2: ok = support_derivative<2>(geo_.pts, geo_.inv_inertia, m.mass, kick_rate, full_v_, full_w_, a_.next, speed, dF, dM, dF2, dM2); break;
    case 3: ok = support_derivative<3>(geo_.pts, geo_.inv_inertia, m.mass, kick_rate, full_v_, full_w_, a_.next, speed, dF, dM, dF2, dM2); break;
    default: ok = support_derivative<4>(geo_.pts, geo_.inv_inertia, m.mass, kick_rate, full_v_, full_w_, a_.next, speed, dF, dM, dF2, dM2); break;
  }
  if (!ok) return 0.0;
  const Vec3 dw = geo_.inv_inertia * dM;
  const double miss = -(dF.z() / m.mass) - dw.cross(r).z();
  // The rotation's part to second order in t: the trial's orientation differs by dtheta(t) =
  // t dw + t^2 / 2 (w x dw + dalpha) (per unit of -(h - d)), the lever turns as r + t w x r, so the
  // height's t^2 term is (dw x (w x r) + (w x dw) x r / 2 + dalpha x r / 2)_z = (dw x (w x r) + w x
  // (dw x r) + dalpha x r)_z / 2 (Jacobi), dalpha the torque-free acceleration's change,
  // -I_w^-1 (dw x L + w x I_w dw), L = I_w w.
  const Vec3& w = full_w_;
  const Vec3 L = geo_.Iw * w;
  const Vec3 dalpha = -(geo_.inv_inertia * (dw.cross(L) + w.cross(geo_.Iw * dw)));
  const double rate = -0.5 * (dw.cross(w.cross(r)) + w.cross(dw.cross(r)) + dalpha.cross(r)).z();
  // The solve's second order: G - model_G gains d (h - d)^2 (F''_z / m + (w'' x r)_z) / 2, i.e.
  // the coefficient c2 (h - t) on top of miss + rate t: folded into both.
  const double c2 = 0.5 * (dF2.z() / m.mass + (geo_.inv_inertia * dM2).cross(r).z());
  if (!std::isfinite(miss) || !std::isfinite(rate) || !std::isfinite(c2)) return 0.0;
  miss_rate_ = rate - c2;
  return miss + c2 * h_;
}

double FixedStepper::hermite_start(double miss, double lo, double hi, double x) const {
  // The corrected model with the arriving corner's height about the COM, q(t) = (R(t) r)_z, replaced
  // by its cubic Hermite interpolant on [0, h] from the full step's own ends (q and its rate
  // (w x R r)_z at t = 0 and t = h: no evaluation of the rotation); every other term of the
  // model is a polynomial of degree <= 3 and kept exactly. Interpolation error about h^4 q4 / 384,
  // q4 the fourth derivative, ~|w|^4 r: ~1e-13 m for a die rocking at 10 rad/s with 1 ms steps,
  // so the root of this cubic starts model_root's Newton within ~1e-12 s of the model's root (one
  // evaluation then meets the tolerance). Newton on the cubic, kept in (lo, hi); x, the secant
  // point, if it leaves.
  // The cubic in powers of t: base + v t + H(t) + g (h - t) t + (miss + rate t) t (h - t).
  const double h = h_, g = m_->gravity;
  const double q0 = hq_[0], p0 = hq_[1], q1 = hq_[2], p1 = hq_[3];
  const double c0 = full_p_.z() - m_->rounding + q0;
  const double c1 = full_v_.z() + p0 + g * h + miss * h;
  const double c2 = (3.0 * (q1 - q0) / h - 2.0 * p0 - p1) / h - g - miss + miss_rate_ * h;
  const double c3 = ((2.0 * (q0 - q1) / h + p0 + p1) / h) / h - miss_rate_;
  const auto cubic = [&](double t, double& df) {
    df = c1 + t * (2.0 * c2 + 3.0 * c3 * t);
    return c0 + t * (c1 + t * (c2 + t * c3));
  };
  // The cubic's own bracket (its values at lo and hi are the model's to the interpolation error),
  // then Newton kept in it, bisecting when a step leaves it (a grazing arrival: the slope nearly
  // 0), until the cubic is within a tenth of model_root's tolerance. A polynomial evaluation costs
  // a few operations against a rotation's hundreds.
  const double tol = 1e-4 * touch_tol_;
  double df = 0.0;
  double a = lo, b = hi;
  if (!(cubic(a, df) > 0.0 && cubic(b, df) <= 0.0)) return x;
  double t = x;
  for (int it = 0; it < 40; ++it) {
    const double f = cubic(t, df);
    if (std::abs(f) <= tol) break;
    (f > 0.0 ? a : b) = t;
    if (!(b - a > 1e-15 * h)) break;
    double next = t - f / df;
    if (!(next > a && next < b)) next = 0.5 * (a + b);
    t = next;
  }
  return t;
}

double FixedStepper::model_root(const ContactSet& c, double miss, double lo, double hi, double f_lo, double f_hi,
                                double& g_model) const {
  if (!m_->curved()) {
    // Newton on the corrected model f(t) = lowest(t) + g (h - t) t + miss t (h - t), its slope
    // the lowest corner's height rate (exact: the free motion's own derivative) plus
    // (g + miss)(h - 2t); from the bracket's secant point, every iterate kept in the bracket (a
    // Newton step that leaves it, or a kink where the lowest corner changes, bisects). The last
    // step is taken without evaluating where it lands when its own error bound, |f''| delta^2 / 2
    // with |f''| <= (w_max^2 + alpha_max) r + 2 |g + miss|, is already below the tolerance (the
    // model's value there from the slope). The same tolerance as Illinois's, 1e-3 of the touch
    // tolerance; fewer evaluations.
    const TorqueFreeRotation& rot = *full_rot_;
    const double curvature =
        (rot.max_omega() * rot.max_omega() + rot.max_alpha()) * m_->bounding_radius + 2.0 * std::abs(m_->gravity + miss) +
        6.0 * std::abs(miss_rate_) * h_;
    const double tol = 1e-3 * touch_tol_;
    double x = hi - f_hi * (hi - lo) / (f_hi - f_lo);
    if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
    if (hermite_) x = hermite_start(miss, lo, hi, x);
    for (int it = 0; it < 100; ++it) {
      Vec3 z_rate;
      const Vec3 z_row = rot.bottom_row(x, z_rate);
      double slope = 0.0;
      g_model = lowest_flat(c, full_p_, full_v_, z_row, z_rate, x, slope) + m_->gravity * (h_ - x) * x;
      const double f = corrected(g_model, miss, x);
      if (std::abs(f) <= tol) break;
      (f > 0.0 ? lo : hi) = x;
      if (!(hi - lo > 1e-15 * h_)) break;
      const double dg = slope + m_->gravity * (h_ - 2.0 * x);  // the model's own slope
      const double delta = -f / (dg + (miss + miss_rate_ * x) * (h_ - 2.0 * x) + miss_rate_ * x * (h_ - x));
      const double next = x + delta;
      if (!(next > lo && next < hi)) {
        x = 0.5 * (lo + hi);
        continue;
      }
      if (0.5 * curvature * delta * delta <= tol) {
        g_model += delta * dg;
        return next;
      }
      x = next;
    }
    return x;
  }
  Illinois br{lo, f_lo, hi, f_hi};
  double mid = hi;
  for (int it = 0; it < 100 && br.hi - br.lo > 1e-15 * h_; ++it) {
    mid = br.next();
    g_model = model_G(c, mid);
    const double f = corrected(g_model, miss, mid);
    if (std::abs(f) <= 1e-3 * touch_tol_) break;
    br.update(mid, f, /*lo_side=*/f > 0.0);
  }
  return mid;
}

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
  if (!(a_min < 0.0)) return h_max_;
  const double d = std::sqrt(2.0 * max_sink_ / -a_min);
  return std::clamp(d, h_max_ / kMinStepDivisor, h_max_);
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

// Trials of the shortened step's length (each a whole step) before taking the best one.
constexpr int kMaxTrials = 12;
// Halvings of a curved die's step whose curvature impulse was capped (step()).
constexpr int kMaxHalvings = 4;

int FixedStepper::step(RigidState& s) { return step(s, kinetic_energy(*m_, s)); }

int FixedStepper::step(RigidState& s, double ke) {
  const DieModel& m = *m_;
  ContactSet c;
  if (s.position.z() <= m.bounding_radius + touch_tol_ && !(soa_vertices_ > 0 && soa_touching(s, c)))
    c = touching_corners(m, s, touch_tol_);
  const bool relanded = land_window_ > 0.0;  // this is the step taken again (below)
  const bool struck = rim_strike_;  // ... or taken again with the rim struck (below)
  rim_strike_ = false;
  if (m.curved() && c.n > 0) add_face_tripod(s, c, land_window_, land_depth_, land_either_);
  land_window_ = land_depth_ = 0.0;
  land_either_ = false;
  const double E0 = ke + m.mass * m.gravity * s.position.z();  // mechanical_energy(m, s)
  // Impact first, at the instant of contact, on the velocity before gravity's kick: restitution
  // returns the approach speed the corner really had (after the kick it would return g h more,
  // and gain energy). Then (in each trial) gravity, then the plastic solve that holds the die up.
  // The impact depends only on the step's start, not on its length: solved once, shared by every
  // trial step.
  RigidState s0 = s;
  impact_ = false;
  geo_.valid = false;  // every solve of this step (its impact, each trial) shares s0.R and c
  Iw_start_ = world_inertia(m, s0.R);
  // The solves' set-up needs the same world inertia (the same expression of the same R): handed over.
  geo_.Iw = Iw_start_;
  geo_.iw_given = true;
  if (c.n > 0) {
    double un = 0.0;
    for (int i = 0; i < c.n; ++i) un = std::min(un, corner_velocity(m, s0, c.vertex[i]).z());
    impact_ = un < -impact_speed(s0);
    if (impact_)
      imp_ = struck ? strike_rim(s0, c) : apply_friction_impact(m, s0, c, /*restitution=*/true, nullptr, nullptr, &geo_);
  }
  // After the impact: every trial's energy check starts here (without one, s0 is s: E0).
  e_start_ = impact_ ? mechanical_energy(m, s0) : E0;
  rims_new_ = false;
  slap_rims_ = 0;
  miss_rate_ = 0.0;
  hermite_ = false;
  // `impulse` (max_sink_): the step's length from its held corners' predicted sink, and what
  // they ask of the solve (try_step): the shallowest one's depth at the start, the deepest one's
  // (the energy check), and a_down_.
  a_down_ = 0.0;
  start_shallow_ = start_depth_max_ = 0.0;
  hold_ = max_sink_ > 0.0 && c.n > 0;
  h_ = hold_ ? predicted_step(s0, c) : h_max_;
  if (hold_) {
    const Vec3 z_row = s0.R.row(2).transpose();
    double shallow = std::numeric_limits<double>::infinity();
    for (int i = 0; i < c.n; ++i) {
      const double depth =
          -(s0.position.z() + z_row.dot(m.vertices[static_cast<std::size_t>(c.vertex[i])]) - m.rounding);
      shallow = std::min(shallow, depth);
      start_depth_max_ = std::max(start_depth_max_, depth);
    }
    start_shallow_ = shallow > touch_tol_ ? shallow : 0.0;
  }
  try_step(s0, c, h_, a_, /*full=*/true);
  if (m.curved() && c.n > 0 && !rims_new_) {
    // A slap (slap_rims_): a touching rim whose lowest point, in the body, turns by more than
    // 90 deg along it over the full step's free motion after the start's solve (its tilt passes
    // through or near zero), the far half of it clear of the floor at the start. The full step
    // is then tried again as a slap's: its new contact the far half (slap_low), the curvature
    // impulse holding only the near half (support_low), and shortened to the far half's arrival,
    // where the next step strikes it (impact first, with restitution). If the far half does not
    // reach the floor in that step, the plain step stands.
    const Vec3& e1 = m.rims.perp;
    const Vec3 e2 = m.rims.axis.cross(e1);
    const Vec3 z0 = s0.R.row(2).transpose(), z1 = free_end_row_;
    const double a0 = z0.dot(e1), b0 = z0.dot(e2), a1 = z1.dot(e1), b1 = z1.dot(e2);
    const double n0 = std::sqrt(a0 * a0 + b0 * b0);
    for (int i = 0; i < c.n; ++i) {
      const int r = c.vertex[i] < 3 ? 0 : 1;
      if ((slap_rims_ & (1 << r)) || !(n0 > 0.0) || !(a0 * a1 + b0 * b1 < 0.0)) continue;
      slap_u_[r][0] = -a0 / n0;
      slap_u_[r][1] = -b0 / n0;
      if (s0.position.z() + slap_low(z0, r) > touch_tol_) slap_rims_ |= 1 << r;
    }
    if (slap_rims_ != 0) {
      try_step(s0, c, h_, a_, /*full=*/true);
      if (!(a_.G < -touch_tol_)) {
        ++slap_no_arrival;
        slap_rims_ = 0;
        try_step(s0, c, h_, a_, /*full=*/true);
      }
    }
  }
  const Attempt* done = &a_;
  double dt = h_;
  // The search for a new contact's instant (below), run again as the plain step's if a slap's
  // located step leaves the rest of its rim below the floor (then the far half was not the first
  // part to arrive: the lowest point ran round the rim, a roll, which the curvature impulse holds).
  const auto locate = [&] {
    done = &a_;
    dt = h_;
    if (!(a_.G < -touch_tol_)) return;
    // A corner not yet touching would end the step below the floor. The step is shortened to the
    // instant it touches: the length d whose whole step (gravity's kick g d, the contact solve,
    // the free motion) ends with that corner on the floor, G(d) = 0 (G: the lowest such corner's
    // height at the step's end). Each trial is a whole step, so the accepted one keeps every
    // property of a step (energy included). The trials' lengths: the root of the full step's model
    // of G (model_G: exact without contact, so one trial), corrected for a flat die by the support
    // solve's predicted share of the kick (predicted_miss: with corners in contact the plain model
    // missed by 10-1000 touch tolerances and the first trial almost never landed), then of the
    // model corrected by the last trial's measured miss (defect correction, while the model stays
    // bracketing), then Illinois on G itself in the bracket the trials have found.
    const Vec3 z_row = s0.R.row(2).transpose();
    double g_lo = std::numeric_limits<double>::infinity();
    if (m.curved()) {
      g_lo = s0.position.z() + curved_low(c, s0.R);
    } else {
      int j = 0;
      for (int i = 0; i < static_cast<int>(m.vertices.size()); ++i) {
        if (j < c.n && c.vertex[j] == i) {
          ++j;
          continue;
        }
        g_lo = std::min(g_lo, s0.position.z() + z_row.dot(m.vertices[i]) - m.rounding);
      }
    }
    double d_lo = 0.0, d_hi = h_, g_hi = a_.G;
    // The model's values at d_lo, d_hi and the next trial's d, each evaluated once (the model is a
    // fixed function during the search: the full step's motion).
    double mg_lo = model_G(c, 0.0), mg_hi = 0.0, mg_d = 0.0;
    bool modelled = mg_lo > 0.0, have_mg_d = false;
    double d = 0.5 * h_;
    if (modelled) {
      // A flat die's model at h_ is the full step itself: its G (lowest_flat of the same p, v, h_
      // and row: try_step_with's R_end row is bit for bit bottom_row(h_)), plus g (h_ - h_) h_ = 0.
      mg_hi = m.curved() ? model_G(c, h_) : a_.G;
      mg_d = mg_hi;
      // The first trial's length from the model corrected by the support solve's predicted
      // effect (predicted_miss), the search started from a cubic interpolant of the arriving
      // corner's motion (hermite_start). Both only move the first trial toward the root.
      double miss0 = 0.0;
      if (!m.curved()) {
        const Vec3 z_end = a_.s.R.row(2).transpose();
        int arg = -1;
        double low = std::numeric_limits<double>::infinity();
        int j = 0;  // c.vertex is ascending
        for (int i = 0; i < static_cast<int>(m.vertices.size()); ++i) {
          if (j < c.n && c.vertex[j] == i) {
            ++j;
            continue;
          }
          const double z = z_end.dot(m.vertices[i]);
          if (z < low) low = z, arg = i;
        }
        if (arg >= 0) {
          const Vec3 r0 = s0.R * m.vertices[arg], r1 = a_.s.R * m.vertices[arg];
          hq_[0] = r0.z();
          hq_[1] = full_w_.cross(r0).z();
          hq_[2] = r1.z();
          hq_[3] = a_.s.omega.cross(r1).z();
          hermite_ = true;
          if (c.n > 0) miss0 = predicted_miss(c, r0);
        }
      }
      d = model_root(c, miss0, 0.0, h_, corrected(mg_lo, miss0, 0.0), corrected(mg_hi, miss0, h_), mg_d);
      have_mg_d = true;
    }
    bool have_lo = false;
    int side = 0;
    done = nullptr;
    Attempt* trial = &b_;
    Attempt* lo = &lo_;
    for (int k = 0; k < kMaxTrials; ++k) {
      try_step(s0, c, d, *trial);
      ++located_trials;
      if (std::abs(trial->G) <= touch_tol_) {
        done = trial;
        dt = d;
        break;
      }
      const double span = d * (h_ - d);
      const double mgd = have_mg_d ? mg_d : model_G(c, d);
      have_mg_d = false;
      const double miss = span > 0.0 ? (trial->G - mgd) / span - miss_rate_ * d : 0.0;
      const bool above = trial->G > 0.0;
      if (above) {
        d_lo = d, g_lo = trial->G, mg_lo = mgd;
        std::swap(trial, lo);  // the attempts are large: swap who is which, not their contents
        have_lo = true;
      } else {
        d_hi = d, g_hi = trial->G, mg_hi = mgd;
      }
      // Defect correction (twice at most) while the corrected model brackets a root in [d_lo, d_hi].
      const double f_lo = modelled ? corrected(mg_lo, miss, d_lo) : 0.0;
      const double f_hi = modelled ? corrected(mg_hi, miss, d_hi) : 0.0;
      modelled = modelled && k < 2 && f_lo > 0.0 && f_hi <= 0.0;
      if (modelled) {
        double mg_next = mg_hi;
        const double next = model_root(c, miss, d_lo, d_hi, f_lo, f_hi, mg_next);
        if (next > d_lo && next < d_hi) {
          d = next;
          mg_d = mg_next;
          have_mg_d = true;
          continue;
        }
        modelled = false;
      }
      // Illinois on G itself (regula falsi halving the stale end's weight).
      if (above) {
        if (side == -1) g_hi *= 0.5;
        side = -1;
      } else {
        if (side == 1) g_lo *= 0.5;
        side = 1;
      }
      d = d_hi - g_hi * (d_hi - d_lo) / (g_hi - g_lo);
      if (!(d > d_lo && d < d_hi)) d = 0.5 * (d_lo + d_hi);
    }
    if (!done) {
      // Not within the tolerance in kMaxTrials trials (the touch is nearly tangential): the longest
      // trial that ends above the floor; the corner touches in the next step. Counted.
      ++located_capped;
      if (have_lo) {
        done = lo;
        dt = d_lo;
      } else {  // every trial ended below: the shortest, its corner lifted to the floor at the end (flat dice)
        try_step(s0, c, d_hi, *trial);
        ++located_trials;
        done = trial;
        dt = d_hi;
      }
    }
    ++located;
  };
  locate();
  if (!m.curved() && c.n > 0 && max_sink_ > 0.0) {
    // What the held corners sank in the accepted step, checked: more than max_sink_ (the start's
    // solve turned the die, or the acceleration changed within the step), the whole step again,
    // shorter by the sink's d^2 law (twice at most; not below the shortest step).
    const double h_min = h_max_ / kMinStepDivisor;
    for (int k = 0; k < 2; ++k) {
      double depth;
      const double sink = held_sink(s0, done->s, c, depth);
      if (!(sink > max_sink_) || !(h_ > h_min)) break;
      h_ = std::max(h_min, 0.9 * h_ * std::sqrt(max_sink_ / sink));
      ++sink_shortened;
      miss_rate_ = 0.0;
      hermite_ = false;
      try_step(s0, c, h_, a_, /*full=*/true);
      locate();
    }
  }
  if (!m.curved() && c.n > 0) {
    double depth;
    const double sink = held_sink(s0, done->s, c, depth);
    max_held_sink = std::max(max_held_sink, depth);
    if (sink > std::max(max_sink_, touch_tol_)) ++held_sinks;
    if (h_ < h_max_) ++short_steps;
  }
  // The accepted step halved (at most kMaxHalvings times) while its capped curvature impulse
  // leaves the rims sinking (why it happens: below).
  const auto halve_while_capped = [&] {
    Attempt* buf = done == &b_ ? &lo_ : &b_;
    double d = dt;
    for (int k = 0; k < kMaxHalvings && done->to_halve(); ++k) {
      d *= 0.5;
      try_step(s0, c, d, *buf);
      done = buf;
      dt = d;
      buf = buf == &b_ ? &lo_ : &b_;
    }
    ++halved;
  };
  // A slap's step whose near half the capped curvature impulse leaves sinking: halved as a plain
  // step would be, still a slap's (its end then before the far half's arrival).
  if (slap_rims_ != 0 && done->to_halve()) halve_while_capped();
  if (slap_rims_ != 0 && done->s.position.z() + rim_lowest(m, done->s.R) < -touch_tol_) {
    ++slap_rim_below;
    slap_rims_ = 0;
    try_step(s0, c, h_, a_, /*full=*/true);
    locate();
  }
  if (m.curved() && done->to_halve() && slap_rims_ == 0) {
    // (Not a slap's step: its end is the far half's arrival, which a halving would miss.)
    // The curvature impulse could not hold the rims on the floor without gaining energy: the
    // lowest point's height is far from quadratic over the step (a near-flat coin spinning fast,
    // its lowest point running round the rim: the slap), or the step's gravity, kicked at its
    // start, is out of phase with the middle's impulse by g P d / 2 (a disc rolling on its rim
    // with w^2 a >> g, Euler's disk). Shorter steps, halved (at most kMaxHalvings times) until it
    // holds; what is still below the floor then is lifted, counted (overlap_fixes). Halved as well
    // (unreflected) while the impulse's own work gains, though the capped one holds the rims: the
    // near-flat coin's, which a shorter step removes (kind B, issue 13: quarter `impulse` 2e4
    // tosses 32 -> 6 clamps); the gravity-phase cap, which it does not, is left to be counted.
    halve_while_capped();
  }
  // A curved die's rims at the accepted step's end, below the floor by this (lifted at the end).
  const double below = m.curved() ? -(done->s.position.z() + rim_lowest(m, done->s.R)) : 0.0;
  if (m.curved() && c.n > 0 && !relanded && !struck) {
    // The accepted step still capped after the halvings (a clamp), or its rim ending below the
    // floor (a lift, at the end): in every case examined a coin landing or lying nearly flat (tilt
    // 1e-6 to 6e-5 rad) on one rim point, whose lowest point runs round the rim while the face comes
    // down. If the face's tripod reaches the floor within the full step at its approach speed, or
    // lies within the depth the lift would close, the step is taken again from its start with the
    // tripod in the contact set: struck at once, as a polyhedron's landing face is (what it
    // closes early is what the step would close anyway, at most the lift it replaces). Once. (The
    // discarded attempt's work counters, located, halved and the slap's, stay counted.)
    if (done->to_halve() || done->clamped || below > touch_tol_) {
      ContactSet wide = c;
      add_face_tripod(s, wide, h_, std::max(0.0, below));
      // Kind B (issue 13): the accepted step still clamps after the halvings, the coin within a
      // few mrad of flat, tumbling at 30-80 rad/s about a nearly horizontal axis: its rim's
      // lowest point jumps across the face within microseconds (a = 12 mm, tilt 3e-4, 46 rad/s:
      // the curvature of its height is a w^2 / tilt ~ 1e5 m/s^2), which no step of the halvings
      // (62.5 us) holds with an impulse that does no work. That is the face coming down: one
      // tripod point descends at ~a w (0.4-1 m/s, 0.5-65 um up) while the other rises, so the
      // rule above (both arriving) does not take it. It is struck as a face, the tripod joining
      // when one of its points reaches the floor within the step (the rising one takes an
      // impulse only if the strike turns it down). Kept only if the step taken again does better
      // than the clamp (and lift) it replaces: the tripod does not cover the arcs between its
      // points, and a face struck while an arc still comes down (a slap's face struck at 1 m/s,
      // CylinderImpulse.SlappingFaceIsStruck) can clamp and lift again; the stepper's state is
      // then restored and the step finished as it was.
      if (wide.n == c.n && done->clamped) {
        add_face_tripod(s, wide, h_, std::max(0.0, below), /*either=*/true);
        if (wide.n > c.n) {
          const FixedStepper kept = *this;  // (rare: a few in 10^4 tosses)
          const RigidState s_in = s;
          const auto before = corrections.total();
          land_window_ = h_;
          land_depth_ = std::max(0.0, below);
          land_either_ = true;
          ++flat_landed;
          const int n = step(s);
          if (corrections.total() - before < (below > touch_tol_ ? 2u : 1u)) {
            ++face_jumped;
            return n;
          }
          *this = kept;
          s = s_in;
          ++face_jump_declined;
        }
      }
      if (wide.n > c.n) {
        land_window_ = h_;
        land_depth_ = std::max(0.0, below);
        ++flat_landed;
        return step(s, ke);
      }
      // The face's tripod already struck by this step's impact, and an arc of the rim between its
      // points still coming down after it (restitution turned a fast spin over: strike_rim): the
      // step taken again with that arc struck too. Kept only if it counts fewer corrections than
      // this step would (a step with none to replace is not taken again: it could not be kept);
      // otherwise the state is restored and the step finished as it was.
      const auto replaced = (impact_ ? imp_.corrections.total() : 0u) + done->sup.corrections.total() +
                            (done->clamped ? 1u : 0u) + (below > touch_tol_ ? 1u : 0u);
      int rim;
      Vec3 p;
      double vz;
      if (replaced > 0 && impact_ && rim_most_approaching(s0, c, h_, rim, p, vz) && vz < -impact_speed(s0)) {
        const FixedStepper kept = *this;  // (rare: a few in 10^5 tosses)
        const RigidState s_in = s;
        const auto before = corrections.total();
        rim_strike_ = true;
        const int n = step(s);
        if (corrections.total() - before < replaced) {
          ++rim_struck;
          return n;
        }
        *this = kept;
        s = s_in;
        ++rim_strike_declined;
      }
    }
  }
  const Attempt& a = *done;
  s = a.s;
  if (a.impact) {
    ++impacts;
    corrections.add(a.imp.corrections);
    sweeps += static_cast<std::uint64_t>(a.imp.iterations);
    dual_solves += static_cast<std::uint64_t>(a.imp.dual_solves);
    exact_fallbacks += static_cast<std::uint64_t>(a.imp.exact_fallbacks);
    max_energy_gain = std::max(max_energy_gain, relative_gain(a.imp.energy_before, a.imp.energy_after));
  }
  // An accepted step whose curvature impulse was capped (to gain no energy) is a clamp, counted
  // as the start's are (the step itself then holds the rims with less than the exact end gap).
  if (a.clamped) ++corrections.energy_clamps;
  if (c.n > 0) {
    corrections.add(a.sup.corrections);
    exact_fallbacks += static_cast<std::uint64_t>(a.sup.exact_fallbacks);
    sweeps += static_cast<std::uint64_t>(a.sup.iterations);
    max_energy_gain = std::max(max_energy_gain, relative_gain(a.sup.energy_before, a.sup.energy_after));
  }
  // (Only the used entries: ContactImpulses holds kMaxContacts of them.)
  warm_.n = a.next.n;
  for (int i = 0; i < a.next.n; ++i) {
    warm_.vertex[i] = a.next.vertex[i];
    warm_.P[i] = a.next.P[i];
  }
  dt_ = dt;
  slap_located_ = rims_new_ && dt < h_;
  if (slap_rims_ != 0 && dt < h_) ++slaps;
  end_ke_ = kinetic_energy(m, s);
  if (a.risen) {
    // A step whose held corners rose: no gain in the rest rules' energy, which adds the deepest
    // corner's depth to the COM height (try_step's check).
    max_energy_gain =
        std::max(max_energy_gain, relative_gain(E0 + m.mass * m.gravity * start_depth_max_, a.held_e));
  } else {
    max_energy_gain = std::max(max_energy_gain, relative_gain(E0, end_ke_ + m.mass * m.gravity * s.position.z()));
  }
  {
    // Plain E over the step (the lifts below are counted corrections, not the step's).
    const double mg = m.mass * m.gravity;
    const double plain = end_ke_ + mg * s.position.z();
    max_step_rise = std::max(max_step_rise, (plain - E0) / mg);
    max_rise_excess = std::max(max_rise_excess, relative_gain(E0 + mg * start_depth_max_, plain));
  }
  if (a.rise_dropped) ++rise_dropped;
  if (!m.curved() && a.G < -touch_tol_) {
    // Only a located step whose every trial ended below the floor (locate: the shortest taken)
    // ends with a corner not in c deeper than the touch tolerance: the COM is lifted by its depth,
    // the corner put on the floor, counted (overlap_fixes; the step is also located_capped).
    s.position.z() -= a.G;
    ++corrections.overlap_fixes;
  }
  if (m.curved()) {
    // The rims end every step within the touch tolerance of the floor or above it; where the step
    // left them deeper (a slapping rim, whose plain solve does not push, rim_support; a bias not
    // bracketed; a search out of trials) the COM is lifted by the residual, counted. (The energy
    // check above is of the step itself; the lift's m g dz is that counted correction.)
    const double pen = below;  // (s is the accepted attempt's state, unchanged since)
    max_penetration = std::max(max_penetration, pen);
    if (pen > touch_tol_) {
      s.position.z() += pen;
      ++corrections.overlap_fixes;
    }
  }
  return c.n;
}

StepperOutcome run_fixed_steps(const DieModel& m, RigidState& s, double& t, int& impacts, double h, double tiebreak,
                               bool allow_liftoff, ImpactThreshold threshold, StepperStats* stats, double max_sink) {
  StepperOutcome out;
  FixedStepper st(m, h, threshold, max_sink);
  st.impacts = impacts;
  const double g = m.gravity, r = m.bounding_radius;
  const double ke_rest = 1e-14 * m.mass * g * r;
  const double nudge = 1e-4 * std::sqrt(g / r);
  // Steps shortened to a new contact make more steps than (max_time - t) / h: a generous cap on
  // the count as well, so that nothing can loop forever.
  const double h_min = max_sink > 0.0 ? h / FixedStepper::kMinStepDivisor : h;
  const auto max_steps = 4 * static_cast<long long>(std::ceil((m.max_time - t) / h_min)) + 1000;
  std::uint64_t steps = 0;
  const auto finish = [&](StepperExit exit) {
    out.exit = exit;
    impacts = st.impacts;
    if (stats) {
      stats->corrections.add(st.corrections);
      stats->sweeps += st.sweeps;
      stats->steps += steps;
      stats->located += st.located;
      stats->located_trials += st.located_trials;
      stats->located_capped += st.located_capped;
      stats->nudges += static_cast<std::uint64_t>(out.nudges);
      stats->max_energy_gain = std::max(stats->max_energy_gain, st.max_energy_gain);
      stats->max_step_rise = std::max(stats->max_step_rise, st.max_step_rise);
      stats->max_rise_excess = std::max(stats->max_rise_excess, st.max_rise_excess);
      stats->max_penetration = std::max(stats->max_penetration, st.max_penetration);
      stats->halved += st.halved;
      stats->curvature_capped += st.curvature_capped;
      stats->support_search_capped += st.support_search_capped;
      stats->slaps += st.slaps;
      stats->slap_no_arrival += st.slap_no_arrival;
      stats->slap_rim_below += st.slap_rim_below;
      stats->flat_landed += st.flat_landed;
      stats->face_jumped += st.face_jumped;
      stats->face_jump_declined += st.face_jump_declined;
      stats->rim_struck += st.rim_struck;
      stats->rim_strike_declined += st.rim_strike_declined;
      stats->depth_held += st.depth_held;
      stats->dual_solves += st.dual_solves;
      stats->exact_fallbacks += st.exact_fallbacks;
      stats->max_held_sink = std::max(stats->max_held_sink, st.max_held_sink);
      stats->held_sinks += st.held_sinks;
      stats->sink_shortened += st.sink_shortened;
      stats->short_steps += st.short_steps;
      stats->rise_dropped += st.rise_dropped;
      // The guards of the sustained phase, reported with the corrections (kept out of the
      // stepper's own, whose totals decide its re-tried steps).
      stats->corrections.located_capped += static_cast<std::uint32_t>(st.located_capped);
      stats->corrections.support_search_capped += static_cast<std::uint32_t>(st.support_search_capped);
      stats->corrections.rise_dropped += static_cast<std::uint32_t>(st.rise_dropped);
      stats->corrections.depth_held += static_cast<std::uint32_t>(st.depth_held);
      stats->corrections.nudges += static_cast<std::uint32_t>(out.nudges);
    }
    return out;
  };
  // The kinetic energy of s, kept up to date (the rest check, the step and the balance test below
  // all read it; each step hands back its end's).
  double ke = kinetic_energy(m, s);
  for (long long k = 0; k < max_steps && t < m.max_time; ++k) {
    const int f = rest_face_down(m, s, tiebreak, ke);
    if (f >= 0) {
      out.face_down = f;
      return finish(StepperExit::Settled);
    }
    if (!allow_liftoff) {  // `stepped`: a flight high above the floor in closed form
      const long long coasted = st.coast(s, t, m.max_time, max_steps - k - 1);
      if (coasted > 0) {
        ke = kinetic_energy(m, s);
        k += coasted;
        steps += static_cast<std::uint64_t>(coasted);
        if (!(k < max_steps && t < m.max_time)) break;
      }
    }
    const int n = st.step(s, ke);
    ke = st.end_ke();
    ++steps;
    t += st.last_dt();
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
        if (!clear) break;
      }
      if (clear) return finish(StepperExit::LiftOff);
      continue;
    }
    // At rest but undecided: an exact balance on an edge or a corner. Break it the toss's way.
    if (ke < ke_rest && out.nudges < 4) {
      const ContactSet c = touching_corners(m, s, 1e-6 * r);
      Vec3 axis;
      if (c.n == 2) {
        axis = m.curved() ? (contact_point(m, s.R, c.vertex[1]) - contact_point(m, s.R, c.vertex[0])).normalized()
                          : (s.R * (m.vertices[c.vertex[1]] - m.vertices[c.vertex[0]])).normalized();
        if (std::fmod(tiebreak * 4096.0, 1.0) < 0.5) axis = -axis;
      } else {
        const SinCos a = sincos_turns(tiebreak);  // the angle 2 pi tiebreak
        axis = Vec3(a.cos, a.sin, 0.0);
      }
      s.omega += nudge * axis;
      ke = kinetic_energy(m, s);
      ++out.nudges;
    }
  }
  return finish(StepperExit::Unresolved);
}

}  // namespace dicesim
