// `fidelity = "auto"`: the cheapest model that the scene's features need, decided once when the
// scene is compiled (never per toss), with the reason in words for `dicesim info`.
#pragma once

#include "sim/body/die_model.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// Sets m.fidelity (never Auto), m.fidelity_requested and m.fidelity_reason from scene.sim.fidelity.
// Needs m.vertex_friction.
void resolve_fidelity(const SceneDef& scene, DieModel& m);

}  // namespace dicesim
