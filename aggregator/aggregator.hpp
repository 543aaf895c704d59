// The aggregator's logic, free of sockets and clocks: bytes in (on_message), messages out (the
// Send callback), time passed in by the caller. The LCM loop (session.hpp), the unit tests, the
// fuzzer and the ingest benchmark all drive this one class.
//
// Correctness rests on the toss index: results are kept in an interval set, so a repeated index
// is a duplicate (counted, ignored) and a missing one is a gap that is leased again until it
// arrives. Counts are kept per block of kTargetBlock indices so that the result over [0, stop)
// is exact even when later tosses arrived first.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "aggregator/checkpoint.hpp"
#include "aggregator/interval_set.hpp"
#include "messages/auth.hpp"
#include "messages/run_spec.hpp"
#include "messages/wire.hpp"
#include "sim/study/monte_carlo.hpp"

namespace dicesim::agg {

struct AggregatorConfig {
  // run_id, seed, total, outcome labels, ...: what run_start announces. spec.labels must be a
  // valid outcome list (wire::valid_outcome_labels), else the constructor throws invalid_argument.
  wire::RunSpec spec;
  double target_halfwidth = 0.0;    // > 0: stop at the first block boundary where it holds
  std::uint64_t max_lease = 32768;  // tosses per lease at most (tens of ms of `paper`, ~1 s of `impulse`)
  std::uint64_t min_lease = 512;    // ... and at least, except for the last ones
  int leases_per_worker = 2;        // one in progress, one queued: a worker never waits
  double worker_timeout_s = 2.0;    // no heartbeat or batch for this long: its leases go elsewhere
  double lost_lease_s = 0.6;        // a lease the worker does not list after this long was lost
  double done_grace_s = 0.3;        // after a worker finished a lease, wait this long for stragglers
  double probabilities_period_s = 0.25;
  double run_start_period_s = 1.0;
  // The run's key (messages/auth.hpp): empty, no authentication; else every message out is sealed
  // and every message in must open, or it is dropped and counted (Health::unauthenticated).
  std::vector<std::uint8_t> key;
  // What made the run, as a JSON object (apps/provenance.hpp's provenance_json, dumped): every
  // probabilities message carries it, so the final answer on the wire says how it was made.
  std::string provenance;
};

// Why messages were ignored: the aggregator's health, published in `probabilities`.
struct Health {
  std::uint64_t batches = 0;     // accepted toss_batch messages
  std::uint64_t duplicates = 0;  // toss results received again
  std::uint64_t foreign = 0;     // messages of another run
  std::uint64_t malformed = 0;   // undecodable (e.g. claims more than kMaxOutcomes), or fields outside their domain
  std::uint64_t range = 0;       // indices outside [0, total)
  std::uint64_t released = 0;    // tosses leased again
  std::uint64_t leases = 0;      // leases granted
  std::uint64_t messages_out = 0;
  std::uint64_t messages_in = 0;
  std::uint64_t unauthenticated = 0;  // with a key: no seal, or a wrong one (forged, tampered, another key)
  // The run's tail: leases split so that an idle worker takes the back half of another's
  // unfinished one (steal), and the tosses so moved. Not in checkpoints (they do not change the answer).
  std::uint64_t splits = 0, split_tosses = 0;
};

// What a resumed aggregator found in its checkpoint.
struct ResumeInfo {
  bool resumed = false;
  double age_s = 0.0;             // how old the checkpoint was when read
  std::uint64_t held = 0;         // toss indices it held
  std::uint64_t requeued = 0;     // indices below its frontier it did not hold (and no restored lease covers): leased again
  std::size_t leases = 0;         // leases it restored (the workers still hold them)
  int resumes = 0;                // including this one
};

class Aggregator {
 public:
  using Send = std::function<void(const char* channel, const std::vector<std::uint8_t>& bytes)>;
  Aggregator(AggregatorConfig cfg, Send send);
  // Continues a run from a checkpoint (cfg.spec must be the checkpoint's run; the caller decodes
  // it from Checkpoint::start). Leases the checkpoint lists are kept for the workers that still
  // hold them; what it did not hold below its frontier is leased again. `now` is the caller's clock.
  Aggregator(AggregatorConfig cfg, Send send, const Checkpoint& from, double now);

  // The state to write to disk (checkpoint.hpp); `elapsed_s`: run time so far, this session included.
  Checkpoint checkpoint(double elapsed_s) const;
  const ResumeInfo& resume_info() const { return resume_; }

  // One received message on `channel`; never throws, whatever the bytes.
  void on_message(std::string_view channel, const void* data, std::size_t len, double now);
  // Periodic work: run_start, probabilities, expired leases, dead workers. Call every ~20 ms.
  void tick(double now);

  bool finished() const { return finished_; }
  // The answer: counts over toss indices [0, stop()) — all of them, or up to the stopping block.
  const RunCounts& result() const { return prefix_; }
  std::uint64_t stop() const { return prefix_end_; }
  std::uint64_t received() const { return received_.size(); }
  std::uint64_t total() const { return cfg_.spec.total; }
  const Health& health() const { return health_; }
  int live_workers() const;
  double rate() const { return rate_; }
  const RunCounts& all_counts() const { return all_; }  // everything received so far
  // A worker that refused the run (a different build or a scene it cannot load): its message.
  const std::vector<std::string>& refusals() const { return refusals_; }

  dicesim_lcm::probabilities snapshot() const;

 private:
  struct Lease {
    std::int64_t id = 0, worker = 0;
    std::uint64_t first = 0, count = 0;
    double granted = 0.0, deadline = 0.0;
    double done_at = -1.0;  // the worker says it sent every batch
  };
  struct Worker {
    double last_seen = 0.0;
    double rate = 0.0;
    bool ready = false;
    std::uint64_t batch = 0;  // its last batch's size: about what it has tossed past what arrived
  };

  void on_batch(const dicesim_lcm::toss_batch& b, double now);
  void on_status(const dicesim_lcm::worker_status& s, double now);
  void ingest(std::uint64_t first, std::uint64_t lo, std::uint64_t hi, const dicesim_lcm::toss_batch& b);
  bool valid_batch(const dicesim_lcm::toss_batch& b) const;
  void advance_prefix();
  void grant(std::int64_t worker, double now);
  void release(const Lease& l);  // hand the lease's missing indices out again
  // Nothing left to lease and `worker` idle: moves the back half of the largest unfinished lease
  // of another worker to [a, b) (false: none worth splitting).
  bool steal(std::int64_t worker, double now, std::uint64_t& a, std::uint64_t& b);
  void finish(double now);
  void publish_run_start();
  void publish_probabilities(double now);
  template <class T>
  void publish(const char* channel, const T& msg);

  AggregatorConfig cfg_;
  Send send_;
  std::uint64_t limit_;  // indices [0, limit_) are wanted
  IntervalSet received_;
  IntervalSet requeue_;   // to lease again
  std::uint64_t frontier_ = 0;  // indices >= frontier_ were never leased
  std::map<std::int64_t, Lease> leases_;
  std::map<std::int64_t, Worker> workers_;
  std::int64_t next_lease_ = 1;
  std::size_t outcomes_;  // the die's outcome count: a settled result is an index below it

  std::map<std::uint64_t, RunCounts> blocks_;  // counts of blocks past the prefix
  RunCounts prefix_;                           // counts of [0, prefix_end_)
  std::uint64_t prefix_end_ = 0;
  RunCounts all_;

  Health health_;
  ResumeInfo resume_;
  int resumes_ = 0;
  wire::Sealer sealer_;
  std::vector<std::string> refusals_;
  std::map<std::int64_t, bool> refused_;
  bool finished_ = false;
  double last_probabilities_ = -1e9, last_run_start_ = -1e9, started_ = -1.0;
  bool run_start_wanted_ = false;  // a worker asked for run_start within 20 ms of the last one
  double rate_ = 0.0, rate_t_ = 0.0;
  std::uint64_t rate_n_ = 0;
};

}  // namespace dicesim::agg
