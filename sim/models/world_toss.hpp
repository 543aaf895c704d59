// A toss of several dice among static obstacles (sim/body/world.hpp), `impulse` physics:
// world_toss.cpp says how. toss() (toss.hpp) sends a model with a world here.
#pragma once

#include <cstdint>
#include <vector>

#include "sim/body/die_model.hpp"
#include "sim/dynamics/flight.hpp"
#include "sim/models/toss.hpp"

namespace dicesim {

// Every die from its start (body frame states, in the world's die order) to rest; m.world set.
// Invalid if a die starts inside another or inside an obstacle.
TossResult run_world(const DieModel& m, const std::vector<RigidState>& starts, const std::vector<double>& tiebreaks,
                     TossProbe* probe);

}  // namespace dicesim
