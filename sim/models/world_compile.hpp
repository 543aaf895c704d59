// compile() for several dice or obstacles (sim/body/world.hpp): world_compile.cpp.
#pragma once

#include <string>

#include "sim/body/die_model.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// The first die's model with the toss's outcomes, pointing to the compiled world. Throws SceneError
// for what a world toss cannot run (a curved die, `paper` or `stepped`, a catch, too many tuples).
DieModel compile_world(const SceneDef& scene, const std::string& origin);

}  // namespace dicesim
