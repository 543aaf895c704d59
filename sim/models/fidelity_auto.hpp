// The fidelity a compiled model starts with. A stated model is taken as stated. `auto` cannot be
// decided at compile time: it needs the run's precision, so compile() keeps Auto requested and
// tosses `impulse` (the safe answer) until resolve_auto (sim/study/auto_pilot.hpp) measures
// whether a cheaper model is adequate for the run at hand.
#pragma once

#include "sim/body/die_model.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// Sets m.fidelity (never Auto), m.fidelity_requested and m.fidelity_reason from scene.sim.fidelity.
void resolve_fidelity(const SceneDef& scene, DieModel& m);

}  // namespace dicesim
