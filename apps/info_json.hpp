// What `dicesim info --json` prints: the compiled die as one JSON object. Shared by the CLI and the
// Python module (python/), so it lives in dicesim_report, which needs nothing of the CLI.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "sim/body/die_model.hpp"

namespace dicesim {

// {"scene", "name", "mass", "com", "inertia", "principal_moments", "principal_axes", "symmetric_top",
//  "bounding_radius", "faces", "corners", "fidelity", "fidelity_requested", "fidelity_reason", "rest"}
nlohmann::json info_json(const std::string& path, const DieModel& m);

}  // namespace dicesim
