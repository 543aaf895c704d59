// The toss worker: hears run_start, rebuilds the run's model, takes the leases addressed to it,
// simulates them in index order and publishes toss_batch messages (and, when the run asks,
// sampled bounce states). Like the aggregator, the logic (WorkerCore) is free of sockets and
// clocks; run_worker() drives it on a live LCM bus.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "messages/auth.hpp"
#include "messages/run_spec.hpp"
#include "messages/wire.hpp"
#include "sim/body/die_model.hpp"

namespace dicesim::worker {

struct WorkerConfig {
  std::int64_t worker_id = 0;        // 0: pick a random one
  std::int64_t only_run = 0;         // non-zero: serve only this run id
  int batch = wire::kDefaultBatch;   // tosses per toss_batch at most (fewer messages, fewer wake-ups)
  // ... and about this much work at most: a batch shrinks (not below 256 tosses) for slow
  // fidelities, so that heartbeats, lease hand-overs and the run's end are never a long batch away.
  double batch_s = 0.05;
  double heartbeat_s = 0.2;
  double run_silence_s = 5.0;        // no run_start for this long: the run is gone
  double max_trace_per_s = 2000.0;   // bounce_state messages per second at most (publishers pace themselves)
  std::function<void(const std::string&)> log;  // human-readable events (stderr)
  std::function<void(std::int64_t run_id)> on_run;  // the run served changed (0: none); e.g. log context
  // The run key (messages/auth.hpp): every message out is sealed, every message in must open
  // (else it is dropped and counted: unauthenticated()). Empty: no authentication.
  std::vector<std::uint8_t> key;
  // Set from a signal handler: a batch in progress stops within 64 tosses, unpublished (the
  // process is stopping; its lease goes elsewhere if the run still needs it).
  const std::atomic<bool>* cancel = nullptr;
};

class WorkerCore {
 public:
  using Send = std::function<void(const char* channel, const std::vector<std::uint8_t>& bytes)>;
  WorkerCore(WorkerConfig cfg, Send send);

  void on_message(std::string_view channel, const void* data, std::size_t len, double now);
  // Serve `spec` at once with `model`, as if its run_start had just been heard and compiled: for a
  // local worker that `dicesim run` forked after compiling the run itself (no wait for run_start,
  // no second compile). The model must be the spec's (fingerprint and labels; else it is compiled
  // from the spec as usual). Tells the aggregator at once that it is ready.
  void adopt(const wire::RunSpec& spec, const DieModel& model, double now);
  // Heartbeats and run expiry. Call often (every batch and every idle wait).
  void tick(double now);
  // Simulates and publishes one batch of the current lease; false when there is nothing to do.
  bool step(double now);

  std::int64_t id() const { return cfg_.worker_id; }
  std::int64_t run_id() const { return run_ ? run_->spec.run_id : 0; }
  // Runs this worker served that have ended: it was leased work, or it heard the run finish. A run
  // that went silent without ever leasing it anything (an abandoned or foreign run_start) was not
  // served, so `--once` goes on listening after it.
  int runs_served() const { return runs_served_; }
  std::uint64_t tosses_done() const { return tosses_done_; }
  std::uint64_t ignored() const { return ignored_; }  // undecodable or inapplicable messages
  std::uint64_t unauthenticated() const { return unauthenticated_; }  // with a key: failed the HMAC check

 private:
  struct Run {
    wire::RunSpec spec;
    std::optional<DieModel> model;  // empty: refused (error says why)
    std::string error;
    double last_heard = 0.0;
  };
  struct Lease {
    std::int64_t id;
    std::uint64_t first, next, end;
  };

  void on_run_start(const dicesim_lcm::run_start& m, double now);
  // Takes up `spec` (run_start's, or adopt's); `known`: its model, already compiled (else compiled here).
  void start_run(wire::RunSpec spec, const DieModel* known, double now);
  void on_lease(const dicesim_lcm::work_lease& m, double now);
  // Every batch of the lease is out: drop it and tell the aggregator.
  void finish_lease(std::deque<Lease>::iterator it, double now);
  // Finished or Replaced: the run is over for good. Silent (its aggregator went quiet): the same
  // run may be served again when its run_start comes back (a resumed aggregator).
  enum class RunEnd { Finished, Replaced, Silent };
  void end_run(RunEnd how);
  void send(const char* channel, std::vector<std::uint8_t> bytes);
  void send_status(double now);
  void trace(std::uint64_t index, double now);

  WorkerConfig cfg_;
  Send send_;
  std::unique_ptr<Run> run_;
  std::set<std::int64_t> ended_runs_;
  std::deque<Lease> leases_;
  std::int64_t last_lease_seen_ = 0, last_done_ = 0;
  std::uint64_t tosses_done_ = 0, ignored_ = 0, traces_skipped_ = 0, unauthenticated_ = 0;
  wire::Sealer sealer_;
  bool told_key_ = false;  // logged once that sealed / unsealed runs were heard
  int runs_served_ = 0;
  int batch_now_ = 0;                    // the next batch's size (batch_s at the measured speed)
  double last_step_ = -1.0;              // when the previous batch began (its size: last_n_)
  std::uint64_t last_n_ = 0;
  double last_status_ = -1e9;
  double rate_ = 0.0, rate_t_ = 0.0;
  std::uint64_t rate_n_ = 0;
  double trace_tokens_ = 0.0, trace_t_ = 0.0;
  std::string host_;
};

struct WorkerOptions {
  std::string url;                            // resolved
  WorkerConfig core;
  // Both set: serve this run from the start (WorkerCore::adopt), without waiting for its run_start.
  const wire::RunSpec* known_spec = nullptr;
  const DieModel* known_model = nullptr;
  bool once = false;                          // exit after the first run it served ends (runs_served)
  const std::atomic<bool>* cancel = nullptr;  // set from a signal handler
};

// 0 when cancelled or (with once) after a run; 1 if LCM cannot be opened.
int run_worker(const WorkerOptions& opt);

}  // namespace dicesim::worker
