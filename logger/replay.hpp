// Replaying a recorded run from its LCM event log alone. The run describes itself (run_start
// carries the scene files, overrides, seed and size), and the log's messages are fed, in order,
// to the aggregator's own code (agg::Aggregator): the counts are those of the live run, computed
// as fast as the file reads. Optionally the messages are also re-published at their recorded pace.
// A traced toss (bounce_state messages) can be checked against a re-simulation of (scene, seed, i).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "aggregator/aggregator.hpp"
#include "messages/run_spec.hpp"
#include "messages/wire.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/models/toss.hpp"

namespace dicesim::eventlog {

struct ReplayOptions {
  std::string path;
  std::int64_t run_id = 0;     // the run to replay (0: the first announced in the log)
  bool live = false;           // also re-publish every event on `url` at the recorded pace
  std::string url;             // resolved (wire::resolve_url); with live only
  double speed = 1.0;          // with live: 2 = twice as fast as recorded
  const std::atomic<bool>* cancel = nullptr;
  std::function<void(std::uint64_t bytes_read, std::uint64_t file_size)> on_progress;  // now and then
  // The run key (messages/auth.hpp): only messages whose HMAC seal opens are used (the rest are
  // counted in health.unauthenticated). Needed for the log of an authenticated run.
  std::vector<std::uint8_t> key;
};
ReplayOptions default_replay_options();

struct ReplayResult {
  wire::RunSpec spec;                // from run_start
  std::vector<int> labels;           // the run's outcome labels (run_start's), counts in this order
  bool model_matches = true;         // the model rebuilt here has the run's fingerprint
  DieModel model;                    // that model (its faces per label, a coin's heads and tails)
  RunCounts counts;                  // over toss indices [0, tosses)
  std::uint64_t tosses = 0;
  agg::Health health;                // what the aggregator ignored, and why
  int workers = 0;                   // distinct workers that served the run (by worker_status)
  std::uint64_t events = 0, bytes = 0;
  double run_span_s = 0.0;           // recorded time from the run's first to its last message
  std::optional<dicesim_lcm::probabilities> recorded_final;  // the live aggregator's last word, if logged
  bool stopped_at_target = false;    // the live run stopped early (--target-halfwidth): replayed to there
  std::vector<std::int64_t> other_runs;  // further runs announced in the same log
  bool cancelled = false;
  // Every (authentic) toss result of the run in the log, counted: minus `tosses`, the tosses that
  // were computed (or sent) more than once, e.g. re-leased after a lost batch or an aggregator restart.
  std::uint64_t results_in_log = 0;
};

// Throws LogError (unreadable, corrupt or truncated log; no such run; the log does not hold the
// whole run) or std::runtime_error (the scene in run_start does not rebuild).
ReplayResult replay(const ReplayOptions& opt);

// Do the recomputed counts equal the live aggregator's final message in the log?
bool same_as_recorded(const ReplayResult& r);

// One traced toss: its bounce states from the log next to a re-simulation.
struct TossCheck {
  wire::RunSpec spec;
  std::uint64_t index = 0;
  std::vector<dicesim_lcm::bounce_state> logged;  // by bounce number, duplicates removed
  std::vector<BounceRecord> simulated;
  TossResult sim;
  bool batch_found = false;                       // the log also holds the toss's result...
  int log_face = 0, log_status = 0, log_bounces = 0;  // ...which is this (log_face: the outcome's label)
  double max_abs_diff = 0.0;                      // over every logged field, against the re-simulation
  bool bit_identical = false;
  bool agree = false;
  bool model_matches = true;
};

// Throws LogError when the log has no bounce state for `index` (the message lists traced indices).
TossCheck check_toss(const std::string& path, std::int64_t run_id, std::uint64_t index,
                     const std::vector<std::uint8_t>& key = {});

}  // namespace dicesim::eventlog
