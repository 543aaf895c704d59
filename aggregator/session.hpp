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
};

SessionResult run_session(const SessionOptions& opt, const AggregatorConfig& cfg);

// One line for stderr: received, duplicates, rejected (foreign / malformed / out of range), released.
std::string health_line(const Health& h);

}  // namespace dicesim::agg
