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
      // qhull's own orientation (as its OFF output): the listed order is counter-clockwise from
      // outside unless toporient. Combinatorial, so also right for Qt's zero-area triangles.
      if (facet->toporient) std::swap(t.v[0], t.v[1]);
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

  // Each group's outline: its triangles' edges whose reverse is not in the group, chained. A
  // group whose outline is not one simple loop (noisy points can make a group touch itself at a
  // corner) is not merged: its triangles stay faces of their own.
  ConvexShape shape;
  std::vector<std::vector<int>> loops;
  auto outline = [&](const std::vector<int>& members, int g) -> std::vector<int> {
    std::map<int, int> next;
    for (int t : members) {
      const auto& v = tris[t].v;
      for (int k = 0; k < 3; ++k) {
        const auto it = edge_owner.find({v[(k + 1) % 3], v[k]});
        if (it != edge_owner.end() && group[it->second] == g && members.size() > 1) continue;
        if (!next.emplace(v[k], v[(k + 1) % 3]).second) return {};
      }
    }
    std::vector<int> loop = {next.begin()->first};
    while (loop.size() <= next.size()) {
      const auto it = next.find(loop.back());
      if (it == next.end()) return {};
      if (it->second == loop.front()) break;
      loop.push_back(it->second);
    }
    if (loop.size() != next.size() || loop.size() < 3) return {};
    return loop;
  };
  auto area_normal = [&](const std::vector<int>& members) {
    Vec3 area = Vec3::Zero();
    for (int t : members) {
      const auto& v = tris[t].v;
      area += (points[v[1]] - points[v[0]]).cross(points[v[2]] - points[v[0]]);
    }
    return area.norm() > 0.0 ? Vec3(area.normalized()) : Vec3(tris[members[0]].normal.normalized());
  };
  for (int g = 0; g < static_cast<int>(groups.size()); ++g) {
    std::vector<int> loop = outline(groups[g], g);
    if (!loop.empty()) {
      // The seed triangle's plane: qhull's supporting plane, which every corner of the group is
      // within the tolerance of (an averaged normal could tilt away from it).
      loops.push_back(std::move(loop));
      shape.normals.push_back(groups[g].size() > 1 ? Vec3(tris[groups[g][0]].normal.normalized()) : area_normal(groups[g]));
      continue;
    }
    for (int t : groups[g]) {
      loops.push_back({tris[t].v[0], tris[t].v[1], tris[t].v[2]});
      shape.normals.push_back(area_normal({t}));
    }
  }

  // Corners that are straight (within tol of the line through their neighbours) on both faces they
  // are on are not corners: points on an edge. (A point on three or more faces stays: removing it
  // from faces whose neighbours differ would leave edges without a partner.)
  std::map<int, bool> straight;  // point -> straight on every face so far
  std::map<int, int> face_count;
  for (const auto& loop : loops)
    for (int p : loop) ++face_count[p];
  for (const auto& loop : loops)
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const Vec3& p = points[loop[(k + loop.size() - 1) % loop.size()]];
      const Vec3& v = points[loop[k]];
      const Vec3& q = points[loop[(k + 1) % loop.size()]];
      const Vec3 dir = (q - p).normalized();
      const bool s = face_count[loop[k]] == 2 && ((v - p) - (v - p).dot(dir) * dir).norm() <= tol;
      const auto [it, fresh] = straight.emplace(loop[k], s);
      if (!fresh) it->second = it->second && s;
    }
  // A face left with 2 corners was a sliver along an edge, narrower than the tolerance: it goes,
  // and the faces on either side meet directly (its points were on those two faces only).
  std::map<int, int> index;  // point -> shape vertex
  std::vector<Vec3> normals;
  for (std::size_t f = 0; f < loops.size(); ++f) {
    std::vector<int> kept;
    for (int p : loops[f])
      if (!straight[p]) kept.push_back(p);
    if (kept.size() < 3) continue;
    for (int& p : kept) {
      const auto [it, fresh] = index.emplace(p, static_cast<int>(shape.vertices.size()));
      if (fresh) shape.vertices.push_back(points[p]);
      p = it->second;
    }
    shape.faces.push_back(std::move(kept));
    normals.push_back(shape.normals[f]);
  }
  shape.normals = std::move(normals);
  if (shape.faces.size() < 4) throw HullError("the hull is degenerate (fewer than 4 faces)");
  canonical_order(shape);
  return shape;
}

}  // namespace dicesim
