// A die as a body: its convex shape, face labels, mass properties and contact materials, all in
// the geometric frame the scene describes. `build_body` is the only place that knows shape kinds;
// the compiler (sim/models/compile.hpp) turns a Body into the DieModel a toss reads.
#pragma once

#include <string>
#include <vector>

#include "sim/body/cylinder.hpp"
#include "sim/body/mass_properties.hpp"
#include "sim/body/shape.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// Face order: box (and a sharp d6) +x, -x, +y, -y, +z, -z; every other shape, and a rounded box,
// the canonical order of shape.hpp (canonical_order). A rounded die's shape is its core (its
// corners are the centres of the corner balls) with shape.rounding = r.
struct Body {
  std::string kind = "box";                 // the scene's die.shape
  ConvexShape shape;                        // what can touch the floor (the hull, for a mesh)
  std::vector<int> face_labels;             // per shape face
  bool read_down = false;                   // the result is the face on the floor (a d4)
  MassProperties mass;                      // of the solid itself (a mesh's, not its hull's)
  std::vector<double> vertex_restitution;   // per shape vertex, from the materials around it
  std::vector<double> vertex_friction;
  bool convex = true;                       // false: a mesh whose solid is not its hull
  // A cylinder (kind "cylinder", cylinder.radius > 0): `shape` is empty; its contact features are
  // points of the two rim circles (sim/body/rim.hpp); face_labels = heads, tails, edge; the
  // per-vertex materials are per rim feature (3 per rim: +z rim first), each the mix of the
  // materials in its face's outer skin.
  CylinderShape cylinder;
  std::vector<double> vertex_rolling;       // per vertex (or rim feature): rolling resistance (m)
  std::vector<double> vertex_pivoting;      // per vertex (or rim feature): pivoting resistance (m)
};

// Builds and checks the body a scene describes. Throws SceneError (key, value, allowed range) for
// a die that cannot exist: a region covering nothing or overlapping another, no mass, ...
Body build_body(const SceneDef& scene, const std::string& origin);

}  // namespace dicesim
