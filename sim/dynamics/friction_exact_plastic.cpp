// The direct (not iterative) plastic multi-point solves: every point sticking (solve_sticking),
// every point sliding (solve_sliding), and two points by their active sets (solve_plastic_pair).
// Each is taken only where Coulomb's law verifies; else Gauss-Seidel takes the solve.
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/friction_impact_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/QR>

namespace dicesim {

namespace friction_detail {

// The plastic multi-point solve when every point sticks, directly (no sweeps). Sticking means
// every point's final velocity is 0: the body's final motion nu_f is the M-orthogonal projection
// of its motion nu_0 on the motions that keep every point still (null(J), J the points' velocity
// map u = J nu): for an edge (two points) the rotation about the edge line, for three or more
// points not in a line, rest. nu_f minimises the kinetic energy over every impulse the points can
// give (any impulse, no cone: nu_0 + M^-1 J^T P = nu_f with J nu_f = 0 is the KKT system of that
// minimisation), so where Coulomb admits it (the impulses in their cones) it is the solution the
// energy-descending Gauss-Seidel sweeps converge to, which Gauss-Seidel reaches only to its
// tolerance. The impulses giving it, J^T P = M (nu_f - nu_0), are not unique: on an edge, equal
// and opposite friction along the edge moves nothing (J^T has a null vector); on three points,
// three internal friction directions; on four, also one normal split. Taken: the minimum-norm
// impulse P = J (J^T J)^+ M (nu_f - nu_0) (for a face's normals the linear pressure
// distribution), and on a level edge, of the impulses P + s z (z the edge's null vector) that fit
// both cones, the one nearest it (minimum norm among the admissible; every choice gives the same
// motion, so the choice only decides which states are accepted here and the next step's warm
// start). Accepted only if every normal impulse is >= 0 and every friction in its cone; else false
// with the body untouched, and the caller's Gauss-Seidel solves it (some point slides or lifts).
bool solve_sticking(const Body& b, const Mat3& Iw, const Points& pts, double lever, double pn[],
                    Eigen::Vector2d pt[]) {
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  const int n = pts.n;
  if (n < 2) return false;
  const Vec3 v0 = b.s->velocity, w0 = b.s->omega;
  Vec3 vf = Vec3::Zero(), wf = Vec3::Zero();
  Vec3 edge = Vec3::Zero();  // unit edge direction (n = 2)
  Vec6 xi = Vec6::Zero();    // null(J) on an edge: w = e, v = r_0 x e (r_0 and r_1 stay still)
  if (n == 2) {
    const Vec3 d = pts.r[0] - pts.r[1];
    const double len = d.norm();
    if (!(len > 1e-6 * lever)) return false;
    edge = d / len;
    const Vec3 xv = pts.r[0].cross(edge);
    const double den = b.mass * xv.squaredNorm() + edge.dot(Iw * edge);
    const double lam = (b.mass * xv.dot(v0) + edge.dot(Iw * w0)) / den;
    vf = lam * xv;
    wf = lam * edge;
    xi << xv, edge;
    xi.normalize();
  } else {
    // Three or more points: rest, if they are not in one line (else Gauss-Seidel).
    int a = 0, c = 1;
    double far = 0.0;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        if (const double dd = (pts.r[i] - pts.r[j]).squaredNorm(); dd > far) far = dd, a = i, c = j;
    const Vec3 line = (pts.r[c] - pts.r[a]).normalized();
    double off = 0.0;
    for (int i = 0; i < n; ++i) off = std::max(off, (pts.r[i] - pts.r[a]).cross(line).norm());
    if (!(off > 1e-6 * lever)) return false;
  }
  // J^T J = sum_i J_i^T J_i, J_i = [1, -[r_i]x]; on an edge plus a multiple of xi xi^T, which
  // makes it definite without changing its solution for right-hand sides orthogonal to xi (f is:
  // f is in range(J^T) = null(J)^perp).
  Mat6 A = Mat6::Zero();
  for (int i = 0; i < n; ++i) {
    const Mat3 X = skew(pts.r[i]);
    A.topLeftCorner<3, 3>() += Mat3::Identity();
    A.topRightCorner<3, 3>() -= X;
    A.bottomRightCorner<3, 3>() -= X * X;
  }
  A.bottomLeftCorner<3, 3>() = A.topRightCorner<3, 3>().transpose();
  if (n == 2) A += (A.trace() / 6.0) * xi * xi.transpose();
  Vec6 f;
  f << b.mass * (vf - v0), Iw * (wf - w0);
  const Eigen::LDLT<Mat6> ldlt(A);
  if (ldlt.info() != Eigen::Success) return false;
  const Vec6 y = ldlt.solve(f);
  if (!y.allFinite()) return false;
  Vec3 P[kMaxContacts];
  for (int i = 0; i < n; ++i) P[i] = y.head<3>() + y.tail<3>().cross(pts.r[i]);
  const auto fits = [&](const Vec3& p, int i) {
    return p.z() >= 0.0 && std::hypot(p.x(), p.y()) <= pts.mu[i] * p.z();
  };
  bool ok = true;
  for (int i = 0; i < n && ok; ++i) ok = fits(P[i], i);
  if (!ok && n == 2 && std::abs(edge.z()) <= 1e-12) {
    // P_0 + s e, P_1 - s e (the normals do not change): each cone an interval of s.
    const Eigen::Vector2d e(edge.x(), edge.y());
    const Eigen::Vector2d t0(P[0].x(), P[0].y()), t1(P[1].x(), P[1].y());
    const double R0 = pts.mu[0] * P[0].z(), R1 = pts.mu[1] * P[1].z();
    const double b0 = t0.dot(e), d0 = b0 * b0 - (t0.squaredNorm() - R0 * R0);
    const double b1 = t1.dot(e), d1 = b1 * b1 - (t1.squaredNorm() - R1 * R1);
    if (P[0].z() >= 0.0 && P[1].z() >= 0.0 && d0 >= 0.0 && d1 >= 0.0) {
      const double lo = std::max(-b0 - std::sqrt(d0), b1 - std::sqrt(d1));
      const double hi = std::min(-b0 + std::sqrt(d0), b1 + std::sqrt(d1));
      if (lo <= hi) {
        const double s = std::clamp(0.0, lo, hi);
        const Vec3 se = s * edge;
        const Vec3 Q0 = P[0] + se, Q1 = P[1] - se;
        if (fits(Q0, 0) && fits(Q1, 1)) {  // (rounding at the interval's ends)
          P[0] = Q0;
          P[1] = Q1;
          ok = true;
        }
      }
    }
  }
  if (!ok) return false;
  b.s->velocity = vf;
  b.s->omega = wf;
  for (int i = 0; i < n; ++i) {
    pn[i] = P[i].z();
    pt[i] = Eigen::Vector2d(P[i].x(), P[i].y());
  }
  return true;
}

namespace {

// Solves the k x k system A x = b (k <= 3) by Cramer's rule; false if A is singular to rounding.
bool solve_small(int k, const double A[3][3], const double b[3], double x[3]) {
  if (k == 1) {
    if (!(std::abs(A[0][0]) > 0.0)) return false;
    x[0] = b[0] / A[0][0];
    return true;
  }
  if (k == 2) {
    const double det = A[0][0] * A[1][1] - A[0][1] * A[1][0];
    const double scale = std::abs(A[0][0] * A[1][1]) + std::abs(A[0][1] * A[1][0]);
    if (!(std::abs(det) > 1e-12 * scale)) return false;
    x[0] = (b[0] * A[1][1] - A[0][1] * b[1]) / det;
    x[1] = (A[0][0] * b[1] - b[0] * A[1][0]) / det;
    return true;
  }
  const double c00 = A[1][1] * A[2][2] - A[1][2] * A[2][1];
  const double c01 = A[1][2] * A[2][0] - A[1][0] * A[2][2];
  const double c02 = A[1][0] * A[2][1] - A[1][1] * A[2][0];
  const double det = A[0][0] * c00 + A[0][1] * c01 + A[0][2] * c02;
  double scale = 0.0;
  for (int i = 0; i < 3; ++i) scale = std::max({scale, std::abs(A[i][0]), std::abs(A[i][1]), std::abs(A[i][2])});
  if (!(std::abs(det) > 1e-12 * scale * scale * scale)) return false;
  const double inv = 1.0 / det;
  const double c10 = A[0][2] * A[2][1] - A[0][1] * A[2][2];
  const double c11 = A[0][0] * A[2][2] - A[0][2] * A[2][0];
  const double c12 = A[0][1] * A[2][0] - A[0][0] * A[2][1];
  const double c20 = A[0][1] * A[1][2] - A[0][2] * A[1][1];
  const double c21 = A[0][2] * A[1][0] - A[0][0] * A[1][2];
  const double c22 = A[0][0] * A[1][1] - A[0][1] * A[1][0];
  x[0] = (c00 * b[0] + c10 * b[1] + c20 * b[2]) * inv;
  x[1] = (c01 * b[0] + c11 * b[1] + c21 * b[2]) * inv;
  x[2] = (c02 * b[0] + c12 * b[1] + c22 * b[2]) * inv;
  return true;
}

}  // namespace

// The plastic multi-point solve when every point slides, directly: the common case of sustained
// contact (a die sliding on an edge or on three corners of a face; 2 000 Die 1 tosses: 70 % of
// the multi-point solves, 78 % of their sweeps). Every point i then takes
// P_i = lambda_i (e_z - mu_i d_i), d_i the unit direction of its final slip (Coulomb with maximal
// dissipation: friction on the cone's edge, opposite the slip) and lambda_i > 0 the normal
// impulse that stops its normal velocity. For given directions the normal velocities are linear
// in lambda: one n x n system (n = 2 or 3: an edge's two normal constraints are independent, a
// triangle's three too; four points of a face are left to Gauss-Seidel, their split of the load
// is not unique). The directions come from a fixed point, d <- the final slip's direction, from
// the slip before the solve: the friction of one step changes a sliding point's velocity by a
// small fraction of its slip, so each iteration shrinks the direction error by about that
// fraction (accelerated by Anderson mixing of the last two residuals). Accepted when the
// directions have converged to 1e-13 of the speeds (the impulses are then Coulomb's to rounding),
// every lambda_i > 0 and every final slip is non-zero; else false with the body
// untouched (a point sticks, lifts, or the fixed point is slow: Gauss-Seidel takes it).
// `start` (optional): the slips to take the first directions from instead (a point's own slip
// before the solve where its start is below the slip floor).
bool solve_sliding(const Body& b, const Points& pts, double speed, double lever, double pn[], Eigen::Vector2d pt[],
                   const Eigen::Vector2d* start) {
  constexpr int kMaxN = 3;
  constexpr int kMaxIterations = 16;
  const int n = pts.n;
  if (n < 2 || n > kMaxN) return false;
  const Vec3 v0 = b.s->velocity, w0 = b.s->omega;
  Vec3 u0[kMaxN];
  Eigen::Vector2d d[kMaxN];
  const double slip_floor = 1e-6 * speed;
  for (int i = 0; i < n; ++i) {
    u0[i] = v0 + w0.cross(pts.r[i]);
    const Eigen::Vector2d t(u0[i].x(), u0[i].y());
    const double tn = t.norm();
    // (A point not approaching may lift: it starts out of the set and joins if it would sink.)
    if (pts.mu[i] == 0.0) return false;
    d[i] = tn > 0.0 ? Eigen::Vector2d(t / tn) : Eigen::Vector2d(1.0, 0.0);
    if (start && start[i].norm() > slip_floor) d[i] = start[i].normalized();
  }
  // Active set: the points that push (lambda > 0); the others must end not approaching.
  bool active[kMaxN];
  for (int i = 0; i < n; ++i) active[i] = true;
  const double tol = 1e-13 * speed;
  Vec3 dv[kMaxN], dw[kMaxN];  // body response to point i's unit normal impulse with its friction
  double lambda[kMaxN] = {};
  for (int changes = 0; changes < n; ++changes) {
    int idx[kMaxN], k = 0;
    for (int i = 0; i < n; ++i)
      if (active[i]) idx[k++] = i;
    if (k == 0) return false;
    bool converged = false;
    // (Zeroed: the first iteration reads prev_next times a gamma of 0. Finite stack garbage gave
    // what zero gives; a NaN or an infinity there took the non-finite branch, d[j] = next[j] not
    // renormalised, so the solve could depend on what ran before in the thread. Valgrind found it.)
    Eigen::Vector2d prev_r[kMaxN], prev_next[kMaxN];
    for (int i = 0; i < kMaxN; ++i) prev_r[i] = prev_next[i] = Eigen::Vector2d::Zero();
    for (int it = 0; it < kMaxIterations && !converged; ++it) {
      for (int a = 0; a < k; ++a) {
        const int i = idx[a];
        const double fx = -pts.mu[i] * d[i].x(), fy = -pts.mu[i] * d[i].y();
        dv[i] = Vec3(fx, fy, 1.0) * b.inv_mass;
        dw[i] = fx * pts.ax[i] + fy * pts.ay[i] + pts.az[i];
      }
      // Point j's velocity per unit normal impulse at i (with its friction).
      double A[3][3], rhs[3], x[3];
      Vec3 Rji[kMaxN][kMaxN];
      for (int a = 0; a < k; ++a) {
        rhs[a] = -u0[idx[a]].z();
        for (int c = 0; c < k; ++c) {
          Rji[a][c] = dv[idx[c]] + dw[idx[c]].cross(pts.r[idx[a]]);
          A[a][c] = Rji[a][c].z();
        }
      }
      if (!solve_small(k, A, rhs, x)) return false;
      for (int i = 0; i < n; ++i) lambda[i] = 0.0;
      for (int a = 0; a < k; ++a) lambda[idx[a]] = x[a];
      // A point that would pull leaves the set (at most one per pass, the most negative).
      int worst = -1;
      for (int a = 0; a < k; ++a)
        if (!(x[a] > 0.0) && (worst < 0 || x[a] < lambda[worst])) worst = idx[a];
      if (worst >= 0) {
        if (it > 0 || changes > 0) return false;  // no cycling between sets: the sweeps decide
        active[worst] = false;
        break;
      }
      // The final slips and the change of the body's motion a direction update would make.
      Vec3 move_v = Vec3::Zero(), move_w = Vec3::Zero();
      Eigen::Vector2d next[kMaxN];
      for (int a = 0; a < k; ++a) {
        const int j = idx[a];
        Vec3 u = u0[j];
        for (int c = 0; c < k; ++c) u += lambda[idx[c]] * Rji[a][c];
        const double tn2 = u.x() * u.x() + u.y() * u.y();
        if (!(tn2 > slip_floor * slip_floor)) return false;  // sticks: not this case
        const double inv_tn = 1.0 / std::sqrt(tn2);
        next[j] = Eigen::Vector2d(u.x() * inv_tn, u.y() * inv_tn);
        const Eigen::Vector2d dd = -pts.mu[j] * lambda[j] * (next[j] - d[j]);
        move_v += Vec3(dd.x(), dd.y(), 0.0) * b.inv_mass;
        move_w += dd.x() * pts.ax[j] + dd.y() * pts.ay[j];
      }
      // |move_v| + lever |move_w| <= tol, tested in squares (no square roots on the iteration's
      // chain): 2 (|move_v|^2 + lever^2 |move_w|^2) <= tol^2 implies it (at most sqrt(2) stricter).
      if (2.0 * (move_v.squaredNorm() + lever * lever * move_w.squaredNorm()) <= tol * tol) {
        converged = true;
      } else {
        // Anderson acceleration (depth 1) of the fixed point: the map is nearly linear, so the
        // last two residuals r = F(d) - d extrapolate toward its fixed point (the acceptance test
        // above is unchanged: only the iterates move faster).
        double rr = 0.0, dd2 = 0.0;
        for (int a = 0; a < k; ++a) {
          const int j = idx[a];
          const Eigen::Vector2d r = next[j] - d[j];
          if (it > 0) {
            const Eigen::Vector2d dr = r - prev_r[j];
            rr += r.dot(dr);
            dd2 += dr.squaredNorm();
          }
          prev_r[j] = r;
        }
        const double gamma = it > 0 && dd2 > 0.0 ? rr / dd2 : 0.0;
        for (int a = 0; a < k; ++a) {
          const int j = idx[a];
          const Eigen::Vector2d x = next[j] - gamma * (next[j] - prev_next[j]);
          const double xn2 = x.squaredNorm();
          prev_next[j] = next[j];
          d[j] = xn2 > 0.0 && std::isfinite(xn2) ? Eigen::Vector2d(x * (1.0 / std::sqrt(xn2))) : next[j];
        }
      }
    }
    if (!converged) {
      bool dropped = false;
      for (int i = 0; i < n; ++i) dropped = dropped || (!active[i] && changes == 0);
      if (!dropped) return false;
      continue;  // a point left the set: solve the rest
    }
    // The points out of the set must not approach.
    Vec3 v = v0, w = w0;
    for (int a = 0; a < k; ++a) {
      v += lambda[idx[a]] * dv[idx[a]];
      w += lambda[idx[a]] * dw[idx[a]];
    }
    for (int i = 0; i < n; ++i)
      if (!active[i] && (v + w.cross(pts.r[i])).z() < 0.0) return false;
    b.s->velocity = v;
    b.s->omega = w;
    for (int i = 0; i < n; ++i) {
      pn[i] = lambda[i];
      pt[i] = active[i] ? Eigen::Vector2d(-pts.mu[i] * lambda[i] * d[i]) : Eigen::Vector2d::Zero();
    }
    return true;
  }
  return false;
}

namespace {

// Coulomb's law with maximal dissipation at every point of a plastic solve, from the impulses
// (pn, pt) and the body's velocities after them: P_n >= 0, u_n >= 0 and u_n = 0 where P_n > 0
// (to 1e-10 of the speeds, the callers' approach test), |P_t| <= mu P_n, and at a point slipping
// faster than 1e-9 of the speeds the friction opposite the slip (the tolerances of the
// restitution phase's edge solve, kVerifyCone, kVerifySlip, kVerifyAlign).
bool plastic_verifies(const Body& b, const Points& pts, const double pn[], const Eigen::Vector2d pt[], double speed) {
  const double normal_tol = 1e-10 * speed, slip_tol = 1e-9 * speed;
  for (int i = 0; i < pts.n; ++i) {
    const Vec3 u = b.point_velocity(pts.r[i]);
    if (!std::isfinite(pn[i]) || !pt[i].allFinite() || pn[i] < 0.0 || u.z() < -normal_tol) return false;
    if (pn[i] > 0.0 && u.z() > normal_tol) return false;
    const double limit = pts.mu[i] * pn[i];
    if (pt[i].norm() > limit * (1.0 + 1e-9)) return false;
    const Eigen::Vector2d slip(u.x(), u.y());
    const double sn = slip.norm();
    // (A point without normal impulse has no friction, |P_t| <= 0 above, and may slip freely: a
    // lifting point, as coulomb_verifies accepts R = 0.)
    if (sn > slip_tol && limit > 0.0 && !((pt[i] / limit + slip / sn).norm() <= 1e-6)) return false;
  }
  return true;
}

// Two points, point i sticking and point j sliding, exactly: with u_i = 0 imposed, P_i =
// -W_ii^-1 (u_i + W_ij P_j), and point j is one point with the Schur complement
// S = W_jj - W_ji W_ii^-1 W_ij as its compliance and c = u_j - W_ji W_ii^-1 u_i as its velocity:
// the one-corner sliding problem (one_corner_sliding_newton; S is singular along the line
// through the points, where the sticking point takes any friction back, which that solve does not
// need inverted). Applied to the body (true) only if Coulomb's law verifies at both points.
bool solve_stick_slide(const Body& b, const Points& pts, int i, int j, double speed, double pn[], Eigen::Vector2d pt[]) {
  const Mat3 Xi = skew(pts.r[i]), Xj = skew(pts.r[j]);
  const Mat3 Wii = b.inv_mass * Mat3::Identity() - Xi * b.inv_inertia * Xi;
  const Mat3 Wij = b.inv_mass * Mat3::Identity() - Xi * b.inv_inertia * Xj;
  const Mat3 Wjj = b.inv_mass * Mat3::Identity() - Xj * b.inv_inertia * Xj;
  const Mat3 Wji = Wij.transpose();
  const Mat3 Wii_inv = Wii.inverse();
  const Vec3 ui = b.point_velocity(pts.r[i]), uj = b.point_velocity(pts.r[j]);
  Mat3 S = Wjj - Wji * Wii_inv * Wij;
  S = 0.5 * (S + S.transpose());
  const Vec3 c = uj - Wji * (Wii_inv * ui);
  if (!(c.z() < 0.0) || !(pts.mu[j] > 0.0)) return false;  // j pushes and slides, or not this case
  Eigen::Vector2d d(-c.x(), -c.y());
  if (!(d.norm() > 1e-9 * speed)) return false;
  d.normalize();
  Vec3 Pj;
  bool by_reference = false;
  if (!one_corner_sliding_newton(S, c, pts.mu[j], d, Pj)) {
    if (!one_corner_sliding_reference(S, c, pts.mu[j], d, Pj)) return false;
    by_reference = true;
  }
  const Vec3 Pi = -(Wii_inv * (ui + Wij * Pj));
  const Vec3 v0 = b.s->velocity, w0 = b.s->omega;
  b.apply(pts.r[i], Pi);
  b.apply(pts.r[j], Pj);
  double qn[2];
  Eigen::Vector2d qt[2];
  qn[i] = Pi.z();
  qt[i] = Eigen::Vector2d(Pi.x(), Pi.y());
  qn[j] = Pj.z();
  qt[j] = Eigen::Vector2d(Pj.x(), Pj.y());
  if (!plastic_verifies(b, pts, qn, qt, speed)) {
    b.s->velocity = v0;
    b.s->omega = w0;
    return false;
  }
  for (int k = 0; k < 2; ++k) {
    pn[k] = qn[k];
    pt[k] = qt[k];
  }
  if (by_reference) b.count_exact_fallback();  // (only a solve that stands)
  return true;
}

// Two points, point i lifting and point j alone: the one-point plastic solve at j (its full
// compliance), kept (true) only if Coulomb's law verifies at both points, i not approaching.
bool solve_lift_one(const Body& b, const Points& pts, int i, double speed, double pn[], Eigen::Vector2d pt[]) {
  const int j = 1 - i;
  Points one;
  one.n = 1;
  one.r[0] = pts.r[j];
  one.e[0] = pts.e[j];
  one.mu[0] = pts.mu[j];
  one.W0 = compliance(b, pts.r[j]);
  one.W0_inverse = one.W0.inverse();
  one.inv_wnn[0] = 1.0 / one.W0(2, 2);
  const Vec3 v0 = b.s->velocity, w0 = b.s->omega;
  double qn[1];
  Eigen::Vector2d qt[1];
  if (solve_plastic_single(b, one, qn, qt)) {
    pn[i] = 0.0;
    pt[i].setZero();
    pn[j] = qn[0];
    pt[j] = qt[0];
    if (plastic_verifies(b, pts, pn, pt, speed)) return true;
  }
  b.s->velocity = v0;
  b.s->omega = w0;
  return false;
}

}  // namespace

// The plastic solve of two points by their active sets, each case exact and taken only where
// Coulomb's law verifies at both points (plastic_verifies): both stick (solve_sticking), one
// sticks and the other slides (solve_stick_slide, both ways), both slide or one lifts
// (solve_sliding). For the two-point solves Gauss-Seidel and its Newton finish leave
// unconverged: a coin on its side, both rims' lowest points touching 2 b apart (b the rims' half
// distance, 0.68 mm on the quarter, against its 12 mm radius). Their normal impulses' split
// tips the coin about a diameter, moving both points sideways ~a/b = 18 times more than it
// moves them vertically: the two normal rows are 0.975 correlated (Gauss-Seidel's error falls
// ~0.5 % a sweep: ~4 000 sweeps), and at one point sticking and the other sliding the
// Alart-Curnier residual's Newton step is no descent (a kink), so the finish stalls. Then one
// point lifting and the other alone (solve_lift_one: a coin on its side, one rim's point
// lifting while the other's slides, quarter `stepped` toss 79149, where solve_sliding's iterate
// changed its active set after its first pass). Last, both sliding again, with the first
// directions from `gs_slip` (the sweeps' final slips; optional): from the slips before the solve
// the normal split, 0.975-correlated rows, can come out with one point pulling, and solve_sliding
// then drops that point for good (dropped quarter `impulse` toss 18686: a coin on its side rolling
// at 30 rad/s, both points sliding at ~1 mm/s; from the slips before the solve the second point
// pulled, from the sweeps' it converges in 9 iterations). The body starts from the state before
// the solve (no impulse applied). False: the body untouched.
bool solve_plastic_pair(const Body& b, const Mat3& Iw, const Points& pts, double speed, double lever, double pn[],
                        Eigen::Vector2d pt[], const Eigen::Vector2d* gs_slip) {
  if (pts.n != 2) return false;
  const Vec3 v0 = b.s->velocity, w0 = b.s->omega;
  const auto verified = [&](bool solved) {
    if (solved && plastic_verifies(b, pts, pn, pt, speed)) return true;
    b.s->velocity = v0;
    b.s->omega = w0;
    return false;
  };
  if (verified(solve_sticking(b, Iw, pts, lever, pn, pt))) return true;
  if (solve_stick_slide(b, pts, 0, 1, speed, pn, pt) || solve_stick_slide(b, pts, 1, 0, speed, pn, pt)) return true;
  if (verified(solve_sliding(b, pts, speed, lever, pn, pt))) return true;
  if (solve_lift_one(b, pts, 0, speed, pn, pt) || solve_lift_one(b, pts, 1, speed, pn, pt)) return true;
  return gs_slip && verified(solve_sliding(b, pts, speed, lever, pn, pt, gs_slip));
}

}  // namespace friction_detail

}  // namespace dicesim
