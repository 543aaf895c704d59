// --fidelity F on any command: a name that is not a fidelity is bad input naming it and the
// choices (SceneError: exit 2), not a complaint about the sim.fidelity override it would become.
#pragma once

#include <string>

namespace dicesim {

// Throws SceneError for a non-empty name that is not a fidelity (cli.cpp).
void check_fidelity_name(const std::string& fidelity);

}  // namespace dicesim
