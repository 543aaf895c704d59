// The plastic impact at one point, exactly: the sticking impulse, else the sliding one from the
// direction condition (one_corner_sliding_newton, one_corner_sliding_reference; friction_impact.hpp).
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/friction_impact_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/atan.hpp"
#include "sim/illinois.hpp"

namespace dicesim {

namespace {

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

namespace friction_detail {

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

}  // namespace friction_detail

}  // namespace dicesim
