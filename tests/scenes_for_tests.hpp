// Scenes built in code for physics tests (no files, so each test states its die exactly).
#pragma once

#include <string>

#include "sim/scene/scene.hpp"

namespace dicesim::testing {

// A cube of edge `edge` with an aluminium slab of thickness fraction `alu_fraction` on the -z side
// and steel above; face +z (label 1) is the all-steel face, -z (label 6) the all-aluminium face.
inline SceneDef slab_scene(double alu_fraction = 0.5, double rho_steel = 7848.0, double rho_alu = 2714.3,
                           double edge = 0.03) {
  SceneDef s = default_scene_def();
  s.name = "test slab die";
  s.materials["steel"] = MaterialDef{rho_steel, 0.487, 0.3};
  s.materials["aluminium"] = MaterialDef{rho_alu, 0.550, 0.3};
  s.die.size = Vec3::Constant(edge);
  s.die.base_material = "aluminium";
  // steel where z >= -edge/2 + alu_fraction * edge, i.e. -z <= edge/2 - alu_fraction * edge
  if (alu_fraction < 1.0)
    s.die.regions.push_back({"steel", {HalfSpace{Vec3(0, 0, -1), 0.5 * edge - alu_fraction * edge}}});
  s.die.face_labels = {2, 5, 3, 4, 1, 6};
  return s;
}

inline SceneDef fair_scene(double edge = 0.03) {
  SceneDef s = default_scene_def();
  s.name = "test fair die";
  s.materials["plastic"] = MaterialDef{1200.0, 0.5, 0.3};
  s.die.size = Vec3::Constant(edge);
  s.die.base_material = "plastic";
  return s;
}

}  // namespace dicesim::testing
