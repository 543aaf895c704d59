// An aggregator's state on disk, so that a run survives the aggregator: `dicesim aggregate
// --checkpoint FILE` writes it at most once a second, `--resume FILE` continues the same run id
// with the workers still serving it. What it holds is exactly what the answer depends on: the run
// description (run_start, byte for byte), the interval set of toss indices held, the counts
// (per block past the complete prefix, so that --target-halfwidth stops where it would have), the
// leases out, and the health counters. A toss result that arrived after the last write is simply
// not held: it is leased again, so the counts stay exact and at most about one checkpoint
// interval's work is computed twice.
//
// Files are JSON (one object, "format": "dicesim-checkpoint-1"), written next to the target and
// renamed over it after fsync (file, then directory): a crash leaves the old file or the new one,
// never a mix. Writing happens on a thread of its own (CheckpointWriter), so the aggregator's
// loop only pays for taking the snapshot.
#pragma once

#include <array>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "aggregator/interval_set.hpp"
#include "dicesim_lcm/run_start.hpp"
#include "sim/study/monte_carlo.hpp"

namespace dicesim::agg {

// Unreadable, not a checkpoint, or inconsistent: bad input (exit 2), naming the file.
struct CheckpointError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct HealthCounts {  // = Health (aggregator.hpp), kept here so this header stands alone
  std::uint64_t batches = 0, duplicates = 0, foreign = 0, malformed = 0, range = 0, released = 0, leases = 0,
                messages_out = 0, messages_in = 0, unauthenticated = 0;
};

struct Checkpoint {
  dicesim_lcm::run_start start;        // the run, as announced
  std::vector<int> labels;             // the die's outcome labels (= run_start's), counts in this order
  double target_halfwidth = 0.0;
  std::uint64_t limit = 0;             // indices [0, limit) wanted (less than total once a target was met)
  std::vector<IntervalSet::Range> received;
  std::uint64_t frontier = 0;          // indices >= frontier were never leased
  std::int64_t next_lease = 1;
  std::uint64_t prefix_end = 0;
  RunCounts prefix, all;
  std::map<std::uint64_t, RunCounts> blocks;
  struct Lease {
    std::int64_t id = 0, worker = 0;
    std::uint64_t first = 0, count = 0;
  };
  std::vector<Lease> leases;
  HealthCounts health;
  double elapsed_s = 0.0;              // run time before this checkpoint, over every session
  std::int64_t written_utime = 0;      // wall clock when taken (to say how old it is)
  bool finished = false;
  int resumes = 0;                     // how many times this run was resumed before
};

std::string to_json(const Checkpoint& c);
Checkpoint checkpoint_from_json(const std::string& text, const std::string& path);  // throws CheckpointError
Checkpoint read_checkpoint(const std::string& path);                                // throws CheckpointError

// Writes `text` to `path` atomically: PATH.tmp, fsync, rename over PATH, fsync of the directory.
// Throws std::runtime_error (with the path and errno) on failure.
void write_atomic(const std::string& path, const std::string& text);

// Writes checkpoints on a thread of its own; only the newest pending one is written.
class CheckpointWriter {
 public:
  explicit CheckpointWriter(std::string path);
  ~CheckpointWriter();  // writes what is pending, then stops
  CheckpointWriter(const CheckpointWriter&) = delete;
  CheckpointWriter& operator=(const CheckpointWriter&) = delete;

  void submit(std::string text);
  void flush();  // returns once everything submitted so far is on disk (or failed)
  struct Stats {
    std::uint64_t writes = 0, bytes = 0;
    double write_s = 0.0, max_write_s = 0.0;  // wall time of write + fsync + rename + fsync (writer thread)
    std::string error;                        // the last failure, if any
  };
  Stats stats() const;

 private:
  void loop();
  std::string path_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::optional<std::string> pending_;
  bool busy_ = false, stop_ = false;
  Stats stats_;
  std::thread thread_;
};

}  // namespace dicesim::agg
