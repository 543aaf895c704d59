// The restitution phase's friction on an edge (two points), exactly, by its active sets
// (solve_friction_edge).
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/friction_impact_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dicesim {

namespace friction_detail {

namespace {

// x on the circle |x| = radius minimising x.A x / 2 + g.x, A symmetric positive semidefinite 2x2
// (possibly singular: min_on_disc assumes definite): x = -(A + lambda 1)^-1 g, lambda >= 0 found
// in its bracket [|g| / radius - l_max, |g| / radius - l_min] by Newton on 1/|x| - 1/radius,
// safeguarded by bisection. False if g = 0 (then any x would do: not this case).
bool min_on_circle(const Eigen::Matrix2d& A, const Eigen::Vector2d& g, double radius, Eigen::Vector2d& x) {
  const double gn = g.norm();
  if (!(gn > 0.0) || !(radius > 0.0)) return false;
  const double a = A(0, 0), b = A(0, 1), c = A(1, 1);
  const double mean = 0.5 * (a + c), diff = 0.5 * (a - c);
  const double root = std::hypot(diff, b);
  const double l1 = std::max(0.0, mean - root), l2 = std::max(0.0, mean + root);
  Eigen::Vector2d q1(1.0, 0.0);
  if (root > 0.0) q1 = (diff >= 0.0 ? Eigen::Vector2d(b, -(diff + root)) : Eigen::Vector2d(root - diff, -b)).normalized();
  const Eigen::Vector2d q2(-q1.y(), q1.x());
  const double c1 = q1.dot(g), c2 = q2.dot(g);
  double lo = std::max(0.0, gn / radius - l2), hi = std::max(lo, gn / radius - l1);
  double lambda = lo > 0.0 || l1 > 0.0 ? lo : 0.5 * (lo + hi);
  for (int it = 0; it < 100 && hi > lo; ++it) {
    const double d1 = l1 + lambda, d2 = l2 + lambda;
    if (!(d1 > 0.0)) {
      lambda = 0.5 * (lo + hi);
      continue;
    }
    const double y1 = c1 / d1, y2 = c2 / d2, norm2 = y1 * y1 + y2 * y2, norm = std::sqrt(norm2);
    if (std::abs(norm - radius) <= 1e-14 * radius) break;
    if (norm > radius) lo = lambda; else hi = lambda;  // |x(lambda)| decreases with lambda
    const double phi = 1.0 / norm - 1.0 / radius;
    const double dphi = (y1 * y1 / d1 + y2 * y2 / d2) / (norm2 * norm);
    double next = lambda - phi / dphi;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (next == lambda) break;
    lambda = next;
  }
  if (!(l1 + lambda > 0.0)) return false;
  x = -(c1 / (l1 + lambda)) * q1 - (c2 / (l2 + lambda)) * q2;
  return x.allFinite();
}

}  // namespace

// The exact solve of the restitution phase's friction on an edge (two points), by its active
// sets. Gauss-Seidel converges slowly there (two corners' tangential compliance A, 4x4, has the
// null vector z = (e, -e), e the edge's horizontal direction: opposite friction along the edge
// moves nothing), and semismooth Newton can stall at the kink where one point changes from
// sticking to sliding. The problem, min over |P_i| <= R_i of P.A P / 2 + g.P (g the slips before),
// is convex; its KKT conditions are Coulomb's law with maximal dissipation at both points, and the
// final velocities are unique. Cases, each closed-form or a small linear system, the first whose
// result verifies is taken:
//  1. both stick: A P = -g (consistent: a rigid body's slips at two floor points have equal
//     components along e), P = P_0 + s z, s from the intersection of two intervals (each disc);
//  2. one sticks, the other slides: the sticking point's P eliminated (its 2x2 block is definite),
//     the sliding point's P on its circle minimises the reduced problem (Schur complement, PSD,
//     singular along e: min_on_circle);
//  3. both slide: P_i = -R_i u_i / |u_i|; the final body velocity nu minimises the strictly convex
//     dual |nu - nu_0|_M^2 / 2 + sum R_i |u_i(nu)|, smooth where both slip: damped Newton (6x6).
// Returns false, leaving the body as it was, if no case verifies (the caller's general solve
// takes it, counted if that fails too).
bool solve_friction_edge(const Body& b, const Points& pts, const double radius[], Eigen::Vector2d pt[], double lever,
                         double speed, int& steps) {
  steps = 0;
  const Vec3 &r1 = pts.r[0], &r2 = pts.r[1];
  const Mat3 X1 = skew(r1), X2 = skew(r2);
  const Eigen::Matrix2d A11 = pts.wtt[0], A22 = pts.wtt[1];
  const Eigen::Matrix2d A12 = (b.inv_mass * Mat3::Identity() - X1 * b.inv_inertia * X2).topLeftCorner<2, 2>();
  const Eigen::Matrix2d A21 = A12.transpose();
  const Vec3 u1 = b.point_velocity(r1), u2 = b.point_velocity(r2);
  const Eigen::Vector2d g1(u1.x(), u1.y()), g2(u2.x(), u2.y());
  const double R1 = radius[0], R2 = radius[1];
  const double slip_tol = kVerifySlip * speed;
  // Coulomb with maximal dissipation at both points for the impulses (P1, P2): the KKT conditions.
  const auto verifies = [&](const Eigen::Vector2d& P1, const Eigen::Vector2d& P2) {
    const Eigen::Vector2d P[2] = {P1, P2};
    const Eigen::Vector2d u[2] = {g1 + A11 * P1 + A12 * P2, g2 + A21 * P1 + A22 * P2};
    const double R[2] = {R1, R2};
    for (int i = 0; i < 2; ++i)
      if (!coulomb_verifies(P[i], u[i], R[i], slip_tol)) return false;
    return true;
  };
  const auto accept = [&](const Eigen::Vector2d& P1, const Eigen::Vector2d& P2) {
    pt[0] = P1;
    pt[1] = P2;
    b.apply(r1, Vec3(P1.x(), P1.y(), 0.0));
    b.apply(r2, Vec3(P2.x(), P2.y(), 0.0));
    return true;
  };
  Eigen::Vector2d e((r1 - r2).x(), (r1 - r2).y());
  if (!(e.norm() > 1e-6 * lever)) return false;
  e.normalize();
  // 1. Both stick.
  {
    ++steps;
    Eigen::Matrix4d A;
    A << A11, A12, A21, A22;
    Eigen::Vector4d z(e.x(), e.y(), -e.x(), -e.y());
    z /= std::sqrt(2.0);
    // A + m^-1 z z' is definite; with g orthogonal to z its solution is A's minimum-norm one.
    const Eigen::Vector4d P = (A + b.inv_mass * z * z.transpose()).ldlt().solve(-Eigen::Vector4d(g1.x(), g1.y(), g2.x(), g2.y()));
    const Eigen::Vector2d P1 = P.head<2>(), P2 = P.tail<2>();
    // |P1 + s e| <= R1 and |P2 - s e| <= R2.
    const double b1 = P1.dot(e), d1 = b1 * b1 - (P1.squaredNorm() - R1 * R1);
    const double b2 = P2.dot(e), d2 = b2 * b2 - (P2.squaredNorm() - R2 * R2);
    if (d1 >= 0.0 && d2 >= 0.0) {
      const double lo = std::max(-b1 - std::sqrt(d1), b2 - std::sqrt(d2));
      const double hi = std::min(-b1 + std::sqrt(d1), b2 + std::sqrt(d2));
      if (lo <= hi) {
        const double sm = 0.5 * (lo + hi);
        const Eigen::Vector2d Q1 = P1 + sm * e, Q2 = P2 - sm * e;
        if (verifies(Q1, Q2)) return accept(Q1, Q2);
      }
    }
  }
  // 2. Point i sticks, point j slides.
  for (int j = 0; j < 2; ++j) {
    ++steps;
    const Eigen::Matrix2d& Aii = j == 1 ? A11 : A22;
    const Eigen::Matrix2d& Ajj = j == 1 ? A22 : A11;
    const Eigen::Matrix2d& Aij = j == 1 ? A12 : A21;
    const Eigen::Matrix2d& Aji = j == 1 ? A21 : A12;
    const Eigen::Vector2d& gi = j == 1 ? g1 : g2;
    const Eigen::Vector2d& gj = j == 1 ? g2 : g1;
    const Eigen::Matrix2d Aii_inv = Aii.inverse();
    // P_i = -Aii^-1 (g_i + Aij P_j): u_i = 0.
    Eigen::Matrix2d S = Ajj - Aji * Aii_inv * Aij;
    S = 0.5 * (S + S.transpose());
    const Eigen::Vector2d cj = gj - Aji * Aii_inv * gi;
    Eigen::Vector2d Pj;
    if (!min_on_circle(S, cj, radius[j], Pj)) continue;
    const Eigen::Vector2d Pi = -(Aii_inv * (gi + Aij * Pj));
    const Eigen::Vector2d P1 = j == 1 ? Pi : Pj, P2 = j == 1 ? Pj : Pi;
    if (verifies(P1, P2)) return accept(P1, P2);
  }
  // 3. Both slide: Newton on the dual, in nu = (v, w).
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Mat26 = Eigen::Matrix<double, 2, 6>;
  Mat26 J[2];
  for (int i = 0; i < 2; ++i) {
    const Mat3 X = skew(pts.r[i]);
    J[i].setZero();
    J[i].leftCols<3>() = Eigen::Matrix<double, 2, 3>::Identity();
    J[i].rightCols<3>() = -X.topRows<2>();  // w x r = -[r]x w
  }
  const Mat3 Iw = b.inv_inertia.inverse();
  Vec6 nu0;
  nu0 << b.s->velocity, b.s->omega;
  const double R[2] = {R1, R2};
  const auto f = [&](const Vec6& nu) {
    const Vec6 d = nu - nu0;
    double val = 0.5 * (b.mass * d.head<3>().squaredNorm() + d.tail<3>().dot(Iw * d.tail<3>()));
    for (int i = 0; i < 2; ++i) val += R[i] * (J[i] * nu).norm();
    return val;
  };
  Vec6 nu = nu0;
  double fv = f(nu);
  bool done = false;
  for (int it = 0; it < 50; ++it) {
    ++steps;
    Vec6 grad;
    Mat6 H = Mat6::Zero();
    grad.head<3>() = b.mass * (nu - nu0).head<3>();
    grad.tail<3>() = Iw * (nu - nu0).tail<3>();
    H.topLeftCorner<3, 3>() = b.mass * Mat3::Identity();
    H.bottomRightCorner<3, 3>() = Iw;
    bool smooth = true;
    for (int i = 0; i < 2; ++i) {
      const Eigen::Vector2d u = J[i] * nu;
      const double un = u.norm();
      if (!(un > 0.0)) {
        smooth = false;
        break;
      }
      const Eigen::Vector2d h = u / un;
      grad += R[i] * J[i].transpose() * h;
      H += (R[i] / un) * J[i].transpose() * (Eigen::Matrix2d::Identity() - h * h.transpose()) * J[i];
    }
    if (!smooth) break;
    const Vec6 step = -H.ldlt().solve(grad);
    if (!step.allFinite()) break;
    double alpha = 1.0;
    bool accepted = false;
    for (int ls = 0; ls < 40; ++ls) {
      const Vec6 trial = nu + alpha * step;
      const double ft = f(trial);
      if (ft <= fv + 1e-4 * alpha * grad.dot(step)) {
        nu = trial;
        fv = ft;
        accepted = true;
        break;
      }
      alpha *= 0.5;
    }
    const double change = alpha * (step.head<3>().norm() + lever * step.tail<3>().norm());
    if (!accepted || change <= 1e-13 * speed) {
      done = true;
      break;
    }
  }
  if (done) {
    Eigen::Vector2d P[2];
    bool ok = true;
    for (int i = 0; i < 2; ++i) {
      const Eigen::Vector2d u = J[i] * nu;
      const double un = u.norm();
      if (!(un > 0.0)) {
        ok = false;
        break;
      }
      P[i] = -R[i] * u / un;
    }
    if (ok && verifies(P[0], P[1])) return accept(P[0], P[1]);
  }
  return false;
}

}  // namespace friction_detail

}  // namespace dicesim
