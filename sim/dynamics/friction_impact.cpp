#include "sim/dynamics/friction_impact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <Eigen/QR>

#include "sim/atan.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/illinois.hpp"

namespace dicesim {
namespace {

Mat3 skew(const Vec3& r) {
  Mat3 X;
  X << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return X;
}

// Sweep caps of the Gauss-Seidel solves; reaching one is counted (pgs_unconverged).
constexpr int kMaxSweeps = 400;
// Sweeps with the cheap tangential update before the exact one takes over.
constexpr int kCheapSweeps = 30;
// Converged when a whole sweep changed the body's velocity (v, and w times the bounding radius)
// by less than this fraction of the speeds involved. (A test on the impulses would never pass on a
// face, whose split of the load over its corners is not unique; the velocities are.)
constexpr double kSweepTolerance = 1e-11;

using Points = ContactPoints;

struct Body {
  double mass, inv_mass;
  Mat3 inv_inertia;  // world
  RigidState* s;
  int* exact_fallbacks = nullptr;  // ImpactResult::exact_fallbacks of the solve, counted where taken
  void count_exact_fallback() const {
    if (exact_fallbacks) ++*exact_fallbacks;
  }
  void apply(const Vec3& r, const Vec3& P) const {
    s->velocity += P * inv_mass;
    s->omega += inv_inertia * r.cross(P);
  }
  Vec3 point_velocity(const Vec3& r) const { return s->velocity + s->omega.cross(r); }
};

// How much a sweep moved the body: |dv| + radius |dw|.
struct SweepProbe {
  Vec3 v, w;
  explicit SweepProbe(const Body& b) : v(b.s->velocity), w(b.s->omega) {}
  double change(const Body& b, double radius) const {
    return (b.s->velocity - v).norm() + radius * (b.s->omega - w).norm();
  }
};

Mat3 compliance(const Body& b, const Vec3& r) {
  const Mat3 X = skew(r);
  return b.inv_mass * Mat3::Identity() - X * b.inv_inertia * X;
}

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

// Plastic sliding impulse at one point, P = lambda (mu d + n) with d a unit vector: lambda
// stops the normal velocity, and the final slip u + W P must point along -d (Coulomb, maximal
// dissipation). That is one equation in the direction of d, G = d x slip = 0 with d . slip < 0.
// d is written as the guess d0 turned by the angle phi with tan(phi / 2) = x (no sin/cos), x in
// [-1, 1] covering the half circle around d0 and the same around -d0; the root is bracketed on
// a grid, nearest the guess first, and refined by Illinois to rounding.
// Returns false if no bracket exists (a jam: no direction stops the point; ~5e-5 of sliding
// impacts in random tests), and the caller falls back to projected Gauss-Seidel.
bool sliding_impulse_by_angle(const Mat3& W, const Vec3& u, double mu, Eigen::Vector2d d0, Vec3& P) {
  struct Eval {
    bool ok;
    double g, lambda;
    Vec3 dir;
  };
  Eigen::Vector2d base;
  const auto eval = [&](double x) {
    Eval e{};
    const double q = 1.0 / (1.0 + x * x), c = (1.0 - x * x) * q, sn = 2.0 * x * q;
    const Vec3 dir(mu * (c * base.x() - sn * base.y()), mu * (sn * base.x() + c * base.y()), 1.0);
    const Vec3 Wd = W * dir;
    if (!(Wd.z() > 0.0)) return e;
    e.lambda = -u.z() / Wd.z();
    const Vec3 after = u + e.lambda * Wd;
    e.g = dir.x() * after.y() - dir.y() * after.x();
    e.dir = dir;
    e.ok = dir.x() * after.x() + dir.y() * after.y() < 0.0;
    return e;
  };
  // A valid root can sit in a narrow window of valid directions: if the coarse grid (22.5
  // degrees) brackets none, finer ones are tried (rare: ~1% of sliding impacts).
  for (const int half_grid : {8, 128, 2048}) {
    for (int half = 0; half < 2; ++half) {
      base = half == 0 ? d0 : Eigen::Vector2d(-d0);
      // Intervals outward from the base direction, nearest first: [0, 1/n], [-1/n, 0],
      // [1/n, 2/n], [-2/n, -1/n], ... (the end shared with the previous one on a side is reused).
      const Eval e_base = eval(0.0);
      Eval prev[2] = {e_base, e_base};
      for (int j = 0; j < 2 * half_grid; ++j) {
        const int side_index = j % 2, k = j / 2;
        const double dir_sign = side_index == 0 ? 1.0 : -1.0;
        const double x0 = dir_sign * static_cast<double>(k) / half_grid;
        const double x1 = dir_sign * static_cast<double>(k + 1) / half_grid;
        const Eval enext = eval(x1);
        const Eval e0 = prev[side_index];
        prev[side_index] = enext;
        if (!e0.ok || !enext.ok || (e0.g > 0.0) == (enext.g > 0.0)) continue;
        Eval elo = x0 < x1 ? e0 : enext, eh = x0 < x1 ? enext : e0;
        // Illinois (never leaves the bracket); a bisection step if an interior point leaves the
        // valid set.
        Illinois br{std::min(x0, x1), elo.g, std::max(x0, x1), eh.g};
        bool valid = true;
        for (int it = 0; it < 200 && br.hi - br.lo > 1e-13 && elo.g != 0.0 && eh.g != 0.0; ++it) {
          double mid = br.next();
          Eval em = eval(mid);
          if (!em.ok) {
            mid = 0.5 * (br.lo + br.hi);
            em = eval(mid);
            if (!em.ok) {
              valid = false;  // the bracket holds an invalid stretch: look further
              break;
            }
          }
          const bool lo_side = (em.g > 0.0) == (elo.g > 0.0);
          if (mid == (lo_side ? br.lo : br.hi)) break;
          (lo_side ? elo : eh) = em;
          br.update(mid, em.g, lo_side);
        }
        if (!valid) continue;
        const Eval& best = std::abs(elo.g) <= std::abs(eh.g) ? elo : eh;
        P = best.lambda * best.dir;
        return true;
      }
    }
  }
  return false;
}

}  // namespace

bool one_corner_sliding_reference(const Mat3& W, const Vec3& u, double mu, Eigen::Vector2d d, Vec3& P,
                                  bool* by_angle) {
  if (by_angle) *by_angle = false;
  Eigen::Vector2d prev_r(0.0, 0.0), prev_nd(0.0, 0.0);
  for (int it = 0; it < 8; ++it) {
    const Vec3 dir(mu * d.x(), mu * d.y(), 1.0);
    const Vec3 Wd = W * dir;
    if (!(Wd.z() > 0.0)) break;  // this direction cannot stop the point: the root-finder looks wider
    const double lambda = -u.z() / Wd.z();
    const Vec3 after = u + lambda * Wd;
    Eigen::Vector2d nd(-after.x(), -after.y());
    const double slip = nd.norm();
    if (slip <= 1e-300) break;
    nd /= slip;
    if ((nd - d).norm() <= 1e-10) {
      P = lambda * dir;
      return true;
    }
    // Anderson mixing (depth 1) of the last two residuals; the acceptance test is unchanged.
    const Eigen::Vector2d res = nd - d;
    double gamma = 0.0;
    if (it > 0) {
      const Eigen::Vector2d dr = res - prev_r;
      const double dd2 = dr.squaredNorm();
      if (dd2 > 0.0) gamma = res.dot(dr) / dd2;
    }
    Eigen::Vector2d x = nd - gamma * (nd - prev_nd);
    prev_r = res;
    prev_nd = nd;
    const double xn = x.norm();
    d = xn > 0.0 && std::isfinite(xn) ? Eigen::Vector2d(x / xn) : nd;
  }
  // The fixed point converges slowly or cycles (it does where W couples slip and normal
  // strongly): solve the same equations as a root in the angle of d instead, from the last iterate.
  if (by_angle) *by_angle = true;
  return sliding_impulse_by_angle(W, u, mu, d, P);
}

// The direction condition in d's angle phi. With m = -u_z, W's blocks A (2x2 tangential), b
// (its tangential-normal column) and a = W_nn, the normal impulse is lambda = m / den,
// den = a + mu b.d, and the final slip s = S / den, S = den u_t + m (b + mu A d) (the quartic in
// tan(phi / 2) of the closed form is S x d = 0; but its roots include the invalid ones, slip along
// the friction). The residual is theta, the angle from d to -S: zero only where the slip opposes
// the friction, +-pi at the invalid roots. theta' = (S x S') / |S|^2 - 1, S' = mu (b.d') u_t +
// m mu A d', d' = perp(d), and since d'' = -d, S'' = a u_t + m b - S (so theta'' is cheap too).
// Near the root (|theta| < 0.1, S.d < 0: almost every iteration) Halley's step on
// r = tan(theta) = (S x d) / (-S.d), which is rational in S, S', S'' and d (1 + r^2 = |S|^2 /
// (S.d)^2): r' = g / (S.d)^2 with g = S x S' - |S|^2, r'' = (2 r g^2 + h) / ((S.d)^2 |S|^2) with
// h = (S x S'') |S|^2 - 2 (S x S') (S.S'), and the step
//   delta = -2 r r' / (2 r'^2 - r r'') = 2 (S x d) g |S|^2 / (2 g^2 (S.d) + (S x d) h):
// one division, no arc tangent, cubic convergence (single4's Newton on theta needed 3.2
// iterations and an arc-tangent series per iteration). Far from it, Newton on theta, with
// theta = 2 atan(q), q = tan(theta / 2) = (S x d) / (|S| - S.d), finite except at theta = pi.
// Each step is taken as d <- (d + t d') / sqrt(1 + t^2), t = tan(delta) (no sin/cos), |delta|
// <= 1 (or 0.1 for Halley's). Safeguards: backtracking when |theta| does not fall (measured by
// sin^2 theta, extended past pi / 2 to stay monotone), the fixed point's step d <- -S / |S| where
// theta' > -1/4, Newton's step where Halley's correction factor leaves [2/3, 2]. From the sliding
// direction; the root is verified (den > 0, the final slip opposite d and perpendicular to it to
// 1e-13 of the speeds), else false.
bool one_corner_sliding_newton(const Mat3& W, const Vec3& u, double mu, Eigen::Vector2d d, Vec3& P,
                               int* iterations) {
  const double m = -u.z();
  const double a = W(2, 2), bx = W(0, 2), by = W(1, 2);
  const double A00 = W(0, 0), A01 = W(0, 1), A11 = W(1, 1);
  const double ux = u.x(), uy = u.y();
  const double Kx = a * ux + m * bx, Ky = a * uy + m * by;  // S'' + S
  // d turned by atan(t): (d + t d') / sqrt(1 + t^2); for small t the inverse root by its series
  // (to 3e-17: the latency of a square root and a division saved in the common last steps).
  const auto turn = [](const Eigen::Vector2d& v, double t) {
    const double t2 = t * t;
    const double c = t2 < 1e-4 ? 1.0 - t2 * (0.5 - t2 * (0.375 - t2 * 0.3125)) : 1.0 / std::sqrt(1.0 + t2);
    return Eigen::Vector2d((v.x() - t * v.y()) * c, (v.y() + t * v.x()) * c);
  };
  bool converged = false;
  Eigen::Vector2d d_prev = d;
  double measure_prev = 0.0, step_prev = 0.0;
  for (int it = 0; it < 40; ++it) {
    if (iterations) *iterations = it + 1;
    const double dx = d.x(), dy = d.y();  // d' = (-dy, dx)
    const double den = a + mu * (bx * dx + by * dy);
    if (!(den > 0.0)) return false;
    const double bdp = by * dx - bx * dy;
    const double Sx = den * ux + m * (bx + mu * (A00 * dx + A01 * dy));
    const double Sy = den * uy + m * (by + mu * (A01 * dx + A11 * dy));
    const double Spx = mu * (bdp * ux + m * (A01 * dx - A00 * dy));
    const double Spy = mu * (bdp * uy + m * (A11 * dx - A01 * dy));
    const double S2 = Sx * Sx + Sy * Sy, cross = Sx * dy - Sy * dx, dot = Sx * dx + Sy * dy;
    const double c = Sx * Spy - Sy * Spx;
    const double g = c - S2;  // theta' S2
    const bool near = dot < 0.0 && cross * cross < 1e-2 * dot * dot;
    double measure, theta = 0.0;  // measure: increasing in |theta| on [0, pi]
    if (near) {
      measure = cross * cross / S2;  // sin^2 theta (off the step's chain)
    } else {
      // (sqrt(x^2 + y^2), not hypot: S is a speed times a compliance, far from overflow.)
      const double q = cross / (std::sqrt(S2) - dot);  // tan(theta / 2): finite except at theta = pi
      const double q2 = q * q;
      theta = q2 < 1e-2 ? 2.0 * q * (1.0 - q2 * (1.0 / 3.0 - q2 * (0.2 - q2 * (1.0 / 7.0)))) : 2.0 * atan_fixed(q);  // not libm: the same bits on every CPU (sim/atan.hpp)
      const double sn = 2.0 * q / (1.0 + q2), sn2 = sn * sn;
      measure = q2 <= 1.0 ? sn2 : 2.0 - sn2;
    }
    if (it > 0 && !(measure < measure_prev)) {
      // No decrease: back to the last iterate with half the step (a safeguard; rare).
      step_prev *= 0.5;
      if (!(std::abs(step_prev) > 1e-9)) return false;
      d = turn(d_prev, step_prev);
      continue;
    }
    d_prev = d;
    measure_prev = measure;
    if (!(g < -0.25 * S2)) {
      // theta nearly flat or rising (theta' >= -1/4): Newton's step is no guide. The fixed
      // point's instead, d <- -S / |S| (the turn by theta), which the next iterate must improve on.
      if (near) theta = -cross / dot;  // tan theta, as the turn wants it (|theta| < 0.1)
      else theta = std::abs(theta) >= 0.25 * M_PI ? (theta > 0.0 ? 1.0 : -1.0) : std::tan(theta);
      step_prev = theta;
      d = Eigen::Vector2d(-Sx, -Sy) * (1.0 / std::sqrt(S2));
      continue;
    }
    // theta'' S2^2 (S'' = K - S, so S x S'' = S x K).
    const double h = (Sx * Ky - Sy * Kx) * S2 - 2.0 * c * (Sx * Spx + Sy * Spy);
    double t;
    bool done;
    if (near) {
      const double hd = 2.0 * g * g * dot, corr = cross * h;
      double delta;
      if (std::abs(corr) <= 0.5 * std::abs(hd)) {
        delta = 2.0 * cross * g * S2 / (hd + corr);  // Halley
        // Cubic convergence (measured on Die 1: the next step ~0.4-0.7 times this one's cube):
        // after a step this small the error is below rounding, so it is not evaluated again.
        done = std::abs(delta) <= 1e-5;
      } else {
        delta = cross * dot / g;  // Newton on tan(theta)
        done = std::abs(delta) <= 1e-9;
      }
      delta = std::clamp(delta, -0.1, 0.1);
      t = delta * (1.0 + delta * delta * (1.0 / 3.0));  // tan(delta) to delta^5
    } else {
      const double hd = 2.0 * g * g, corr = -theta * h;
      double step;
      if (std::abs(corr) <= 0.5 * hd) {
        step = -2.0 * theta * g * S2 / (hd + corr);  // Halley on theta
        done = std::abs(step) <= 1e-5;
      } else {
        step = -theta * S2 / g;  // Newton
        done = std::abs(step) <= 1e-9;
      }
      if (!std::isfinite(step)) return false;
      t = std::clamp(step, -1.0, 1.0);
      if (std::abs(t) < 0.1) t *= 1.0 + t * t * (1.0 / 3.0);  // tan(step) to step^5

    }
    if (!std::isfinite(t)) return false;
    step_prev = t;
    d = turn(d, t);
    if (done) {
      converged = true;
      break;
    }
  }

  if (!converged) return false;
  const Vec3 dir(mu * d.x(), mu * d.y(), 1.0);
  const Vec3 Wd = W * dir;
  if (!(Wd.z() > 0.0)) return false;
  const double lambda = m / Wd.z();
  const double sx = ux + lambda * Wd.x(), sy = uy + lambda * Wd.y();
  if (!(sx * d.x() + sy * d.y() < 0.0)) return false;  // the slip opposes the friction
  // And is anti-parallel to it, to 1e-13 of the speeds |u| + lambda |Wd|; compared in squares
  // against |u|^2 + lambda^2 |Wd|^2 (no square roots; at most sqrt(2) stricter).
  const double cr = sx * d.y() - sy * d.x();
  if (!(cr * cr <= 1e-26 * (u.squaredNorm() + lambda * lambda * Wd.squaredNorm()))) return false;
  P = lambda * dir;
  return true;
}

namespace {

// The same problem for one point, exactly: the sticking impulse if it lies in the cone, else
// sliding: P = lambda (n + mu d) with the final slip -s d (s >= 0, maximal dissipation) and zero
// final normal velocity; d by Newton on its angle (one_corner_sliding_newton), and where that
// does not verify, the fixed point and angle search (one_corner_sliding_reference). Returns false
// (the caller falls back to the iterative solver) only for a jam.
bool solve_plastic_single(const Body& b, const Points& pts, double pn[], Eigen::Vector2d pt[]) {
  const Vec3& r = pts.r[0];
  const Vec3 u = b.point_velocity(r);
  pn[0] = 0.0;
  pt[0].setZero();
  if (u.z() >= 0.0) return true;  // separating: no impulse
  const Vec3 stick = -(pts.W0_inverse * u);
  const double mu = pts.mu[0];
  // (Squared: impulses of N s scale cannot overflow.)
  if (stick.z() >= 0.0 && stick.x() * stick.x() + stick.y() * stick.y() <= mu * mu * stick.z() * stick.z()) {
    b.apply(r, stick);
    pn[0] = stick.z();
    pt[0] = Eigen::Vector2d(stick.x(), stick.y());
    return true;
  }
  if (mu == 0.0) {
    const Vec3 P(0.0, 0.0, -u.z() * pts.inv_wnn[0]);
    b.apply(r, P);
    pn[0] = P.z();
    return true;
  }
  Eigen::Vector2d d(-u.x(), -u.y());
  if (d.norm() <= 1e-300) d = Eigen::Vector2d(stick.x(), stick.y());
  if (d.norm() <= 1e-300) return false;
  d.normalize();
  Vec3 P;
  if (!one_corner_sliding_newton(pts.W0, u, mu, d, P)) {
    if (!one_corner_sliding_reference(pts.W0, u, mu, d, P)) return false;
    b.count_exact_fallback();
  }
  b.apply(r, P);
  pn[0] = P.z();
  pt[0] = Eigen::Vector2d(P.x(), P.y());
  return true;
}

}  // namespace

namespace {

struct SweepResult {
  int sweeps = 0;
  bool converged = true;
  bool dual = false;  // solve_friction: taken by its dual fallback (counted, ImpactResult::dual_solves)
};

// Semismooth Newton on the Alart-Curnier equations of the same plastic frictional problem, for
// the solves Gauss-Seidel leaves unconverged. Those are edges (two corners) near the stick-slip
// boundary: the compliance of two corners has rank 5 (equal and opposite friction along the edge
// moves nothing), so Gauss-Seidel's error decays by only ~1-4% per sweep there. Newton on
// F(P) = P - Phi(P), Phi_n = max(0, P_n - rho u_n), Phi_t = the projection of P_t - rho u_t on
// the disc of radius mu Phi_n (F = 0 is exactly Coulomb's law with maximal dissipation, any
// rho > 0), converges quadratically from the Gauss-Seidel iterate; its linear systems are solved
// in the least-squares, minimum-norm sense (complete orthogonal decomposition), which copes with
// the rank deficiency. Starts from (pn, pt) as applied to the body; ends with P = Phi(P), so every
// impulse is exactly in its cone. Converged when that last correction and the last Newton step
// each move the body's velocity by less than the sweeps' tolerance.
constexpr int kNewtonMaxPoints = 8;
constexpr int kNewtonMaxIterations = 40;
using NewtonMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3 * kNewtonMaxPoints, 3 * kNewtonMaxPoints>;
using NewtonVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3 * kNewtonMaxPoints, 1>;

struct NewtonResult {
  int iterations = 0;
  bool converged = false;
};

NewtonResult newton_attempt(const Body& b, const Points& pts, double pn[], Eigen::Vector2d pt[], double radius,
                            double speed, const double* fixed_radius, double rho_scale) {
  NewtonResult res;
  const int n = pts.n, dim = 3 * n;
  if (n > kNewtonMaxPoints) return res;
  // Delassus matrix W (u = u0 + W P), world axes per point: x, y tangential, z normal.
  NewtonMat W(dim, dim);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Mat3 Xi = skew(pts.r[i]), Xj = skew(pts.r[j]);
      W.block<3, 3>(3 * i, 3 * j) = b.inv_mass * Mat3::Identity() - Xi * b.inv_inertia * Xj;
    }
  double rho[kNewtonMaxPoints];
  for (int i = 0; i < n; ++i) rho[i] = rho_scale * 3.0 / W.block<3, 3>(3 * i, 3 * i).trace();
  NewtonVec P(dim), F(dim), Phi(dim), u(dim);
  for (int i = 0; i < n; ++i) P.segment<3>(3 * i) = Vec3(pt[i].x(), pt[i].y(), fixed_radius ? 0.0 : pn[i]);
  NewtonMat J(dim, dim), dPhi(dim, dim);
  // Phi(P) and, optionally, its generalised Jacobian, at the body's current velocities.
  const auto eval = [&](bool jacobian) {
    for (int i = 0; i < n; ++i) u.segment<3>(3 * i) = b.point_velocity(pts.r[i]);
    if (jacobian) dPhi.setZero();
    for (int i = 0; i < n; ++i) {
      const int k = 3 * i;
      // With fixed radii (the restitution phase's friction) the normal impulses are not unknowns:
      // Phi_n = P_n (= 0), F_n = 0.
      const double xn = fixed_radius ? 0.0 : P(k + 2) - rho[i] * u(k + 2);
      const double phin = fixed_radius ? P(k + 2) : std::max(0.0, xn);
      const Eigen::Vector2d xt(P(k) - rho[i] * u(k), P(k + 1) - rho[i] * u(k + 1));
      const double R = fixed_radius ? fixed_radius[i] : pts.mu[i] * phin, xtn = xt.norm();
      const bool inside = xtn <= R;
      const Eigen::Vector2d phit = inside ? xt : (xtn > 0.0 ? Eigen::Vector2d(xt * (R / xtn)) : Eigen::Vector2d::Zero());
      Phi.segment<3>(k) = Vec3(phit.x(), phit.y(), phin);
      if (!jacobian) continue;
      // d(xi)/dP = E - rho W (rows of point i).
      Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 3 * kNewtonMaxPoints> dxi = -rho[i] * W.middleRows<3>(k);
      dxi.block<3, 3>(0, k) += Mat3::Identity();
      if (fixed_radius) {
        dPhi(k + 2, k + 2) = 1.0;
      } else if (xn > 0.0) {
        dPhi.row(k + 2) = dxi.row(2);
      }
      if (inside) {
        dPhi.middleRows<2>(k) = dxi.topRows<2>();
      } else if (xtn > 0.0) {
        const Eigen::Vector2d h = xt / xtn;
        const Eigen::Matrix2d Pp = (R / xtn) * (Eigen::Matrix2d::Identity() - h * h.transpose());
        dPhi.middleRows<2>(k) = Pp * dxi.topRows<2>();
        if (xn > 0.0) dPhi.middleRows<2>(k) += pts.mu[i] * h * dxi.row(2);
      }
    }
    F = P - Phi;
  };
  const auto apply = [&](const NewtonVec& dP) {
    for (int i = 0; i < n; ++i) b.apply(pts.r[i], dP.segment<3>(3 * i));
  };
  const auto body_change = [&](const NewtonVec& dP) {
    Vec3 dv = Vec3::Zero(), dw = Vec3::Zero();
    for (int i = 0; i < n; ++i) {
      dv += dP.segment<3>(3 * i) * b.inv_mass;
      dw += b.inv_inertia * pts.r[i].cross(Vec3(dP.segment<3>(3 * i)));
    }
    return dv.norm() + radius * dw.norm();
  };
  const double tol = kSweepTolerance * speed;
  const NewtonVec P_start = P;
  const Vec3 v_start = b.s->velocity, w_start = b.s->omega;
  eval(true);
  double f2 = F.squaredNorm();
  Eigen::CompleteOrthogonalDecomposition<NewtonMat> cod(dim, dim);
  NewtonVec dP(dim), trial(dim);
  for (int it = 0; it < kNewtonMaxIterations; ++it) {
    if (f2 == 0.0) {
      res.converged = true;
      break;
    }
    ++res.iterations;
    J = NewtonMat::Identity(dim, dim) - dPhi;
    if (fixed_radius)  // the normal impulses are not unknowns: their columns out, dP_n = 0
      for (int i = 0; i < n; ++i) {
        J.col(3 * i + 2).setZero();
        J(3 * i + 2, 3 * i + 2) = 1.0;
      }
    cod.compute(J);
    dP = -cod.solve(F);
    // Backtracking on |F|^2 (the step from a kink can overshoot, and a step in the null space of
    // W, free for the velocities, can leave the cones).
    double alpha = 1.0;
    bool accepted = false;
    const NewtonVec P0 = P;
    for (int ls = 0; ls < 30; ++ls) {
      trial = alpha * dP;
      P = P0 + trial;
      apply(trial);
      eval(false);
      const double g2 = F.squaredNorm();
      if (g2 <= (1.0 - 1e-4 * alpha) * f2) {
        f2 = g2;
        accepted = true;
        break;
      }
      apply(-trial);
      P = P0;
      alpha *= 0.5;
    }
    if (!accepted) {
      // No descent left: at the rounding floor if even the full step is below the tolerance.
      eval(false);
      res.converged = body_change(dP) <= tol && body_change(Phi - P) <= tol;
      break;
    }
    eval(true);
    if (body_change(trial) <= tol && body_change(Phi - P) <= tol) {
      res.converged = true;
      break;
    }
  }
  // End on the cones: P = Phi(P).
  const NewtonVec fix = Phi - P;
  if (res.converged) {
    apply(fix);
    P = Phi;
  } else {  // failed: back to the Gauss-Seidel iterate (the caller counts it unconverged)
    b.s->velocity = v_start;
    b.s->omega = w_start;
    P = P_start;
  }
  for (int i = 0; i < n; ++i) {
    pt[i] = Eigen::Vector2d(P(3 * i), P(3 * i + 1));
    if (!fixed_radius) pn[i] = P(3 * i + 2);
  }
  return res;
}

// Newton with rho_i = 3 / tr W_ii, else (it can stall at a kink of Phi where F has a part outside
// the range of the generalised Jacobian; which kink depends on rho) with rho / 8, then 8 rho, each
// from the Gauss-Seidel iterate.
NewtonResult polish_newton(const Body& b, const Points& pts, double pn[], Eigen::Vector2d pt[], double radius,
                           double speed, const double* fixed_radius = nullptr) {
  NewtonResult total;
  for (const double scale : {1.0, 0.125, 8.0}) {
    const NewtonResult r = newton_attempt(b, pts, pn, pt, radius, speed, fixed_radius, scale);
    total.iterations += r.iterations;
    if (r.converged) {
      total.converged = true;
      break;
    }
  }
  return total;
}

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
bool solve_sliding(const Body& b, const Points& pts, double speed, double lever, double pn[], Eigen::Vector2d pt[]) {
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
    Eigen::Vector2d prev_r[kMaxN], prev_next[kMaxN];
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

// The plastic solve of two points by their active sets, each case exact and taken only where
// Coulomb's law verifies at both points (plastic_verifies): both stick (solve_sticking), one
// sticks and the other slides (solve_stick_slide, both ways), both slide or one lifts
// (solve_sliding). For the two-point solves Gauss-Seidel and its Newton finish leave
// unconverged: a coin on its side, both rims' lowest points touching 2 b apart (b the rims' half
// distance, 0.68 mm on the quarter, against its 12 mm radius). Their normal impulses' split
// tips the coin about a diameter, moving both points sideways ~a/b = 18 times more than it
// moves them vertically: the two normal rows are 0.975 correlated (Gauss-Seidel's error falls
// ~0.5 % a sweep: ~4 000 sweeps), and at one point sticking and the other sliding the
// Alart-Curnier residual's Newton step is no descent (a kink), so the finish stalls. Last, one
// point lifting and the other alone (solve_lift_one: a coin on its side, one rim's point
// lifting while the other's slides, quarter `stepped` toss 79149, where solve_sliding's iterate
// changed its active set after its first pass). The body starts from the state before the solve (no
// impulse applied). False: the body untouched.
bool solve_plastic_pair(const Body& b, const Mat3& Iw, const Points& pts, double speed, double lever, double pn[],
                        Eigen::Vector2d pt[]) {
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
  return solve_lift_one(b, pts, 0, speed, pn, pt) || solve_lift_one(b, pts, 1, speed, pn, pt);
}

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
constexpr double kVerifyCone = 1e-9;   // |P_i| <= R_i (1 + this)
constexpr double kVerifySlip = 1e-9;   // a point slipping less than this fraction of the speeds sticks
constexpr double kVerifyAlign = 1e-6;  // sliding: |P_i / R_i + u_i / |u_i|| <= this

// Coulomb with maximal dissipation at one point, as the exact solves accept it: |P| <= R (to
// kVerifyCone) and, where it slips more than slip_tol and carries friction, P opposite the slip.
bool coulomb_verifies(const Eigen::Vector2d& P, const Eigen::Vector2d& u, double R, double slip_tol) {
  if (!P.allFinite() || P.norm() > R * (1.0 + kVerifyCone)) return false;
  const double un = u.norm();
  return un <= slip_tol || !(R > 0.0) || !((P / R + u / un).norm() > kVerifyAlign);
}

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

// The sweeps' and the direct multi-point solves' terms of the set-up (ContactPoints::sweep_terms).
void set_up_sweep_terms(ContactGeometry& geo) {
  Points& pts = geo.pts;
  if (pts.sweep_terms) return;
  for (int i = 0; i < pts.n; ++i) {
    pts.inv_wtt[i] = pts.wtt[i].inverse();
    const Vec3& r = pts.r[i];
    pts.ax[i] = geo.inv_inertia * Vec3(0.0, r.z(), -r.y());
    pts.ay[i] = geo.inv_inertia * Vec3(-r.z(), 0.0, r.x());
    pts.az[i] = geo.inv_inertia * Vec3(r.y(), -r.x(), 0.0);
  }
  pts.sweep_terms = true;
}

// The part of a solve's set-up that depends only on the orientation R and the contact set; the
// points' lever arms r (from the COM, world), or (null) the contact set's features' own.
void set_up_geometry(const DieModel& m, const Body& b, const Mat3& R, const ContactSet& c, ContactGeometry& geo,
                     const Vec3* r = nullptr) {
  if (!geo.iw_given) geo.Iw = world_inertia(m, R);
  geo.inv_inertia = b.inv_inertia;
  Points& pts = geo.pts;
  pts.n = c.n;
  // The lever arms in one contact plane: every point at the lowest one's height. Touching corners
  // differ in height by up to the touch tolerance (a face landing a few 1e-9 m out of level); with
  // each corner's own height, the tangential velocities of a face's corners depend on the plane's
  // tilt, no motion makes all of them stick, the true solution slips at ~1e-9 of the speeds, and
  // the solves stall there (pgs_unconverged on faces of Die 3 and the prisms). In one plane the
  // face's problem is exactly consistent. (The lowest, not the mean: independent of the order.)
  // Only points within the largest touch tolerance of the callers (1e-6 r) of the lowest: a set
  // spread wider (a cylinder sunk into the floor by the stepper's drift, both rims' lowest points
  // "touching") keeps its own geometry rather than a lever arm moved by a visible amount.
  double plane_z = 0.0, top_z = 0.0;
  std::optional<RimFeatures> rims;  // a cylinder's points share their set-up
  if (!r && m.curved()) rims.emplace(m, R);
  for (int i = 0; i < c.n; ++i) {
    pts.r[i] = r ? r[i] : rims ? rims->point(c.vertex[i]) : contact_point(m, R, c.vertex[i]);
    plane_z = i == 0 ? pts.r[i].z() : std::min(plane_z, pts.r[i].z());
    top_z = i == 0 ? pts.r[i].z() : std::max(top_z, pts.r[i].z());
  }
  const bool one_plane = top_z - plane_z <= 1e-6 * m.bounding_radius;
  for (int i = 0; i < c.n; ++i) {
    const int v = c.vertex[i];
    if (one_plane) pts.r[i].z() = plane_z;
    pts.e[i] = m.vertex_restitution[v];
    pts.mu[i] = m.vertex_friction[v];
    const Mat3 W = compliance(b, pts.r[i]);
    if (i == 0) pts.W0 = W;
    pts.inv_wnn[i] = 1.0 / W(2, 2);
    pts.wtt[i] = W.topLeftCorner<2, 2>();
    pts.wz[i] = W.col(2);
  }
  pts.sweep_terms = false;
  if (c.n == 1) pts.W0_inverse = pts.W0.inverse();
  else set_up_sweep_terms(geo);  // (one point: only if its exact solve falls back to the sweeps)
  geo.valid = true;
}

}  // namespace

ContactSet touching_corners(const DieModel& m, const RigidState& s, double tol) {
  ContactSet c;
  double z[kMaxContacts];
  const int nv = m.vertex_count();
  std::optional<RimFeatures> rims;  // a cylinder's six features share their set-up
  if (m.curved()) rims.emplace(m, s.R);
  for (int i = 0; i < nv; ++i) {
    const double zi = rims ? s.position.z() + rims->point(i).z() : corner_height(m, s, i);
    if (zi > tol) continue;
    if (c.n < kMaxContacts) {
      z[c.n] = zi;
      c.vertex[c.n++] = i;
      continue;
    }
    ++c.dropped;  // full: one corner is left out (replace the highest if this one is lower)
    int hi = 0;
    for (int k = 1; k < c.n; ++k)
      if (z[k] > z[hi]) hi = k;
    if (zi < z[hi]) {
      z[hi] = zi;
      c.vertex[hi] = i;
    }
  }
  // Ascending vertex order, as the stepper's search for new contacts expects.
  for (int a = 1; a < c.n; ++a)
    for (int b = a; b > 0 && c.vertex[b - 1] > c.vertex[b]; --b) std::swap(c.vertex[b - 1], c.vertex[b]);
  return c;
}

namespace {

// Whether every point's tangential slip is at least mu times its approach speed (|u_t| >= mu |u_n|),
// the state in which a plastic impulse at the friction cone's edge leaves the point sliding.
bool slips_past_cone(const Body& b, const Points& pts) {
  for (int i = 0; i < pts.n; ++i) {
    const Vec3 u = b.point_velocity(pts.r[i]);
    const double mu_un = pts.mu[i] * u.z();
    if (u.x() * u.x() + u.y() * u.y() < mu_un * mu_un) return false;
  }
  return true;
}

}  // namespace

ImpactResult apply_friction_impact_at(const DieModel& m, RigidState& s, const ContactSet& c, const Vec3* r,
                                      bool restitution) {
  // (Body's own initialisation from the product, as apply_friction_impact's set-up has it.)
  const Body b0{m.mass, 1.0 / m.mass, s.R * m.principal_moments.cwiseInverse().asDiagonal() * s.R.transpose(), &s};
  ContactGeometry geo;
  set_up_geometry(m, b0, s.R, c, geo, r);
  return apply_friction_impact(m, s, c, restitution, nullptr, nullptr, &geo);
}

ImpactResult apply_friction_impact(const DieModel& m, RigidState& s, const ContactSet& c, bool restitution,
                                   const ContactImpulses* warm, ContactImpulses* out, ContactGeometry* geometry,
                                   bool direct) {
  ImpactResult res;
  if (out) out->n = 0;
  if (c.n == 0) return res;
  if (c.dropped > 0) ++res.corrections.fallbacks;  // never silent: corners beyond kMaxContacts got no impulse
  const RigidState s0 = s;
  // The set-up below depends only on the orientation and the contact set: shared through
  // `geometry` by the solves of one stepper step (its impact and every trial).
  ContactGeometry local;
  ContactGeometry& geo = geometry ? *geometry : local;
  if (!geo.valid) {
    // (Body's own initialisation from the product, as the solve always had it: assigning the
    // product to a matrix instead rounds differently.)
    const Body b0{m.mass, 1.0 / m.mass, s.R * m.principal_moments.cwiseInverse().asDiagonal() * s.R.transpose(), &s};
    set_up_geometry(m, b0, s.R, c, geo);
  }
  const Mat3& Iw = geo.Iw;
  Body b{m.mass, 1.0 / m.mass, geo.inv_inertia, &s, &res.exact_fallbacks};
  const Points& pts = geo.pts;
  double u0n[kMaxContacts];
  for (int i = 0; i < c.n; ++i) u0n[i] = b.point_velocity(pts.r[i]).z();
  const auto energy = [&](const RigidState& x) {
    return 0.5 * m.mass * x.velocity.squaredNorm() + 0.5 * x.omega.dot(Iw * x.omega);
  };
  const double E0 = energy(s0);
  res.energy_before = E0;
  // The speeds involved (convergence and rounding tests are relative to it).
  const double lever = m.bounding_radius;
  // (Plus a floor, 1e-2 of the tolerance at the die's natural speed sqrt(g r), where the speeds
  // are so small, a die at rest, that rounding would keep the sweep from ever meeting them.)
  const double speed = s0.velocity.norm() + s0.omega.norm() * lever + 1e-2 * std::sqrt(m.gravity * lever);

  // 1. Compression: the plastic frictional impulse.
  double pn[kMaxContacts];
  Eigen::Vector2d pt[kMaxContacts];
  bool solved = false;
  if (c.n == 1) {
    solved = solve_plastic_single(b, pts, pn, pt);
    // A jam (no sliding direction found that stops the point): the general solve below takes it
    // (Gauss-Seidel, finished by Newton), an exact fallback if it converges, else unconverged.
  }
  const bool jammed = c.n == 1 && !solved;
  if (!solved && direct && c.n >= 2 && (!m.curved() || slips_past_cone(b, pts))) {
    // The two common cases directly: every point sliding (or lifting), then every point sticking;
    // else the sweeps. Each answer is kept only where Coulomb's law verifies at every point, so
    // which solve runs first changes the cost, not the law. A cylinder's rim points try them only
    // when every point slips faster than mu times its approach: slower, a rolling rim's points
    // stick, the sliding iteration runs out without converging (133 317 of 135 898 tries in 300
    // tosses of the three-sided coin), and the sweeps, warm-started, solve sticking rims faster than
    // solve_sticking's 6x6 factorisation. (Polyhedra keep the unconditional order: their pins.)
    solved = solve_sliding(b, pts, speed, lever, pn, pt);
    if (!solved) solved = solve_sticking(b, Iw, pts, lever, pn, pt);
  }
  if (!solved) {
    set_up_sweep_terms(geo);
    for (int i = 0; i < c.n; ++i) {
      pn[i] = 0.0;
      pt[i].setZero();
    }
    if (warm && warm->n > 0) {
      for (int i = 0; i < c.n; ++i)
        for (int j = 0; j < warm->n; ++j)
          if (warm->vertex[j] == c.vertex[i]) {
            pn[i] = std::max(0.0, warm->P[j].z());
            Eigen::Vector2d t(warm->P[j].x(), warm->P[j].y());
            const double lim = pts.mu[i] * pn[i], tn = t.norm();
            if (tn > lim) t *= tn > 0.0 ? lim / tn : 0.0;
            pt[i] = t;
            b.apply(pts.r[i], Vec3(t.x(), t.y(), pn[i]));
            break;
          }
      if (energy(s) > E0) {  // a stale warm start that adds energy: start from zero instead
        s.velocity = s0.velocity;
        s.omega = s0.omega;
        for (int i = 0; i < c.n; ++i) {
          pn[i] = 0.0;
          pt[i].setZero();
        }
      }
    }
    SweepResult sr = solve_plastic(b, pts, pn, pt, lever, speed);
    if (!sr.converged && c.n == 2) {
      // Two points the sweeps and Newton leave unconverged (a coin on its side: solve_plastic_pair):
      // the exact solve by their active sets, from the state before the solve. Only here, after
      // the sweeps, so that every converged solve is as it was.
      const RigidState gs = s;
      s.velocity = s0.velocity;
      s.omega = s0.omega;
      double qn[2];
      Eigen::Vector2d qt[2];
      if (solve_plastic_pair(b, Iw, pts, speed, lever, qn, qt)) {
        for (int i = 0; i < 2; ++i) {
          pn[i] = qn[i];
          pt[i] = qt[i];
        }
        sr.converged = true;
        ++res.exact_fallbacks;
      } else {
        s.velocity = gs.velocity;
        s.omega = gs.omega;
      }
    }
    res.iterations += sr.sweeps;
    if (!sr.converged) ++res.corrections.pgs_unconverged;
    else if (jammed) ++res.exact_fallbacks;
  }
  Vec3 total[kMaxContacts];
  for (int i = 0; i < c.n; ++i) total[i] = Vec3(pt[i].x(), pt[i].y(), pn[i]);

  // 2. Restitution: energetic, with friction.
  if (restitution) {
    double w_sum = 0.0, we_sum = 0.0;
    for (int i = 0; i < c.n; ++i) {
      const double w = std::max(0.0, -u0n[i]);
      w_sum += w;
      we_sum += w * pts.e[i];
    }
    const double e = w_sum > 0.0 ? we_sum / w_sum : 0.0;
    if (e > 0.0) {
      double work_n = 0.0;
      double F = 0.0;
      Vec3 M = Vec3::Zero();
      for (int i = 0; i < c.n; ++i) {
        work_n += pn[i] * 0.5 * (u0n[i] + b.point_velocity(pts.r[i]).z());
        F += pn[i];
        M += pts.r[i].cross(Vec3(0.0, 0.0, pn[i]));
      }
      const double dE_c = energy(s) - E0;
      const double stored = std::max(0.0, std::min(-work_n, -dE_c));
      const double released = e * e * stored;
      const Vec3 dw = b.inv_inertia * M;
      // E(k) = E1 + k a + k^2 q / 2 for the normal impulses k pn_i.
      const double a = s.velocity.z() * F + s.omega.dot(M);
      const double q = F * F * b.inv_mass + M.dot(dw);
      if (released > 0.0 && q > 0.0) {
        const double root = std::sqrt(a * a + 2.0 * q * released);
        const double k = a >= 0.0 ? 2.0 * released / (a + root) : (root - a) / q;
        s.velocity.z() += k * F * b.inv_mass;
        s.omega += k * dw;
        double radius[kMaxContacts];
        for (int i = 0; i < c.n; ++i) radius[i] = pts.mu[i] * k * pn[i];
        Eigen::Vector2d ft[kMaxContacts];
        const SweepResult sr = solve_friction(b, pts, radius, ft, lever, speed);
        res.iterations += sr.sweeps;
        if (sr.dual) ++res.dual_solves;
        if (!sr.converged) ++res.corrections.pgs_unconverged;
        for (int i = 0; i < c.n; ++i) total[i] += Vec3(ft[i].x(), ft[i].y(), k * pn[i]);
      }
    }
  }

  // A point still approaching (rounding aside: < 1e-10 of the speeds involved): the restitution
  // tipped a neighbour into the floor, or a solve stopped short. One more plastic pass (a new
  // impact of those points, without restitution); failing that, a frictionless one (always
  // dissipative: it removes (u.n)^2 / 2 W_nn at each point), counted.
  const double speed_tol = 1e-10 * speed;
  const auto approaching = [&] {
    for (int i = 0; i < c.n; ++i)
      if (b.point_velocity(pts.r[i]).z() < -speed_tol) return true;
    return false;
  };
  for (int pass = 0; pass < 2 && approaching(); ++pass) {
    set_up_sweep_terms(geo);
    Points p2 = pts;
    if (pass == 1) {
      ++res.corrections.fallbacks;
      for (int i = 0; i < c.n; ++i) p2.mu[i] = 0.0;
    }
    for (int i = 0; i < c.n; ++i) {
      pn[i] = 0.0;
      pt[i].setZero();
    }
    const SweepResult sr = solve_plastic(b, p2, pn, pt, lever, speed);
    res.iterations += sr.sweeps;
    if (!sr.converged) ++res.corrections.pgs_unconverged;
    for (int i = 0; i < c.n; ++i) total[i] += Vec3(pt[i].x(), pt[i].y(), pn[i]);
  }

  // The energy assertion: by the argument above an impact cannot gain energy, so this scales back
  // only what rounding (or an unconverged solve) broke, and counts it.
  // E(lambda) - E0 = lambda a + lambda^2 q for the impulse scaled by lambda.
  double after = energy(s);
  if (after > E0 * (1.0 + 1e-12)) {
    const Vec3 dv = s.velocity - s0.velocity, dw = s.omega - s0.omega;
    const double a = m.mass * s0.velocity.dot(dv) + s0.omega.dot(Iw * dw);
    const double q = 0.5 * m.mass * dv.squaredNorm() + 0.5 * dw.dot(Iw * dw);
    const double lambda = (a < 0.0 && q > 0.0) ? std::min(1.0, -a / q) * (1.0 - 1e-12) : 0.0;
    s.velocity = s0.velocity + lambda * dv;
    s.omega = s0.omega + lambda * dw;
    for (int i = 0; i < c.n; ++i) total[i] *= lambda;
    ++res.corrections.energy_clamps;
    after = energy(s);
  }
  res.energy_after = after;
  res.normal_impulse = m.mass * (s.velocity.z() - s0.velocity.z());
  if (out) {
    out->n = c.n;
    for (int i = 0; i < c.n; ++i) {
      out->vertex[i] = c.vertex[i];
      out->P[i] = total[i];
    }
  }
  return res;
}

}  // namespace dicesim
