// What made a result: every command's table header and JSON carry one Provenance, written by the
// functions here only (the CLI, the aggregator and Python alike).
//
// JSON (the "provenance" key of every result object):
//   {"version": "git describe --always --dirty at build time" (a tarball: "<project version>-nogit"),
//    "dirty": true/false (null: not built from a git checkout),
//    "scene": the scene file as given, "scene_sha256": the fully resolved scene's hash
//    (sim/scene/scene_hash.hpp: after extends and --set; canonical, the same on any machine),
//    "overrides": ["KEY=VALUE", ...] in the order applied (--fidelity F is the last, sim.fidelity="F"),
//    "fidelity": the model run, "fidelity_requested": what the scene asked for (may be "auto"),
//    "fidelity_reason": why (the model's reason), "seed", "tosses": asked for (per point or per
//    evaluation for sweep, fit and power), "threads"}
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sim/body/die_model.hpp"

namespace dicesim {

// Generated at build time (apps/git_version.cmake).
const char* git_describe();
int git_dirty();  // 1 dirty, 0 clean, -1 unknown (not a git checkout)

struct Provenance {
  std::string version = git_describe();
  int dirty = git_dirty();
  std::string scene;
  std::string scene_sha256;
  std::vector<std::string> overrides;
  std::string fidelity, fidelity_requested, fidelity_reason;
  std::uint64_t seed = 0;
  std::uint64_t tosses = 0;
  int threads = 1;
};

// From the scene's hash and the model compiled from it (the fidelity, as chosen, and why).
// `scene_sha256`: scene_sha256(scene_path, overrides) (sim/scene/scene_hash.hpp) or the like.
Provenance make_provenance(const std::string& scene_path, const std::vector<std::string>& overrides,
                           const std::string& scene_sha256, const DieModel& model, std::uint64_t seed, std::uint64_t tosses,
                           int threads);
nlohmann::json provenance_json(const Provenance& p);
// The table header's lines: "dicesim VERSION, scene sha256 HASH\noverrides: ...\nfidelity F (asked: A): REASON\n".
std::string provenance_lines(const Provenance& p);
// A CSV file's first line: "# provenance {JSON}" (readers that skip '#' lines, as dicesim's own, skip it).
std::string provenance_csv_comment(const Provenance& p);

}  // namespace dicesim
