// FixedStepper's location of a new contact inside a step: the lowest new point over the step's
// free motion (lowest_new), the flat die's prediction of the shortened steps' miss
// (predicted_miss, from the support solve's derivative in the step length), and the root search
// on the corrected model (hermite_start, model_root).
#include "sim/dynamics/contact_stepper.hpp"

#include <cmath>
#include <limits>

#include "sim/dynamics/friction_impact.hpp"
#include "sim/illinois.hpp"

namespace dicesim {

double FixedStepper::lowest_new(const ContactSet& c, const Vec3& p, const Vec3& v, const TorqueFreeRotation& rot,
                                double t) const {
  // At t = 0 the step's own orientation, bit for bit as touching_corners saw it (so a corner left
  // out of the contact set is above the tolerance here too).
  if (m_->curved()) {  // a cylinder's rim points need the whole orientation
    const Mat3 R = t == 0.0 ? rot_start_ : rot.orientation(t);
    return p.z() + v.z() * t + curved_low(c, R);
  }
  return lowest_flat(c, p, v, t == 0.0 ? Vec3(rot_start_.row(2).transpose()) : rot.bottom_row(t), t);
}

namespace {

Mat3 skew_of(const Vec3& r) {
  Mat3 S;
  S << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return S;
}

// The derivative in the step length of a plastic support solve's impulses at K points, the solve's
// regime fixed (FixedStepper::predicted_miss): dP (3K) from one linear system, the rows of point i
// by its regime at the solved state: no impulse (dP_i = 0), sticking (its velocity stays 0) or
// sliding (normal velocity 0; P_t = -mu P_n s/|s| linearised). The pre-solve velocities change by
// -g e_z per unit length. W_ij = I/m - [r_i]x I_w^-1 [r_j]x, the points' compliance blocks. False
// if the system has no solution to 1e-9 (a sticking edge's or face's impulses are not unique, but
// then any solution gives the same motion, and the residual accepts it).
//
// Also the second derivative (dF2, dM2): the same matrix (the regime's equations are linear in
// the impulses but for a sliding point's friction direction d = s / |s|, s its slip after the
// solve), its right side the direction's curvature along the first derivative: with x the slip's
// rate, the sliding rows P_t + mu P_n d = 0 twice differentiated give
// A P'' = -mu (2 P'_n x_perp / |s| - P_n (2 (d.x) x_perp + |x_perp|^2 d) / |s|^2), x_perp = x - (d.x) d
// (the kick is linear in the step length, so the normal rows' right side is 0).
template <int K>
bool support_derivative(const ContactPoints& pts, const Mat3& Iinv, double mass, double g, const Vec3& v,
                        const Vec3& w, const ContactImpulses& P, double speed, Vec3& dF, Vec3& dM, Vec3& dF2,
                        Vec3& dM2) {
  constexpr int N = 3 * K;
  Eigen::Matrix<double, N, N> A = Eigen::Matrix<double, N, N>::Zero();
  Eigen::Matrix<double, N, 1> b = Eigen::Matrix<double, N, 1>::Zero();
  Mat3 S[K], T[K];
  for (int j = 0; j < K; ++j) {
    S[j] = skew_of(pts.r[j]);
    T[j] = Iinv * S[j];
  }
  const Mat3 Im = Mat3::Identity() / mass;
  for (int i = 0; i < K; ++i) {
    const Vec3& Pi = P.P[i];
    const Vec3 u = v + w.cross(pts.r[i]);  // the point's velocity after the solve
    const Eigen::Vector2d slip(u.x(), u.y());
    const double sn = slip.norm();
    if (!(Pi.z() > 0.0)) {
      A.template block<3, 3>(3 * i, 3 * i).setIdentity();
      continue;
    }
    b(3 * i + 2) = g;
    if (sn <= 1e-9 * speed) {
      for (int j = 0; j < K; ++j) A.template block<3, 3>(3 * i, 3 * j) = Im - S[i] * T[j];
      continue;
    }
    const Eigen::Vector2d dir = slip / sn;
    const double cf = pts.mu[i] * Pi.z() / sn;
    const Eigen::Matrix2d Pr = cf * (Eigen::Matrix2d::Identity() - dir * dir.transpose());
    for (int j = 0; j < K; ++j) {
      const Mat3 W = Im - S[i] * T[j];
      A.template block<1, 3>(3 * i + 2, 3 * j) = W.row(2);
      A.template block<2, 3>(3 * i, 3 * j) = Pr * W.template topRows<2>();
    }
    A(3 * i, 3 * i) += 1.0;
    A(3 * i + 1, 3 * i + 1) += 1.0;
    A(3 * i, 3 * i + 2) += pts.mu[i] * dir.x();
    A(3 * i + 1, 3 * i + 2) += pts.mu[i] * dir.y();
  }
  const Eigen::PartialPivLU<Eigen::Matrix<double, N, N>> lu = A.partialPivLu();
  const Eigen::Matrix<double, N, 1> x = lu.solve(b);
  if (!x.allFinite() || !((A * x - b).norm() <= 1e-9 * b.norm())) return false;
  dF.setZero();
  dM.setZero();
  for (int j = 0; j < K; ++j) {
    const Vec3 Pj = x.template segment<3>(3 * j);
    dF += Pj;
    dM += pts.r[j].cross(Pj);
  }
  const Vec3 dw = Iinv * dM;
  Eigen::Matrix<double, N, 1> b2 = Eigen::Matrix<double, N, 1>::Zero();
  for (int i = 0; i < K; ++i) {
    const Vec3& Pi = P.P[i];
    const Vec3 u = v + w.cross(pts.r[i]);
    const Eigen::Vector2d slip(u.x(), u.y());
    const double sn = slip.norm();
    if (!(Pi.z() > 0.0) || sn <= 1e-9 * speed) continue;  // no impulse, or sticking: linear
    const Vec3 du = dF / mass + dw.cross(pts.r[i]);
    const Eigen::Vector2d dir = slip / sn, xs(du.x(), du.y());
    const double dx = dir.dot(xs);
    const Eigen::Vector2d xp = xs - dx * dir;
    const Eigen::Vector2d r2 =
        -pts.mu[i] * (2.0 * x(3 * i + 2) * xp / sn - Pi.z() * (2.0 * dx * xp + xp.squaredNorm() * dir) / (sn * sn));
    b2(3 * i) = r2.x();
    b2(3 * i + 1) = r2.y();
  }
  dF2.setZero();
  dM2.setZero();
  const Eigen::Matrix<double, N, 1> y = lu.solve(b2);
  if (!y.allFinite()) return true;
  for (int j = 0; j < K; ++j) {
    const Vec3 Pj = y.template segment<3>(3 * j);
    dF2 += Pj;
    dM2 += pts.r[j].cross(Pj);
  }
  return true;
}

}  // namespace

double FixedStepper::predicted_miss(const ContactSet& c, const Vec3& r) {
  // The model (model_G) moves the full step's free motion by what a shorter gravity kick alone
  // changes; but with corners in contact the support solve absorbs part of the kick, so the
  // shortened step's motion after its solve differs from the model's to first order in (h - d):
  // G(d) - model_G(d) = -d (h - d) [v'_z + g + (w' x r(d/2))_z] + O(d (h - d)^2), v' and w' the
  // derivatives in the step length of the velocities after the solve, r(d/2) the arriving
  // corner's lever half-way (its lever at the start turned by the full step's spin, to first
  // order: the miss's rate in t). v' and w' come from the full step's solve linearised with its
  // regime fixed (support_derivative). Only a prediction of the first trial's length: every trial
  // is still a whole step, accepted only within the touch tolerance, and the search goes on from
  // the misses it measures. 0 (the plain model) when the linearisation has no solution. r: the
  // arriving corner's lever at the step's start.
  const DieModel& m = *m_;
  const int k = c.n;
  // (geo_ is the start's set-up: a fixed step's solve fills it, a leapfrog step's middle solve does not, so
  // a leapfrog step without an impact at its start has none: the plain model then.)
  if (m.curved() || k == 0 || k > 4 || a_.next.n != k || !geo_.valid) return 0.0;
  const double g = m.gravity;
  // The solve sees the pre-solve normal velocity shifted by the kick g d and the held corners'
  // rise b(d) (try_step): per unit step length g + b'. With no depth at the start b is linear in
  // d (b = d k min(a_n / 2, g)), so b' = b(h) / h exactly for the full step's branch k.
  const double kick_rate = kick_g_ + (start_shallow_ > 0.0 ? 0.0 : full_bias_ / h_);
  const double speed = full_v_.norm() + full_w_.norm() * m.bounding_radius + 1e-2 * std::sqrt(g * m.bounding_radius);
  Vec3 dF, dM, dF2, dM2;
  bool ok = false;
  switch (k) {
    case 1: ok = support_derivative<1>(geo_.pts, geo_.inv_inertia, m.mass, kick_rate, full_v_, full_w_, a_.next, speed, dF, dM, dF2, dM2); break;
    case 2: ok = support_derivative<2>(geo_.pts, geo_.inv_inertia, m.mass, kick_rate, full_v_, full_w_, a_.next, speed, dF, dM, dF2, dM2); break;
    case 3: ok = support_derivative<3>(geo_.pts, geo_.inv_inertia, m.mass, kick_rate, full_v_, full_w_, a_.next, speed, dF, dM, dF2, dM2); break;
    default: ok = support_derivative<4>(geo_.pts, geo_.inv_inertia, m.mass, kick_rate, full_v_, full_w_, a_.next, speed, dF, dM, dF2, dM2); break;
  }
  if (!ok) return 0.0;
  const Vec3 dw = geo_.inv_inertia * dM;
  const double miss = -(dF.z() / m.mass) - dw.cross(r).z();
  // The rotation's part to second order in t: the trial's orientation differs by dtheta(t) =
  // t dw + t^2 / 2 (w x dw + dalpha) (per unit of -(h - d)), the lever turns as r + t w x r, so the
  // height's t^2 term is (dw x (w x r) + (w x dw) x r / 2 + dalpha x r / 2)_z = (dw x (w x r) + w x
  // (dw x r) + dalpha x r)_z / 2 (Jacobi), dalpha the torque-free acceleration's change,
  // -I_w^-1 (dw x L + w x I_w dw), L = I_w w.
  const Vec3& w = full_w_;
  const Vec3 L = geo_.Iw * w;
  const Vec3 dalpha = -(geo_.inv_inertia * (dw.cross(L) + w.cross(geo_.Iw * dw)));
  const double rate = -0.5 * (dw.cross(w.cross(r)) + w.cross(dw.cross(r)) + dalpha.cross(r)).z();
  // The solve's second order: G - model_G gains d (h - d)^2 (F''_z / m + (w'' x r)_z) / 2, i.e.
  // the coefficient c2 (h - t) on top of miss + rate t: folded into both.
  const double c2 = 0.5 * (dF2.z() / m.mass + (geo_.inv_inertia * dM2).cross(r).z());
  if (!std::isfinite(miss) || !std::isfinite(rate) || !std::isfinite(c2)) return 0.0;
  miss_rate_ = rate - c2;
  return miss + c2 * h_;
}

double FixedStepper::hermite_start(double miss, double lo, double hi, double x) const {
  // The corrected model with the arriving corner's height about the COM, q(t) = (R(t) r)_z, replaced
  // by its cubic Hermite interpolant on [0, h] from the full step's own ends (q and its rate
  // (w x R r)_z at t = 0 and t = h: no evaluation of the rotation); every other term of the
  // model is a polynomial of degree <= 3 and kept exactly. Interpolation error about h^4 q4 / 384,
  // q4 the fourth derivative, ~|w|^4 r: ~1e-13 m for a die rocking at 10 rad/s with 1 ms steps,
  // so the root of this cubic starts model_root's Newton within ~1e-12 s of the model's root (one
  // evaluation then meets the tolerance). Newton on the cubic, kept in (lo, hi); x, the secant
  // point, if it leaves.
  // The cubic in powers of t: base + v t + H(t) + g (h - t) t + (miss + rate t) t (h - t).
  const double h = h_, g = kick_g_;
  const double q0 = hq_[0], p0 = hq_[1], q1 = hq_[2], p1 = hq_[3];
  // The kick's powers of t (model_kick): g h t - g t^2, or leapfrog's (g h + model_slope_) t - g t^2 / 2.
  const double k1 = leapfrog() ? g * h + model_slope_ : g * h;
  const double k2 = leapfrog() ? 0.5 * g : g;
  const double c0 = full_p_.z() - m_->rounding + q0;
  const double c1 = full_v_.z() + p0 + k1 + miss * h;
  const double c2 = (3.0 * (q1 - q0) / h - 2.0 * p0 - p1) / h - k2 - miss + miss_rate_ * h;
  const double c3 = ((2.0 * (q0 - q1) / h + p0 + p1) / h) / h - miss_rate_;
  const auto cubic = [&](double t, double& df) {
    df = c1 + t * (2.0 * c2 + 3.0 * c3 * t);
    return c0 + t * (c1 + t * (c2 + t * c3));
  };
  // The cubic's own bracket (its values at lo and hi are the model's to the interpolation error),
  // then Newton kept in it, bisecting when a step leaves it (a grazing arrival: the slope nearly
  // 0), until the cubic is within a tenth of model_root's tolerance. A polynomial evaluation costs
  // a few operations against a rotation's hundreds.
  const double tol = 1e-4 * touch_tol_;
  double df = 0.0;
  double a = lo, b = hi;
  if (!(cubic(a, df) > 0.0 && cubic(b, df) <= 0.0)) return x;
  double t = x;
  for (int it = 0; it < 40; ++it) {
    const double f = cubic(t, df);
    if (std::abs(f) <= tol) break;
    (f > 0.0 ? a : b) = t;
    if (!(b - a > 1e-15 * h)) break;
    double next = t - f / df;
    if (!(next > a && next < b)) next = 0.5 * (a + b);
    t = next;
  }
  return t;
}

double FixedStepper::model_root(const ContactSet& c, double miss, double lo, double hi, double f_lo, double f_hi,
                                double& g_model) const {
  if (!m_->curved()) {
    // Newton on the corrected model f(t) = lowest(t) + g (h - t) t + miss t (h - t), its slope
    // the lowest corner's height rate (exact: the free motion's own derivative) plus
    // (g + miss)(h - 2t); from the bracket's secant point, every iterate kept in the bracket (a
    // Newton step that leaves it, or a kink where the lowest corner changes, bisects). The last
    // step is taken without evaluating where it lands when its own error bound, |f''| delta^2 / 2
    // with |f''| <= (w_max^2 + alpha_max) r + 2 |g + miss|, is already below the tolerance (the
    // model's value there from the slope). The same tolerance as Illinois's, 1e-3 of the touch
    // tolerance; fewer evaluations.
    const TorqueFreeRotation& rot = *full_rot_;
    const double curvature =
        (rot.max_omega() * rot.max_omega() + rot.max_alpha()) * m_->bounding_radius + 2.0 * std::abs(kick_g_ + miss) +
        6.0 * std::abs(miss_rate_) * h_;
    const double tol = 1e-3 * touch_tol_;
    double x = hi - f_hi * (hi - lo) / (f_hi - f_lo);
    if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
    if (hermite_) x = hermite_start(miss, lo, hi, x);
    for (int it = 0; it < 100; ++it) {
      Vec3 z_rate;
      const Vec3 z_row = rot.bottom_row(x, z_rate);
      double slope = 0.0;
      double kick_slope;
      g_model = lowest_flat(c, full_p_, full_v_, z_row, z_rate, x, slope) + model_kick(x, kick_slope);
      const double f = corrected(g_model, miss, x);
      if (std::abs(f) <= tol) break;
      (f > 0.0 ? lo : hi) = x;
      if (!(hi - lo > 1e-15 * h_)) break;
      const double dg = slope + kick_slope;  // the model's own slope
      const double delta = -f / (dg + (miss + miss_rate_ * x) * (h_ - 2.0 * x) + miss_rate_ * x * (h_ - x));
      const double next = x + delta;
      if (!(next > lo && next < hi)) {
        x = 0.5 * (lo + hi);
        continue;
      }
      if (0.5 * curvature * delta * delta <= tol) {
        g_model += delta * dg;
        return next;
      }
      x = next;
    }
    return x;
  }
  Illinois br{lo, f_lo, hi, f_hi};
  double mid = hi;
  for (int it = 0; it < 100 && br.hi - br.lo > 1e-15 * h_; ++it) {
    mid = br.next();
    g_model = model_G(c, mid);
    const double f = corrected(g_model, miss, mid);
    if (std::abs(f) <= 1e-3 * touch_tol_) break;
    br.update(mid, f, /*lo_side=*/f > 0.0);
  }
  return mid;
}

}  // namespace dicesim
