#include "apps/worker_processes.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <thread>

#include "apps/commands.hpp"

namespace dicesim {

bool WorkerProcesses::spawn(const std::string& url, std::int64_t run_id, const std::string& key_file,
                            const PreparedRun* prepared) {
  const pid_t parent = getpid();
  const bool in_process = prepared && prepared->spec.run_id == run_id && thread_count() == 1;
  const std::string run = std::to_string(run_id);
  // Built before fork: the child then only execs (when it does not serve the run in-process).
  std::vector<std::string> args = {"dicesim", "worker", "--lcm", url, "--quiet"};
  if (run_id != 0) args.insert(args.end(), {"--run", run, "--once"});
  if (!key_file.empty()) args.insert(args.end(), {"--key-file", key_file});
  std::vector<char*> argv;
  for (std::string& s : args) argv.push_back(s.data());
  argv.push_back(nullptr);
  // Whatever the parent has buffered must not be written twice (by the child's exit too).
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return false;
  if (pid == 0) {
    // A worker must not outlive its parent, even after a kill -9 of the parent.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(1);
    if (in_process) {
      // The parent's handlers (run's stop flag) are not the worker's: serve_forked_worker sets its own.
      std::signal(SIGINT, SIG_DFL);
      std::signal(SIGTERM, SIG_DFL);
      const int code = serve_forked_worker(url, key_file, *prepared);
      std::fflush(nullptr);
      _exit(code);  // not exit(): the parent's static objects and atexit handlers are the parent's
    }
    execv("/proc/self/exe", argv.data());
    _exit(127);
  }
  pids_.push_back(pid);
  return true;
}

int WorkerProcesses::poll() {
  for (auto it = pids_.begin(); it != pids_.end();) {
    int status = 0;
    if (waitpid(*it, &status, WNOHANG) == *it) {
      if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0))
        std::fprintf(stderr, "dicesim: warning: worker %d %s %d\n", *it, WIFSIGNALED(status) ? "killed by signal" : "exited with",
                     WIFSIGNALED(status) ? WTERMSIG(status) : WEXITSTATUS(status));
      it = pids_.erase(it);
    } else {
      ++it;
    }
  }
  return static_cast<int>(pids_.size());
}

void WorkerProcesses::terminate_all() {
  for (pid_t p : pids_) kill(p, SIGTERM);
}

void WorkerProcesses::stop_all() {
  terminate_all();
  const auto t0 = std::chrono::steady_clock::now();
  while (!pids_.empty()) {
    for (auto it = pids_.begin(); it != pids_.end();) {
      if (waitpid(*it, nullptr, WNOHANG) == *it) it = pids_.erase(it);
      else ++it;
    }
    if (pids_.empty()) break;
    if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(2)) {
      for (pid_t p : pids_) kill(p, SIGKILL), waitpid(p, nullptr, 0);
      pids_.clear();
      break;
    }
    // Workers that saw the run finish exit on their own within a few ms: poll finely, the run's
    // wall time includes this wait.
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

int thread_count() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("Threads:", 0) == 0) return std::atoi(line.c_str() + 8);
  return 0;
}

std::string private_lcm_url() {
  std::random_device rd;
  return "udpm://239.255.76.67:" + std::to_string(20000 + rd() % 40000) + "?ttl=0";
}

}  // namespace dicesim
