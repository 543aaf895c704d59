// The resolved scene of a run as run_start describes it: its SHA-256 (sim/scene/scene_hash.hpp),
// the same as `dicesim toss` of the original files reports, for a result's provenance.
#pragma once

#include <string>

#include "messages/run_spec.hpp"

namespace dicesim::wire {

// Throws SceneError as compile_spec does.
std::string spec_scene_sha256(const RunSpec& spec);

}  // namespace dicesim::wire
