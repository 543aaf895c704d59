// The scene -> model compiler (as MuJoCo's compiler fills mjModel): geometry and mass properties
// from sim/body, the resting geometry and fidelity choice that sim/dynamics and sim/models need,
// all computed once. Lives above the dynamics it precomputes for.
#pragma once

#include <string>

#include "sim/body/body.hpp"
#include "sim/body/die_model.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// Compiles a validated scene. Throws SceneError for a die that cannot be simulated
// (zero mass, a region covering nothing, ...).
DieModel compile(const SceneDef& scene, const std::string& origin = "scene");

// The same from a body already built (sim/body/body.hpp): the scene gives materials' floor
// override, simulation settings and the throw. Throws SceneError for a body that is not a closed,
// consistently oriented convex hull with a label per face and a material per corner.
DieModel compile_body(const Body& body, const SceneDef& scene, const std::string& origin = "scene");

}  // namespace dicesim
