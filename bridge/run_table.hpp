// What the bridge knows about each run it has heard of, from run_start, worker_status and
// probabilities, and when that knowledge should go out as a `dicesim_run_status` sample.
// Pure bookkeeping: time is passed in (seconds on any steady clock), so tests drive it directly.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "dicesim_dds/run_status.h"
#include "dicesim_lcm/probabilities.hpp"
#include "dicesim_lcm/run_start.hpp"
#include "dicesim_lcm/worker_status.hpp"

namespace dicesim::bridge {

struct RunTableDef {
  double silent_after_s = 3.0;    // aggregator quiet this long (it repeats run_start every 1 s): RUN_SILENT
  double worker_timeout_s = 2.0;  // a worker heart-beats every 0.2 s
  double status_period_s = 1.0;   // a running run's status is refreshed at least this often
  std::size_t max_runs = 32;      // older runs are forgotten (and disposed on DDS)
};
RunTableDef default_run_table_def();

struct RunRecord {
  std::int64_t run_id = 0;
  dicesim_dds_run_state state = dicesim_dds_RUN_ANNOUNCED;
  std::string origin, scene_hash, fidelity;
  std::int64_t seed = 0, total = 0, done = 0;
  double tosses_per_s = 0.0;
  std::int64_t last_answer_utime = 0;
  double first_heard = 0.0;
  double last_heard = 0.0;  // from its aggregator: run_start or probabilities
  std::map<std::int64_t, double> workers;  // worker id -> last heartbeat for this run
  std::set<std::int64_t> refused;
  bool changed = true;            // something a subscriber should see now
  double last_published = -1e300;
};

// A run_status sample that points into the strings of its record (valid while the record is).
dicesim_dds_run_status to_dds(const RunRecord& r, std::int64_t utime);

class RunTable {
 public:
  explicit RunTable(const RunTableDef& def = default_run_table_def()) : def_(def) {}

  void on_run_start(const dicesim_lcm::run_start& m, double now);
  void on_probabilities(const dicesim_lcm::probabilities& m, double now);
  void on_worker_status(const dicesim_lcm::worker_status& m, double now);

  // Advances time: silences quiet runs, drops stale workers, forgets the oldest runs beyond
  // max_runs. Returns the runs whose status should be published now (and marks them published).
  // A run first heard of through its answers (the bridge started mid-run) waits for its
  // run_start (repeated every second) to be published with its scene, for at most silent_after_s.
  std::vector<std::int64_t> tick(double now);
  // Runs forgotten since the last call (their DDS instances should be disposed).
  std::vector<std::int64_t> take_forgotten();

  const RunRecord* find(std::int64_t run_id) const;
  std::size_t size() const { return runs_.size(); }

 private:
  RunRecord& record(std::int64_t run_id, double now);
  RunTableDef def_;
  std::map<std::int64_t, RunRecord> runs_;
  std::vector<std::int64_t> forgotten_;
};

}  // namespace dicesim::bridge
