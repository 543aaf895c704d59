// Parameter sweeps with common random numbers: P(face) of one scene at many values of one key.
//
// Every point of a sweep is the base scene with one more `--set KEY=VALUE` override, tossed with
// the same seed and the same toss indices 0..N-1 as every other point. A toss draws its throw
// only from (seed, index), so two points differ only through the parameter: curves are smooth
// and the difference between two points is measured far more precisely than either point.
//
// A sweep comes from the command line (`--param KEY --values SPEC`) or from a sweep file (TOML,
// `[sweep]` table, see scenes/paper/sweeps/README.md); both become one SweepSpec.
// Pure computation: nothing here prints.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sim/study/auto_pilot.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/study/statistics.hpp"

namespace dicesim {

// SPEC: "start:stop:step" (stop included when it is reached within rounding) or a list
// "a,b,c". Every number may be a fraction "p/q" (e.g. "1/30:30/30:1/30"). At most 100 000 values.
// Throws SceneError naming `origin` and `key` (e.g. "dicesim sweep", "--values").
std::vector<double> parse_values(const std::string& spec, const std::string& origin = "dicesim sweep",
                                 const std::string& key = "--values");

// The shortest decimal text that reads back as the same double ("0.1", not "0.10000000000000001").
std::string number_text(double v);
// Six significant digits, for labels and tables ("0.0333333").
std::string short_text(double v);

// How one x value of a sweep becomes a scene override: the scene value is scale * x + shift,
// written into `value_template` at "{}" (default "{}": the number itself). So
//   key = "throw.velocity.mean", value_template = "[{}, 0, 0]"  sweeps the x component only;
//   key = "die.regions", value_template = "[{ material = \"aluminium\", cuts = [{ normal = [0, 0, 1],
//   offset = {} }] }]", scale = 0.03, shift = -0.015  sweeps an aluminium slab's volume fraction.
struct SweepParam {
  std::string key;
  std::vector<double> values;
  std::string value_template = "{}";
  double scale = 1.0;
  double shift = 0.0;
  std::string override_for(double x) const;  // "KEY=VALUE"
};

struct SweepPoint {
  double x = 0.0;                        // what the x axis shows
  std::string label;                     // e.g. "0.5" or "face 3 up"
  std::vector<std::string> overrides;    // this point's --set overrides (after the sweep's own)
};

struct SweepSpec {
  std::string title;                     // e.g. "Sec. 5.4: volume ratio"
  std::string scene;                     // base scene path
  std::vector<std::string> overrides;    // applied at every point, before the point's own
  std::string x_label;                   // axis label (default: the key)
  double reference = 0.0;                // the question's probability (a line on the plot), e.g. 1/3; 0: none
  std::vector<SweepPoint> points;
  bool categorical = false;              // points carry their own labels ([[sweep.points]])
  std::uint64_t tosses = 10000;
  std::uint64_t seed = 1;
  // Only from sweep files: what the sweep reproduces.
  std::string reproduces;                // e.g. "Table 8 (sec. 5.4)"
  std::string seed_table;                // path of a CSV: x, P1..P6 (resolved against the file)
  std::uint64_t seed_tosses = 0;         // tosses per point in the seed's run (for chi-square)
  std::string reading;                   // how the seed's settings were read
  std::string notes;                     // what explains disagreements
  std::string source;                    // the sweep file, if any
};

// A sweep of `param` over its values on `scene`.
SweepSpec sweep_from_param(const std::string& scene, const SweepParam& param,
                           const std::vector<std::string>& overrides = {});

// True if `path` is a TOML file with a top-level [sweep] table (a sweep file, not a scene).
bool is_sweep_file(const std::string& path);

// Reads and checks a sweep file; paths inside it are relative to the file. Throws SceneError
// naming the file, key, value and what is allowed.
SweepSpec load_sweep_file(const std::string& path);

struct SweepPointResult {
  SweepPoint point;
  RunCounts counts;
  std::vector<int> labels;  // the model's outcome labels (counts.faces in this order)
  std::string fidelity;
  std::string fidelity_reason;  // why (auto: each point's own pilot, at the sweep's tosses per point)
  FidelityPilot pilot;
  std::string scene_sha256;     // the point's fully resolved scene (sim/scene/scene_hash.hpp)
  // Cancelled during this point (in-process only): counts are the complete prefix 0..k-1 of its
  // tosses (k = counts.total() < tosses), the same as a point of k tosses.
  bool partial = false;
};

struct SweepResult {
  std::vector<SweepPointResult> points;  // those done, in order (a cancelled sweep: a prefix of the points)
  double elapsed_s = 0.0;
};

struct SweepRunOptions {
  int threads = 1;
  // (tosses done over the whole sweep, total) about every 100 ms.
  std::function<void(std::uint64_t, std::uint64_t)> progress;
  const std::atomic<bool>* cancel = nullptr;
  // How one point is tossed; empty: run_tosses in this process. `overrides` are the point's full
  // list (the sweep's, then its own), so a distributed runner can describe the run to workers.
  // `progress` (tosses done of this point) may be called from any thread.
  using PointRunner = std::function<RunCounts(const DieModel& model, const std::vector<std::string>& overrides,
                                              const RunConfig& cfg, const std::function<void(std::uint64_t)>& progress)>;
  PointRunner run_point;
};

// Loads and compiles every point first (bad input fails before any toss), then tosses each with
// run_tosses over the same seed and indices 0..tosses-1. Every point's die must have the same
// outcome labels (any number of them), and a seed table (P1..P6) needs six labelled 1..6: else
// SceneError naming the point.
SweepResult run_sweep(const SweepSpec& spec, const SweepRunOptions& opt);

// Per-outcome values of a point, in label order (ascending), one per outcome of the die.
struct FaceEstimate {
  int label = 0;
  std::uint64_t count = 0;
  double p = 0.0;
  Interval ci95;
};
std::vector<FaceEstimate> face_estimates(const RunCounts& counts, const std::vector<int>& labels);

// A table of P(face) against x from a CSV such as the seed's tables: '#' comment lines, one
// header line, then rows x,P1,...,P6 (faces 1..6). Throws SceneError naming the file and line.
struct ReferenceRow {
  double x = 0.0;
  std::array<double, 6> p{};
};
std::vector<ReferenceRow> load_reference_table(const std::string& path);

// The reference row whose x matches (relative tolerance 1e-4), if any.
std::optional<ReferenceRow> find_reference(const std::vector<ReferenceRow>& rows, double x);

}  // namespace dicesim
