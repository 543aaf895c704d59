// dicesim record: a live run's DICESIM_ messages into an LCM event log (logger/record.hpp).
#include <csignal>
#include <cstdio>

#include <spdlog/spdlog.h>

#include "apps/commands.hpp"
#include "apps/interrupt.hpp"
#include "logger/event_log.hpp"
#include "logger/log.hpp"
#include "logger/record.hpp"
#include "messages/wire.hpp"

namespace dicesim {
namespace {

struct RecordArgs {
  std::string lcm;
  std::string out;
  std::string channels = "DICESIM_.*";
  bool until_done = false;
  std::int64_t run = 0;
  double timeout_s = 0.0;
  std::string key_file;
};

int run_record(const RecordArgs& a) {
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  eventlog::RecordOptions opt = eventlog::default_record_options();
  opt.url = wire::resolve_url(a.lcm);
  opt.path = a.out;
  opt.channels = a.channels;
  opt.until_done = a.until_done;
  opt.run_id = a.run;
  opt.timeout_s = a.timeout_s;
  opt.cancel = &g_stop;
  opt.key = load_run_key(a.key_file);
  if (a.run != 0) logging::set_run_id(a.run);
  // User-facing, not a log line: scripts wait for it before they start the run.
  opt.on_ready = [&] {
    std::fprintf(stderr, "dicesim record: recording %s on %s to %s (%s)\n", opt.channels.c_str(), opt.url.c_str(),
                 opt.path.c_str(), a.until_done ? "until the run is done" : "Ctrl-C to stop");
  };
  eventlog::RecordResult res;
  try {
    res = eventlog::record(opt);
  } catch (const eventlog::LogError& e) {
    std::fprintf(stderr, "dicesim: error: %s\n", e.what());
    return kExitBadInput;
  }
  spdlog::info("recorded {} events ({:.1f} MB) in {:.1f} s to {}", res.events, static_cast<double>(res.bytes) / 1e6,
               res.elapsed_s, a.out);
  if (res.unauthenticated > 0)
    spdlog::warn("{} run_start/probabilities messages failed the HMAC check (recorded as heard; replay --key-file "
                 "drops them)",
                 res.unauthenticated);
  switch (res.end) {
    case eventlog::RecordEnd::Done:
    case eventlog::RecordEnd::Stopped: return kExitOk;
    case eventlog::RecordEnd::TimedOut:
      if (!a.until_done) return kExitOk;
      std::fprintf(stderr, "dicesim: failed: timed out after %g s before the run finished (the log holds what came)\n",
                   a.timeout_s);
      return kExitFailed;
    case eventlog::RecordEnd::Failed: break;
  }
  std::fprintf(stderr, "dicesim: failed: %s\n", res.error.c_str());
  return kExitFailed;
}

}  // namespace

void register_record(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<RecordArgs>();
  CLI::App* cmd = app.add_subcommand(
      "record",
      "Record a live run: every message on the DICESIM_ channels, as received, into an LCM event log\n"
      "(the stock lcm-logger's format: lcm-logplayer plays it, `dicesim replay` recomputes the run\n"
      "from it). Start it before the run; it stops on Ctrl-C / SIGTERM, with --until-done when the run's\n"
      "final result appears, or after --timeout.\n\n"
      "Examples:\n"
      "  dicesim record -o run.lcmlog --until-done &\n"
      "  dicesim aggregate scenes/paper/die1.toml -n 1000000      # with workers on the same URL\n"
      "  dicesim replay run.lcmlog --json\n"
      "  dicesim record --lcm 'udpm://239.255.76.67:7667?ttl=1' -o lan.lcmlog --timeout 600");
  cmd->add_option("-o,--output", args->out, "The event log to write (replaced if it exists)")->type_name("RUN.lcmlog")->required();
  cmd->add_option("--lcm", args->lcm,
                  "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0, which never leaves this host)")
      ->type_name("URL");
  cmd->add_flag("--until-done", args->until_done,
                "Stop when the run's final result (DICESIM_PROBABILITIES, finished) arrives: the first run\n"
                "announced after the start, or --run ID");
  cmd->add_option("--run", args->run, "With --until-done: the run to wait for")->type_name("ID")->check(CLI::PositiveNumber);
  cmd->add_option("--timeout", args->timeout_s,
                  "Stop after S seconds (with --until-done: fail, exit 1, if the run has not finished by then)")
      ->type_name("S")
      ->check(CLI::Range(0.0, 1e9));
  add_key_file_option(cmd, args->key_file)
      ->description("An authenticated run: messages are recorded as heard, seals included, but only those whose\n"
                    "HMAC-SHA-256 seal opens with the key in FILE tell the recorder which run it is and when it\n"
                    "ends (--until-done). Replay the log with `dicesim replay --key-file FILE`");
  cmd->add_option("--channels", args->channels, "LCM channel regular expression to record")->capture_default_str();
  cmd->callback([args, &exit_code] { exit_code = run_record(*args); });
}

}  // namespace dicesim
