// A shard's file (`dicesim toss --shard I/N --out FILE`) and `dicesim merge`: the toss's --json
// report plus a "shard" object holding what merging needs and checks -- the build's version, the
// scene's hash (its files, assets and overrides, fidelity included), the compiled model's
// fingerprint, seed, fidelity, whole-run size, I/N with its index block, and the raw counts.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/report.hpp"
#include "sim/study/shard.hpp"

namespace dicesim {

// A shard file that cannot be read or merged: bad input (exit 2); the message names the file.
struct ShardError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct ShardHeader {
  std::string version;      // the dicesim build that tossed it
  std::string scene_hash;   // wire::scene_hash of the scene's files, assets and overrides
  std::string fingerprint;  // wire::model_fingerprint of the compiled model (hex)
  std::uint64_t total = 0;  // the whole run's tosses
  Shard shard;
  IndexRange range;
};

// The dicesim version this build reports in shard files.
std::string build_version();
// The header of shard `s` of a `total`-toss run of `scene_path` with `overrides` (fidelity among them).
ShardHeader make_shard_header(const std::string& scene_path, const std::vector<std::string>& overrides,
                              const DieModel& model, std::uint64_t total, Shard s);
// report_json(r) plus "shard": {"version", "scene_hash", "model_fingerprint", "index", "count",
// "first", "tosses", "total", "labels", "faces_per_label", "names", "counts": {"faces" (in label
// order), "settled", "unresolved", "invalid", "bounces", "corrections"}}.
nlohmann::json shard_json(const RunReport& r, const ShardHeader& h);

struct ShardPart {
  std::string file;
  ShardHeader header;
  RunReport report;
};
// Throws ShardError naming `file`.
ShardPart read_shard_file(const std::string& file);
// The whole run from its shards: counts added, tosses = the whole run, threads and elapsed_s the
// shards' added. Throws ShardError naming the file: mixed versions, scenes, models, seeds,
// fidelities or run sizes, a shard given twice (overlap), a shard missing.
RunReport merge_shards(const std::vector<ShardPart>& parts);

}  // namespace dicesim
