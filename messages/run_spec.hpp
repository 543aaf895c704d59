// What a run is, as run_start carries it: the scene files (the main one and every file it
// `extends`), the overrides, the seed and the size. Both sides rebuild the model through the
// same load_scene() call as `dicesim toss`, so a worker's model is the aggregator's model; a
// fingerprint of the compiled model proves it (a mismatched build refuses the run).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "dicesim_lcm/run_start.hpp"
#include "sim/body/die_model.hpp"

namespace dicesim::wire {

struct SceneFile {
  std::string path;  // relative to the files' common root, '/'-separated
  std::string text;
};

struct RunSpec {
  std::int64_t run_id = 0;
  std::string origin;              // as the user typed it
  std::vector<SceneFile> files;    // files[0] is the scene itself, then its bases
  std::vector<std::string> overrides;
  std::string fidelity;
  std::uint64_t seed = 1;
  std::uint64_t total = 0;
  int trace_every = 0;
  std::uint64_t fingerprint = 0;   // model_fingerprint of the compiled model
  std::string hash;                // scene_hash()
  std::vector<int> labels;         // the model's outcome_labels: results are indices into these
  std::vector<SceneFile> assets;   // files the scene reads besides TOML (a mesh's OBJ), same root as files
};

// The die fits the wire: 1 to kMaxOutcomes outcomes, labels in [0, kMaxLabel] (messages/wire.hpp).
// Throws SceneError naming `origin`, the outcome count and the limit otherwise.
void check_wire_outcomes(const DieModel& m, const std::string& origin);

// Reads `path` and the files it extends (throws SceneError if unreadable). Does not compile.
// `asset_paths` (e.g. a mesh's OBJ) are read too, into `assets`, relative to the same root.
std::vector<SceneFile> read_scene_files(const std::string& path, const std::vector<std::string>& asset_paths = {},
                                        std::vector<SceneFile>* assets = nullptr);

// FNV-1a 64 over every path, text and override (hex): names the exact input of a run.
std::string scene_hash(const std::vector<SceneFile>& files, const std::vector<std::string>& overrides);

// Hash of everything in a compiled model that a toss reads (bit patterns of the doubles).
std::uint64_t model_fingerprint(const DieModel& m);

// Writes the files into a private temporary directory, loads and compiles them exactly as
// `dicesim toss` would load the original, and removes the directory. Throws SceneError.
DieModel compile_spec(const RunSpec& spec);

// What compile_spec does for callers that need more than the model (`dicesim serve`'s pages: the
// scene's definition too): writes the files into a private temporary directory, calls f(the main
// scene's path there, the overrides to apply) and removes the directory. Throws SceneError.
void with_spec_files(const RunSpec& spec, const std::function<void(const std::string&, const std::vector<std::string>&)>& f);

// The description of a run of `scene_path` with `overrides` (any fidelity choice among them),
// whose compiled model is `model`. Checks that the description rebuilds into exactly that model,
// as every worker will rebuild it, and throws std::runtime_error if not.
RunSpec make_run_spec(std::int64_t run_id, const std::string& scene_path, const std::vector<std::string>& overrides,
                      const DieModel& model, std::uint64_t seed, std::uint64_t total, int trace_every = 0);

// A fresh non-zero run id (63 bits from std::random_device: run ids name runs, they never
// influence a result).
std::int64_t new_run_id();

dicesim_lcm::run_start to_message(const RunSpec& spec);
RunSpec from_message(const dicesim_lcm::run_start& msg);

}  // namespace dicesim::wire
