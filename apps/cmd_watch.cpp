// dicesim watch: follow runs live from the LCM bus, one line per answer the aggregator
// publishes (DICESIM_PROBABILITIES), until Ctrl-C, or until a run finishes (--until-finished).
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <memory>

#include <lcm/lcm-cpp.hpp>

#include "messages/lcm_wait.hpp"
#include "apps/commands.hpp"
#include "apps/interrupt.hpp"
#include "messages/auth.hpp"
#include "messages/wire.hpp"

namespace dicesim {
namespace {

struct WatchArgs {
  std::string lcm;
  std::int64_t run = 0;
  bool until_finished = false;
  double timeout_s = 0.0;
  std::string key_file;
};

// One answer as one line: progress, workers, and each outcome's p with its 95% half-width (label order).
std::string answer_line(const dicesim_lcm::probabilities& m) {
  char buf[160];
  const double pct = m.total > 0 ? 100.0 * static_cast<double>(m.done) / static_cast<double>(m.total) : 0.0;
  std::snprintf(buf, sizeof buf, "run %lld  %s %lld/%lld (%.1f%%)  %d workers |", static_cast<long long>(m.run_id),
                m.finished ? "FINISHED" : "running", static_cast<long long>(m.done), static_cast<long long>(m.total),
                pct, m.workers);
  std::string line = buf;
  for (std::size_t f = 0; f < m.labels.size(); ++f) {
    std::snprintf(buf, sizeof buf, "  %d: %.4f±%.4f", m.labels[f], m.p[f], 0.5 * (m.ci_hi[f] - m.ci_lo[f]));
    line += buf;
  }
  if (m.unresolved || m.invalid) {
    std::snprintf(buf, sizeof buf, "  (unresolved %lld, invalid %lld)", static_cast<long long>(m.unresolved),
                  static_cast<long long>(m.invalid));
    line += buf;
  }
  return line;
}

struct Printer {
  const WatchArgs* args;
  wire::Sealer sealer;  // an authenticated run: only answers whose seal opens are shown
  bool finished = false;
  std::int64_t provenance_shown = 0;  // the run whose provenance was printed last (once per run)
  std::uint64_t malformed = 0;  // undecodable answers (e.g. more than kMaxOutcomes), dropped
  const char* legacy = nullptr;  // an answer of the six-outcome wire was heard
  void handle(const lcm::ReceiveBuffer* rb, const std::string& channel) {
    const auto len = sealer.open(channel, rb->data, rb->data_size);
    if (!len) return;
    const auto m = wire::decode<dicesim_lcm::probabilities>(rb->data, *len);
    if (!m) {
      ++malformed;
      if (!legacy && (legacy = wire::legacy_format(rb->data, *len)))
        std::fprintf(stderr, "dicesim: heard a %s: an older dicesim's run, not shown\n", legacy);
      return;
    }
    if (args->run != 0 && m->run_id != args->run) return;
    std::printf("%s\n", answer_line(*m).c_str());
    // The finished answer says what made it (the aggregator's provenance, a JSON object).
    if (m->finished && m->run_id != provenance_shown && !m->provenance.empty()) {
      provenance_shown = m->run_id;
      std::printf("run %lld provenance: %s\n", static_cast<long long>(m->run_id), m->provenance.c_str());
    }
    std::fflush(stdout);
    if (m->finished) finished = true;
  }
};

int watch(const WatchArgs& a) {
  const std::string url = wire::resolve_url(a.lcm);
  lcm::LCM bus(url);
  if (!bus.good()) {
    std::fprintf(stderr, "dicesim: failed: cannot open LCM at '%s'\n", url.c_str());
    return kExitFailed;
  }
  Printer printer{&a, wire::Sealer(load_run_key(a.key_file))};
  bus.subscribe(wire::kProbabilities, &Printer::handle, &printer);
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  // Nothing may be heard for a while (no run yet): say where we listen, on stderr (stdout is the answers).
  std::fprintf(stderr, "dicesim: watching %s on %s for %s; Ctrl-C to stop\n", wire::kProbabilities, url.c_str(),
               a.run != 0 ? ("run " + std::to_string(a.run)).c_str() : "any run");
  const auto t0 = std::chrono::steady_clock::now();
  while (!g_stop && !(a.until_finished && printer.finished)) {
    wire::listen_timeout(bus, 100);
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (a.timeout_s > 0 && t > a.timeout_s) {
      std::fprintf(stderr, "dicesim: failed: %s after %g s\n", a.until_finished ? "no run finished" : "timed out",
                   a.timeout_s);
      return kExitFailed;
    }
  }
  if (printer.malformed > 0)
    std::fprintf(stderr, "dicesim: ignored %llu undecodable answers\n", static_cast<unsigned long long>(printer.malformed));
  return kExitOk;
}

}  // namespace

void register_watch(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<WatchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "watch",
      "Follow runs live: one line per answer an aggregator publishes on DICESIM_PROBABILITIES\n"
      "(4 a second): progress, live workers, each face's probability with its 95% half-width;\n"
      "when a run finishes, one line more: 'run ID provenance: {JSON}' (version, scene hash,\n"
      "overrides, fidelity, seed, tosses: what made the answer).\n"
      "Runs until Ctrl-C, or until a run finishes with --until-finished.\n\n"
      "Examples:\n"
      "  dicesim watch\n"
      "  dicesim watch --until-finished --lcm 'udpm://239.255.76.67:7667?ttl=1'");
  cmd->add_option("--lcm", args->lcm,
                  "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0, which never leaves this host)")
      ->type_name("URL");
  cmd->add_option("--run", args->run, "Only this run id");
  add_key_file_option(cmd, args->key_file)->description("An authenticated run: show only answers whose HMAC-SHA-256 seal opens with the key in FILE");
  cmd->add_flag("--until-finished", args->until_finished, "Exit 0 after a run's final answer");
  cmd->add_option("--timeout", args->timeout_s, "Fail (exit 1) after this many seconds (0: never)")
      ->type_name("S")
      ->check(CLI::Range(0.0, 1e9));
  cmd->callback([args, &exit_code] { exit_code = watch(*args); });
}

}  // namespace dicesim
