// A cylinder's contact features at one orientation: the lowest point of each rim circle, in
// closed form, and the two points 120 deg either side of it (sim/body/die_model.hpp, Rims). The
// exact curved side: a cylinder on its side touches with both rims' lowest points (the ends of
// its contact line), on a rim with one, flat on a face with that rim's tripod.
#pragma once

#include <cmath>

#include "sim/body/die_model.hpp"

namespace dicesim {

// Unit vector in rim plane (perpendicular to the world axis K) pointing most nearly down; a fixed
// body direction when the axis is vertical (then every rim point is equally low).
inline Vec3 rim_down(const DieModel& m, const Mat3& R, const Vec3& K) {
  // -e_z minus its component along K. Its z, K_z^2 - 1 = -(K_x^2 + K_y^2) for a unit K, is taken
  // from K_x and K_y where rounding (|K| a little above 1) leaves K_z^2 >= 1 at a tilt of ~1e-8:
  // the point found was then the rim's highest, its tripod 120 deg either side the lowest (a
  // three-sided coin landing flat in `stepped`, toss 96416: the face was not seen, kind B).
  const double kz2 = K.z() * K.z() - 1.0;
  Vec3 u(K.z() * K.x(), K.z() * K.y(), kz2 < 0.0 ? kz2 : -(K.x() * K.x() + K.y() * K.y()));
  const double n = u.norm();
  if (n < 1e-12) return R * m.rims.perp;
  return u / n;
}

// The features at one orientation: what all six share (the world axis, the rim plane's centre,
// the down direction and its perpendicular) computed once, for callers that visit several.
// point(v) is rim_point(m, R, v), bit for bit.
class RimFeatures {
 public:
  RimFeatures(const DieModel& m, const Mat3& R)
      : m_(&m), K_(R * m.rims.axis), centre_(R * m.rims.centre), u_(rim_down(m, R, K_)), side_(K_.cross(u_)) {}

  // Feature v's contact point relative to the COM (world), the rounding included.
  Vec3 point(int v) const {
    const Rims& rim = m_->rims;
    const Vec3 c = centre_ + ((v < 3) ? rim.half : -rim.half) * K_;
    const int j = v % 3;
    Vec3 p;
    if (j == 0) {
      p = c + rim.radius * u_;
    } else {
      constexpr double kCos = -0.5, kSin = 0.86602540378443864676;
      p = c + rim.radius * (kCos * u_ + (j == 1 ? kSin : -kSin) * side_);
    }
    p.z() -= m_->rounding;
    return p;
  }

  const Vec3& axis() const { return K_; }        // the world axis K
  const Vec3& centre() const { return centre_; }  // the rims' mid-plane centre, from the COM (world)
  const Vec3& down() const { return u_; }         // unit, in the rim plane, most nearly down (rim_down)
  const Vec3& side() const { return side_; }      // K x down

 private:
  const DieModel* m_;
  Vec3 K_, centre_, u_, side_;
};

// Feature v's contact point relative to the COM (world), the rounding included.
inline Vec3 rim_point(const DieModel& m, const Mat3& R, int v) { return RimFeatures(m, R).point(v); }

// Height of the die's lowest point relative to its COM (world z), rounding included.
inline double rim_lowest(const DieModel& m, const Mat3& R) {
  const Vec3 K = R * m.rims.axis;
  const double cz = R.row(2).dot(m.rims.centre);
  const double drop = m.rims.radius * std::sqrt(std::max(0.0, 1.0 - K.z() * K.z()));
  return cz - m.rims.half * std::abs(K.z()) - drop - m.rounding;
}

}  // namespace dicesim
