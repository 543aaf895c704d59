// The aggregator on a live LCM bus: subscribes to every DICESIM_ channel (raw bytes, so that the
// Aggregator itself judges them), pumps messages and ticks until the run finishes, is cancelled,
// or fails.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "aggregator/aggregator.hpp"

namespace dicesim::agg {

struct SessionOptions {
  std::string url;                              // already resolved (wire::resolve_url)
  const std::atomic<bool>* cancel = nullptr;    // set from a signal handler: stop now
  // Called about every 20 ms; return a non-empty message to abort the run as failed.
  std::function<std::string(const Aggregator&)> on_tick;
  int queue_capacity = 4096;                    // per subscription (LCM 1.3.1's default is 30)
  std::string checkpoint_path;                  // non-empty: write the state there (checkpoint.hpp)
  double checkpoint_period_s = 1.0;             // at most this often (and once at the end)
  const Checkpoint* resume = nullptr;           // continue this run instead of starting it
  // Called once the aggregator exists (e.g. to log what a resume found).
  std::function<void(const Aggregator&)> on_start;
};

enum class SessionEnd { Finished, Cancelled, Failed };

struct SessionResult {
  SessionEnd end = SessionEnd::Failed;
  std::string error;
  double elapsed_s = 0.0;
  RunCounts counts;          // over [0, tosses) when Finished
  std::uint64_t tosses = 0;
  Health health;
  std::vector<std::string> refusals;
  double run_elapsed_s = 0.0;         // over every session of the run (resumes included)
  // Checkpoint cost: the aggregator's own loop pays snapshot_s (taking and serialising the
  // state); the writer thread spends writer.write_s in write + fsync + rename + fsync.
  std::uint64_t snapshots = 0;
  double snapshot_s = 0.0, max_snapshot_s = 0.0;
  CheckpointWriter::Stats writer;
};

SessionResult run_session(const SessionOptions& opt, const AggregatorConfig& cfg);

// One line for stderr: received, duplicates, rejected (foreign / malformed / out of range), released.
std::string health_line(const Health& h);

}  // namespace dicesim::agg
