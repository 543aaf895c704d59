// The restitution phase's friction, any number of points, by its dual (solve_friction_dual).
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/friction_impact_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/QR>

namespace dicesim {

namespace friction_detail {

// The restitution phase's friction, any number of points, by its dual: the final body velocity
// nu = (v, w) minimises F(nu) = |nu - nu_0|_M^2 / 2 + sum_i R_i |u_i(nu)| (u_i the tangential
// velocity at point i, linear in nu; M the mass matrix), strictly convex whatever the points, so
// unique even where the impulses are not (a face's coplanar points: their tangential compliance
// has rank 3 of 2K, and Gauss-Seidel can crawl along its near-null directions). Then
// P_i = -R_i u_i / |u_i| at a sliding point; a sticking point's P_i is the multiplier of u_i = 0.
// Solved by damped Newton on the smoothed F (|u| -> sqrt(|u|^2 + eps^2)), eps lowered by decades
// to far below the slip tolerance, each level warm-started; the impulses, applied to the start
// state, are then verified as the edge's are (Coulomb with maximal dissipation at every point).
// Returns false, the body as it was, if they do not verify. Only a fallback (solve_friction).
bool solve_friction_dual(const Body& b, const Points& pts, const double radius[], Eigen::Vector2d pt[],
                         double speed, double lever) {
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  const int n = pts.n;
  if (!(speed > 0.0)) return false;  // the smoothing's decades start from the speed
  const Mat3 Iw = b.inv_inertia.inverse();
  Mat6 M = Mat6::Zero();
  M.topLeftCorner<3, 3>() = b.mass * Mat3::Identity();
  M.bottomRightCorner<3, 3>() = Iw;
  // u_i = T_i nu: the x, y rows of v + w x r_i = v - [r_i]x w.
  Eigen::Matrix<double, 2, 6> T[kMaxContacts];
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix<double, 3, 6> J;
    J << Mat3::Identity(), -skew(pts.r[i]);
    T[i] = J.topRows<2>();
  }
  Vec6 nu0;
  nu0 << b.s->velocity, b.s->omega;
  const double slip_tol = kVerifySlip * speed;
  const auto F = [&](const Vec6& nu, double eps) {
    const Vec6 d = nu - nu0;
    double f = 0.5 * d.dot(M * d);
    for (int i = 0; i < n; ++i)
      if (radius[i] > 0.0) f += radius[i] * std::sqrt((T[i] * nu).squaredNorm() + eps * eps);
    return f;
  };
  Vec6 nu = nu0;
  for (double eps = speed; eps >= 1e-4 * slip_tol; eps *= 0.1) {
    for (int it = 0; it < 60; ++it) {
      Vec6 grad = M * (nu - nu0);
      Mat6 H = M;
      for (int i = 0; i < n; ++i) {
        if (!(radius[i] > 0.0)) continue;
        const Eigen::Vector2d u = T[i] * nu;
        const double sq = std::sqrt(u.squaredNorm() + eps * eps);
        grad += radius[i] / sq * T[i].transpose() * u;
        const Eigen::Matrix2d Hu = radius[i] / sq * (Eigen::Matrix2d::Identity() - u * u.transpose() / (sq * sq));
        H += T[i].transpose() * Hu * T[i];
      }
      const Vec6 step = -H.ldlt().solve(grad);
      if (!step.allFinite()) return false;
      // Backtracking: F is convex, a Newton direction descends.
      const double f0 = F(nu, eps);
      double t = 1.0;
      while (t > 1e-12 && !(F(nu + t * step, eps) <= f0)) t *= 0.5;
      nu += t * step;
      if ((t * step).head<3>().norm() + lever * (t * step).tail<3>().norm() <= 1e-3 * eps) break;
    }
  }
  // The smoothed impulses of sticking points are ill-determined (R u / eps with u at rounding), and
  // their split is not unique anyway: polish by the active sets the velocity shows. Sliding points
  // (slip above the tolerance): P_i = -R_i u_i / |u_i|; sticking ones: the impulses that stop
  // their slip given the sliding ones, T_s M^-1 T_s^T P_s = -T_s nu_b (the minimum-norm solution:
  // any solution gives the same motion), nu_b the motion with the sliding impulses only; then the
  // sliding directions again from the new motion, a few times.
  Eigen::Vector2d P[kMaxContacts];
  Mat6 Minv = Mat6::Zero();
  Minv.topLeftCorner<3, 3>() = b.inv_mass * Mat3::Identity();
  Minv.bottomRightCorner<3, 3>() = b.inv_inertia;
  bool stick[kMaxContacts];
  int ns = 0;
  int idx[kMaxContacts];
  for (int i = 0; i < n; ++i) {
    stick[i] = radius[i] > 0.0 && (T[i] * nu).norm() <= slip_tol;
    if (stick[i]) idx[ns++] = i;
  }
  constexpr int kRounds = 4;
  Eigen::Vector2d P_round[kRounds][kMaxContacts];
  for (int round = 0; round < kRounds; ++round) {
    Vec6 nu_b = nu0;
    for (int i = 0; i < n; ++i) {
      P[i].setZero();
      if (stick[i] || !(radius[i] > 0.0)) continue;
      const Eigen::Vector2d u = T[i] * nu;
      P[i] = -radius[i] * u / u.norm();
      nu_b += Minv * T[i].transpose() * P[i];
    }
    nu = nu_b;
    if (ns > 0) {
      // Dynamic sizes with fixed maxima: on the stack, no allocation in a toss.
      constexpr int kMax = 2 * kMaxContacts;
      Eigen::Matrix<double, Eigen::Dynamic, 6, 0, kMax, 6> Ts(2 * ns, 6);
      for (int k = 0; k < ns; ++k) Ts.middleRows<2>(2 * k) = T[idx[k]];
      const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMax, kMax> A = Ts * Minv * Ts.transpose();
      const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMax, 1> Ps =
          A.completeOrthogonalDecomposition().solve(-(Ts * nu_b));
      for (int k = 0; k < ns; ++k) P[idx[k]] = Ps.segment<2>(2 * k);
      nu = nu_b + Minv * Ts.transpose() * Ps;
    }
    for (int i = 0; i < n; ++i) P_round[round][i] = P[i];
  }
  // The last round's impulses, else the earliest round's that verify: where a sliding point
  // slips at ~1e-7 of the speeds, its direction moves ~10^3 times more than the motion from one
  // round to the next, and the rounds diverge from an answer the first one had (quarter-table
  // `stepped` toss 33234: a coin's tripod, two points sliding at ~1e-6 m/s, one sticking; round 0
  // verifies, round 3 slips at 0.56 m/s along its friction).
  const RigidState start = *b.s;
  for (int k = 0; k < kRounds; ++k) {
    const int round = k == 0 ? kRounds - 1 : k - 1;
    for (int i = 0; i < n; ++i) b.apply(pts.r[i], Vec3(P_round[round][i].x(), P_round[round][i].y(), 0.0));
    bool verifies = true;
    for (int i = 0; i < n && verifies; ++i) {
      const Vec3 u = b.point_velocity(pts.r[i]);
      verifies = coulomb_verifies(P_round[round][i], Eigen::Vector2d(u.x(), u.y()), radius[i], slip_tol);
    }
    if (verifies) {
      for (int i = 0; i < n; ++i) pt[i] = P_round[round][i];
      return true;
    }
    *b.s = start;
  }
  return false;
}

}  // namespace friction_detail

}  // namespace dicesim
