// The impact law's driver (friction_impact.hpp): apply_friction_impact sets the contact up, takes
// the compression phase (the one-point exact solve, the direct multi-point solves, else Gauss-
// Seidel), then restitution with its friction, and checks the energy of the result. The solves
// live in the friction_*.cpp files (sim/dynamics/README.md).
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/friction_impact_internal.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "sim/dynamics/contact.hpp"

namespace dicesim {
// friction_detail's names are brought in per function, never for the whole namespace: its Body
// would otherwise clash with dicesim::Body in a unity build (sim/CMakeLists.txt).
namespace friction_detail {
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
}  // namespace friction_detail

ImpactResult apply_friction_impact_at(const DieModel& m, RigidState& s, const ContactSet& c, const Vec3* r,
                                      bool restitution, const ContactImpulses* warm, ContactImpulses* out) {
  using namespace friction_detail;
  using friction_detail::Body;
  // (Body's own initialisation from the product, as apply_friction_impact's set-up has it.)
  const Body b0{m.mass, 1.0 / m.mass, s.R * m.principal_moments.cwiseInverse().asDiagonal() * s.R.transpose(), &s};
  ContactGeometry geo;
  set_up_geometry(m, b0, s.R, c, geo, r);
  return apply_friction_impact(m, s, c, restitution, warm, out, &geo);
}

ImpactResult apply_friction_impact(const DieModel& m, RigidState& s, const ContactSet& c, bool restitution,
                                   const ContactImpulses* warm, ContactImpulses* out, ContactGeometry* geometry,
                                   bool direct) {
  using namespace friction_detail;
  using friction_detail::Body;
  using friction_detail::SweepResult;
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
      Eigen::Vector2d gs_slip[2];  // the sweeps' final slips: the last attempt's start
      for (int i = 0; i < 2; ++i) {
        const Vec3 u = b.point_velocity(pts.r[i]);
        gs_slip[i] = Eigen::Vector2d(u.x(), u.y());
      }
      s.velocity = s0.velocity;
      s.omega = s0.omega;
      double qn[2];
      Eigen::Vector2d qt[2];
      if (solve_plastic_pair(b, Iw, pts, speed, lever, qn, qt, gs_slip)) {
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
