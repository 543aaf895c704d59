// Torque-free rotation in closed form.
//
// Notation: a_i = 1/I_i (inverse principal moments), L_b = R^T L (body angular momentum),
// 2E = sum a_i L_b,i^2 (twice the kinetic energy). Body-frame Euler equations in terms of L_b:
//   dL_b/dt = L_b x omega_b,  omega_b = diag(a) L_b,
// i.e. dL_i/dt = L_j L_k (a_k - a_j) for (i, j, k) cyclic.
//
// Symmetric top (Landau-Lifshitz §33, §35): L_a is constant, the body spins about e_a relative to
// a frame that precesses about L at |L| a_perp: R(t) = Rot(L^, |L| a_perp t) R0 Rot(e_a, (a_a - a_perp) L_a t).
//
// Asymmetric top: Jacobi's solution (Landau-Lifshitz §37). Name the axes
//   d: the axis L_b circles: the largest moment when L^2 > 2E I_m, the smallest when L^2 < 2E I_m,
//   m: the middle moment,  c: the remaining one.
// Then, with u = lambda t + u0 and modulus k,
//   L_c = P cn(u, k),  L_m = Q sn(u, k),  L_d = D dn(u, k),
//   P^2 = (2E - a_d L^2)/(a_c - a_d),  D^2 = (a_c L^2 - 2E)/(a_c - a_d),  Q = P q,
//   k^2 = (a_c - a_m)(2E - a_d L^2) / ((a_m - a_d)(a_c L^2 - 2E)),
//   lambda = |D| sqrt((a_d - a_m)(a_d - a_c)),  q = s sign(D) (a_c - a_d) / sqrt((a_d - a_m)(a_d - a_c)),
// where s = +1 if (c, m, d) is a cyclic order of the axes and -1 otherwise (these signs follow from
// substituting the ansatz into the Euler equations). Every small quantity above is formed from
// differences a_i - a_j = (I_j - I_i)/(I_i I_j) and sums of same-sign terms, never by cancellation,
// so k -> 0 (nearly symmetric body) and k -> 1 (near the separatrix) keep full relative accuracy.
//
// Orientation: relabel the body axes cyclically as (x, y, z = d) (right-handed). With Euler angles
// about L (Landau-Lifshitz §35): L_b = |L| (sin th sin psi, sin th cos psi, cos th) in (x, y, z), and
//   d phi/dt = |L| (a_x L_x^2 + a_y L_y^2) / (L_x^2 + L_y^2) = |L| (a_d + (a_c - a_d) / (1 + n' sn^2 u)),
// with the constant n' = (a_c - a_m)/(a_m - a_d) (the P, D, k above make the ratio state independent).
// Integrating: phi(t) - phi(0) = |L| a_c t - |L| (a_c - a_d)/lambda (f(u) - f(u0)), where
//   f(u) = int_0^u n' sn^2/(1 + n' sn^2) du = u - Pi(-n'; am u | k)
//        = (n'/3) sn^3 R_J(cn^2, dn^2, 1, 1 + n' sn^2)          for |u| <= K  (Carlson's form),
// and f(u + 2K j) = f(u) + j f(2K) unwraps it over whole half periods so phi is continuous for all t.
// R(t) = F Rz(phi(t) - phi(0)) B(t), where B(t) (body -> frame with z along L_b) holds the angles
// theta and psi, and the fixed world frame F = R0 B(0)^T makes R(0) = R0 to rounding.
//
// sn, cn, dn come from the descending Landen transformation (A&S 16.12) fed with k^2 and k'^2
// separately, not from boost::math::jacobi_elliptic: that takes the modulus k alone, so k' is lost
// once k' < 1e-8 (k rounds to 1), e.g. a die spun about its middle axis with a 1e-7 perturbation
// would never flip. The ladder depends on k only, so it is built once and each call costs one
// sincos and a few divisions. The separatrix itself (k' = 0 exactly) uses sn = tanh, cn = dn = sech.
#include "sim/dynamics/torque_free.hpp"

#include "sim/atan.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>

#include <boost/math/policies/policy.hpp>
#include <boost/math/special_functions/ellint_rf.hpp>

#include "sim/sincos.hpp"

namespace dicesim {
namespace {

// Double precision evaluation: Boost's default promotes double arguments to long double (slower,
// and needless at these well-conditioned arguments). Arguments are valid by construction.
using CarlsonPolicy = boost::math::policies::policy<boost::math::policies::promote_double<false>>;

double carlson_rf(double x, double y, double z) { return boost::math::ellint_rf(x, y, z, CarlsonPolicy()); }

// R_J(x, y, 1, p) for the precession integral on the hot path, where x = cn^2, y = dn^2 <= 1 <= p.
// Carlson's duplication algorithm (Carlson 1995; DLMF 19.36.ii), the same method as Boost's
// ellint_rj, specialised to these arguments: p >= x, y, z makes every E_m >= 0, so each
// R_C(1, 1 + E_m) is atan(sqrt E)/sqrt E, and once E_m is small (it falls ~64x per step) its series
// replaces the atan. Compared against Boost over this argument range to a few ulps.
double carlson_rj_precession(double x, double y, double p) {
  double z = 1.0;
  const double A0 = (x + y + z + 2.0 * p) / 5.0;
  // Duplication stops once 4^-m Q < A_m, Q = (eps/5)^(-1/8) max|A0 - arg|: the 5th-order series is
  // then exact to rounding (Boost's criterion, eps = 2^-52).
  constexpr double kStop = 110.7;  // (2^-52 / 5)^(-1/8) = 110.68
  const double Q = kStop * std::max({std::abs(A0 - x), std::abs(A0 - y), std::abs(A0 - z), std::abs(A0 - p)});
  double A = A0, delta = (p - x) * (p - y) * (p - z), scale = 1.0, rc_sum = 0.0;
  const double x0 = x, y0 = y, z0 = z;
  for (int iteration = 0; iteration < 64; ++iteration) {
    const double rx = std::sqrt(x), ry = std::sqrt(y), rz = std::sqrt(z), rp = std::sqrt(p);
    const double D = (rp + rx) * (rp + ry) * (rp + rz);
    const double E = delta / (D * D);
    // R_C(1, 1 + E) = atan(sqrt E) / sqrt E = 1 - E/3 + E^2/5 - ...
    double rc;
    if (E < 2e-3) {
      rc = 1.0 + E * (-1.0 / 3 + E * (1.0 / 5 + E * (-1.0 / 7 + E * (1.0 / 9 + E * (-1.0 / 11 + E / 13)))));
    } else {
      const double rE = std::sqrt(E);
      rc = atan_fixed(rE) / rE;  // not libm's: the same bits on every CPU (sim/atan.hpp)
    }
    rc_sum += scale / D * rc;
    const double lambda = rx * ry + rx * rz + ry * rz;
    A = (A + lambda) / 4.0;
    scale /= 4.0;
    if (scale * Q < A) break;
    x = (x + lambda) / 4.0;
    y = (y + lambda) / 4.0;
    z = (z + lambda) / 4.0;
    p = (p + lambda) / 4.0;
    delta /= 64.0;
  }
  const double X = scale * (A0 - x0) / A, Y = scale * (A0 - y0) / A, Z = scale * (A0 - z0) / A;
  const double P = -(X + Y + Z) / 2.0;
  const double E2 = X * Y + X * Z + Y * Z - 3.0 * P * P;
  const double E3 = X * Y * Z + 2.0 * E2 * P + 4.0 * P * P * P;
  const double E4 = (2.0 * X * Y * Z + E2 * P + 3.0 * P * P * P) * P;
  const double E5 = X * Y * Z * P * P;
  const double series = 1.0 - 3.0 * E2 / 14.0 + E3 / 6.0 + 9.0 * E2 * E2 / 88.0 - 3.0 * E4 / 22.0 -
                        9.0 * E2 * E3 / 52.0 + 3.0 * E5 / 26.0 - E2 * E2 * E2 / 16.0 + 3.0 * E3 * E3 / 40.0 +
                        3.0 * E2 * E4 / 20.0 + 45.0 * E2 * E2 * E3 / 272.0 - 9.0 * (E3 * E4 + E2 * E5) / 68.0;
  return scale / (A * std::sqrt(A)) * series + 6.0 * rc_sum;
}

constexpr double kSymmetricTolerance = 1e-12;
// Landen descent stops once k_n^2 is below this: sn = sin, cn = cos, dn = 1 to within rounding.
constexpr double kNegligibleParameter = 1e-18;
// The bounds add a relative margin and an absolute one on the scale a_max |L| |omega|_max, far
// above the rounding of any evaluation of the motion and still tight for contact advancement.
constexpr double kBoundMargin = 1e-10;

bool nearly_equal(double a, double b) {
  return std::abs(a - b) <= kSymmetricTolerance * std::max(std::abs(a), std::abs(b));
}

// a_i - a_j = 1/I_i - 1/I_j without cancellation.
double inv_diff(const Vec3& I, int i, int j) { return (I[j] - I[i]) / (I[i] * I[j]); }

double sq(double x) { return x * x; }

}  // namespace

bool is_symmetric_top(const Vec3& moments) {
  return nearly_equal(moments[0], moments[1]) || nearly_equal(moments[1], moments[2]) ||
         nearly_equal(moments[0], moments[2]);
}

TorqueFreeRotation::Moments::Moments(const Vec3& moments) : I(moments) {
  const bool e01 = nearly_equal(I[0], I[1]), e12 = nearly_equal(I[1], I[2]), e02 = nearly_equal(I[0], I[2]);
  if (!(e01 || e12 || e02)) {  // not is_symmetric_top(I)
    general = true;
    return;
  }
  const Vec3 a = I.cwiseInverse();
  if (int(e01) + int(e12) + int(e02) >= 2) {
    // A sphere (all three agree): pure rotation about L at |L|/I; the axis choice is immaterial.
    const double a_mean = a.sum() / 3.0;
    axis = 2, inv_I_axis = a_mean, inv_I_perp = a_mean;
  } else if (e01) {
    axis = 2, inv_I_axis = a[2], inv_I_perp = 0.5 * (a[0] + a[1]);
  } else if (e12) {
    axis = 0, inv_I_axis = a[0], inv_I_perp = 0.5 * (a[1] + a[2]);
  } else {
    axis = 1, inv_I_axis = a[1], inv_I_perp = 0.5 * (a[0] + a[2]);
  }
  p = (axis + 1) % 3;
  q = (axis + 2) % 3;
}

TorqueFreeRotation::TorqueFreeRotation(const Moments& moments, const Mat3& R0, const Vec3& L_world, bool bounds)
    : I_(moments.I), R0_(R0), L_(L_world) {
  if (L_.squaredNorm() == 0.0) {  // zero, or so small that |L|^2 underflows (omega ~ 0 anyway)
    kind_ = Kind::Still;
    return;
  }
  const Vec3 L_body = R0_.transpose() * L_;
  if (moments.general) {
    kind_ = Kind::General;
    init_general(L_body, bounds);
    return;
  }
  kind_ = Kind::SymmetricTop;
  init_symmetric(moments.axis, moments.p, moments.q, moments.inv_I_axis, moments.inv_I_perp, L_body, bounds);
}

void TorqueFreeRotation::init_symmetric(int axis, int p, int q, double inv_I_axis, double inv_I_perp,
                                        const Vec3& L_body, bool bounds) {
  Symmetric& s = sym_;
  s.axis = axis;
  s.p = p;
  s.q = q;
  const double L_norm = L_.norm();
  const Vec3 L_hat = L_ / L_norm;
  s.precession_rate = L_norm * inv_I_perp;
  s.spin_rate = (inv_I_axis - inv_I_perp) * L_body[axis];
  s.inv_I_perp = inv_I_perp;
  // Rodrigues: Rot(n, alpha) = n n^T + cos(alpha) (1 - n n^T) + sin(alpha) [n]x, applied to R0 once here.
  s.along = L_hat * (L_hat.transpose() * R0_);
  s.across = R0_ - s.along;
  for (int j = 0; j < 3; ++j) s.cross.col(j) = L_hat.cross(R0_.col(j));  // [L^]x R0
  if (!bounds) return;

  // |omega| and |alpha| are constant in regular precession: omega_world = a_perp L + spin_rate R e_a,
  // d(R e_a)/dt = a_perp L x R e_a, so |alpha| = |spin_rate| a_perp |L x e_a| = |spin_rate| a_perp L_perp.
  const double L_axis = L_body[axis];
  const double L_perp = std::sqrt(sq(L_body[s.p]) + sq(L_body[s.q]));
  const double omega = std::sqrt(sq(inv_I_perp * L_perp) + sq(inv_I_axis * L_axis));
  const double alpha = std::abs(s.spin_rate) * inv_I_perp * L_perp;
  const double a_max = 1.0 / I_.minCoeff();  // = max_i 1/I_i exactly: division is monotone
  max_omega_ = omega * (1.0 + kBoundMargin);
  max_alpha_ = alpha * (1.0 + kBoundMargin) + kBoundMargin * a_max * L_norm * max_omega_;
}

void TorqueFreeRotation::init_general(const Vec3& L_body, bool bounds) {
  General& g = gen_;
  g.steady = false;
  g.inv_I = I_.cwiseInverse();
  const Vec3& a = g.inv_I;
  const double L_norm = L_.norm();

  // A steady rotation about a principal axis (exactly): regular precession with a_perp = a_i is exact.
  for (int i = 0; i < 3; ++i) {
    if (L_body[(i + 1) % 3] == 0.0 && L_body[(i + 2) % 3] == 0.0) {
      g.steady = true;
      init_symmetric(i, (i + 1) % 3, (i + 2) % 3, a[i], a[i], L_body, bounds);
      return;
    }
  }

  int lo = 0, hi = 0;
  for (int i = 1; i < 3; ++i) {
    if (I_[i] < I_[lo]) lo = i;
    if (I_[i] > I_[hi]) hi = i;
  }
  const int mid = 3 - lo - hi;
  // Z = a_m L^2 - 2E, formed from differences: its sign picks the axis L_b circles.
  const double Z = inv_diff(I_, mid, lo) * sq(L_body[lo]) + inv_diff(I_, mid, hi) * sq(L_body[hi]);
  const bool about_largest = Z > 0.0 || (Z == 0.0 && L_body[hi] != 0.0);
  g.separatrix = Z == 0.0;
  g.c = about_largest ? lo : hi;
  g.m = mid;
  g.d = about_largest ? hi : lo;
  g.x = (g.d + 1) % 3;
  g.y = (g.d + 2) % 3;
  const int c = g.c, m = g.m, d = g.d;
  const double s = (c == g.x) ? 1.0 : -1.0;  // +1 iff (c, m, d) is cyclic

  const double a_cd = inv_diff(I_, c, d), a_cm = inv_diff(I_, c, m), a_md = inv_diff(I_, m, d);
  const double Lc0 = L_body[c], Lm0 = L_body[m], Ld0 = L_body[d];
  const double X = a_cd * sq(Lc0) + a_md * sq(Lm0);  // 2E - a_d L^2
  const double Y = a_cm * sq(Lm0) + a_cd * sq(Ld0);  // a_c L^2 - 2E
  const double P2 = X / a_cd, D2 = Y / a_cd;
  if (g.separatrix) {
    g.k2 = 1.0;
    g.kc2 = 0.0;
  } else {
    g.k2 = std::clamp(a_cm * X / (a_md * Y), 0.0, 1.0);
    g.kc2 = std::clamp(Z * a_cd / (a_md * Y), 0.0, 1.0);
  }
  const double root = std::sqrt(a_md * a_cd);  // sqrt((a_d - a_m)(a_d - a_c)), the factors share a sign
  g.D = std::copysign(std::sqrt(D2), Ld0);
  g.lambda = std::abs(g.D) * root;
  g.q_ratio = s * std::copysign(1.0, g.D) * a_cd / root;
  g.n_prime = a_cm / a_md;
  g.phi_rate = L_norm * a[c];
  g.phi_coeff = L_norm * a_cd / g.lambda;

  if (g.separatrix) {
    // k = 1: sn = tanh, cn = dn = sech never change sign, so L_c keeps the sign of P.
    g.P = std::copysign(std::sqrt(P2), Lc0);
    g.sign_P = g.P < 0.0 ? -1.0 : 1.0;
    g.Q = g.P * g.q_ratio;
    // tanh(u0) = L_m0 / Q and sech(u0) = |(L_c0, L_d0)| / |(P, D)|, so sinh(u0) = tanh / sech.
    const double sech0 = std::sqrt((sq(Lc0) + sq(Ld0)) / (P2 + D2));
    g.u0 = std::asinh(Lm0 / g.Q / sech0);
  } else {
    g.P = std::sqrt(P2);
    g.sign_P = 1.0;
    g.Q = g.P * g.q_ratio;
    // Descending Landen transformation (Abramowitz & Stegun 16.12) with both k^2 and k'^2 carried
    // exactly: k_{n+1} = k_n^2 / (1 + k'_n)^2, k'_{n+1} = 2 sqrt(k'_n) / (1 + k'_n), and
    // 1 - k_{n+1} = 2 k'_n / (1 + k'_n) (used in dn).
    double m_n = g.k2, kc_n = std::sqrt(g.kc2), scale = 1.0;
    int levels = 0;
    while (m_n > kNegligibleParameter && levels < kMaxLandenLevels) {
      const double one_plus_kc = 1.0 + kc_n;
      const double k_next = m_n / sq(one_plus_kc);
      g.landen_k[levels] = k_next;
      g.landen_one_minus_k[levels] = 2.0 * kc_n / one_plus_kc;
      kc_n = 2.0 * std::sqrt(kc_n) / one_plus_kc;
      m_n = sq(k_next);
      scale /= 1.0 + k_next;
      ++levels;
    }
    g.landen_levels = levels;
    g.landen_scale = scale;
    g.two_K = kPi / scale;  // sn(u) = sin(u * scale) at the bottom, so am(K) = pi/2 there
    g.inv_two_K = scale / kPi;
    // Precession integral over a half period: f(K) = (n'/3) R_J(0, k'^2, 1, 1 + n').
    g.two_fK = 2.0 * g.n_prime / 3.0 * carlson_rj_precession(0.0, g.kc2, 1.0 + g.n_prime);
    // Initial amplitude: (sn u0, cn u0) is the direction of (L_m0 / q, L_c0) (P > 0), defined
    // even when P = 0; then u0 = F(am u0 | k) by Carlson's form sn R_F(cn^2, dn^2, 1).
    double sn0 = Lm0 / g.q_ratio, cn0 = Lc0;
    const double norm = std::sqrt(sq(sn0) + sq(cn0));
    if (norm > 0.0) {
      sn0 /= norm;
      cn0 /= norm;
    } else {
      sn0 = 0.0;
      cn0 = 1.0;
    }
    const double F_reduced = sn0 * carlson_rf(sq(cn0), sq(cn0) + g.kc2 * sq(sn0), 1.0);
    // |am| > pi/2: F(am) = 2K - F(pi - am) (mod 4K, the period of sn and cn).
    g.u0 = cn0 >= 0.0 ? F_reduced : g.two_K - F_reduced;
  }
  const JacobiState start = jacobi_state(0.0);
  g.f0 = start.f;

  // F = R0 B(0)^T: general_orientation at t = 0 then returns R0 B(0)^T B(0) = R0.
  g.frame = Mat3::Identity();
  const Mat3 B0 = general_orientation(start, 0.0, nullptr);  // = B(0) while frame is the identity
  g.frame = R0_ * B0.transpose();

  if (!bounds) return;
  // Bounds. Along the orbit s = sn^2 runs over [0, 1] and L_c^2 = P^2 (1 - s), L_m^2 = Q^2 s,
  // L_d^2 = D^2 (k'^2 + k^2 (1 - s)). |omega|^2 is linear in s: its sup is at an end.
  const double Q2 = sq(g.Q);
  const double w2_s0 = sq(a[c]) * P2 + sq(a[d]) * D2;
  const double w2_s1 = sq(a[m]) * Q2 + sq(a[d]) * D2 * g.kc2;
  const double omega = std::sqrt(std::max(w2_s0, w2_s1));
  // |alpha|^2 = sum_k a_k^2 (a_i - a_j)^2 L_i^2 L_j^2 (from alpha_b = I^-1 (L_b x omega_b)) is
  // quadratic in s: the sup is at an end or at the vertex. Each candidate is evaluated as a sum of
  // non-negative products, so it is accurate even when alpha is tiny.
  const double A_cm = sq(a[d] * a_cm), A_md = sq(a[c] * a_md), A_cd = sq(a[m] * a_cd);
  auto alpha2_at = [&](double s_) {
    const double Lc2 = P2 * (1.0 - s_), Lm2 = Q2 * s_, Ld2 = D2 * (g.kc2 + g.k2 * (1.0 - s_));
    return A_cm * Lc2 * Lm2 + A_md * Lm2 * Ld2 + A_cd * Lc2 * Ld2;
  };
  double alpha2 = std::max(alpha2_at(0.0), alpha2_at(1.0));
  const double g1 = A_cm * P2 * Q2 + A_md * Q2 * D2 - A_cd * P2 * D2 * (1.0 + g.k2);
  const double g2 = -A_cm * P2 * Q2 - A_md * Q2 * D2 * g.k2 + A_cd * P2 * D2 * g.k2;
  if (g2 < 0.0) {
    const double s_star = -g1 / (2.0 * g2);
    if (s_star > 0.0 && s_star < 1.0) alpha2 = std::max(alpha2, alpha2_at(s_star));
  }
  max_omega_ = omega * (1.0 + kBoundMargin);
  max_alpha_ = std::sqrt(alpha2) * (1.0 + kBoundMargin) + kBoundMargin * a.maxCoeff() * L_norm * max_omega_;
}

TorqueFreeRotation::JacobiState TorqueFreeRotation::jacobi_state(double t) const {
  const General& g = gen_;
  const double u = g.lambda * t + g.u0;
  JacobiState js;
  if (g.separatrix) {
    // k = 1: f(u) = u - int du / (1 + n' tanh^2 u) = (n' u - sqrt(n') atan(sqrt(n') tanh u)) / (1 + n').
    js.sn = std::tanh(u);
    js.cn = 1.0 / std::cosh(u);  // 0 once cosh overflows: the limit, no NaN
    js.dn = js.cn;
    const double rn = std::sqrt(g.n_prime);
    js.f = (g.n_prime * u - rn * std::atan(rn * js.sn)) / (1.0 + g.n_prime);
    return js;
  }
  // Reduce to r in [-K, K]: sn(r + 2Kj) = (-1)^j sn r, cn likewise, dn(r + 2Kj) = dn r,
  // f(r + 2Kj) = f(r) + j f(2K).
  const double half_periods = std::nearbyint(u * g.inv_two_K);
  const double r = std::fma(-g.two_K, half_periods, u);
  // Ascending through the Landen ladder from sn = sin, cn = cos, dn = 1 at the negligible modulus.
  const SinCos scv = sincos(r * g.landen_scale);
  double sn = scv.sin, cn = scv.cos, dn = 1.0;
  for (int n = g.landen_levels - 1; n >= 0; --n) {
    const double k = g.landen_k[n];
    const double inv_den = 1.0 / (1.0 + k * sn * sn);
    const double sn_up = (1.0 + k) * sn * inv_den;
    const double cn_up = cn * dn * inv_den;
    const double dn_up = (g.landen_one_minus_k[n] + k * cn * cn) * inv_den;  // (1 - k sn^2) / den
    sn = sn_up;
    cn = cn_up;
    dn = dn_up;
  }
  const double sn2 = sn * sn;
  const double f_r = g.n_prime / 3.0 * sn2 * sn * carlson_rj_precession(cn * cn, dn * dn, 1.0 + g.n_prime * sn2);
  const bool odd = half_periods != 2.0 * std::floor(0.5 * half_periods);
  js.sn = odd ? -sn : sn;
  js.cn = odd ? -cn : cn;
  js.dn = dn;
  js.f = half_periods * g.two_fK + f_r;
  return js;
}

void TorqueFreeRotation::symmetric_orientation(double t, Mat3& R) const {
  const Symmetric& s = sym_;
  SinCos a, b;  // both angles in one SSE2 pass: the same numbers as two sincos calls
  sincos2(s.precession_rate * t, s.spin_rate * t, a, b);
  R = s.along + a.cos * s.across + a.sin * s.cross;
  if (s.spin_rate != 0.0) {
    const double cb = b.cos, sb = b.sin;
    const Vec3 col_p = R.col(s.p), col_q = R.col(s.q);
    R.col(s.p) = cb * col_p + sb * col_q;
    R.col(s.q) = cb * col_q - sb * col_p;
  }
}

Mat3 TorqueFreeRotation::general_orientation(const JacobiState& js, double t, Vec3* L_body) const {
  const General& g = gen_;
  const double Lc = g.P * js.cn, Lm = g.Q * js.sn, Ld = g.D * js.dn;
  // Direction of (L_c, L_m) in the plane normal to e_d: sign(P) (cn, q sn), defined even when P = 0
  // (L_b on the d axis), where psi is the limit of nearby orbits and keeps phi + psi right.
  double wc = g.sign_P * js.cn, wm = g.sign_P * g.q_ratio * js.sn;
  const double w_norm = std::sqrt(wc * wc + wm * wm);
  wc /= w_norm;
  wm /= w_norm;
  const double rho = std::abs(g.P) * w_norm;  // |(L_c, L_m)|
  const double h = std::sqrt(rho * rho + Ld * Ld);
  const double sin_theta = rho / h, cos_theta = Ld / h;
  // (sin psi, cos psi) is the direction of (L_x, L_y).
  const bool c_is_x = g.c == g.x;
  const double sin_psi = c_is_x ? wc : wm, cos_psi = c_is_x ? wm : wc;
  // B = (Rz(-psi) Rx(-theta))^T composed with the relabelling: maps L_b to (0, 0, |L|).
  Mat3 B;
  B.col(g.x) << cos_psi, cos_theta * sin_psi, sin_theta * sin_psi;
  B.col(g.y) << -sin_psi, cos_theta * cos_psi, sin_theta * cos_psi;
  B.col(g.d) << 0.0, -sin_theta, cos_theta;
  const double dphi = g.phi_rate * t - g.phi_coeff * (js.f - g.f0);
  const SinCos p = sincos(dphi);
  const double cp = p.cos, sp = p.sin;
  Mat3 M;
  M.row(0) = cp * B.row(0) - sp * B.row(1);
  M.row(1) = sp * B.row(0) + cp * B.row(1);
  M.row(2) = B.row(2);
  if (L_body) {
    (*L_body)[g.c] = Lc;
    (*L_body)[g.m] = Lm;
    (*L_body)[g.d] = Ld;
  }
  return g.frame * M;
}

Vec3 TorqueFreeRotation::bottom_row(double t) const {
  if (kind_ == Kind::Still) return R0_.row(2).transpose();
  if (kind_ == Kind::General && !gen_.steady) return orientation(t).row(2).transpose();
  // symmetric_orientation, row 2 only.
  const Symmetric& s = sym_;
  SinCos a, b;
  sincos2(s.precession_rate * t, s.spin_rate * t, a, b);
  Vec3 r = s.along.row(2).transpose() + a.cos * s.across.row(2).transpose() + a.sin * s.cross.row(2).transpose();
  if (s.spin_rate != 0.0) {
    const double cb = b.cos, sb = b.sin;
    const double rp = r(s.p), rq = r(s.q);
    r(s.p) = cb * rp + sb * rq;
    r(s.q) = cb * rq - sb * rp;
  }
  return r;
}

Vec3 TorqueFreeRotation::bottom_row_at(const Moments& moments, const Mat3& R0, const Vec3& L_world, double t) {
  if (L_world.squaredNorm() == 0.0) return R0.row(2).transpose();  // Still
  if (moments.general) return TorqueFreeRotation(moments, R0, L_world, /*bounds=*/false).bottom_row(t);
  // The constructor's and init_symmetric's expressions, row 2 of along, across and cross only.
  const Vec3 L_body = R0.transpose() * L_world;
  const double L_norm = L_world.norm();
  const Vec3 L_hat = L_world / L_norm;
  const double precession_rate = L_norm * moments.inv_I_perp;
  const double spin_rate = (moments.inv_I_axis - moments.inv_I_perp) * L_body[moments.axis];
  const Eigen::RowVector3d LR = L_hat.transpose() * R0;  // along = L_hat LR
  SinCos a, b;
  sincos2(precession_rate * t, spin_rate * t, a, b);
  Vec3 r;
  for (int j = 0; j < 3; ++j) {
    const double along = L_hat.z() * LR(j);
    const double across = R0(2, j) - along;
    const double cross = L_hat.cross(R0.col(j)).z();
    r(j) = along + a.cos * across + a.sin * cross;
  }
  if (spin_rate != 0.0) {
    const int p = moments.p, q = moments.q;
    const double cb = b.cos, sb = b.sin;
    const double rp = r(p), rq = r(q);
    r(p) = cb * rp + sb * rq;
    r(q) = cb * rq - sb * rp;
  }
  return r;
}

Vec3 TorqueFreeRotation::bottom_row(double t, Vec3& rate) const {
  if (kind_ == Kind::Still) {
    rate.setZero();
    return R0_.row(2).transpose();
  }
  if (kind_ == Kind::General && !gen_.steady) {
    Mat3 R;
    Vec3 w;
    state(t, R, w);
    rate = R.transpose() * Vec3(-w.y(), w.x(), 0.0);
    return R.row(2).transpose();
  }
  // bottom_row's formulas differentiated: the precession angle a = precession_rate t turns the
  // row, then the spin b = spin_rate t turns its p, q components.
  const Symmetric& s = sym_;
  SinCos a, b;
  sincos2(s.precession_rate * t, s.spin_rate * t, a, b);
  Vec3 r = s.along.row(2).transpose() + a.cos * s.across.row(2).transpose() + a.sin * s.cross.row(2).transpose();
  Vec3 dr = s.precession_rate * (a.cos * s.cross.row(2).transpose() - a.sin * s.across.row(2).transpose());
  if (s.spin_rate != 0.0) {
    const double cb = b.cos, sb = b.sin;
    const double rp = r(s.p), rq = r(s.q), dp = dr(s.p), dq = dr(s.q);
    r(s.p) = cb * rp + sb * rq;
    r(s.q) = cb * rq - sb * rp;
    dr(s.p) = cb * dp + sb * dq + s.spin_rate * r(s.q);
    dr(s.q) = cb * dq - sb * dp - s.spin_rate * r(s.p);
  }
  rate = dr;
  return r;
}

Mat3 TorqueFreeRotation::orientation(double t) const {
  switch (kind_) {
    case Kind::Still:
      return R0_;
    case Kind::SymmetricTop:
      return symmetric_orientation(t);
    case Kind::General:
      break;
  }
  return gen_.steady ? symmetric_orientation(t) : general_orientation(jacobi_state(t), t, nullptr);
}

void TorqueFreeRotation::state(double t, Mat3& R, Vec3& omega_world) const {
  if (kind_ == Kind::Still) {
    R = R0_;
    omega_world.setZero();
    return;
  }
  if (kind_ == Kind::SymmetricTop || gen_.steady) {
    // omega_b = a_perp L_b + (a_a - a_perp) L_a e_a, so omega_world = a_perp L + spin_rate R e_a.
    symmetric_orientation(t, R);
    omega_world = sym_.inv_I_perp * L_ + sym_.spin_rate * R.col(sym_.axis);
    return;
  }
  Vec3 L_body;
  R = general_orientation(jacobi_state(t), t, &L_body);
  omega_world = R * L_body.cwiseProduct(gen_.inv_I);
}

}  // namespace dicesim
