// RunCounts as JSON, the part a checkpoint (checkpoint.hpp) and a shard file (apps/shard_file.hpp)
// write alike: "faces" (in label order), "settled", "unresolved", "invalid", "bounces". Each writes
// "corrections" its own way -- a checkpoint as an array in RunCorrections::for_each order (old
// files hold 4), a shard file as an object by name, as --json reports print it -- so the caller
// passes and reads that one.
#pragma once

#include <nlohmann/json.hpp>

#include "sim/study/monte_carlo.hpp"

namespace dicesim::agg {

// The five fields plus "corrections": `corrections`.
nlohmann::json count_fields_json(const RunCounts& c, nlohmann::json corrections);
// The five fields (nlohmann::json::exception when one is missing or of another type); the
// corrections are left at 0 for the caller to read from j["corrections"].
RunCounts count_fields_from(const nlohmann::json& j);

}  // namespace dicesim::agg
