// The surface of a convex die, in the geometric frame the scene describes (the compiler later
// moves it to the principal COM frame). Every shape kind reduces to this; a rounded die is this
// polytope (its core) swept by a ball of radius `rounding`, so its outer size is core + rounding.
#pragma once

#include <array>
#include <vector>

#include "sim/math.hpp"

namespace dicesim {

struct ConvexShape {
  std::vector<Vec3> vertices;           // the core's corners
  std::vector<std::vector<int>> faces;  // per face: vertex indices, counter-clockwise seen from outside
  std::vector<Vec3> normals;            // per face: outward unit normal
  double rounding = 0.0;                // radius of the ball swept over the core (m)
};

// A closed surface as triangles, each counter-clockwise seen from outside (a triangle soup: no
// shared indices are needed, only that the triangles close up). Convex or not.
using Triangles = std::vector<std::array<Vec3, 3>>;

// The shape's faces fanned into triangles (the core's, ignoring rounding).
Triangles shape_triangles(const ConvexShape& s);

// Face i's area (of the core's face).
double face_area(const ConvexShape& s, std::size_t i);

// The order every shape but the box (and d6) is listed in, so that it does not depend on how the
// shape was built: faces by decreasing z of the outward normal, then by increasing azimuth
// atan2(y, x) in (-pi, pi] (both compared after rounding to 1e-9, so symmetric faces tie
// exactly); vertices likewise by decreasing z, then azimuth, then distance from the z axis
// (relative to the shape's size); each face's loop starts at its lowest vertex index.
void canonical_order(ConvexShape& s);

// The box of edge lengths `size` centred at the origin: vertex c has bit k set <=> + side along
// axis k; faces in the order +x, -x, +y, -y, +z, -z.
ConvexShape box_shape(const Vec3& size);

}  // namespace dicesim
