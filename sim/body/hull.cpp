#include "sim/body/hull.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <utility>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace dicesim {
namespace {

struct HullTriangle {
  std::array<int, 3> v;  // indices into the input points, counter-clockwise from outside
  Vec3 normal;           // qhull's plane normal (shared by the triangles of one qhull facet)
};

// qhull with option Qt: every facet a triangle. Indices refer to `points`.
std::vector<HullTriangle> qhull_triangles(const std::vector<Vec3>& points) {
  std::vector<coordT> coords;
  coords.reserve(3 * points.size());
  for (const Vec3& p : points) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  // qhull reports errors on a FILE*; the message we give is our own (the checks before qhull).
  std::unique_ptr<FILE, int (*)(FILE*)> sink(std::fopen("/dev/null", "w"), &std::fclose);
  qhT qh_qh;
  qhT* qh = &qh_qh;
  qh_zero(qh, sink.get());
  char options[] = "qhull Qt";
  const int exit_code = qh_new_qhull(qh, 3, static_cast<int>(points.size()), coords.data(), False, options, nullptr,
                                     sink.get());
  std::vector<HullTriangle> out;
  if (exit_code == 0) {
    facetT* facet;
    FORALLfacets {
      HullTriangle t;
      int k = 0;
      vertexT *vertex, **vertexp;
      FOREACHvertex_(facet->vertices) {
        if (k < 3) t.v[k] = qh_pointid(qh, vertex->point);
        ++k;
      }
      if (k != 3) continue;
      t.normal = Vec3(facet->normal[0], facet->normal[1], facet->normal[2]);
      const Vec3 e = (points[t.v[1]] - points[t.v[0]]).cross(points[t.v[2]] - points[t.v[0]]);
      if (e.dot(t.normal) < 0.0) std::swap(t.v[1], t.v[2]);
      out.push_back(t);
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int cur_long = 0, tot_long = 0;
  qh_memfreeshort(qh, &cur_long, &tot_long);
  if (exit_code != 0) throw HullError("qhull could not build the hull (error " + std::to_string(exit_code) + ")");
  return out;
}

// The points must span a solid: find a large tetrahedron greedily.
void check_solid(const std::vector<Vec3>& points, double tol) {
  if (points.size() < 4) throw HullError("needs at least 4 points not all in one plane");
  const Vec3& a = points[0];
  auto farthest = [&](auto&& distance) {
    std::size_t best = 0;
    double d = -1.0;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (const double di = distance(points[i]); di > d) {
        d = di;
        best = i;
      }
    return std::make_pair(best, d);
  };
  const auto [ib, db] = farthest([&](const Vec3& p) { return (p - a).norm(); });
  if (db <= tol) throw HullError("all points coincide; needs at least 4 points not all in one plane");
  const Vec3 u = (points[ib] - a) / db;
  const auto [ic, dc] = farthest([&](const Vec3& p) { return ((p - a) - (p - a).dot(u) * u).norm(); });
  if (dc <= tol) throw HullError("all points lie on one line; needs at least 4 points not all in one plane");
  const Vec3 n = u.cross(points[ic] - a).normalized();
  const auto [id, dd] = farthest([&](const Vec3& p) { return std::abs((p - a).dot(n)); });
  if (dd <= tol) throw HullError("all points lie in one plane (a flat hull); needs at least 4 points not all in one plane");
}

}  // namespace

ConvexShape convex_hull(const std::vector<Vec3>& points) {
  for (const Vec3& p : points)
    if (!p.allFinite()) throw HullError("a point is not finite");
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double tol = kCoplanarTolerance * (points.empty() ? 0.0 : (hi - lo).norm());
  check_solid(points, tol);
  const std::vector<HullTriangle> tris = qhull_triangles(points);

  // Neighbours across each directed edge.
  std::map<std::pair<int, int>, int> edge_owner;
  for (int t = 0; t < static_cast<int>(tris.size()); ++t)
    for (int k = 0; k < 3; ++k) edge_owner[{tris[t].v[k], tris[t].v[(k + 1) % 3]}] = t;

  // Region growing from a seed triangle: a neighbour joins when all its corners lie within tol of
  // the seed's plane (a fixed plane, so a gently curved surface does not drift into one face).
  std::vector<int> group(tris.size(), -1);
  std::vector<std::vector<int>> groups;
  for (int s = 0; s < static_cast<int>(tris.size()); ++s) {
    if (group[s] >= 0) continue;
    const int g = static_cast<int>(groups.size());
    groups.push_back({s});
    group[s] = g;
    const Vec3 n = tris[s].normal.normalized();
    const double d = n.dot(points[tris[s].v[0]]);
    for (std::size_t head = 0; head < groups[g].size(); ++head) {
      const HullTriangle& t = tris[groups[g][head]];
      for (int k = 0; k < 3; ++k) {
        const auto it = edge_owner.find({t.v[(k + 1) % 3], t.v[k]});
        if (it == edge_owner.end() || group[it->second] >= 0) continue;
        const HullTriangle& u = tris[it->second];
        bool coplanar = u.normal.dot(n) > 0.0;
        for (int c : u.v) coplanar = coplanar && std::abs(n.dot(points[c]) - d) <= tol;
        if (!coplanar) continue;
        group[it->second] = g;
        groups[g].push_back(it->second);
      }
    }
  }

  // Each group's outline: its triangles' edges whose reverse is not in the group, chained.
  ConvexShape shape;
  std::vector<std::vector<int>> loops;
  for (int g = 0; g < static_cast<int>(groups.size()); ++g) {
    std::map<int, int> next;
    Vec3 area = Vec3::Zero();
    for (int t : groups[g]) {
      const auto& v = tris[t].v;
      area += (points[v[1]] - points[v[0]]).cross(points[v[2]] - points[v[0]]);
      for (int k = 0; k < 3; ++k) {
        const auto it = edge_owner.find({v[(k + 1) % 3], v[k]});
        if (it != edge_owner.end() && group[it->second] == g) continue;
        if (!next.emplace(v[k], v[(k + 1) % 3]).second) throw HullError("the hull is degenerate (a face's outline is not one loop)");
      }
    }
    std::vector<int> loop = {next.begin()->first};
    while (loop.size() <= next.size()) {
      const auto it = next.find(loop.back());
      if (it == next.end()) throw HullError("the hull is degenerate (a face's outline is not closed)");
      if (it->second == loop.front()) break;
      loop.push_back(it->second);
    }
    if (loop.size() != next.size() || loop.size() < 3) throw HullError("the hull is degenerate (a face's outline is not one loop)");
    loops.push_back(std::move(loop));
    shape.normals.push_back(area.norm() > 0.0 ? Vec3(area.normalized()) : tris[groups[g][0]].normal.normalized());
  }

  // Corners that are straight (within tol of the line through their neighbours) on every face they
  // are on are not corners: points on an edge.
  std::map<int, bool> straight;  // point -> straight on every face so far
  for (const auto& loop : loops)
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const Vec3& p = points[loop[(k + loop.size() - 1) % loop.size()]];
      const Vec3& v = points[loop[k]];
      const Vec3& q = points[loop[(k + 1) % loop.size()]];
      const Vec3 dir = (q - p).normalized();
      const bool s = ((v - p) - (v - p).dot(dir) * dir).norm() <= tol;
      const auto [it, fresh] = straight.emplace(loop[k], s);
      if (!fresh) it->second = it->second && s;
    }
  std::map<int, int> index;  // point -> shape vertex
  for (auto& loop : loops) {
    std::vector<int> kept;
    for (int p : loop)
      if (!straight[p]) {
        const auto [it, fresh] = index.emplace(p, static_cast<int>(shape.vertices.size()));
        if (fresh) shape.vertices.push_back(points[p]);
        kept.push_back(it->second);
      }
    if (kept.size() < 3) throw HullError("the hull is degenerate (a face has fewer than 3 corners)");
    shape.faces.push_back(std::move(kept));
  }
  canonical_order(shape);
  return shape;
}

}  // namespace dicesim
