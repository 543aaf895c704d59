// Local worker processes for the commands that start their own (`run`, `sweep --workers`): this
// same binary as `dicesim worker`, stopped whatever happens to the parent (RAII, and
// PR_SET_PDEATHSIG should the parent be killed outright). `run`'s workers are forked without exec
// when the parent is still single-threaded: they skip process start-up (dynamic linking, static
// initialisers, parsing) and start with the parent's compiled run.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace dicesim {

struct PreparedRun;  // apps/commands.hpp

class WorkerProcesses {
 public:
  WorkerProcesses() = default;
  WorkerProcesses(const WorkerProcesses&) = delete;
  WorkerProcesses& operator=(const WorkerProcesses&) = delete;
  ~WorkerProcesses() { stop_all(); }

  // Starts `dicesim worker --lcm URL --quiet`; with run_id != 0 it serves only that run and exits
  // after it (--run ID --once), with 0 it serves every run on the URL in turn.
  // A non-empty key_file is passed on as --key-file (an authenticated run).
  // With `run` (its spec's run id is run_id), and this process single-threaded, the child is a
  // fork that serves `run` at once (serve_forked_worker) instead of exec'ing `dicesim worker`.
  bool spawn(const std::string& url, std::int64_t run_id, const std::string& key_file = "",
             const PreparedRun* run = nullptr);
  // Reaps exited workers (warning on stderr for abnormal exits); returns how many still run.
  int poll();
  // Sends SIGTERM to every worker still running (stop_all then only waits).
  void terminate_all();
  // SIGTERM, then SIGKILL for those still running after 2 s.
  void stop_all();

 private:
  std::vector<pid_t> pids_;
};

// A URL on the host-confined multicast group with a port of its own (20000-59999, random), so
// that two local runs on one machine never meet.
std::string private_lcm_url();

// This process's thread count (/proc/self/status; 0 if unknown). A fork is safe to use without
// exec only from a single thread: another thread might hold a lock (malloc, a logger) forever.
int thread_count();

}  // namespace dicesim
