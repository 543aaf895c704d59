// Semismooth Newton on the Alart-Curnier equations: the finish of a Gauss-Seidel solve left
// unconverged (polish_newton).
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/friction_impact_internal.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/QR>

namespace dicesim {

namespace friction_detail {

namespace {

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

}  // namespace

// Newton with rho_i = 3 / tr W_ii, else (it can stall at a kink of Phi where F has a part outside
// the range of the generalised Jacobian; which kink depends on rho) with rho / 8, then 8 rho, each
// from the Gauss-Seidel iterate.
NewtonResult polish_newton(const Body& b, const Points& pts, double pn[], Eigen::Vector2d pt[], double radius,
                           double speed, const double* fixed_radius) {
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

}  // namespace friction_detail

}  // namespace dicesim
