// What `dicesim serve`'s page shows, fed from the bus: the aggregator's latest answer per run
// (DICESIM_PROBABILITIES) and the workers' heartbeats (DICESIM_WORKER_STATUS), as one JSON state
// with a version that changes on every update. Thread-safe: the bus thread feeds it, the HTTP
// threads read it and wait for changes.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "messages/auth.hpp"
#include "messages/run_spec.hpp"

namespace dicesim::web {

class LiveBoard {
 public:
  // key: a run key (messages/auth.hpp): only messages whose seal opens count, the others are
  // counted as unauthenticated. Empty: unsealed messages count, sealed ones (a run with a key)
  // are counted as sealed and not shown.
  // trace_every K > 0: the state names the run's latest K-th toss index reached (the page animates
  // it, web/serve.js), and run_start messages (DICESIM_RUN_START) are kept: run_spec().
  explicit LiveBoard(const std::vector<std::uint8_t>& key = {}, std::uint64_t trace_every = 0);

  // One message as heard on `channel` (sealed bytes). Others' channels are ignored.
  void handle(const std::string& channel, const void* data, std::size_t len);

  // The state as JSON text, and its version (0 before anything was heard):
  // {"version", "run": {run_id, run_id_text (exact in JavaScript, whose numbers are doubles), labels, counts, p, ci_lo, ci_hi, settled, unresolved, invalid, done,
  //  total, tosses_per_s, eta_s, finished, workers, duplicates, rejected_foreign, rejected_malformed,
  //  rejected_range, rejected_unauthenticated, released} or null, "workers": [{id, host, pid, state,
  //  error, tosses_done, tosses_per_s, age_s, health: "ok"|"late"|"silent"}],
  //  "heard": {unauthenticated (seal missing or wrong), sealed (sealed, and this server has no key),
  //  malformed} (what this server could not open or decode), "key": whether it has a key,
  //  "trace": null, or (trace_every K) {"every": K, "run": run_id as text, "index": K floor((done - 1) / K),
  //  the latest K-th index the run has reached (null before any toss), "run_start": heard or not}}.
  std::string json(std::uint64_t* version = nullptr) const;
  // Waits until the version differs from `seen` or `timeout` passes; returns the version.
  std::uint64_t wait(std::uint64_t seen, std::chrono::milliseconds timeout) const;

  // The run as its run_start described it (trace_every > 0 only), if one was heard for run_id.
  std::optional<wire::RunSpec> run_spec(std::int64_t run_id) const;
  // The run's provenance as its answers carry it (null if none was heard or it is not JSON).
  nlohmann::json provenance(std::int64_t run_id) const;

 private:
  struct Worker {
    nlohmann::json last;
    std::chrono::steady_clock::time_point heard;
  };
  mutable std::mutex mu_;
  mutable std::condition_variable changed_;
  wire::Sealer sealer_;
  std::uint64_t version_ = 0;
  nlohmann::json run_;  // the latest answer (of the latest run heard)
  std::int64_t run_id_ = 0;
  nlohmann::json provenance_;  // of run_id_
  std::uint64_t trace_every_ = 0;
  std::optional<wire::RunSpec> spec_;  // the latest run_start heard (trace_every > 0)
  std::map<std::int64_t, Worker> workers_;
  std::uint64_t unauthenticated_ = 0, sealed_ = 0, malformed_ = 0;
};

}  // namespace dicesim::web
