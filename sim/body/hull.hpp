// The convex hull of points as a ConvexShape: qhull's triangles, coplanar ones merged into faces.
#pragma once

#include <stdexcept>
#include <vector>

#include "sim/body/shape.hpp"

namespace dicesim {

// Coplanar tolerance, relative to the points' bounding-box diagonal D: adjacent hull triangles
// whose corners all lie within kCoplanarTolerance * D of one face's plane are one face, and a
// corner within that distance of the line through its neighbours on every face it is on is not a
// corner. The same tolerance decides that the points are flat (no hull).
inline constexpr double kCoplanarTolerance = 1e-6;

// Thrown for points without a solid hull; the message says why (fewer than 4 points, all in one
// plane, on one line, ...). build_body turns it into a SceneError naming the key.
struct HullError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The hull in the canonical order of shape.hpp (canonical_order). Faces: planar within the
// tolerance above, counter-clockwise from outside, outward normals (area-weighted mean of the
// face's triangles' normals). Uses qhull (libqhull_r, option Qt).
ConvexShape convex_hull(const std::vector<Vec3>& points);

}  // namespace dicesim
