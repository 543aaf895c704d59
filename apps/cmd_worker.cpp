// dicesim worker: a toss-worker process for distributed runs (sim/worker does the work).
#include <unistd.h>

#include <csignal>
#include <cstdio>

#include <spdlog/spdlog.h>

#include "apps/commands.hpp"
#include "apps/interrupt.hpp"
#include "logger/log.hpp"
#include "messages/run_spec.hpp"
#include "messages/wire.hpp"
#include "sim/worker/worker.hpp"

namespace dicesim {
namespace {

struct WorkerArgs {
  std::string lcm;
  std::int64_t run = 0;
  bool once = false;
  bool quiet = false;
  int batch = wire::kDefaultBatch;
  std::string key_file;
};

int run_worker_cmd(const WorkerArgs& a, const PreparedRun* known = nullptr) {
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  worker::WorkerOptions opt;
  if (known) opt.known_spec = &known->spec, opt.known_model = &known->model;
  opt.url = wire::resolve_url(a.lcm);
  opt.once = a.once;
  opt.cancel = opt.core.cancel = &g_stop;
  opt.core.only_run = a.run;
  opt.core.batch = a.batch;
  opt.core.key = load_run_key(a.key_file);
  // The id is chosen here, not in WorkerCore, so that every log line can carry it from the start.
  opt.core.worker_id = wire::new_run_id();
  logging::set_worker_id(opt.core.worker_id);
  logging::set_run_id(a.run);
  opt.core.on_run = [only = a.run](std::int64_t run) { logging::set_run_id(run != 0 ? run : only); };
  // --quiet (how `dicesim run` starts its workers) moves the worker's event lines to debug.
  const auto level = a.quiet ? spdlog::level::debug : spdlog::level::info;
  opt.core.log = [level](const std::string& s) { spdlog::log(level, "{}", s); };
  const int code = worker::run_worker(opt);
  if (code != 0) std::fprintf(stderr, "dicesim worker: failed: cannot open LCM at '%s'\n", opt.url.c_str());
  return code == 0 ? kExitOk : kExitFailed;
}

}  // namespace

namespace {
// An LCM URL whose datagrams never leave this machine: udpm with TTL 0 (LCM's default TTL).
bool host_confined(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0) return false;
  const std::size_t q = url.find('?');
  if (q == std::string::npos) return true;
  const std::size_t t = url.find("ttl=", q);
  return t == std::string::npos || (url.compare(t, 5, "ttl=0") == 0 && (t + 5 == url.size() || url[t + 5] == '&'));
}
}  // namespace

int serve_forked_worker(const std::string& url, const std::string& key_file, const PreparedRun& run) {
  WorkerArgs a;
  a.lcm = url;
  // Loopback only (run's own URL): the largest batches, a quarter of the messages and wake-ups.
  if (host_confined(url)) a.batch = wire::kMaxBatch;
  a.run = run.spec.run_id;
  a.once = true;
  a.quiet = true;
  a.key_file = key_file;
  // tests/integration (run_cmd) checks for this line: the fast path must not fall back unnoticed.
  spdlog::debug("worker process {} forked by `dicesim run` (no exec): serving run {} with the run's compiled model",
                static_cast<long>(getpid()), run.spec.run_id);
  try {
    return run_worker_cmd(a, &run);
  } catch (const std::exception& e) {  // e.g. the key file went away since the parent read it
    std::fprintf(stderr, "dicesim worker: failed: %s\n", e.what());
    return kExitFailed;
  }
}

void register_worker(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<WorkerArgs>();
  CLI::App* cmd = app.add_subcommand(
      "worker",
      "Serve distributed runs: wait for a run (dicesim aggregate / dicesim run), take the index\n"
      "ranges leased to this process, toss them and publish the results over LCM. Runs until\n"
      "Ctrl-C (or, with --once, until its run ends). Start one per core; they may join at any time.\n\n"
      "Examples:\n"
      "  dicesim worker                                   # host-confined default URL\n"
      "  dicesim worker --lcm 'udpm://239.255.76.67:7667?ttl=1'   # a LAN: see README, Scale-out\n"
      "  LCM_DEFAULT_URL='udpm://239.255.76.67:7700?ttl=0' dicesim worker --once");
  cmd->add_option("--lcm", args->lcm,
                  "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0, which never leaves this host)")
      ->type_name("URL");
  cmd->add_option("--run", args->run, "Serve only the run with this id (dicesim run uses it)")->type_name("ID");
  cmd->add_flag("--once", args->once, "Exit after the first run it served ends (one that leased it work, or that it heard finish; a run that fell silent without leasing it anything does not count)");
  cmd->add_option("--batch", args->batch, "Tosses per published batch")
      ->capture_default_str()
      ->check(CLI::Range(1, wire::kMaxBatch));
  add_key_file_option(cmd, args->key_file);
  cmd->add_flag("-q,--quiet", args->quiet, "Log the worker's events at debug level, not info (so none at the default level)");
  cmd->callback([args, &exit_code] { exit_code = run_worker_cmd(*args); });
}

}  // namespace dicesim
