#include "sim/models/initial_state.hpp"

#include <cmath>

#include "sim/models/toss_random.hpp"
#include "sim/sincos.hpp"

namespace dicesim {

Mat3 uniform_rotation(double u1, double u2, double u3) {
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  const SinCos t2 = sincos_turns(u2), t3 = sincos_turns(u3);  // angles 2 pi u2, 2 pi u3
  // A unit quaternion to rounding (a^2 + b^2 = 1, cos^2 + sin^2 = 1): normalising again would
  // change only the last bits, at the cost of a square root and four divisions.
  const Quat q(b * t3.cos, a * t2.sin, a * t2.cos, b * t3.sin);  // (w, x, y, z)
  return q.toRotationMatrix();
}

Vec3 uniform_unit_vector(double u1, double u2) {
  const double z = 2.0 * u1 - 1.0;
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const SinCos a = sincos_turns(u2);
  return {r * a.cos, r * a.sin, z};
}

static double draw(TossRandom& rng, const NormalScalar& d) {
  return d.sd > 0.0 ? d.mean + d.sd * rng.normal() : d.mean;
}

InitialState draw_initial_state(const ThrowDef& thr, std::uint64_t seed, std::uint64_t toss, bool motion) {
  TossRandom rng(seed, toss);
  InitialState s;

  switch (thr.orientation.kind) {
    case OrientationKind::Uniform: {
      const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
      s.orientation = uniform_rotation(u1, u2, u3);
      break;
    }
    case OrientationKind::EulerUniform: {
      const double psi = 2.0 * kPi * rng.uniform(), theta = 2.0 * kPi * rng.uniform(),
                   phi = 2.0 * kPi * rng.uniform();
      s.orientation = euler_zxz(psi, theta, phi);
      break;
    }
    case OrientationKind::Fixed: {
      const Vec3 e = thr.orientation.euler_deg * (kPi / 180.0);
      s.orientation = euler_zxz(e.x(), e.y(), e.z());
      break;
    }
  }

  s.com_position = Vec3(0.0, 0.0, draw(rng, thr.height));
  if (!motion) return s;
  for (int k = 0; k < 3; ++k) s.velocity[k] = draw(rng, {thr.velocity.mean[k], thr.velocity.sd[k]});

  switch (thr.spin.kind) {
    case SpinKind::Normal:
      for (int k = 0; k < 3; ++k) s.omega[k] = draw(rng, {thr.spin.components.mean[k], thr.spin.components.sd[k]});
      break;
    case SpinKind::RandomAxis: {
      const double u1 = rng.uniform(), u2 = rng.uniform();
      s.omega = uniform_unit_vector(u1, u2) * draw(rng, thr.spin.magnitude);
      break;
    }
    case SpinKind::OctantAxis: {
      Vec3 axis(rng.uniform(), rng.uniform(), rng.uniform());  // each in (0, 1): never all zero
      s.omega = axis.normalized() * draw(rng, thr.spin.magnitude);
      break;
    }
    case SpinKind::BodyAxis: {
      // A thumb's flip: the angular velocity at angle tilt from a body axis, azimuth uniform,
      // given in the die's geometric frame and carried to the world by the orientation.
      const Vec3 a = thr.spin.axis.normalized();
      const Vec3 e1 = a.unitOrthogonal(), e2 = a.cross(e1);
      const double tilt = draw(rng, thr.spin.tilt_deg) * (kPi / 180.0);
      const SinCos tl = sincos(tilt), az = sincos_turns(rng.uniform());  // azimuth 2 pi u
      const Vec3 dir = tl.cos * a + tl.sin * (az.cos * e1 + az.sin * e2);
      s.omega = s.orientation * dir * draw(rng, thr.spin.magnitude);
      break;
    }
  }
  if (thr.catch_time) s.catch_time = draw(rng, *thr.catch_time);
  return s;
}

}  // namespace dicesim
