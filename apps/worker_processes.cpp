#include "apps/worker_processes.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <thread>

namespace dicesim {

bool WorkerProcesses::spawn(const std::string& url, std::int64_t run_id, const std::string& key_file) {
  const pid_t parent = getpid();
  const std::string run = std::to_string(run_id);
  // Built before fork: the child only execs.
  std::vector<std::string> args = {"dicesim", "worker", "--lcm", url, "--quiet"};
  if (run_id != 0) args.insert(args.end(), {"--run", run, "--once"});
  if (!key_file.empty()) args.insert(args.end(), {"--key-file", key_file});
  std::vector<char*> argv;
  for (std::string& s : args) argv.push_back(s.data());
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return false;
  if (pid == 0) {
    // A worker must not outlive its parent, even after a kill -9 of the parent.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(1);
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

void WorkerProcesses::stop_all() {
  for (pid_t p : pids_) kill(p, SIGTERM);
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
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

std::string private_lcm_url() {
  std::random_device rd;
  return "udpm://239.255.76.67:" + std::to_string(20000 + rd() % 40000) + "?ttl=0";
}

}  // namespace dicesim
