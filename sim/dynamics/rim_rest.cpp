#include "sim/dynamics/rim_rest.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/sincos.hpp"

namespace dicesim {
namespace {

// Distance from the COM (origin) to the nearest point of the circle centre c, axis k, radius a.
double circle_distance(const Vec3& c, const Vec3& k, double a) {
  const Vec3 w = -c;
  const double par = w.dot(k);
  const double perp = (w - par * k).norm();
  return std::sqrt(par * par + (perp - a) * (perp - a));
}

}  // namespace

void compute_rim_rest_geometry(DieModel& m) {
  const Rims& rim = m.rims;
  const Vec3& k = rim.axis;
  const Vec3& o = rim.centre;
  const double ok = o.dot(k), o_perp = (o - ok * k).norm();
  const double r = m.rounding;
  m.face_height = {ok + rim.half + r, -ok + rim.half + r, rim.radius - o_perp + r};
  m.face_hold = {rim.radius - o_perp, rim.radius - o_perp, rim.half - std::abs(ok)};
  const double e0 = circle_distance(o + rim.half * k, k, rim.radius) + r;
  const double e1 = circle_distance(o - rim.half * k, k, rim.radius) + r;
  m.face_escape = {e0, e1, std::min(e0, e1)};
  m.face_tip_ratio.resize(3);
  for (int f = 0; f < 3; ++f) m.face_tip_ratio[f] = m.face_hold[f] / m.face_height[f];
  const Mat3 I = m.principal_moments.asDiagonal();
  m.face_gyro = {k.cross(I * k).norm(), k.cross(I * k).norm(), 0.0};
  m.face_area = {kPi * rim.radius * rim.radius, kPi * rim.radius * rim.radius, 2.0 * kPi * rim.radius * 2.0 * rim.half};
}

int rim_quasi_static_down(const DieModel& m, const Mat3& R, double tiebreak) {
  const Rims& rim = m.rims;
  const Vec3& k = rim.axis;
  const Vec3& o = rim.centre;
  const bool valley = std::abs(o.dot(k)) < rim.half;
  const bool face_stable = (o - o.dot(k) * k).norm() < rim.radius;
  constexpr double kStep = 1e-3;  // rad
  Vec3 d = R.transpose() * Vec3(0.0, 0.0, -1.0);
  const double o_perp = (o - o.dot(k) * k).norm();
  if (o_perp <= 1e-12 * rim.radius && valley) {
    // COM on the axis: the roll stays in the plane of the axis and the down direction; at angle
    // theta from the face normal sigma = (s o.k + b) cos theta + a sin theta, so the die falls
    // onto the face iff a cos theta > (s o.k + b) sin theta, else onto its side.
    const double dk = d.dot(k), s = dk >= 0.0 ? 1.0 : -1.0;
    const double lhs = rim.radius * std::abs(dk), rhs = (s * o.dot(k) + rim.half) * (d - dk * k).norm();
    const int face = dk >= 0.0 ? 0 : 1;
    if (lhs == rhs) return tiebreak < 0.5 ? face : 2;
    return lhs > rhs ? face : 2;
  }
  for (int it = 0; it < 20000; ++it) {
    const double dk = d.dot(k);
    const Vec3 dp = d - dk * k;
    const double np = dp.norm();
    if (np < kStep && face_stable) return dk > 0.0 ? 0 : 1;
    if (std::abs(dk) < 1e-15 && valley) return 2;  // exactly on the side
    Vec3 g = o + (dk > 0.0 ? rim.half : -rim.half) * k;
    if (np > 0.0) g += rim.radius * dp / np;
    Vec3 gt = g - g.dot(d) * d;
    if (gt.norm() <= 1e-12 * rim.radius) {  // balanced exactly: the toss decides the way
      const Vec3 u = d.unitOrthogonal(), v = d.cross(u);
      const SinCos a = sincos_turns(tiebreak);  // the angle 2 pi tiebreak
      gt = a.cos * u + a.sin * v;
    }
    const Vec3 next = (d - kStep * gt.normalized()).normalized();
    if ((next.dot(k) > 0.0) != (dk > 0.0) && valley) return 2;  // reached the side's valley
    d = next;
  }
  return -1;
}

int rim_rest_face_down(const DieModel& m, const RigidState& s, double tiebreak, double ke) {
  const double mg = m.mass * m.gravity;
  // Above every barrier: only lying flat can decide, and only with a rim point on the floor.
  const bool above_barriers = ke + mg * s.position.z() >= mg * m.max_escape;
  if (above_barriers && s.position.z() > m.bounding_radius) return -1;
  const double low = s.position.z() + rim_lowest(m, s.R);
  if (!above_barriers) {
    const double energy = ke + mg * (s.position.z() + std::max(0.0, -low));
    const int basin = rim_quasi_static_down(m, s.R, tiebreak);
    if (basin >= 0 && energy < mg * m.face_escape[static_cast<std::size_t>(basin)] * (1.0 - 1e-9)) {
      // On the side, the barrier out of the basin is small for a thin coin (tens of um of lift):
      // a coin below it may still spin upright or roll for a second. It cannot fall, but it is
      // named `edge` only once it has stopped (every point slower than v_tol), so no answer is
      // read from a coin that is still moving.
      if (basin != 2) return basin;
      return s.velocity.norm() + s.omega.norm() * m.bounding_radius <= rest_speed_tol(m) ? basin : -1;
    }
  }

  // Lying flat on a face, sliding or spinning but not rocking (as a polytope's face, rest.hpp, and
  // like it whatever the kinetic energy): the face's tripod on the floor with vanishing normal
  // velocity, friction's and the spin's shifts of the centre of pressure (mu h, and w^2 |n x I n|
  // / (m g) with w the largest spin the flat motion can reach, 0 for a symmetric coin) within
  // face_hold. Such a coin cannot turn over.
  const double kz = s.R.row(2).dot(m.rims.axis);
  if (std::abs(kz) < 0.999) return -1;
  const int down = kz < 0.0 ? 0 : 1;  // face 0 (heads face) down when the axis points down
  const std::size_t di = static_cast<std::size_t>(down);
  const double flat_tol = 1e-6 * m.bounding_radius;
  const double v_tol = rest_speed_tol(m);
  const Vec3& n = m.rims.axis;  // body frame: the face normals are +-axis
  const double spin_max2 = 2.0 * ke / n.dot(m.principal_moments.cwiseProduct(n));
  if (!(m.face_hold[di] > 0.0 &&
        m.max_friction * m.face_height[di] + spin_max2 * m.face_gyro[di] / mg < 0.999 * m.face_hold[di]))
    return -1;
  const RimFeatures rims(m, s.R);
  for (int j = 0; j < 3; ++j) {
    const Vec3 r = rims.point(3 * down + j);
    if (s.position.z() + r.z() - std::min(low, 0.0) > flat_tol) return -1;
    if (std::abs((s.velocity + s.omega.cross(r)).z()) > v_tol) return -1;
  }
  return down;
}

double rim_lowest_excluding(const DieModel& m, const Mat3& R, const ContactSet& c) {
  double low = std::numeric_limits<double>::infinity();
  const RimFeatures rims(m, R);
  int j = 0;  // c.vertex is ascending
  for (int i = 0; i < kRimFeatures; ++i) {
    if (j < c.n && c.vertex[j] == i) {
      ++j;
      continue;
    }
    low = std::min(low, rims.point(i).z());
  }
  return low;
}

void apply_rolling_resistance(const DieModel& m, RigidState& s, const ContactSet& c, double normal_impulse) {
  if (c.n == 0 || !(normal_impulse > 0.0)) return;
  // The roll: rotation about the horizontal projection of the axis (the horizontal perpendicular
  // to the rim's tangent at its lowest point), which moves the contact along the floor. Tipping
  // (about that tangent) and pivoting (about the vertical) move no contact and are not resisted.
  const Vec3 K = s.R * m.rims.axis;
  const Vec3 kh(K.x(), K.y(), 0.0);
  const double nk = kh.norm();
  if (nk <= 1e-9) return;  // lying flat: nothing to roll on
  const Vec3 u = kh / nk;
  const double w = s.omega.dot(u);
  if (w == 0.0) return;
  double delta = 0.0;
  for (int i = 0; i < c.n; ++i) delta += m.vertex_rolling[static_cast<std::size_t>(c.vertex[i])];
  delta /= c.n;
  if (delta <= 0.0) return;
  const Vec3 inv_u = s.R * (s.R.transpose() * u).cwiseQuotient(m.principal_moments);  // I_w^-1 u
  const double lam = std::min(delta * normal_impulse, std::abs(w) / u.dot(inv_u));
  s.omega -= (w > 0.0 ? lam : -lam) * inv_u;
}

void apply_pivoting_resistance(const DieModel& m, RigidState& s, const ContactSet& c, double normal_impulse) {
  if (c.n != 1 || !(normal_impulse > 0.0)) return;
  const double w = s.omega.z();
  const double delta = m.vertex_pivoting[static_cast<std::size_t>(c.vertex[0])];
  if (w == 0.0 || delta <= 0.0) return;
  const Vec3 inv_z = s.R * s.R.row(2).transpose().cwiseQuotient(m.principal_moments);  // I_w^-1 e_z
  const double lam = std::min(delta * normal_impulse, std::abs(w) / inv_z.z());
  s.omega -= (w > 0.0 ? lam : -lam) * inv_z;
}

}  // namespace dicesim
