// What a die is made of, for `dicesim info` (a maker checking an insert): the volume and mass of
// the base material's part and of each region. Kept out of Body and DieModel: no toss reads it.
#pragma once

#include <string>
#include <vector>

#include "sim/scene/scene.hpp"

namespace dicesim {

struct MaterialPart {
  std::string what;      // "base" (all that no region covers) or "region k" (die.regions[k])
  std::string material;  // the scene's material name
  double density = 0.0;  // kg/m^3
  double volume = 0.0;   // m^3, exact as the mass properties are
  double mass = 0.0;     // kg
};

// The base part first, then each region in scene order. Builds the body again (sim/body/body.hpp):
// throws SceneError as build_body does.
std::vector<MaterialPart> material_parts(const SceneDef& scene, const std::string& origin);

}  // namespace dicesim
