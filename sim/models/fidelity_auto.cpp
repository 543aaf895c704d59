#include "sim/models/fidelity_auto.hpp"

#include <algorithm>
#include <cstdio>

namespace dicesim {

void resolve_fidelity(const SceneDef& scene, DieModel& m) {
  m.fidelity_requested = scene.sim.fidelity;
  if (scene.sim.fidelity != Fidelity::Auto) {
    m.fidelity = scene.sim.fidelity;
    m.fidelity_reason = "stated by the scene (sim.fidelity)";
    return;
  }
  const double mu = *std::max_element(m.vertex_friction.begin(), m.vertex_friction.end());
  char buf[400];
  if (mu == 0.0 && scene.sim.stop_speed > 0.0) {
    m.fidelity = Fidelity::Paper;
    std::snprintf(buf, sizeof buf,
                  "auto: no friction at any corner and the seed's stop rule (sim.stop_speed = %g m/s) ends the "
                  "toss, so the frictionless vertex-impulse model `paper` is all this scene needs (the cheapest "
                  "dynamic model)",
                  scene.sim.stop_speed);
  } else {
    m.fidelity = Fidelity::Impulse;
    if (mu > 0.0)
      std::snprintf(buf, sizeof buf,
                    "auto: corners have friction (up to mu = %g), which only the models with a friction impact law "
                    "and rolling to rest use; `impulse` is the cheapest of them (exact flight between impacts)",
                    mu);
    else
      std::snprintf(buf, sizeof buf,
                    "auto: sim.stop_speed = 0 asks for the die at rest, which needs rolling and tipping to rest; "
                    "`impulse` is the cheapest model that has them");
  }
  m.fidelity_reason = buf;
}

}  // namespace dicesim
