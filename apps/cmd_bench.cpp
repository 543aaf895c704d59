// dicesim bench: end-to-end throughput of this machine on a scene (per thread and scaled), and
// where a toss spends its time. Micro-benchmarks live in bench/ (Google Benchmark).
#include <chrono>
#include <cstdio>
#include <thread>

#include <nlohmann/json.hpp>

#include "apps/commands.hpp"
#include "sim/body/die_model.hpp"
#include "sim/models/compile.hpp"
#include "sim/study/monte_carlo.hpp"

namespace dicesim {
namespace {

struct BenchArgs {
  SceneArgs scene;
  std::uint64_t tosses = 200000;
  std::uint64_t seed = 1;
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool json = false;
};

double timed_run(const DieModel& m, const BenchArgs& a, int threads, RunCounts& out) {
  RunConfig cfg;
  cfg.seed = a.seed;
  cfg.tosses = a.tosses;
  cfg.threads = threads;
  const auto t0 = std::chrono::steady_clock::now();
  out = run_tosses(m, cfg);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int run_bench(const BenchArgs& a) {
  const DieModel m = compile(a.scene.load(), a.scene.path);

  RunCounts one, many;
  timed_run(m, a, 1, one);  // warm-up: caches, page faults, frequency
  const double t1 = timed_run(m, a, 1, one);
  const double tn = timed_run(m, a, a.threads, many);
  const double rate1 = static_cast<double>(a.tosses) / t1;
  const double raten = static_cast<double>(a.tosses) / tn;

  // Where the time goes: one thread, instrumented (the clock reads cost a few percent).
  TossProbe probe;
  probe.timing = true;
  const std::uint64_t n_probe = std::max<std::uint64_t>(1, a.tosses / 4);
  const auto p0 = std::chrono::steady_clock::now();
  for (std::uint64_t i = 0; i < n_probe; ++i) toss(m, a.seed, i, &probe);
  const double probe_total = std::chrono::duration<double>(std::chrono::steady_clock::now() - p0).count();
  const double other = std::max(0.0, probe_total - probe.flight_s - probe.impact_s);

  const nlohmann::json j = {
      {"scene", a.scene.path},
      {"fidelity", to_string(m.fidelity)},
      {"shape", m.kind},
      {"faces", m.face_count()},
      {"vertices", m.vertex_count()},
      {"tosses", a.tosses},
      {"tosses_per_s_1_thread", rate1},
      {"threads", a.threads},
      {"tosses_per_s", raten},
      {"scaling_efficiency", raten / (rate1 * a.threads)},
      {"identical_counts", one == many},
      {"impacts_per_toss", static_cast<double>(one.bounces) / static_cast<double>(a.tosses)},
      {"search_steps_per_flight", probe.flights ? static_cast<double>(probe.search_iterations) / probe.flights : 0.0},
      {"time_split", {{"flight", probe.flight_s / probe_total}, {"impacts", probe.impact_s / probe_total},
                      {"draw_and_other", other / probe_total}}}};
  if (a.json) {
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("%s  (fidelity %s, %s: %d corners, %d faces; %llu tosses)\n", a.scene.path.c_str(), to_string(m.fidelity),
                m.kind.c_str(), m.vertex_count(), m.face_count(), static_cast<unsigned long long>(a.tosses));
    std::printf("1 thread            %12.0f tosses/s  (%.3f us per toss)\n", rate1, 1e6 / rate1);
    std::printf("%d threads %s        %12.0f tosses/s  (scaling efficiency %.1f%%)\n", a.threads,
                a.threads < 10 ? " " : "", raten, 100.0 * raten / (rate1 * a.threads));
    std::printf("identical counts    %s\n", one == many ? "yes" : "NO (a bug: please report)");
    std::printf("impacts per toss    %.3f\nsearch steps/flight %.2f\n", j["impacts_per_toss"].get<double>(),
                j["search_steps_per_flight"].get<double>());
    std::printf("time split          flight %.1f%%, impacts %.1f%%, drawing the throw and other %.1f%%\n",
                100.0 * probe.flight_s / probe_total, 100.0 * probe.impact_s / probe_total, 100.0 * other / probe_total);
  }
  return one == many ? kExitOk : kExitFailed;
}

}  // namespace

void register_bench(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Measure tosses per second on this machine: one thread, then all threads (scaling), and\n"
      "the split of a toss's time between flight (contact search) and impacts.\n\n"
      "Example:  dicesim bench scenes/paper/die1.toml --tosses 1000000");
  args->scene.add_to(cmd);
  cmd->add_option("-n,--tosses", args->tosses, "Tosses per measurement")->capture_default_str()->check(CLI::Range(1ULL, 1ULL << 40));
  cmd->add_option("--seed", args->seed, "Run seed")->capture_default_str();
  cmd->add_option("-j,--threads", args->threads, "Threads for the scaled measurement")->capture_default_str()->check(CLI::Range(1, 1024));
  cmd->add_flag("--json", args->json, "One JSON object on stdout");
  cmd->callback([args, &exit_code] { exit_code = run_bench(*args); });
}

}  // namespace dicesim
