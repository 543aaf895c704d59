#include "sim/models/fidelity_auto.hpp"

#include <string>

namespace dicesim {

void resolve_fidelity(const SceneDef& scene, DieModel& m) {
  m.fidelity_requested = scene.sim.fidelity;
  if (scene.sim.fidelity != Fidelity::Auto) {
    m.fidelity = scene.sim.fidelity;
    // The scene file, an `extends` base, --set sim.fidelity or --fidelity: all reach sim.fidelity.
    m.fidelity_reason = std::string("stated: sim.fidelity = \"") + to_string(m.fidelity) +
                        "\" (in the scene, a scene it extends, --set or --fidelity)";
    return;
  }
  m.fidelity = Fidelity::Impulse;
  m.fidelity_reason =
      "auto, not yet measured: `impulse` (the reference every cheaper model is checked against) until a pilot at "
      "the run's precision shows a cheaper model adequate";
}

}  // namespace dicesim
