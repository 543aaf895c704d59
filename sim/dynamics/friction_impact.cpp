#include "sim/dynamics/friction_impact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/dynamics/contact.hpp"

namespace dicesim {
namespace {

Mat3 skew(const Vec3& r) {
  Mat3 X;
  X << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return X;
}

// The contact points of one solve: lever arms, materials and the compliance blocks.
struct Points {
  int n = 0;
  Vec3 r[kMaxContacts];
  double e[kMaxContacts], mu[kMaxContacts];
  double inv_wnn[kMaxContacts];              // 1 / W_nn
  Eigen::Matrix2d inv_wtt[kMaxContacts];     // (tangential 2x2 block of W)^-1
  Mat3 W0;                                   // full compliance of point 0 (single-contact law)
};

struct Body {
  double mass, inv_mass;
  Mat3 inv_inertia;  // world
  RigidState* s;
  void apply(const Vec3& r, const Vec3& P) const {
    s->velocity += P * inv_mass;
    s->omega += inv_inertia * r.cross(P);
  }
  Vec3 point_velocity(const Vec3& r) const { return s->velocity + s->omega.cross(r); }
};

Mat3 compliance(const Body& b, const Vec3& r) {
  const Mat3 X = skew(r);
  return b.inv_mass * Mat3::Identity() - X * b.inv_inertia * X;
}

// Projected Gauss-Seidel on the perfectly plastic frictional contact problem: at every point
// P_n >= 0, u_n >= 0, P_n u_n = 0, |P_t| <= mu P_n (the sticking impulse, else on the cone).
// Returns the normal impulses in `pn`.
void solve_plastic(const Body& b, const Points& pts, double pn[], Eigen::Vector2d pt[]) {
  constexpr int kMaxIterations = 200;
  for (int i = 0; i < pts.n; ++i) {
    pn[i] = 0.0;
    pt[i].setZero();
  }
  for (int it = 0; it < kMaxIterations; ++it) {
    double change = 0.0, total = 0.0;
    for (int i = 0; i < pts.n; ++i) {
      const Vec3& r = pts.r[i];
      Vec3 u = b.point_velocity(r);
      const double new_n = std::max(0.0, pn[i] - u.z() * pts.inv_wnn[i]);
      const double dn = new_n - pn[i];
      pn[i] = new_n;
      if (dn != 0.0) b.apply(r, Vec3(0.0, 0.0, dn));
      u = b.point_velocity(r);
      const Eigen::Vector2d slip(u.x(), u.y());
      Eigen::Vector2d t = pt[i] - pts.inv_wtt[i] * slip;
      const double limit = pts.mu[i] * pn[i];
      const double tn = t.norm();
      if (tn > limit) {
        // Sliding: Coulomb friction at the cone's edge, opposite to the slip (maximal dissipation).
        const double sn = slip.norm();
        t = sn > 0.0 ? Eigen::Vector2d(-limit * slip / sn) : Eigen::Vector2d(t * (limit / tn));
      }
      const Eigen::Vector2d dt = t - pt[i];
      pt[i] = t;
      if (dt.x() != 0.0 || dt.y() != 0.0) b.apply(r, Vec3(dt.x(), dt.y(), 0.0));
      change = std::max(change, std::abs(dn) + dt.norm());
      total += pn[i];
    }
    if (change <= 1e-14 * total || total == 0.0) break;
  }
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
        double lo = std::min(x0, x1), hi = std::max(x0, x1);
        Eval elo = x0 < x1 ? e0 : enext, eh = x0 < x1 ? enext : e0;
        // Illinois (regula falsi halving the stale end's weight): superlinear, never leaves
        // the bracket; a bisection step if an interior point leaves the valid set.
        double glo = elo.g, ghi = eh.g;
        int side = 0;
        bool valid = true;
        for (int it = 0; it < 200 && hi - lo > 1e-13 && elo.g != 0.0 && eh.g != 0.0; ++it) {
          double mid = hi - ghi * (hi - lo) / (ghi - glo);
          if (!(mid > lo && mid < hi)) mid = 0.5 * (lo + hi);
          Eval em = eval(mid);
          if (!em.ok) {
            mid = 0.5 * (lo + hi);
            em = eval(mid);
            if (!em.ok) {
              valid = false;  // the bracket holds an invalid stretch: look further
              break;
            }
          }
          if ((em.g > 0.0) == (elo.g > 0.0)) {
            if (mid == lo) break;
            lo = mid;
            elo = em;
            glo = em.g;
            if (side == -1) ghi *= 0.5;
            side = -1;
          } else {
            if (mid == hi) break;
            hi = mid;
            eh = em;
            ghi = em.g;
            if (side == 1) glo *= 0.5;
            side = 1;
          }
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

// The same problem for one point, exactly: the sticking impulse if it lies in the cone, else
// sliding: P = lambda (n + mu d) with the final slip -s d (s >= 0, maximal dissipation) and zero
// final normal velocity; d from two fixed-point iterations on its direction (the guess), then
// the angle root-finder above. Returns false (the caller falls back to the iterative solver)
// only for a jam.
bool solve_plastic_single(const Body& b, const Points& pts, double pn[], Eigen::Vector2d pt[]) {
  const Vec3& r = pts.r[0];
  const Vec3 u = b.point_velocity(r);
  pn[0] = 0.0;
  pt[0].setZero();
  if (u.z() >= 0.0) return true;  // separating: no impulse
  const Mat3 Winv = pts.W0.inverse();
  const Vec3 stick = -(Winv * u);
  const double mu = pts.mu[0];
  if (stick.z() >= 0.0 && std::hypot(stick.x(), stick.y()) <= mu * stick.z()) {
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
  const Mat3& W = pts.W0;
  for (int it = 0; it < 2; ++it) {
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
      const Vec3 P = lambda * dir;
      b.apply(r, P);
      pn[0] = P.z();
      pt[0] = Eigen::Vector2d(P.x(), P.y());
      return true;
    }
    d = nd;
  }
  // The fixed point converges slowly or cycles (it does where W couples slip and normal
  // strongly, ~15% of sliding impacts of Die 1): solve the same equations as a root in the
  // angle of d instead, from the last iterate.
  Vec3 P;
  if (!sliding_impulse_by_angle(W, u, mu, d, P)) return false;
  b.apply(r, P);
  pn[0] = P.z();
  pt[0] = Eigen::Vector2d(P.x(), P.y());
  return true;
}

}  // namespace

ContactSet touching_corners(const DieModel& m, const RigidState& s, double tol) {
  ContactSet c;
  double z[kMaxContacts];
  const int nv = m.vertex_count();
  for (int i = 0; i < nv; ++i) {
    const double zi = corner_height(m, s, i);
    if (zi > tol) continue;
    if (c.n < kMaxContacts) {
      z[c.n] = zi;
      c.vertex[c.n++] = i;
      continue;
    }
    int hi = 0;  // full: replace the highest if this one is lower
    for (int k = 1; k < c.n; ++k)
      if (z[k] > z[hi]) hi = k;
    if (zi < z[hi]) {
      z[hi] = zi;
      c.vertex[hi] = i;
    }
  }
  return c;
}

ImpactResult apply_friction_impact(const DieModel& m, RigidState& s, const ContactSet& c, bool restitution) {
  ImpactResult out;
  if (c.n == 0) return out;
  const RigidState s0 = s;
  const Mat3 Iw = world_inertia(m, s.R);
  Body b{m.mass, 1.0 / m.mass, s.R * m.principal_moments.cwiseInverse().asDiagonal() * s.R.transpose(), &s};
  Points pts;
  pts.n = c.n;
  for (int i = 0; i < c.n; ++i) {
    const int v = c.vertex[i];
    pts.r[i] = contact_point(m, s.R, v);
    pts.e[i] = m.vertex_restitution[v];
    pts.mu[i] = m.vertex_friction[v];
    const Mat3 W = compliance(b, pts.r[i]);
    if (i == 0) pts.W0 = W;
    pts.inv_wnn[i] = 1.0 / W(2, 2);
    pts.inv_wtt[i] = W.topLeftCorner<2, 2>().inverse();
  }
  const auto energy = [&](const RigidState& x) { return 0.5 * m.mass * x.velocity.squaredNorm() + 0.5 * x.omega.dot(Iw * x.omega); };
  out.energy_before = energy(s0);

  double pn[kMaxContacts];
  Eigen::Vector2d pt[kMaxContacts];
  if (c.n == 1 && solve_plastic_single(b, pts, pn, pt)) {
    // One point. Sticking fits the cone: Chatterjee-Ruina, P = P_I + e (P_I.n) n. Sliding: the
    // plastic sliding impulse of maximal dissipation times (1 + e), rather than CR's projection
    // of P^ onto the cone (which keeps the sticking normal impulse and can make even a plastic
    // impact rebound fast).
    if (restitution && pn[0] > 0.0 && pts.e[0] > 0.0) {
      const bool sliding = pt[0].norm() >= pts.mu[0] * pn[0] * (1.0 - 1e-12) && pts.mu[0] > 0.0;
      const Vec3 extra = sliding ? Vec3(pt[0].x(), pt[0].y(), pn[0]) : Vec3(0.0, 0.0, pn[0]);
      b.apply(pts.r[0], pts.e[0] * extra);
    }
  } else {
    solve_plastic(b, pts, pn, pt);  // (one point reaches here only if its exact solve failed)
    if (restitution) {
      bool same_e = true;
      for (int i = 1; i < c.n; ++i) same_e = same_e && pts.e[i] == pts.e[0];
      if (same_e) {
        // Poisson with one e: the restitution impulse is e times the compression impulse, whose
        // effect on the body is unique even where the split over the points is not (a face).
        s.velocity.z() += pts.e[0] * (s.velocity.z() - s0.velocity.z());
        double pz = 0.0;
        Vec3 moment = Vec3::Zero();
        for (int i = 0; i < c.n; ++i) {
          pz += pn[i];
          moment += pts.r[i].cross(Vec3(0.0, 0.0, pn[i]));
        }
        (void)pz;
        s.omega += pts.e[0] * (b.inv_inertia * moment);
      } else {
        for (int i = 0; i < c.n; ++i)
          if (pn[i] > 0.0 && pts.e[i] > 0.0) b.apply(pts.r[i], Vec3(0.0, 0.0, pts.e[i] * pn[i]));
      }
    }
  }

  // Energy guard: E(lambda) - E0 = lambda a + lambda^2 b for the impulse scaled by lambda.
  double after = energy(s);
  if (after > out.energy_before * (1.0 + 1e-13)) {  // above rounding (1e-13 relative)
    const Vec3 dv = s.velocity - s0.velocity, dw = s.omega - s0.omega;
    const double a = m.mass * s0.velocity.dot(dv) + s0.omega.dot(Iw * dw);
    const double q = 0.5 * m.mass * dv.squaredNorm() + 0.5 * dw.dot(Iw * dw);
    // (1 - 1e-12): the root itself, rounded, could sit a few ulps above E0.
    const double lambda = (a < 0.0 && q > 0.0) ? std::min(1.0, -a / q) * (1.0 - 1e-12) : 0.0;
    s.velocity = s0.velocity + lambda * dv;
    s.omega = s0.omega + lambda * dw;
    out.energy_clamped = true;
  }
  // A point still approaching (the energy guard scaled the impulse back, or the frictional solve
  // did not converge): stop it without friction, which is always dissipative (it removes
  // (u.n)^2 / 2 W_nn at each point).
  // (Rounding leaves |u_n| ~ 1e-16 of the speeds involved: that is not approaching.)
  const double speed_tol = 1e-12 * (s0.velocity.norm() + s0.omega.norm() * m.bounding_radius);
  bool approaching = false;
  for (int i = 0; i < c.n; ++i) approaching = approaching || b.point_velocity(pts.r[i]).z() < -speed_tol;
  if (approaching) {
    Points frictionless = pts;
    for (int i = 0; i < c.n; ++i) frictionless.mu[i] = 0.0;
    solve_plastic(b, frictionless, pn, pt);
  }
  after = energy(s);
  out.energy_after = after;
  out.normal_impulse = m.mass * (s.velocity.z() - s0.velocity.z());
  return out;
}

}  // namespace dicesim
