// A scene's [[obstacles]] as the convex pieces the dice collide with (issue 41): every composition
// (tray, backboard, tower, cup) expanded into boxes and pyramids, in world coordinates. The floor
// z = 0 is not a piece: it stays the resting surface. Static geometry only; no dynamics here.
#pragma once

#include <string>
#include <vector>

#include "sim/math.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// One convex piece: a half-space (a plane) or a convex polyhedron.
struct ObstaclePiece {
  bool plane = false;
  // plane: the solid {x : normal . x <= offset}, normal unit, pointing into the free space.
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
  std::vector<Vec3> corners;       // polyhedron: world corners of its convex hull (only hull vertices)
  std::vector<Vec3> face_normals;  // polyhedron: outward unit face normals (world)
  std::vector<Vec3> face_points;   // polyhedron: per face, one of its corners (face f's plane: n_f . (x - p_f) = 0)
  std::vector<Vec3> edge_dirs;     // polyhedron: unit edge directions (world), one per parallel class
  double restitution = 0.5, friction = 0.3;  // from its material
  std::string material;            // the [materials] key it is made of
  std::string name;                // e.g. "obstacles[2] tray wall +x", for reports and errors
};

// Every [[obstacles]] entry of `s` expanded, in entry order (within an entry, in the order its kind
// lists below):
//   plane       one half-space.
//   polyhedron  the convex hull of `vertices` (sim/body/hull.hpp; throws HullError if flat).
//   box         one box of edge lengths `size` at `centre`, turned by `yaw_deg`.
//   tray        four wall boxes of `thickness` around the inner rectangle size.x by size.y, size.z
//               high: walls +x and -x span the outer width (size.y + 2 thickness), +y and -y the
//               inner length, so the corners are closed.
//   backboard   the board (a box `thickness` deep behind the face, `width` by `height`), then the
//               pyramids row by row from the bottom, each row from local -y to +y: square bases of
//               `pyramid_base` on the face in a grid of `pyramid_pitch` centred on the face (as
//               many as fit), apexes `pyramid_height` out toward local -x.
//   tower       walls -x, +y, -y (full height), +x above the exit (from `exit_height` up), then the
//               baffles from the bottom (thin boxes of `thickness`, the full inner y width).
//   cup         `sides` wall boxes, wall j facing azimuth yaw + 360 deg * j / sides.
// A piece's friction and restitution are its material's.
std::vector<ObstaclePiece> obstacle_pieces(const SceneDef& s);

}  // namespace dicesim
