// The scene -> model compiler (as MuJoCo's compiler fills mjModel): geometry and mass properties
// from sim/body, the resting geometry and fidelity choice that sim/dynamics and sim/models need,
// all computed once. Lives above the dynamics it precomputes for.
#pragma once

#include <string>

#include "sim/body/die_model.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// Compiles a validated scene. Throws SceneError for a die that cannot be simulated
// (zero mass, a region covering nothing, ...).
DieModel compile(const SceneDef& scene, const std::string& origin = "scene");

}  // namespace dicesim
