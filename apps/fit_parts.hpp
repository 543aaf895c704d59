// A fit sharded by point: the part files of `dicesim fit --points I/N --parts DIR` and their
// reading for `dicesim fit --merge DIR` (the stages and passes: sim/study/fit.hpp, FitPointCounts).
// A part is one shard's block of one stage, DIR/fit-part-s<STAGE>-<I>of<N>.json:
//   {"fit_part": {"fit": {identity}, "index": I, "count": N, "stage": K, "label": "round 1/3",
//                 "stage_points": P, "points": [{"point", "theta", "tosses", "faces", "settled"}]}}
// The identity is what every part of one fit shares: the build, each data set's scene (resolved
// hash), overrides and observed counts, the keys and ranges, seed, tosses, rounds and batches.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/shard_file.hpp"
#include "sim/study/fit.hpp"

namespace dicesim {

nlohmann::json fit_identity(const std::vector<FitParam>& params, const std::vector<FitData>& data, const FitOptions& opt);

std::string fit_part_path(const std::string& dir, int stage, Shard s);

// Writes a pass's tossed block (FitStageIncomplete::tossed) atomically (a temporary, then renamed);
// returns the path.
std::string write_fit_part(const std::string& dir, const nlohmann::json& identity, Shard s, const FitStageIncomplete& inc);

struct FitParts {
  std::vector<FitPointCounts> points;  // origin: the part file
  std::uint64_t count = 0;             // N, the shards of every part (0: no part found)
  std::size_t files = 0;
};
// Every DIR/fit-part-*.json. Throws ShardError naming the file: unreadable, not a fit part, a part
// of another fit (its identity differs: the first differing field is named), or of another N than
// `count` (0: the first part's).
FitParts read_fit_parts(const std::string& dir, const nlohmann::json& identity, std::uint64_t count);

// The merge's refusal for a stage not wholly counted: names the first missing part file.
std::string missing_parts_message(const std::string& dir, std::uint64_t count, const FitStageIncomplete& inc);

}  // namespace dicesim
