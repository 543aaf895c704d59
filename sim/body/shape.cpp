#include "sim/body/shape.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace dicesim {

ConvexShape box_shape(const Vec3& size) {
  ConvexShape s;
  const Vec3 half = 0.5 * size;
  for (int c = 0; c < 8; ++c) {
    Vec3 v;
    for (int a = 0; a < 3; ++a) v[a] = ((c >> a) & 1) ? half[a] : -half[a];
    s.vertices.push_back(v);
  }
  for (int f = 0; f < 6; ++f) {
    const int axis = f / 2;
    const bool plus = f % 2 == 0;
    Vec3 n = Vec3::Zero();
    n[axis] = plus ? 1.0 : -1.0;
    // The face's corners in cyclic order, then oriented counter-clockwise about n.
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    const int bit = plus ? (1 << axis) : 0;
    std::vector<int> loop = {bit, bit | (1 << u), bit | (1 << u) | (1 << w), bit | (1 << w)};
    const Vec3 e1 = s.vertices[loop[1]] - s.vertices[loop[0]];
    const Vec3 e2 = s.vertices[loop[2]] - s.vertices[loop[1]];
    if (e1.cross(e2).dot(n) < 0.0) std::swap(loop[1], loop[3]);
    s.faces.push_back(loop);
    s.normals.push_back(n);
  }
  return s;
}

Triangles shape_triangles(const ConvexShape& s) {
  Triangles out;
  for (const auto& loop : s.faces)
    for (std::size_t k = 1; k + 1 < loop.size(); ++k)
      out.push_back({s.vertices[loop[0]], s.vertices[loop[k]], s.vertices[loop[k + 1]]});
  return out;
}

double face_area(const ConvexShape& s, std::size_t i) {
  const auto& loop = s.faces[i];
  Vec3 a = Vec3::Zero();
  for (std::size_t k = 1; k + 1 < loop.size(); ++k)
    a += (s.vertices[loop[k]] - s.vertices[loop[0]]).cross(s.vertices[loop[k + 1]] - s.vertices[loop[0]]);
  return 0.5 * a.norm();
}

namespace {

long long quantize(double x) { return std::llround(x * 1e9); }

std::tuple<long long, long long, long long> direction_key(const Vec3& v, double scale) {
  const Vec3 u = v / scale;
  const bool on_axis = std::hypot(u.x(), u.y()) <= 1e-12;
  return {-quantize(u.z()), on_axis ? 0 : quantize(std::atan2(u.y(), u.x())), quantize(std::hypot(u.x(), u.y()))};
}

}  // namespace

void canonical_order(ConvexShape& s) {
  double scale = 0.0;
  for (const Vec3& v : s.vertices) scale = std::max(scale, v.norm());
  if (!(scale > 0.0)) scale = 1.0;
  std::vector<int> vorder(s.vertices.size());
  std::iota(vorder.begin(), vorder.end(), 0);
  std::stable_sort(vorder.begin(), vorder.end(), [&](int a, int b) {
    return direction_key(s.vertices[a], scale) < direction_key(s.vertices[b], scale);
  });
  std::vector<int> new_index(s.vertices.size());
  std::vector<Vec3> vertices(s.vertices.size());
  for (std::size_t k = 0; k < vorder.size(); ++k) {
    new_index[vorder[k]] = static_cast<int>(k);
    vertices[k] = s.vertices[vorder[k]];
  }
  for (auto& loop : s.faces) {
    for (int& v : loop) v = new_index[v];
    std::rotate(loop.begin(), std::min_element(loop.begin(), loop.end()), loop.end());
  }
  std::vector<int> forder(s.faces.size());
  std::iota(forder.begin(), forder.end(), 0);
  std::stable_sort(forder.begin(), forder.end(), [&](int a, int b) {
    const auto ka = direction_key(s.normals[a], 1.0), kb = direction_key(s.normals[b], 1.0);
    return std::make_pair(std::get<0>(ka), std::get<1>(ka)) < std::make_pair(std::get<0>(kb), std::get<1>(kb));
  });
  std::vector<std::vector<int>> faces;
  std::vector<Vec3> normals;
  for (int f : forder) {
    faces.push_back(std::move(s.faces[f]));
    normals.push_back(s.normals[f]);
  }
  s.vertices = std::move(vertices);
  s.faces = std::move(faces);
  s.normals = std::move(normals);
}

}  // namespace dicesim
