// GJK distance between two convex polytopes over their Minkowski difference A - B, with the
// signed-volumes sub-algorithm (Montanari, Petrinic, Barbieri 2017), and the separating-axis test
// for the depth once the origin is found inside. Everything runs in A's frame (one relative
// rotation, so a far-away pair loses no digits to its world position); fixed-size arrays only.
#include "sim/dynamics/convex_distance.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace dicesim {
namespace {

// Polytopes converge in a handful of iterations; a cap this high is only reached by cycling.
constexpr int kMaxIterations = 64;
// Duality gap |v|^2 - v.w at which v is accepted: |v| - distance <= gap / |v|, so 1e-12 of |v|^2
// is a 1e-12 relative distance.
constexpr double kRelativeGap = 1e-12;
// The gap's own rounding is ~eps |w|^2 (v's components carry eps |w|): a step that makes no
// progress with the gap below this many |w|^2 is a tie at rounding, converged; above, a stall.
constexpr double kRoundingGap = 1e-13;
// |v| below 1e-12 of the largest |w| seen: the hulls touch to rounding; the SAT decides.
constexpr double kTouching2 = 1e-24;
// Edge pairs closer to parallel than this (|e_a x e_b|^2) give no axis of their own: their
// normalised cross product would be noise, and the faces' normals cover that direction.
constexpr double kParallel2 = 1e-12;
// A triangle whose sine of angle is below 1e-10 has no plane worth projecting onto; a tetrahedron
// whose volume is below 1e-10 of its edges' product has no reliable sign.
constexpr double kCollinear2 = 1e-20;
constexpr double kFlat2 = 1e-20;

// The pair in A's frame: A's corners as they are, B's through Rb (B -> A) and xb.
struct Pair {
  std::span<const Vec3> ca, cb;
  Mat3 Rb;
  Vec3 xb;
};

// A point of A - B and the corners it came from (for the witness points, and to notice that a
// support repeats a vertex: exact convergence on a polytope).
struct Vertex {
  Vec3 w;
  int ia, ib;
};

// The support searches are half the time spent: one plain loop, whose select the compiler makes
// branch-free (two interleaved running maxima measured slower: they compiled to branches).
inline int argmax_dot(std::span<const Vec3> c, const Vec3& d) {
  const double dx = d[0], dy = d[1], dz = d[2];
  const Vec3* q = c.data();
  const int n = static_cast<int>(c.size());
  int best = 0;
  double m = q[0][0] * dx + q[0][1] * dy + q[0][2] * dz;
  for (int i = 1; i < n; ++i) {
    const double t = q[i][0] * dx + q[i][1] * dy + q[i][2] * dz;
    if (t > m) {
      m = t;
      best = i;
    }
  }
  return best;
}

// 3x3 times 3-vector written out: Eigen's product is not always inlined at -O2.
inline Vec3 mul(const Mat3& M, const Vec3& v) {
  return Vec3(M(0, 0) * v[0] + M(0, 1) * v[1] + M(0, 2) * v[2], M(1, 0) * v[0] + M(1, 1) * v[1] + M(1, 2) * v[2],
              M(2, 0) * v[0] + M(2, 1) * v[1] + M(2, 2) * v[2]);
}
inline Vec3 mul_transpose(const Mat3& M, const Vec3& v) {
  return Vec3(M(0, 0) * v[0] + M(1, 0) * v[1] + M(2, 0) * v[2], M(0, 1) * v[0] + M(1, 1) * v[1] + M(2, 1) * v[2],
              M(0, 2) * v[0] + M(1, 2) * v[1] + M(2, 2) * v[2]);
}

// Support of A - B in direction d (A's frame): A's farthest corner along d minus B's along -d.
inline Vertex support(const Pair& p, const Vec3& d) {
  const int ia = argmax_dot(p.ca, d);
  const int ib = argmax_dot(p.cb, -mul_transpose(p.Rb, d));
  return {p.ca[ia] - (mul(p.Rb, p.cb[ib]) + p.xb), ia, ib};
}

using Simplex = std::array<Vertex, 4>;

// The point of a sub-simplex nearest the origin, as weights on the simplex's vertices (0: not in
// the support set, dropped).
struct Closest {
  std::array<double, 4> lambda{};
  Vec3 v = Vec3::Zero();
  double v2 = std::numeric_limits<double>::infinity();
  bool inside = false;  // the origin is inside (or on) the tetrahedron
};

Closest closest_segment(const Simplex& s, int i, int j) {
  Closest c;
  const Vec3& p = s[i].w;
  const Vec3 t = s[j].w - p;
  const double t2 = t.squaredNorm();
  const double mu = t2 > 0.0 ? -p.dot(t) / t2 : 0.0;
  if (mu <= 0.0) {
    c.lambda[i] = 1.0;
    c.v = p;
  } else if (mu >= 1.0) {
    c.lambda[j] = 1.0;
    c.v = s[j].w;
  } else {
    c.lambda[i] = 1.0 - mu;
    c.lambda[j] = mu;
    c.v = p + mu * t;  // from the nearer end's offset, not a weighted sum: one rounding less
  }
  c.v2 = c.v.squaredNorm();
  return c;
}

inline void keep_nearer(Closest& best, const Closest& c) {
  if (c.v2 < best.v2) best = c;
}

// Signed-volumes S2D: the origin projected onto the triangle's plane, and its barycentric
// coordinates as signed areas in the coordinate plane where the triangle's shadow is largest (the
// projection that loses least). Outside: the nearest of the edges the origin lies beyond.
Closest closest_triangle(const Simplex& s, int i, int j, int k) {
  const Vec3& a = s[i].w;
  const Vec3& b = s[j].w;
  const Vec3& c = s[k].w;
  const Vec3 ab = b - a, ac = c - a;
  const Vec3 n = ab.cross(ac);
  const double n2 = n.squaredNorm();
  if (n2 <= kCollinear2 * ab.squaredNorm() * ac.squaredNorm()) {  // no plane to project onto
    Closest best = closest_segment(s, i, j);
    keep_nearer(best, closest_segment(s, j, k));
    keep_nearer(best, closest_segment(s, k, i));
    return best;
  }
  const double nx = std::abs(n[0]), ny = std::abs(n[1]), nz = std::abs(n[2]);
  const int ax = nx >= ny ? (nx >= nz ? 0 : 2) : (ny >= nz ? 1 : 2);
  const double mu = n[ax];  // the shadow's signed area (x, y cyclic after ax)
  const Vec3 p = n * (a.dot(n) / n2);
  const int x = (ax + 1) % 3, y = (ax + 2) % 3;
  auto area = [&](const Vec3& q, const Vec3& r) {
    return (q[x] - p[x]) * (r[y] - p[y]) - (q[y] - p[y]) * (r[x] - p[x]);
  };
  const double ca = area(b, c), cb = area(c, a), cc = area(a, b);
  if (ca * mu >= 0.0 && cb * mu >= 0.0 && cc * mu >= 0.0) {
    Closest out;
    const double sum = ca + cb + cc;  // == mu up to rounding; the weights then sum to 1
    out.lambda[i] = ca / sum;
    out.lambda[j] = cb / sum;
    out.lambda[k] = cc / sum;
    // The projection itself, not the weighted sum: its direction is the face's normal to rounding
    // however near the origin the face is (the sum carries eps |w| of noise into every component).
    out.v = p;
    out.v2 = p.squaredNorm();
    return out;
  }
  Closest best;
  if (ca * mu < 0.0) keep_nearer(best, closest_segment(s, j, k));
  if (cb * mu < 0.0) keep_nearer(best, closest_segment(s, k, i));
  if (cc * mu < 0.0) keep_nearer(best, closest_segment(s, i, j));
  return best;
}

inline double det3(const Vec3& a, const Vec3& b, const Vec3& c) { return a.dot(b.cross(c)); }

// Signed-volumes S3D: the volumes of the tetrahedra with one vertex replaced by the origin are the
// origin's barycentric coordinates (times the whole volume, their sum). All of the whole volume's
// sign: inside. Otherwise the nearest of the faces the origin lies beyond, or of every face when the
// tetrahedron is flat (then the whole volume's sign is rounding: four coplanar corners tie on a
// face of A - B whenever two faces are parallel).
Closest closest_tetrahedron(const Simplex& s) {
  const Vec3 &w0 = s[0].w, &w1 = s[1].w, &w2 = s[2].w, &w3 = s[3].w;
  const std::array<double, 4> C{det3(w1, w2, w3), -det3(w0, w2, w3), det3(w0, w1, w3), -det3(w0, w1, w2)};
  // The whole volume from the edges, whose sign and size do not depend on how far the origin is.
  const Vec3 e1 = w1 - w0, e2 = w2 - w0, e3 = w3 - w0;
  const double mu = det3(e1, e2, e3);
  const bool flat = mu * mu <= kFlat2 * e1.squaredNorm() * e2.squaredNorm() * e3.squaredNorm();
  const double sum = C[0] + C[1] + C[2] + C[3];
  if (!flat && C[0] * mu >= 0.0 && C[1] * mu >= 0.0 && C[2] * mu >= 0.0 && C[3] * mu >= 0.0 && sum != 0.0) {
    Closest out;
    for (int q = 0; q < 4; ++q) out.lambda[q] = C[q] / sum;
    out.v = Vec3::Zero();
    out.v2 = 0.0;
    out.inside = true;
    return out;
  }
  static constexpr std::array<std::array<int, 3>, 4> kOpposite{{{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}}};
  Closest best;
  for (int q = 0; q < 4; ++q)
    if (flat || C[q] * mu < 0.0) keep_nearer(best, closest_triangle(s, kOpposite[q][0], kOpposite[q][1], kOpposite[q][2]));
  return best;
}

// The SAT once the origin is in A - B: over A's face normals, B's, and the edge pairs' cross
// products, both ways round, the least of max_A u.a - min_B u.b (the support of A - B along u, an
// upper bound of the depth for every u, and equal to it at a face normal of A - B, which these
// axes include). Fills distance, normal, witness points (world).
void overlap_by_sat(const PlacedHull& a, const PlacedHull& b, const Pair& p, Separation& out) {
  const Mat3 RbT = p.Rb.transpose();
  double best = std::numeric_limits<double>::infinity();
  Vec3 axis = Vec3::UnitZ();
  auto test = [&](const Vec3& u) {
    double amin = std::numeric_limits<double>::infinity(), amax = -amin;
    for (const Vec3& c : p.ca) {
      const double t = c.dot(u);
      amin = std::min(amin, t);
      amax = std::max(amax, t);
    }
    const Vec3 ub = RbT * u;
    const double off = u.dot(p.xb);
    double bmin = std::numeric_limits<double>::infinity(), bmax = -bmin;
    for (const Vec3& c : p.cb) {
      const double t = c.dot(ub);
      bmin = std::min(bmin, t);
      bmax = std::max(bmax, t);
    }
    bmin += off;
    bmax += off;
    if (amax - bmin < best) {
      best = amax - bmin;
      axis = u;
    }
    if (bmax - amin < best) {
      best = bmax - amin;
      axis = -u;
    }
  };
  for (const Vec3& n : a.face_normals) test(n);
  for (const Vec3& n : b.face_normals) test(p.Rb * n);
  for (const Vec3& ea : a.edge_dirs)
    for (const Vec3& eb : b.edge_dirs) {
      const Vec3 u = ea.cross(p.Rb * eb);
      const double u2 = u.squaredNorm();
      if (u2 > kParallel2 * ea.squaredNorm() * eb.squaredNorm()) test(u / std::sqrt(u2));
    }
  out.sat = true;
  if (!(best < std::numeric_limits<double>::infinity())) {
    // No axes given: all that is known is that they touch or overlap.
    out.degenerate = true;
    best = 0.0;
    if (p.xb.squaredNorm() > 0.0) axis = p.xb.normalized();
  }
  const int ia = argmax_dot(p.ca, axis);
  const int ib = argmax_dot(p.cb, -(RbT * axis));
  out.distance = -best;
  out.normal = a.R * axis;
  out.point_a = a.R * p.ca[ia] + a.x;
  out.point_b = b.R * p.cb[ib] + b.x;
}

// Keeps the first `count` vertices of s that carry weight in c (the sub-simplex nearest the
// origin), in order, with their weights; returns how many.
int keep_support(Simplex& s, std::array<double, 4>& lambda, const Closest& c, int count) {
  int m = 0;
  for (int q = 0; q < count; ++q)
    if (c.lambda[q] > 0.0) {
      s[m] = s[q];
      lambda[m] = c.lambda[q];
      ++m;
    }
  return m;
}

}  // namespace

Separation separation(const PlacedHull& a, const PlacedHull& b, SeparationCache* cache) {
  const Mat3 RaT = a.R.transpose();
  const Pair p{a.corners, b.corners, RaT * b.R, RaT * (b.x - a.x)};
  Separation out;

  // Start from the support toward B's origin: the side of A - B that faces the origin; or from
  // the cached simplex's corners where the hulls are now, reduced to its part nearest the origin.
  Simplex s;
  int n = 1;
  std::array<double, 4> lambda{1.0, 0.0, 0.0, 0.0};
  Vec3 v;
  double v2;
  if (cache && cache->n > 0) {
    n = cache->n;
    for (int q = 0; q < n; ++q) {
      const int ia = cache->ia[q], ib = cache->ib[q];
      s[q] = {p.ca[ia] - (mul(p.Rb, p.cb[ib]) + p.xb), ia, ib};
    }
    Closest c;
    if (n == 1) {
      c.lambda[0] = 1.0;
      c.v = s[0].w;
      c.v2 = c.v.squaredNorm();
    } else {
      c = n == 2 ? closest_segment(s, 0, 1) : n == 3 ? closest_triangle(s, 0, 1, 2) : closest_tetrahedron(s);
    }
    if (!c.inside) n = keep_support(s, lambda, c, n);
    v = c.v;
    v2 = c.v2;
  } else {
    s[0] = support(p, p.xb.squaredNorm() > 0.0 ? p.xb : Vec3::UnitX());
    v = s[0].w;
    v2 = v.squaredNorm();
  }
  double max_w2 = 0.0;
  for (int q = 0; q < n; ++q) max_w2 = std::max(max_w2, s[q].w.squaredNorm());
  bool overlap = v2 == 0.0 || (n > 1 && v2 <= kTouching2 * max_w2);
  bool converged = false;

  while (!overlap && out.iterations < kMaxIterations) {
    ++out.iterations;
    const Vertex w = support(p, -v);
    max_w2 = std::max(max_w2, w.w.squaredNorm());
    bool repeat = false;
    for (int q = 0; q < n; ++q) repeat |= (s[q].ia == w.ia && s[q].ib == w.ib);
    const double gap = v2 - v.dot(w.w);
    if (repeat || gap <= kRelativeGap * v2) {
      converged = true;
      break;
    }
    s[n] = w;
    const Closest c = n == 1 ? closest_segment(s, 0, 1) : n == 2 ? closest_triangle(s, 0, 1, 2) : closest_tetrahedron(s);
    if (c.inside) {
      overlap = true;
      ++n;  // (the tetrahedron, kept for the cache)
      break;
    }
    if (!(c.v2 < v2)) {
      // No progress: w ties with the simplex to rounding (converged), or, with a gap beyond
      // rounding, rounding has the better of the sub-algorithm (a stall). Either way the previous
      // simplex is the best estimate.
      out.degenerate = gap > kRoundingGap * max_w2;
      converged = true;
      break;
    }
    n = keep_support(s, lambda, c, n + 1);
    v = c.v;
    v2 = c.v2;
    if (v2 <= kTouching2 * max_w2) overlap = true;
  }
  if (!overlap && !converged) out.degenerate = true;  // the cap

  if (cache) {
    cache->n = n;
    for (int q = 0; q < cache->n; ++q) {
      cache->ia[q] = s[q].ia;
      cache->ib[q] = s[q].ib;
    }
  }
  if (overlap) {
    overlap_by_sat(a, b, p, out);
    return out;
  }
  Vec3 pa = Vec3::Zero(), pb = Vec3::Zero();  // A's frame, B's frame
  for (int q = 0; q < n; ++q) {
    pa += lambda[q] * p.ca[s[q].ia];
    pb += lambda[q] * p.cb[s[q].ib];
  }
  out.distance = std::sqrt(v2);
  out.normal = a.R * (v / -out.distance);
  out.point_a = a.R * pa + a.x;
  out.point_b = b.R * pb + b.x;
  return out;
}

double point_distance(const PlacedHull& h, const Vec3& p, Vec3* closest) {
  static const Vec3 kOrigin = Vec3::Zero();
  PlacedHull point;
  point.corners = std::span<const Vec3>(&kOrigin, 1);
  point.x = p;
  const Separation s = separation(h, point);
  // Inside, the SAT's axis is the nearest face's normal (a point has no faces or edges of its own).
  if (closest) *closest = s.sat ? Vec3(p - s.distance * s.normal) : s.point_a;
  return s.distance;
}

}  // namespace dicesim
