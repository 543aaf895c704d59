// Projected Gauss-Seidel: the plastic frictional solve (solve_plastic) and the restitution
// phase's friction (solve_friction), with their exact per-point updates (min_on_disc) and their
// hand-overs to the exact and Newton solves when they stall.
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/friction_impact_internal.hpp"

#include <algorithm>
#include <cmath>

namespace dicesim {

namespace friction_detail {

namespace {

// argmin over |x| <= radius of x.A x / 2 + g.x, A symmetric positive definite 2x2: the exact
// energy minimiser of one point's tangential impulse (a trust-region subproblem). Inside: -A^-1 g;
// else x = -(A + lambda 1)^-1 g on the circle, lambda > 0 by Newton on 1/|x(lambda)| - 1/radius
// (monotone and convergent from lambda = 0, More & Sorensen), in A's eigenbasis.
Eigen::Vector2d min_on_disc(const Eigen::Matrix2d& A, const Eigen::Vector2d& g, double radius) {
  if (!(radius > 0.0)) return Eigen::Vector2d::Zero();
  const double a = A(0, 0), b = A(0, 1), c = A(1, 1);
  const double det = a * c - b * b;
  const Eigen::Vector2d x0(-(c * g.x() - b * g.y()) / det, -(a * g.y() - b * g.x()) / det);
  if (x0.squaredNorm() <= radius * radius) return x0;
  // Eigen-decomposition of the 2x2 (closed form).
  const double mean = 0.5 * (a + c), diff = 0.5 * (a - c);
  // (sqrt(x^2 + y^2), not hypot: compliances, far from overflow.)
  const double root = std::sqrt(diff * diff + b * b);
  const double l1 = mean - root, l2 = mean + root;  // ascending
  // Eigenvector of l1 from the better-conditioned row of (A - l1 1) q1 = 0.
  Eigen::Vector2d q1(1.0, 0.0);
  if (root > 0.0) q1 = (diff >= 0.0 ? Eigen::Vector2d(b, -(diff + root)) : Eigen::Vector2d(root - diff, -b)).normalized();
  const Eigen::Vector2d q2(-q1.y(), q1.x());
  const double c1 = q1.dot(g), c2 = q2.dot(g);
  // From the largest of two lower bounds of the root, |g| / radius - l2 and |c1| / radius - l1 (if
  // positive): still left of it, |x(lambda)| >= radius there, since
  // |x|^2 = c1^2 / (l1 + lambda)^2 + c2^2 / (l2 + lambda)^2 >= |g|^2 / (l2 + lambda)^2 and
  // >= c1^2 / (l1 + lambda)^2. (From 0 it took 4.1 iterations per Die 1 solve, from these 2.x.)
  const double inv_radius = 1.0 / radius;
  double lambda = std::max({0.0, std::sqrt(c1 * c1 + c2 * c2) * inv_radius - l2, std::abs(c1) * inv_radius - l1});
  for (int it = 0; it < 60; ++it) {
    const double d1 = l1 + lambda, d2 = l2 + lambda;
    const double y1 = c1 / d1, y2 = c2 / d2;
    const double norm2 = y1 * y1 + y2 * y2;
    const double norm = std::sqrt(norm2);
    if (std::abs(norm - radius) <= 1e-14 * radius) break;
    // phi = 1/|x| - 1/radius, phi' = (sum c_i^2 / d_i^3) / |x|^3: Newton from the left of the root
    // increases lambda monotonically (phi is concave there).
    const double phi = 1.0 / norm - inv_radius;
    const double dphi = (y1 * y1 / d1 + y2 * y2 / d2) / (norm2 * norm);
    const double next = std::max(0.0, lambda - phi / dphi);
    if (next == lambda) break;
    // Quadratic convergence: a step this small leaves an error ~ its square, below rounding,
    // so the point it lands on is not evaluated again.
    const bool last = std::abs(next - lambda) <= 1e-8 * (l1 + next);
    lambda = next;
    if (last) break;
  }
  Eigen::Vector2d x = -(c1 / (l1 + lambda)) * q1 - (c2 / (l2 + lambda)) * q2;
  const double xn = x.norm();
  if (xn > radius) x *= radius / xn;  // rounding: stay in the cone
  return x;
}

}  // namespace

// Projected Gauss-Seidel on the perfectly plastic frictional contact problem: at every point
// P_n >= 0, u_n >= 0, P_n u_n = 0, |P_t| <= mu P_n, friction opposite the final slip. Each normal
// update is the exact minimiser of the kinetic energy over P_n >= 0; the tangential one sticks or
// puts the friction on the cone's edge opposite the current slip: its fixed points are exactly
// Coulomb's law with maximal dissipation. Sweeps alternate forward and backward
// (symmetric Gauss-Seidel: no point is always solved last). Starts from the impulses in pn, pt
// (already applied to the body: a warm start, or zero).
SweepResult solve_plastic(const Body& b, const Points& pts, double pn[], Eigen::Vector2d pt[], double radius,
                          double speed) {
  for (int it = 0; it < kMaxSweeps; ++it) {
    const SweepProbe probe(b);
    Vec3& v = b.s->velocity;
    Vec3& w = b.s->omega;
    for (int k = 0; k < pts.n; ++k) {
      const int i = it % 2 == 0 ? k : pts.n - 1 - k;
      Vec3 u = v + w.cross(pts.r[i]);
      const double new_n = std::max(0.0, pn[i] - u.z() * pts.inv_wnn[i]);
      const double dn = new_n - pn[i];
      if (dn != 0.0) {
        pn[i] = new_n;
        v.z() += dn * b.inv_mass;
        w += dn * pts.az[i];
        u += dn * pts.wz[i];
      }
      // Tangential: the sticking update, or on the cone's edge opposite the slip (whose fixed
      // points are the same Coulomb law as the exact disc minimiser's, at a fraction of the cost).
      const Eigen::Vector2d slip(u.x(), u.y());
      const double limit = pts.mu[i] * pn[i];
      Eigen::Vector2d t = pt[i] - pts.inv_wtt[i] * slip;
      if (it >= kCheapSweeps) {
        // Slow to converge (strong coupling of slip and normal): the exact minimiser of the
        // kinetic energy over the disc, a true block-coordinate descent.
        t = min_on_disc(pts.wtt[i], slip - pts.wtt[i] * pt[i], limit);
      } else if (const double tn = t.norm(); tn > limit) {
        const double sn = slip.norm();
        t = sn > 0.0 ? Eigen::Vector2d(-limit * slip / sn) : Eigen::Vector2d(t * (limit / tn));
      }
      const Eigen::Vector2d dt = t - pt[i];
      pt[i] = t;
      if (dt.x() != 0.0 || dt.y() != 0.0) {
        v.x() += dt.x() * b.inv_mass;
        v.y() += dt.y() * b.inv_mass;
        w += dt.x() * pts.ax[i] + dt.y() * pts.ay[i];
      }
    }
    if (probe.change(b, radius) <= kSweepTolerance * speed) return {it + 1, true};
  }
  const NewtonResult nr = polish_newton(b, pts, pn, pt, radius, speed);
  return {kMaxSweeps + nr.iterations, nr.converged};
}

// Friction of the restitution phase: tangential impulses only, |P_t,i| <= radius_i, minimising the
// kinetic energy (a convex problem: every block update lowers it, so this phase only dissipates;
// its solution has the friction opposite the final slip at every sliding point). From zero.
SweepResult solve_friction(const Body& b, const Points& pts, const double radius[], Eigen::Vector2d pt[],
                           double lever, double speed) {
  double total = 0.0;
  for (int i = 0; i < pts.n; ++i) {
    pt[i].setZero();
    total += radius[i];
  }
  if (total == 0.0) return {0, true};
  const Vec3 v_start = b.s->velocity, w_start = b.s->omega;
  if (pts.n == 2 && radius[0] > 0.0 && radius[1] > 0.0) {
    int steps = 0;
    const bool exact = solve_friction_edge(b, pts, radius, pt, lever, speed, steps);
    if (exact) return {steps, true};
    // None verified (the body is untouched): Gauss-Seidel and Newton below, counted if they fail.
    for (int i = 0; i < pts.n; ++i) pt[i].setZero();
  }
  const int max_sweeps = pts.n == 1 ? 1 : kMaxSweeps;  // one point: one exact update
  for (int it = 0; it < max_sweeps; ++it) {
    const SweepProbe probe(b);
    for (int k = 0; k < pts.n; ++k) {
      const int i = it % 2 == 0 ? k : pts.n - 1 - k;
      if (radius[i] == 0.0) continue;
      const Vec3 u = b.point_velocity(pts.r[i]);
      const Eigen::Vector2d g = Eigen::Vector2d(u.x(), u.y()) - pts.wtt[i] * pt[i];
      const Eigen::Vector2d t = min_on_disc(pts.wtt[i], g, radius[i]);
      const Eigen::Vector2d dt = t - pt[i];
      pt[i] = t;
      if (dt.x() != 0.0 || dt.y() != 0.0) b.apply(pts.r[i], Vec3(dt.x(), dt.y(), 0.0));
    }
    if (pts.n == 1 || probe.change(b, lever) <= kSweepTolerance * speed) return {pts.n == 1 ? 0 : it + 1, true};
  }
  const NewtonResult nr = polish_newton(b, pts, nullptr, pt, lever, speed, radius);
  if (nr.converged) return {kMaxSweeps + nr.iterations, true};
  // Still unconverged: if only two of the points carry friction (the others had no normal impulse
  // to scale: radius 0, so they take no impulse and constrain nothing), the problem is an edge's,
  // and the edge's exact solve takes it from the start. (Three corners of a face of Dice 2 and 3
  // landing flat at ~0.2 m/s and spinning, one of them unloaded: 3 solves in 3e5 `stepped` tosses
  // reached the sweep cap.) Only here, after Gauss-Seidel, so that every converged solve is as it was.
  int carry[2], carrying = 0;
  for (int i = 0; i < pts.n; ++i)
    if (radius[i] > 0.0 && carrying++ < 2) carry[carrying - 1] = i;
  if (carrying == 2) {
    Points edge;
    edge.n = 2;
    double edge_radius[2];
    for (int k = 0; k < 2; ++k) {
      edge.r[k] = pts.r[carry[k]];
      edge.wtt[k] = pts.wtt[carry[k]];
      edge_radius[k] = radius[carry[k]];
    }
    const Vec3 v_gs = b.s->velocity, w_gs = b.s->omega;
    b.s->velocity = v_start;
    b.s->omega = w_start;
    Eigen::Vector2d edge_pt[2];
    int steps = 0;
    if (solve_friction_edge(b, edge, edge_radius, edge_pt, lever, speed, steps)) {
      for (int i = 0; i < pts.n; ++i) pt[i].setZero();
      for (int k = 0; k < 2; ++k) pt[carry[k]] = edge_pt[k];
      b.count_exact_fallback();
      return {kMaxSweeps + nr.iterations + steps, true};
    }
    b.s->velocity = v_gs;  // back to the Gauss-Seidel iterate, counted by the caller
    b.s->omega = w_gs;
  }
  // Any number of points (an edge's solve above failed too, or more than two carry friction): the
  // dual solve, from the start. (Quarter-table `impulse` toss 97669, seed 1: a coin landing flat
  // on its face's tripod at 0.4 m/s, its restitution friction still moving at 20 000 sweeps.)
  {
    const Vec3 v_gs = b.s->velocity, w_gs = b.s->omega;
    b.s->velocity = v_start;
    b.s->omega = w_start;
    Eigen::Vector2d dual_pt[kMaxContacts];
    if (solve_friction_dual(b, pts, radius, dual_pt, speed, lever)) {
      for (int i = 0; i < pts.n; ++i) pt[i] = dual_pt[i];
      return {kMaxSweeps + nr.iterations + 1, true, true};
    }
    b.s->velocity = v_gs;  // back to the Gauss-Seidel iterate, counted by the caller
    b.s->omega = w_gs;
  }
  return {kMaxSweeps + nr.iterations, false};
}

}  // namespace friction_detail

}  // namespace dicesim
