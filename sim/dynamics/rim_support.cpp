// A curved die's (a coin's, a cylinder's) contact geometry in FixedStepper: its lowest point over
// what counts as new contact (curved_low, slap_low, support_low), and the impacts that strike its
// face's tripod or its rim's most approaching arc (add_face_tripod, rim_most_approaching,
// strike_rim). Its sustained step is rim_step.cpp.
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/contact_stepper_internal.hpp"

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


double FixedStepper::support_low(const Vec3& z_row, int rim) const {
  return (slap_rims_ & (1 << rim)) ? slap_low(z_row, -rim - 1) : stepper_detail::rim_low_z(*m_, z_row, rim);
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
