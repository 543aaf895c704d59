// The ready-made shapes: the regular dice d4..d20 and the regular n-gon prism, centred at the origin.
#pragma once

#include "sim/body/shape.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// A regular die with `size` = distance between opposite faces (d4: from a face to the opposite
// vertex). d6 is box_shape (its face order +x, -x, +y, -y, +z, -z); the others are in the
// canonical order (shape.hpp). Orientation:
//   d4:  the tetrahedron with corners along (1,1,1), (1,-1,-1), (-1,1,-1), (-1,-1,1)
//   d8:  corners on the axes;  d12: corners (+-1,+-1,+-1), (0,+-1/phi,+-phi) and cyclic
//   d20: corners (0,+-1,+-phi) and cyclic
//   d10: the pentagonal trapezohedron (planar kites) dual to the uniform pentagonal antiprism:
//        apexes on the z axis, face normals at elevation +-atan(1/2), upper ones at azimuth 72k deg,
//        lower ones at 36 + 72k deg.
ConvexShape preset_shape(ShapeKind kind, double size);

// The regular `sides`-gon prism along z: n-gon of circumradius `radius` with corners at azimuth
// 360 (k + 1/2) / n deg, so side faces have outward normals at azimuth 360 j / n deg; `length` along z.
ConvexShape prism_shape(int sides, double radius, double length);

// Distance from the origin to the nearest face plane (the inradius for a centred regular die).
double min_face_distance(const ConvexShape& s);

}  // namespace dicesim
