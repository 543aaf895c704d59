// The convex hull of points as a ConvexShape: qhull's triangles, coplanar ones merged into faces.
#pragma once

#include <stdexcept>
#include <vector>

#include "sim/body/shape.hpp"

namespace dicesim {

// Coplanar tolerance, relative to the points' bounding-box diagonal D: adjacent hull triangles
// whose corners all lie within kCoplanarTolerance * D of one face's plane are one face, and a
// point on exactly two faces within that distance of the line through its neighbours on both is
// not a corner (a point on an edge; a face left with two corners, a sliver along an edge, goes).
// The same tolerance decides that the points are flat (no hull).
inline constexpr double kCoplanarTolerance = 1e-6;

// Thrown for points without a solid hull; the message says why (fewer than 4 points, all in one
// plane, on one line, ...). build_body turns it into a SceneError naming the key.
struct HullError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The hull in the canonical order of shape.hpp (canonical_order). Faces: planar within the
// tolerance above, counter-clockwise from outside, outward normals (qhull's supporting plane of
// the face's first triangle; a face of one triangle: that triangle's own normal). Uses qhull (libqhull_r, option Qt).
ConvexShape convex_hull(const std::vector<Vec3>& points);

}  // namespace dicesim
