// The impact law at one contact point between two bodies (pair_impact.hpp), in the contact frame.
// It mirrors the floor law's one-point path step for step: compression as friction_one_corner.cpp's
// solve_plastic_single (calling its one_corner_sliding_newton / _reference), restitution and the
// rescue passes and energy check as apply_friction_impact (friction_impact.cpp) does for one point,
// and restitution's friction as friction_gauss_seidel.cpp's solve_friction does for one point (its
// min_on_disc, private there, is solved here by a bracketed root instead). One departure: a jam (no
// sliding direction found), which the floor hands to its multi-point sweeps, is solved here exactly
// as a root in the normal impulse. The floor's code works on one body's state, so it could not be
// shared as it stands without changing its rounding, which many tests pin; this file works on (W, u)
// alone.
#include "sim/dynamics/pair_impact.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "sim/dynamics/friction_impact.hpp"
#include "sim/illinois.hpp"

namespace dicesim {
// (A namespace of its own: the library may be compiled as unity batches beside the friction files.)
namespace pair_detail {
namespace {

Mat3 cross_matrix(const Vec3& r) {
  Mat3 X;
  X << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return X;
}

// One side's share of the compliance, written as the floor's (friction_impact_internal.hpp,
// compliance) so that a die against a fixed body (which adds exact zeros) has the floor's W to the bit.
Mat3 side_compliance(const PairSide& s) {
  const Mat3 X = cross_matrix(s.r);
  return s.inv_mass * Mat3::Identity() - X * s.inv_inertia * X;
}

// Columns t1, t2, n: orthonormal, exactly the identity for n = +z (the floor's frame). For -n the
// same axes up to sign (t1 is even in n, t2 odd), so swapping the bodies poses the same problem up to
// exact sign changes, and gives exactly -P.
Mat3 contact_frame(const Vec3& n) {
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(n(i)) > std::abs(n(k))) k = i;
  const Vec3 h = Vec3::Unit((k + 1) % 3);  // |h.n| <= 1/sqrt(2): never parallel to n
  Vec3 t1 = h - h.dot(n) * n;
  t1 /= t1.norm();
  Mat3 F;
  F.col(0) = t1;
  F.col(1) = n.cross(t1);
  F.col(2) = n;
  return F;
}

// argmin over |x| <= radius of x.A x / 2 + g.x (A symmetric positive definite): the kinetic energy's
// least over a tangential impulse in the friction disc. Inside: -A^-1 g; else x(l) = -(A + l 1)^-1 g
// on the circle, l > 0 the root of 1/radius - 1/|x(l)| (increasing in l, nearly linear: |x| ~ |g| / l),
// bracketed by [0, |g| / radius] (there |x| < |g| / l = radius) and found by Illinois to rounding.
Eigen::Vector2d least_energy_in_disc(const Eigen::Matrix2d& A, const Eigen::Vector2d& g, double radius) {
  if (!(radius > 0.0)) return Eigen::Vector2d::Zero();
  const double a = A(0, 0), b = A(0, 1), c = A(1, 1);
  const auto x_at = [&](double l) {
    const double det = (a + l) * (c + l) - b * b;
    return Eigen::Vector2d(-((c + l) * g.x() - b * g.y()) / det, -((a + l) * g.y() - b * g.x()) / det);
  };
  Eigen::Vector2d x = x_at(0.0);
  if (x.squaredNorm() <= radius * radius) return x;
  const auto f = [&](double l) { return 1.0 / radius - 1.0 / x_at(l).norm(); };
  Illinois br{0.0, f(0.0), g.norm() / radius, 0.0};
  br.f_hi = f(br.hi);
  for (int it = 0; it < 200 && br.f_hi < 0.0 && br.hi - br.lo > 1e-15 * br.hi; ++it) {
    const double l = br.next();
    if (l == br.lo || l == br.hi) break;
    const double fl = f(l);
    if (fl == 0.0) {
      br.hi = l;
      break;
    }
    br.update(l, fl, fl > 0.0);
  }
  x = x_at(br.hi);  // the end inside the disc
  const double xn = x.norm();
  if (xn > radius) x *= radius / xn;  // rounding: stay in the disc
  return x;
}

// A jam (no sliding direction found; rare, where W couples slip and normal strongly; the floor hands
// it to its Gauss-Seidel sweeps): the plastic impulse as a root in P_n alone. For a normal impulse p,
// the tangential impulse of least kinetic energy in the disc mu p, P_t(p), is Coulomb's with maximal
// dissipation (inside: sticking; else on the edge, opposite the final slip), so the plastic impulse is
// (P_t(p), p) where the final normal velocity f(p) = u_n + W_nn p + W_nt.P_t(p) vanishes (continuous,
// as P_t(p) is; f(0) = u_n < 0). The first sign change on a scan, refined by Illinois; its separating
// end is taken. False if f stays negative.
bool plastic_by_normal_root(const Mat3& W, const Vec3& u, double mu, Vec3& P) {
  const Eigen::Matrix2d A = W.topLeftCorner<2, 2>();
  const auto impulse = [&](double p) {
    const Eigen::Vector2d g = u.head<2>() + W.block<2, 1>(0, 2) * p;
    const Eigen::Vector2d t = least_energy_in_disc(A, g, mu * p);
    return Vec3(t.x(), t.y(), p);
  };
  const auto f = [&](double p) { return u.z() + W.row(2).dot(impulse(p)); };
  const double p0 = -u.z() / W(2, 2);  // the frictionless impulse
  // Steps of p0 / 8 up to 4 p0, then growing by a quarter each (to ~1e16 p0): the first crossing.
  Illinois br{0.0, u.z(), 0.0, 0.0};
  bool bracketed = false;
  for (int j = 1; j <= 200 && !bracketed; ++j) {
    const double p = j <= 32 ? p0 * j / 8.0 : p0 * 4.0 * std::pow(1.25, j - 32);
    const double fp = f(p);
    if (fp >= 0.0) {
      br.hi = p, br.f_hi = fp;
      bracketed = true;
    } else {
      br.lo = p, br.f_lo = fp;
    }
  }
  if (!bracketed) return false;
  for (int it = 0; it < 200 && br.f_hi > 0.0 && br.hi - br.lo > 1e-15 * br.hi; ++it) {
    const double p = br.next();
    if (p == br.lo || p == br.hi) break;
    const double fp = f(p);
    if (fp == 0.0) {
      br.hi = p;
      break;
    }
    br.update(p, fp, fp < 0.0);
  }
  P = impulse(br.hi);
  return true;
}

// The plastic frictional impulse for relative velocity u (friction_one_corner.cpp,
// solve_plastic_single): sticking P = -W^-1 u if it fits the cone, else sliding (Newton on the slip's
// angle, its reference where Newton's root does not verify), else the root in P_n; failing that too
// (none found in any test), the frictionless impulse, counted.
Vec3 compress(const Mat3& W, const Mat3& W_inverse, const Vec3& u, double mu, PairImpactResult& res, bool* sliding) {
  if (!(u.z() < 0.0)) return Vec3::Zero();
  const Vec3 stick = -(W_inverse * u);
  if (stick.z() >= 0.0 && stick.x() * stick.x() + stick.y() * stick.y() <= mu * mu * stick.z() * stick.z())
    return stick;
  if (sliding) *sliding = true;
  if (mu == 0.0) return Vec3(0.0, 0.0, -u.z() * (1.0 / W(2, 2)));
  Eigen::Vector2d d(-u.x(), -u.y());
  if (d.norm() <= 1e-300) d = Eigen::Vector2d(stick.x(), stick.y());
  Vec3 P;
  if (d.norm() > 1e-300) {
    d.normalize();
    if (one_corner_sliding_newton(W, u, mu, d, P)) return P;
    if (one_corner_sliding_reference(W, u, mu, d, P)) {
      ++res.exact_fallbacks;
      return P;
    }
  }
  if (plastic_by_normal_root(W, u, mu, P)) {
    ++res.exact_fallbacks;
    return P;
  }
  ++res.corrections.fallbacks;
  return Vec3(0.0, 0.0, -u.z() * (1.0 / W(2, 2)));
}

}  // namespace
}  // namespace pair_detail

PairImpactResult point_impact(const Mat3& W, const Vec3& u, double e, double mu) {
  PairImpactResult res;
  if (!(u.z() < 0.0) || !(W(2, 2) > 0.0)) return res;
  const Mat3 W_inverse = W.inverse();
  res.energy_before = 0.5 * u.dot(W_inverse * u);
  const auto energy_change = [&](const Vec3& P) { return u.dot(P) + 0.5 * P.dot(W * P); };

  // 1. Compression.
  Vec3 P = pair_detail::compress(W, W_inverse, u, mu, res, &res.sliding);

  // 2. Restitution (friction_impact.hpp): the normal impulse scaled by k releases e^2 of what
  // compression stored, min(-W_n, -dE_c); then friction in the disc mu k P_n, least energy.
  if (e > 0.0) {
    const Vec3 u1 = u + W * P;
    const double work_n = P.z() * 0.5 * (u.z() + u1.z());
    const double stored = std::max(0.0, std::min(-work_n, -energy_change(P)));
    const double released = e * e * stored;
    // dE(k) = k a + k^2 q / 2 for the normal impulse k P_n.
    const double a = P.z() * u1.z();
    const double q = P.z() * P.z() * W(2, 2);
    if (released > 0.0 && q > 0.0) {
      const double root = std::sqrt(a * a + 2.0 * q * released);
      const double k = a >= 0.0 ? 2.0 * released / (a + root) : (root - a) / q;
      const double pn = k * P.z();
      const Vec3 u2 = u1 + W.col(2) * pn;
      const Eigen::Vector2d t =
          pair_detail::least_energy_in_disc(W.topLeftCorner<2, 2>(), u2.head<2>(), mu * k * P.z());
      P += Vec3(t.x(), t.y(), pn);
    }
  }

  // Still approaching (the restitution's friction, coupled to the normal through W, can push the
  // point back in): one more plastic pass; failing that a frictionless one (always dissipative), counted.
  const double speed_tol = 1e-10 * u.norm();
  for (int pass = 0; pass < 2; ++pass) {
    const Vec3 uf = u + W * P;
    if (!(uf.z() < -speed_tol)) break;
    if (pass == 0) {
      P += pair_detail::compress(W, W_inverse, uf, mu, res, nullptr);
    } else {
      ++res.corrections.fallbacks;
      P.z() -= uf.z() / W(2, 2);
    }
  }

  // The energy assertion: the law cannot gain energy; this scales back only what rounding broke, and
  // counts it. dE(lambda) = lambda a + lambda^2 q for the impulse scaled by lambda.
  double dE = energy_change(P);
  if (dE > 1e-12 * res.energy_before) {
    const double a = u.dot(P), q = 0.5 * P.dot(W * P);
    const double lambda = (a < 0.0 && q > 0.0) ? std::min(1.0, -a / q) * (1.0 - 1e-12) : 0.0;
    P *= lambda;
    ++res.corrections.energy_clamps;
    dE = energy_change(P);
  }
  res.P = P;
  res.energy_after = res.energy_before + dE;
  return res;
}

PairImpactResult apply_pair_impact(PairSide a, PairSide b, const Vec3& n, double e, double mu) {
  const auto point_velocity = [](const PairSide& s) -> Vec3 { return *s.velocity + s.omega->cross(s.r); };
  const Vec3 u = point_velocity(a) - point_velocity(b);
  if (!(u.dot(n) < 0.0)) return {};
  const Mat3 F = pair_detail::contact_frame(n);
  const Mat3 W = F.transpose() * (pair_detail::side_compliance(a) + pair_detail::side_compliance(b)) * F;
  PairImpactResult res = point_impact(W, F.transpose() * u, e, mu);
  res.P = F * res.P;
  // (As the floor's Body::apply; a fixed body's zeros leave it as it was.)
  *a.velocity += res.P * a.inv_mass;
  *a.omega += a.inv_inertia * a.r.cross(res.P);
  *b.velocity -= res.P * b.inv_mass;
  *b.omega -= b.inv_inertia * b.r.cross(res.P);
  return res;
}

}  // namespace dicesim
