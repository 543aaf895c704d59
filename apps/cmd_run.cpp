// dicesim run: the one-command local distributed run. K worker processes (this same binary,
// `dicesim worker --run ID --once`) and the aggregator in this process, on a host-confined LCM
// URL with a port of its own, so that two runs on one machine never meet.
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <random>
#include <thread>

#include "apps/commands.hpp"
#include "messages/wire.hpp"
#include "sim/die_model.hpp"

namespace dicesim {
namespace {

std::atomic<bool> g_stop{false};
void on_stop_signal(int) { g_stop = true; }

struct RunArgs {
  AggregateArgs agg;
  int workers = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
};

// The children, stopped whatever happens to the run (RAII: also on exceptions).
class Children {
 public:
  ~Children() { stop_all(); }
  bool spawn(const std::string& url, std::int64_t run_id) {
    const pid_t parent = getpid();
    const std::string run = std::to_string(run_id);
    const pid_t pid = fork();
    if (pid < 0) return false;
    if (pid == 0) {
      // A worker must not outlive its run's parent, even after a kill -9 of the parent.
      prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (getppid() != parent) _exit(1);
      execl("/proc/self/exe", "dicesim", "worker", "--lcm", url.c_str(), "--run", run.c_str(), "--once", "--quiet",
            static_cast<char*>(nullptr));
      _exit(127);
    }
    pids_.push_back(pid);
    return true;
  }
  // Reaps exited children; returns how many are still running and reports abnormal exits.
  int poll() {
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
  void stop_all() {
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

 private:
  std::vector<pid_t> pids_;
};

int run_run(const RunArgs& a) {
  (void)compile(a.agg.scene.load(), a.agg.scene.path);  // bad input: exit 2 before any child starts
  std::random_device rd;
  std::int64_t run_id = 0;
  while (run_id == 0) run_id = static_cast<std::int64_t>(((std::uint64_t{rd()} << 32) ^ rd()) & INT64_MAX);
  // --lcm or $LCM_DEFAULT_URL if given; else the host-confined group on a port of this run's own.
  std::string url = wire::resolve_url(a.agg.lcm);
  if (a.agg.lcm.empty() && url == wire::kDefaultUrl)
    url = "udpm://239.255.76.67:" + std::to_string(20000 + rd() % 40000) + "?ttl=0";

  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  Children children;
  for (int k = 0; k < a.workers; ++k)
    if (!children.spawn(url, run_id)) {
      std::fprintf(stderr, "dicesim: failed: cannot start worker %d\n", k + 1);
      return kExitFailed;
    }
  const int code = aggregate_and_report(
      a.agg, url, run_id, a.workers,
      [&children]() -> std::string {
        // After Ctrl-C the workers (same process group) exit too: that is the interrupt, not a failure.
        return children.poll() == 0 && !g_stop ? "every worker process exited before the run finished" : "";
      },
      &g_stop);
  children.stop_all();
  return code;
}

}  // namespace

void register_run(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "A distributed run on this machine in one command: K worker processes and an aggregator,\n"
      "over a host-confined LCM URL. Live progress on stderr; Ctrl-C stops every child. Prints the\n"
      "same table / JSON as `dicesim toss`, with identical counts for the same scene, seed and N.\n\n"
      "Examples:\n"
      "  dicesim run scenes/paper/die1.toml --workers 2 --tosses 1000000\n"
      "  dicesim run scenes/paper/die3.toml --workers 4 --target-halfwidth 0.001 --json\n"
      "  dicesim run scenes/fair.toml --workers 2 --trace-every 500   # bounce states for lcm-spy");
  args->agg.add_to(cmd);
  cmd->add_option("-w,--workers", args->workers, "Worker processes (default: all cores)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  cmd->callback([args, &exit_code] { exit_code = run_run(*args); });
}

}  // namespace dicesim
