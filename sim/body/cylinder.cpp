#include "sim/body/cylinder.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace dicesim {
namespace {

using V2 = Eigen::Vector2d;
// Area moments of a plane region: A, int x, int y, int x^2, int y^2, int xy.
using Area6 = std::array<double, 6>;
// Volume moments as a vector: V, int x, int y, int z, xx, yy, zz, xy, xz, yz.
using Vol10 = std::array<double, 10>;

struct Line {  // n . p <= d
  V2 n;
  double d;
};

// Green's theorem, int x^p y^q dA = contour integral of x^(p+1) y^q / (p+1) dy, along one piece
// of the boundary given by point(t) and its derivative dy(t); `w` a quadrature weight.
void add_boundary(Area6& m, const V2& p, double dy, double w) {
  const double x = p.x(), y = p.y();
  m[0] += w * x * dy;
  m[1] += w * 0.5 * x * x * dy;
  m[2] += w * x * y * dy;
  m[3] += w * x * x * x / 3.0 * dy;
  m[4] += w * x * y * y * dy;
  m[5] += w * 0.5 * x * x * y * dy;
}

// Segment a -> b: the integrands are cubics in t, so 2-point Gauss-Legendre is exact.
void add_segment(Area6& m, const V2& a, const V2& b) {
  const double g = 0.5 / std::sqrt(3.0);
  for (double t : {0.5 - g, 0.5 + g}) add_boundary(m, a + t * (b - a), b.y() - a.y(), 0.5);
}

// Arc of the circle of radius rho from angle t0 to t1 (counter-clockwise): trigonometric
// polynomials of degree 4, integrated by 8-point Gauss-Legendre on pieces of at most pi/4
// (error far below 1e-16 relative).
void add_arc(Area6& m, double rho, double t0, double t1) {
  static constexpr double x8[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
  static constexpr double w8[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
  const int pieces = std::max(1, static_cast<int>(std::ceil((t1 - t0) / (kPi / 4.0))));
  const double h = (t1 - t0) / pieces;
  for (int k = 0; k < pieces; ++k) {
    const double mid = t0 + (k + 0.5) * h;
    for (int i = 0; i < 4; ++i)
      for (double sgn : {-1.0, 1.0}) {
        const double t = mid + sgn * x8[i] * 0.5 * h;
        const V2 p(rho * std::cos(t), rho * std::sin(t));
        add_boundary(m, p, rho * std::cos(t), w8[i] * 0.5 * h);
      }
  }
}

// The disc of radius rho at the origin intersected with the half-planes.
Area6 clipped_disc(double rho, const std::vector<Line>& lines) {
  Area6 m{};
  if (rho <= 0.0) return m;
  // The polygon of the half-planes, inside a square that holds the disc.
  std::vector<V2> poly = {V2(-2 * rho, -2 * rho), V2(2 * rho, -2 * rho), V2(2 * rho, 2 * rho), V2(-2 * rho, 2 * rho)};
  for (const Line& l : lines) {
    std::vector<V2> out;
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) {
      const V2& a = poly[i];
      const V2& b = poly[(i + 1) % n];
      const double fa = l.n.dot(a) - l.d, fb = l.n.dot(b) - l.d;
      if (fa <= 0.0) out.push_back(a);
      if ((fa < 0.0 && fb > 0.0) || (fa > 0.0 && fb < 0.0)) out.push_back(a + fa / (fa - fb) * (b - a));
    }
    poly = std::move(out);
    if (poly.size() < 3) return m;
  }
  const auto inside_poly = [&](const V2& p) {
    for (const Line& l : lines)
      if (l.n.dot(p) > l.d) return false;
    return true;
  };
  // Polygon edges inside the disc; where an edge crosses the circle, an arc may start or end.
  std::vector<double> crossings;
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const V2 a = poly[i], b = poly[(i + 1) % n], d = b - a;
    const double A = d.squaredNorm(), B = a.dot(d), C = a.squaredNorm() - rho * rho;
    const double disc = B * B - A * C;
    if (A <= 0.0 || disc <= 0.0) continue;
    const double sq = std::sqrt(disc);
    const double t0 = std::max(0.0, (-B - sq) / A), t1 = std::min(1.0, (-B + sq) / A);
    if (t1 <= t0) continue;
    const V2 p0 = a + t0 * d, p1 = a + t1 * d;
    add_segment(m, p0, p1);
    if (t0 > 0.0) crossings.push_back(std::atan2(p0.y(), p0.x()));
    if (t1 < 1.0) crossings.push_back(std::atan2(p1.y(), p1.x()));
  }
  if (crossings.empty()) {
    if (inside_poly(V2(rho, 0.0)) && inside_poly(V2(-rho, 0.0))) add_arc(m, rho, 0.0, 2.0 * kPi);
    return m;
  }
  std::sort(crossings.begin(), crossings.end());
  const std::size_t k = crossings.size();
  for (std::size_t i = 0; i < k; ++i) {
    const double t0 = crossings[i];
    const double t1 = i + 1 < k ? crossings[i + 1] : crossings[0] + 2.0 * kPi;
    if (t1 - t0 <= 0.0) continue;
    const double mid = 0.5 * (t0 + t1);
    if (inside_poly(V2(rho * std::cos(mid), rho * std::sin(mid)))) add_arc(m, rho, t0, t1);
  }
  return m;
}

struct Slicer {
  CylinderShape c;
  std::vector<HalfSpace> cuts;

  double radius_at(double z) const {
    const double u = std::abs(z) - c.core_half();
    if (u <= 0.0) return c.radius;
    const double r = c.rounding;
    return c.core_radius() + std::sqrt(std::max(0.0, r * r - u * u));
  }

  Vol10 at(double z) const {
    std::vector<Line> lines;
    lines.reserve(cuts.size());
    for (const HalfSpace& h : cuts) {
      const V2 n(h.normal.x(), h.normal.y());
      const double d = h.offset - h.normal.z() * z;
      if (n.squaredNorm() <= 1e-30 * h.normal.squaredNorm()) {  // a cut parallel to the slice
        if (d < 0.0) return Vol10{};
        continue;
      }
      lines.push_back({n, d});
    }
    const Area6 a = clipped_disc(radius_at(z), lines);
    return {a[0], a[1], a[2], z * a[0], a[3], a[4], z * z * a[0], a[5], z * a[1], z * a[2]};
  }
};

// Adaptive Gauss-Kronrod 7/15 on [lo, hi]: the error of the volume (relative to `vol`) and of the
// second moments (relative to `sec`) below `tol` times the interval's share of `span` (never below
// 1e-3 of it: rounding must not drive the bisection).
struct Scales {
  double vol, sec, span, tol;
};
void integrate(const Slicer& s, double lo, double hi, const Scales& sc, int depth, Vol10& out) {
  static constexpr double xk[8] = {0.991455371120812639, 0.949107912342758525, 0.864864423359769073,
                                   0.741531185599394440, 0.586087235467691130, 0.405845151377397167,
                                   0.207784955007898468, 0.0};
  static constexpr double wk[8] = {0.022935322010529225, 0.063092092629978553, 0.104790010322250184,
                                   0.140653259715525919, 0.169004726639267903, 0.190350578064785410,
                                   0.204432940075298892, 0.209482141084727828};
  static constexpr double wg[4] = {0.129484966168869693, 0.279705391489276668, 0.381830050505118945,
                                   0.417959183673469388};
  const double c = 0.5 * (lo + hi), h = 0.5 * (hi - lo);
  Vol10 k{}, g{};
  for (int i = 0; i < 8; ++i) {
    const int signs = i == 7 ? 1 : 2;
    for (int sgn = 0; sgn < signs; ++sgn) {
      const Vol10 f = s.at(c + (sgn ? -1.0 : 1.0) * xk[i] * h);
      for (int j = 0; j < 10; ++j) {
        k[j] += wk[i] * f[j];
        if (i % 2 == 1) g[j] += wg[i / 2] * f[j];
      }
    }
  }
  double err = std::abs(k[0] - g[0]) * h / sc.vol;
  for (int j : {4, 5, 6}) err = std::max(err, std::abs(k[j] - g[j]) * h / sc.sec);
  if (depth > 0 && err > sc.tol * std::max(2.0 * h / sc.span, 1e-3)) {
    integrate(s, lo, c, sc, depth - 1, out);
    integrate(s, c, hi, sc, depth - 1, out);
    return;
  }
  for (int j = 0; j < 10; ++j) out[j] += k[j] * h;
}

}  // namespace

VolumeMoments cylinder_moments(const CylinderShape& c, const std::vector<HalfSpace>& cuts) {
  Slicer s{c, cuts};
  const double b = 0.5 * c.height, b0 = c.core_half();
  // Errors relative to the whole cylinder's volume V and second-moment scale V L^2.
  const double L = std::max(c.radius, b);
  const double V = kPi * c.radius * c.radius * c.height;
  const Scales sc{V, V * L * L, c.height, 1e-13};
  Vol10 v{};
  std::array<double, 4> breaks = {-b, -b0, b0, b};
  for (int i = 0; i < 3; ++i)
    if (breaks[i + 1] > breaks[i]) integrate(s, breaks[i], breaks[i + 1], sc, 30, v);
  VolumeMoments m;
  m.volume = v[0];
  m.first = Vec3(v[1], v[2], v[3]);
  m.second << v[4], v[7], v[8], v[7], v[5], v[9], v[8], v[9], v[6];
  return m;
}

}  // namespace dicesim
