#include "sim/body/shape.hpp"

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

}  // namespace dicesim
