// dicesim run: the one-command local distributed run. K worker processes (this same binary,
// `dicesim worker --run ID --once`) and the aggregator in this process, on a host-confined LCM
// URL with a port of its own, so that two runs on one machine never meet.
#include <csignal>
#include <cstdio>
#include <thread>

#include "apps/commands.hpp"
#include "apps/interrupt.hpp"
#include "apps/lcm_hub.hpp"
#include "apps/worker_processes.hpp"
#include "messages/run_spec.hpp"
#include "messages/wire.hpp"
#include "sim/body/die_model.hpp"
#include "sim/models/compile.hpp"

namespace dicesim {
namespace {

struct RunArgs {
  AggregateArgs agg;
  int workers = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string transport = "udp";  // udp: multicast on this host; tcp: a hub of its own (apps/lcm_hub.hpp)
};

int run_run(const RunArgs& a) {
  // Bad input (scene or key file): exit 2 before any child starts. The run is compiled once, here:
  // the workers forked below start with it (worker_processes.hpp).
  const PreparedRun prepared = prepare_run(a.agg, wire::new_run_id());
  (void)load_run_key(a.agg.key_file);
  const std::int64_t run_id = prepared.spec.run_id;
  // --lcm or $LCM_DEFAULT_URL if given; else the host-confined group on a port of this run's own.
  std::string url = wire::resolve_url(a.agg.lcm);
  HubProcess hub;  // --transport tcp: LCM's TCP hub, started before any worker, stopped last
  if (a.transport == "tcp") {
    if (!a.agg.lcm.empty()) {
      std::fprintf(stderr, "dicesim: error: --transport tcp starts a hub of its own; with --lcm %s leave it out\n", a.agg.lcm.c_str());
      return kExitBadInput;
    }
    if (const std::string why = hub.start(); !why.empty()) {
      std::fprintf(stderr, "dicesim: failed: --transport tcp: %s\n", why.c_str());
      return kExitFailed;
    }
    url = hub.url();
  } else if (a.agg.lcm.empty() && url == wire::kDefaultUrl) {
    url = private_lcm_url();
  }

  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  WorkerProcesses children;
  for (int k = 0; k < a.workers; ++k)
    if (!children.spawn(url, run_id, a.agg.key_file, &prepared)) {
      std::fprintf(stderr, "dicesim: failed: cannot start worker %d\n", k + 1);
      return kExitFailed;
    }
  const int code = aggregate_and_report(
      a.agg, url, run_id, a.workers,
      [&children]() -> std::string {
        // After Ctrl-C the workers (same process group) exit too: that is the interrupt, not a failure.
        return children.poll() == 0 && !g_stop ? "every worker process exited before the run finished" : "";
      },
      &g_stop, &prepared,
      // The run is over: the workers may stop (a batch in progress too) while the report prints.
      [&children] { children.terminate_all(); });
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
      "  dicesim run scenes/fair.toml --workers 2 --trace-every 500 --lcm 'udpm://239.255.76.67:7667?ttl=0'  # for lcm-spy\n"
      "  dicesim run scenes/paper/die1.toml --workers 2 --key-file run.key   # an authenticated run\n"
      "  dicesim run scenes/paper/die1.toml --workers 2 --transport tcp      # no multicast: a TCP hub of its own");
  args->agg.add_to(cmd);
  // Unlike every other command, `run` does not default to the shared URL: see run_run.
  cmd->get_option("--lcm")->description(
      "LCM URL (default: $LCM_DEFAULT_URL if set, else a port of this run's own on the host-confined\n"
      "group, udpm://239.255.76.67:PORT?ttl=0 with a random PORT in 20000-59999, so that concurrent\n"
      "runs never meet; give --lcm to watch or record the run from outside)");
  cmd->add_option("-w,--workers", args->workers, "Worker processes (default: all cores)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  cmd->add_option("--transport", args->transport,
                  "udp: LCM multicast on this host (default); tcp: start LCM's TCP hub (dicesim hub) on a free\n"
                  "port and run over tcpq://127.0.0.1:PORT, for hosts whose multicast is off (needs liblcm-java\n"
                  "and a Java runtime; the hub listens on every interface while the run lasts)")
      ->capture_default_str()
      ->check(CLI::IsMember({"udp", "tcp"}));
  cmd->callback([args, &exit_code] { exit_code = run_run(*args); });
}

}  // namespace dicesim
