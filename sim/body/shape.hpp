// The surface of a convex die, in the geometric frame the scene describes (the compiler later
// moves it to the principal COM frame). Every shape kind reduces to this; a rounded die is this
// polytope (its core) swept by a ball of radius `rounding`, so its outer size is core + rounding.
#pragma once

#include <vector>

#include "sim/math.hpp"

namespace dicesim {

struct ConvexShape {
  std::vector<Vec3> vertices;           // the core's corners
  std::vector<std::vector<int>> faces;  // per face: vertex indices, counter-clockwise seen from outside
  std::vector<Vec3> normals;            // per face: outward unit normal
  double rounding = 0.0;                // radius of the ball swept over the core (m)
};

// The box of edge lengths `size` centred at the origin: vertex c has bit k set <=> + side along
// axis k; faces in the order +x, -x, +y, -y, +z, -z.
ConvexShape box_shape(const Vec3& size);

}  // namespace dicesim
