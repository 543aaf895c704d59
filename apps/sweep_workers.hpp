// `dicesim sweep --workers K` / `--lcm URL`: every point of a sweep becomes a distributed run on
// the LCM bus (its own run id, the same seed and toss indices 0..N-1 as every other point), served
// by K local worker processes started here and by any `dicesim worker` listening on the URL.
#pragma once

#include <atomic>
#include <string>

#include "apps/worker_processes.hpp"
#include "sim/study/sweep.hpp"

namespace dicesim {

class SweepOverLcm {
 public:
  // Starts `local_workers` worker processes on `url` that serve every run there in turn.
  // `scene_path` is the sweep's base scene (what run_start carries, with each point's overrides).
  SweepOverLcm(std::string scene_path, std::string url, int local_workers, const std::atomic<bool>* cancel);
  // The point runner for SweepRunOptions; it throws std::runtime_error when a point's run fails.
  SweepRunOptions::PointRunner runner();

 private:
  RunCounts run_point(const DieModel& model, const std::vector<std::string>& overrides, const RunConfig& cfg,
                      const std::function<void(std::uint64_t)>& progress);

  std::string scene_, url_;
  int local_workers_;
  const std::atomic<bool>* cancel_;
  WorkerProcesses workers_;
};

}  // namespace dicesim
