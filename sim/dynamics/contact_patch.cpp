// Features as convex polygons in the plane across the normal (a point and a segment are polygons
// of one and two corners), and their overlap's corners: a corner of one inside the other, or a
// crossing of two edges; then the four that span them. The scratch is per thread and kept between
// calls (a toss calls this at every slow contact): no allocation once it has grown, and no cap on
// a face's corners (a prism's end face may have hundreds).
#include "sim/dynamics/contact_patch.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace dicesim {
namespace {

struct P2 {
  double x = 0.0, y = 0.0;
};
P2 operator-(P2 a, P2 b) { return {a.x - b.x, a.y - b.y}; }
double cross(P2 a, P2 b) { return a.x * b.y - a.y * b.x; }
double dot(P2 a, P2 b) { return a.x * b.x + a.y * b.y; }
double norm(P2 a) { return std::sqrt(dot(a, a)); }

using Polygon = std::vector<P2>;

// The corners of a convex polygon around `pts` (Andrew's monotone chain), counter-clockwise,
// without repeats or corners on an edge (within eps), into `h`: 1 corner (a point), 2 (a segment)
// or more; none for no points. `pts` is reordered; `chain` is scratch.
void hull(std::vector<P2>& pts, std::vector<P2>& chain, Polygon& h, double eps) {
  h.clear();
  if (pts.empty()) return;
  std::sort(pts.begin(), pts.end(), [](P2 a, P2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  const int n = static_cast<int>(pts.size());
  chain.assign(2 * pts.size(), P2{});
  int k = 0;
  const auto turn = [&](P2 o, P2 a, P2 b) {  // a left turn by more than eps |ob|
    return cross(a - o, b - o) > eps * std::max(norm(b - o), eps);
  };
  for (int i = 0; i < n; ++i) {  // lower chain
    while (k >= 2 && !turn(chain[k - 2], chain[k - 1], pts[i])) --k;
    chain[k++] = pts[i];
  }
  for (int i = n - 2, lower = k + 1; i >= 0; --i) {  // upper chain
    while (k >= lower && !turn(chain[k - 2], chain[k - 1], pts[i])) --k;
    chain[k++] = pts[i];
  }
  // The last repeats the first; drop it, and corners closer than eps (a point, or a segment's ends).
  for (int i = 0; i < std::max(1, k - 1); ++i) {
    const P2 q = chain[i];
    bool dup = false;
    for (const P2& c : h) dup |= norm(q - c) <= eps;
    if (!dup) h.push_back(q);
  }
}

// A side's feature: its corners within slab of its surface's plane (height measured toward the
// other body), across the normal.
void feature(const PatchSide& s, const Vec3& n, double sign, double level, const Vec3& u, const Vec3& v, double slab,
             std::vector<P2>& pts, std::vector<P2>& chain, Polygon& out) {
  pts.clear();
  for (const Vec3& c : s.corners) {
    // sign +1 (body a above): its surface at n.c - rounding, above level; -1 (b): n.c + rounding.
    const double off = sign * (n.dot(c) - level) - s.rounding;
    if (off <= slab) pts.push_back({u.dot(c), v.dot(c)});
  }
  hull(pts, chain, out, slab);
}

bool inside(const Polygon& g, P2 q, double eps) {
  const std::size_t n = g.size();
  if (n == 0) return false;
  if (n == 1) return norm(q - g[0]) <= eps;
  if (n == 2) {
    const P2 e = g[1] - g[0];
    const double t = std::clamp(dot(q - g[0], e) / dot(e, e), 0.0, 1.0);
    return norm(q - P2{g[0].x + t * e.x, g[0].y + t * e.y}) <= eps;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const P2 a = g[i], e = g[(i + 1) % n] - a;
    if (cross(e, q - a) < -eps * norm(e)) return false;
  }
  return true;
}

std::size_t edge_count(const Polygon& g) { return g.size() < 2 ? 0 : g.size() == 2 ? 1 : g.size(); }

// Four points that span a set (as contact manifolds keep): the two farthest apart, then the
// farthest from their line on either side. A flat patch's solve needs no more, and extra points
// in one plane only slow the Gauss-Seidel solve of the impact law (its rank is three).
void span_four(const std::vector<P2>& p, std::vector<P2>& out) {
  out.clear();
  if (p.size() <= 4) {
    out = p;
    return;
  }
  std::size_t a = 0, b = 0;
  double far = -1.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j)
      if (dot(p[i] - p[j], p[i] - p[j]) > far) far = dot(p[i] - p[j], p[i] - p[j]), a = i, b = j;
  const P2 ab = p[b] - p[a];
  std::size_t c = a, d = a;
  double most = 0.0, least = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double area = cross(ab, p[i] - p[a]);
    if (area > most) most = area, c = i;
    if (area < least) least = area, d = i;
  }
  for (const std::size_t i : {a, b, c, d})
    if (std::find_if(out.begin(), out.end(), [&](P2 q) { return q.x == p[i].x && q.y == p[i].y; }) == out.end())
      out.push_back(p[i]);
}

}  // namespace

ContactPatch contact_patch(const PatchSide& a, const PatchSide& b, const Vec3& n, double level_a, double level_b,
                           double slab) {
  thread_local std::vector<P2> pts, chain, found, kept;
  thread_local Polygon fa, fb;
  const Vec3 u = n.unitOrthogonal(), v = n.cross(u);
  found.clear();
  const auto add = [&](P2 q) {
    for (const P2& f : found)
      if (norm(q - f) <= slab) return;
    found.push_back(q);
  };
  feature(a, n, 1.0, level_a, u, v, slab, pts, chain, fa);
  if (b.corners.empty()) {  // a half-space under all of a's feature
    for (const P2& q : fa) add(q);
  } else {
    feature(b, n, -1.0, level_b, u, v, slab, pts, chain, fb);
    for (const P2& q : fa)
      if (inside(fb, q, slab)) add(q);
    for (const P2& q : fb)
      if (inside(fa, q, slab)) add(q);
    for (std::size_t i = 0; i < edge_count(fa); ++i) {
      const P2 p = fa[i], r = fa[(i + 1) % fa.size()] - p;
      for (std::size_t j = 0; j < edge_count(fb); ++j) {
        const P2 q = fb[j], s = fb[(j + 1) % fb.size()] - q;
        const double d = cross(r, s);
        if (std::abs(d) <= 1e-12 * norm(r) * norm(s)) continue;  // parallel: their ends are inside tests
        const double t = cross(q - p, s) / d, w = cross(q - p, r) / d;
        if (t >= 0.0 && t <= 1.0 && w >= 0.0 && w <= 1.0) add({p.x + t * r.x, p.y + t * r.y});
      }
    }
  }
  span_four(found, kept);
  ContactPatch out;
  const double mid = 0.5 * (level_a + level_b);
  for (const P2& q : kept) out.points[static_cast<std::size_t>(out.n++)] = q.x * u + q.y * v + mid * n;
  return out;
}

}  // namespace dicesim
