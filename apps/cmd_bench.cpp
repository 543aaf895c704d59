// dicesim bench: end-to-end throughput of this machine on a scene, per fidelity (one thread, then
// all threads), and where a toss spends its time, phase by phase. Micro-benchmarks live in bench/
// (Google Benchmark).
#include <chrono>
#include <cstdio>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "apps/commands.hpp"
#include "sim/body/die_model.hpp"
#include "sim/models/compile.hpp"
#include "sim/study/auto_pilot.hpp"
#include "sim/study/monte_carlo.hpp"

namespace dicesim {
namespace {

struct BenchArgs {
  SceneArgs scene;
  std::string fidelities;  // comma-separated, or "all"; empty: the scene's (or --fidelity)
  CLI::Option* tosses_opt = nullptr;
  std::uint64_t tosses = 0;  // 0: a default per fidelity (default_tosses)
  std::uint64_t seed = 1;
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool json = false;
};

// About a second of one core today for each fidelity.
std::uint64_t default_tosses(Fidelity f) {
  switch (f) {
    case Fidelity::Static: return 1'000'000;
    case Fidelity::Paper: return 400'000;
    case Fidelity::Impulse: return 20'000;
    case Fidelity::Stepped: return 2'000;
    case Fidelity::Auto: break;
  }
  return 20'000;
}

double timed_run(const DieModel& m, std::uint64_t n, std::uint64_t seed, int threads, RunCounts& out) {
  RunConfig cfg;
  cfg.seed = seed;
  cfg.tosses = n;
  cfg.threads = threads;
  const auto t0 = std::chrono::steady_clock::now();
  out = run_tosses(m, cfg);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Which phase's count is "per toss" in words (the text report).
const char* phase_unit(Phase p) {
  switch (p) {
    case Phase::Draw: return "draws";
    case Phase::Search: return "searches";
    case Phase::Impact: return "impacts";
    case Phase::Steps: return "stepper runs";
    case Phase::Rest: return "rest checks";
  }
  return "";
}

nlohmann::json bench_one(const BenchArgs& a, const std::string& fidelity) {
  SceneArgs sa = a.scene;
  if (!fidelity.empty()) sa.fidelity = fidelity;
  DieModel m = compile(sa.load(), sa.path);
  // auto: the model a `toss` of this many tosses (default 100000) would take; the pilot is not timed.
  resolve_auto(m, precision_of_run(m, a.tosses > 0 ? a.tosses : 100000), a.threads);
  const std::uint64_t n = a.tosses > 0 ? a.tosses : default_tosses(m.fidelity);

  RunCounts one, many;
  timed_run(m, std::max<std::uint64_t>(1, n / 10), a.seed, 1, one);  // warm-up: caches, page faults, frequency
  const double t1 = timed_run(m, n, a.seed, 1, one);
  const double tn = timed_run(m, n, a.seed, a.threads, many);
  const double rate1 = static_cast<double>(n) / t1;
  const double raten = static_cast<double>(n) / tn;

  // Where the time goes: one thread, each phase timed (two clock reads per phase entered; the
  // instrumented run's own rate is reported, so their cost is visible).
  TossProbe probe;
  probe.timing = true;
  const std::uint64_t n_probe = std::max<std::uint64_t>(1, n / 4);
  const auto p0 = std::chrono::steady_clock::now();
  for (std::uint64_t i = 0; i < n_probe; ++i) toss(m, a.seed, i, &probe);
  const double probe_total = std::chrono::duration<double>(std::chrono::steady_clock::now() - p0).count();
  double timed = 0.0;
  nlohmann::json phases = nlohmann::json::object();
  for (int k = 0; k < kPhaseCount; ++k) {
    const auto p = static_cast<Phase>(k);
    timed += probe.phase_s[k];
    if (probe.phase_n[k] == 0) continue;
    phases[to_string(p)] = {{"share", probe.phase_s[k] / probe_total},
                            {"per_toss", static_cast<double>(probe.phase_n[k]) / static_cast<double>(n_probe)},
                            {"us_each", 1e6 * probe.phase_s[k] / static_cast<double>(probe.phase_n[k])}};
  }
  const double np = static_cast<double>(n_probe);
  return {{"fidelity", to_string(m.fidelity)},
          {"tosses", n},
          {"tosses_per_s_1_thread", rate1},
          {"us_per_toss_1_thread", 1e6 / rate1},
          {"threads", a.threads},
          {"tosses_per_s", raten},
          // One thread has nothing to scale: two one-thread runs' ratio is only timing noise.
          {"scaling_efficiency", a.threads > 1 ? nlohmann::json(raten / (rate1 * a.threads)) : nlohmann::json(nullptr)},
          {"identical_counts", one == many},
          {"impacts_per_toss", static_cast<double>(one.bounces) / static_cast<double>(n)},
          {"search_steps_per_flight", probe.flights ? static_cast<double>(probe.search_iterations) / probe.flights : 0.0},
          {"fixed_steps_per_toss", static_cast<double>(probe.steps) / np},
          // The stepper's adaptive steps (not corrections): shortened to a new contact's instant,
          // and, for a curved die, halved for a capped curvature impulse, its capped impulses, and
          // shortened to a slapping face's arrival.
          {"located_steps_per_toss", static_cast<double>(probe.located_steps) / np},
          // Located steps whose search ran out of trials (a nearly tangential touch; the longest
          // trial above the floor taken), and exact balances at rest broken by a tiny spin.
          {"located_capped_per_toss", static_cast<double>(probe.located_capped) / np},
          {"nudges_per_toss", static_cast<double>(probe.nudges) / np},
          {"halved_steps_per_toss", static_cast<double>(probe.halved) / np},
          {"curvature_capped_per_toss", static_cast<double>(probe.curvature_capped) / np},
          // Curved dice: support searches out of iterations (the bracket's end above the floor taken).
          {"support_search_capped_per_toss", static_cast<double>(probe.support_search_capped) / np},
          {"slaps_per_toss", static_cast<double>(probe.slaps) / np},
          // The slap's re-decisions: the plain step when its far half does not arrive, the plain
          // search again when a located slap leaves the rest of the rim below the floor.
          {"slap_no_arrival_per_toss", static_cast<double>(probe.slap_no_arrival) / np},
          {"slap_rim_below_per_toss", static_cast<double>(probe.slap_rim_below) / np},
          // Steps taken again with a nearly flat face's tripod struck (a coin landing or lying flat).
          {"flat_landed_per_toss", static_cast<double>(probe.flat_landed) / np},
          // Curvature impulses that held a start's depth below the floor (within the touch
          // tolerance) because closing it within a short step would gain energy.
          // Clamped near-flat steps taken again with the face struck (kind B): kept, and declined
          // (the step restored and finished as before).
          {"face_jumped_per_toss", static_cast<double>(probe.face_jumped) / np},
          {"face_jump_declined_per_toss", static_cast<double>(probe.face_jump_declined) / np},
          // Flat coins' tripod impacts taken again with the rim's approaching arc struck: kept,
          // and declined.
          {"rim_struck_per_toss", static_cast<double>(probe.rim_struck) / np},
          {"rim_strike_declined_per_toss", static_cast<double>(probe.rim_strike_declined) / np},
          // Impacts whose restitution friction stalled in Gauss-Seidel and was solved by its dual.
          {"dual_solves", probe.dual_solves},
          // Solves whose first method failed and an exact second one took (the same law, verified):
          // a one-point slide's reference solve after its Newton, an edge's or a pair's exact
          // solve after the sweeps.
          {"exact_fallbacks", probe.exact_fallbacks},
          // A flat die's held corners: the deepest one below the floor at a step's end (m), the
          // steps in which one sank more than the bound, and (`impulse`) the steps tried again
          // shorter for the bound and those whose full length was below the contact step.
          {"max_held_sink_m", probe.max_held_sink},
          {"held_sinks_per_toss", static_cast<double>(probe.held_sinks) / np},
          {"sink_shortened_per_toss", static_cast<double>(probe.sink_shortened) / np},
          {"short_steps_per_toss", static_cast<double>(probe.short_steps) / np},
          {"rise_dropped_per_toss", static_cast<double>(probe.rise_dropped) / np},
          // Several dice and obstacles (docs/world.md): windows of conservative advancement, those
          // taken again at half length (a near pair went too deep), contacts struck between
          // bodies, dice struck at rest and moving again, slow strikes on a die at rest (held),
          // instants at the sweep cap, touches struck at the witness alone (an empty patch),
          // strikes of the nearest point after the patch's, narrow-phase calls at their iteration
          // cap, the deepest overlap.
          {"world_windows_per_toss", static_cast<double>(probe.windows) / np},
          {"world_windows_halved_per_toss", static_cast<double>(probe.windows_halved) / np},
          {"world_interactions_per_toss", static_cast<double>(probe.interactions) / np},
          {"world_woken_per_toss", static_cast<double>(probe.woken) / np},
          {"world_held_at_rest_per_toss", static_cast<double>(probe.held_at_rest) / np},
          {"world_perched_per_toss", static_cast<double>(probe.perched) / np},
          {"world_retries_capped", probe.retries_capped},
          {"world_sweeps_capped", probe.sweeps_capped},
          {"world_patch_witness_only", probe.patch_witness_only},
          {"world_witness_strikes", probe.witness_strikes},
          {"world_narrow_degenerate", probe.narrow_degenerate},
          {"world_max_overlap_m", probe.max_overlap},
          {"timed_tosses", n_probe},
          {"timed_tosses_per_s", np / probe_total},
          {"phases", phases},
          {"other_share", std::max(0.0, probe_total - timed) / probe_total},
          // Earlier shape, kept for scripts: flight = search, impacts, the rest.
          {"time_split",
           {{"flight", probe.phase_s[static_cast<int>(Phase::Search)] / probe_total},
            {"impacts", probe.phase_s[static_cast<int>(Phase::Impact)] / probe_total},
            {"draw_and_other",
             std::max(0.0, probe_total - probe.phase_s[static_cast<int>(Phase::Search)] -
                               probe.phase_s[static_cast<int>(Phase::Impact)]) /
                 probe_total}}}};
}

void print_text(const nlohmann::json& r) {
  const double rate1 = r["tosses_per_s_1_thread"].get<double>();
  const int threads = r["threads"].get<int>();
  std::printf("fidelity %s  (%llu tosses per measurement)\n", r["fidelity"].get<std::string>().c_str(),
              static_cast<unsigned long long>(r["tosses"].get<std::uint64_t>()));
  std::printf("  1 thread            %12.0f tosses/s  (%.3f us per toss)\n", rate1, 1e6 / rate1);
  // Efficiency: the N-thread rate over N times the one-thread rate (100%: perfect scaling). Above
  // 100% it is the two timings' noise (another process, the clock's frequency), said so.
  if (threads > 1) {
    const double eff = 100.0 * r["scaling_efficiency"].get<double>();
    std::printf("  %d threads %s        %12.0f tosses/s  (%.1f%% of %d x the 1-thread rate%s)\n", threads,
                threads < 10 ? " " : "", r["tosses_per_s"].get<double>(), eff, threads,
                eff > 100.0 ? "; above 100%: timing noise, load or clock speed changed between the runs" : "");
  }
  std::printf("  identical counts    %s\n", r["identical_counts"].get<bool>() ? "yes" : "NO (a bug: please report)");
  std::printf("  impacts per toss    %.3f\n  search steps/flight %.2f\n", r["impacts_per_toss"].get<double>(),
              r["search_steps_per_flight"].get<double>());
  if (r["dual_solves"].get<std::uint64_t>() > 0)
    std::printf("  dual friction solves %llu (restitution friction that stalled in Gauss-Seidel; verified)\n",
                static_cast<unsigned long long>(r["dual_solves"].get<std::uint64_t>()));
  if (r["exact_fallbacks"].get<std::uint64_t>() > 0)
    std::printf("  exact fallbacks     %llu (solves whose first method failed, taken by an exact second; verified)\n",
                static_cast<unsigned long long>(r["exact_fallbacks"].get<std::uint64_t>()));
  if (r["fixed_steps_per_toss"].get<double>() > 0) {
    std::printf("  fixed steps/toss    %.1f\n", r["fixed_steps_per_toss"].get<double>());
    std::printf("    located %.3f (out of trials %.4f)  halved %.3f  capped curvature %.3f  support searches out of "
                "iterations %.4f  slaps %.3f (no arrival %.4f, rim below %.4f)  landed flat %.4f  face "
                "struck %.4f (declined %.4f)  rim struck %.4f (declined %.4f)  balances nudged %.4f (per toss)\n",
                r["located_steps_per_toss"].get<double>(), r["located_capped_per_toss"].get<double>(),
                r["halved_steps_per_toss"].get<double>(), r["curvature_capped_per_toss"].get<double>(),
                r["support_search_capped_per_toss"].get<double>(), r["slaps_per_toss"].get<double>(),
                r["slap_no_arrival_per_toss"].get<double>(), r["slap_rim_below_per_toss"].get<double>(),
                r["flat_landed_per_toss"].get<double>(),
                r["face_jumped_per_toss"].get<double>(), r["face_jump_declined_per_toss"].get<double>(),
                r["rim_struck_per_toss"].get<double>(), r["rim_strike_declined_per_toss"].get<double>(),
                r["nudges_per_toss"].get<double>());
    if (r["max_held_sink_m"].get<double>() > 0)
      std::printf(
          "    held corners: deepest %.2g m  sank more than the bound %.3f  shortened %.3f  short %.3f  rise dropped "
          "%.4f (per toss)\n",
          r["max_held_sink_m"].get<double>(), r["held_sinks_per_toss"].get<double>(),
          r["sink_shortened_per_toss"].get<double>(), r["short_steps_per_toss"].get<double>(),
          r["rise_dropped_per_toss"].get<double>());
  }
  std::printf("  time split (one thread, each phase timed: %.0f tosses/s while timed)\n",
              r["timed_tosses_per_s"].get<double>());
  for (int k = 0; k < kPhaseCount; ++k) {
    const auto p = static_cast<Phase>(k);
    if (!r["phases"].contains(to_string(p))) continue;
    const nlohmann::json& ph = r["phases"][to_string(p)];
    std::printf("    %-8s %5.1f%%  %8.2f %s per toss, %9.3f us each\n", to_string(p), 100.0 * ph["share"].get<double>(),
                ph["per_toss"].get<double>(), phase_unit(p), ph["us_each"].get<double>());
  }
  std::printf("    %-8s %5.1f%%  (result, counting, clock reads)\n", "other", 100.0 * r["other_share"].get<double>());
}

int run_bench(const BenchArgs& a) {
  std::vector<std::string> list;
  if (a.fidelities == "all") {
    list = {"static", "paper", "impulse", "stepped"};
  } else if (!a.fidelities.empty()) {
    std::stringstream ss(a.fidelities);
    for (std::string f; std::getline(ss, f, ',');) {
      if (!parse_fidelity(f))
        throw CLI::ValidationError("--fidelities", "'" + f + "' is not a fidelity (" + kFidelityChoices + ", or all)");
      list.push_back(f);
    }
  } else {
    list = {""};  // the scene's, or --fidelity
  }
  // Bad input first (the scene and every fidelity), before any measurement.
  for (const std::string& f : list) {
    SceneArgs sa = a.scene;
    if (!f.empty()) sa.fidelity = f;
    (void)compile(sa.load(), sa.path);
  }

  std::vector<nlohmann::json> results;
  bool identical = true;
  const DieModel first = compile(a.scene.load(), a.scene.path);
  if (!a.json)
    std::printf("%s  (%s: %d corners, %d faces)\n", a.scene.path.c_str(), first.kind.c_str(), first.vertex_count(),
                first.face_count());
  for (const std::string& f : list) {
    results.push_back(bench_one(a, f));
    identical = identical && results.back()["identical_counts"].get<bool>();
    if (!a.json) print_text(results.back());
    std::fflush(stdout);
  }
  if (a.json) {
    nlohmann::json j = {{"scene", a.scene.path},
                        {"shape", first.kind},
                        {"faces", first.face_count()},
                        {"vertices", first.vertex_count()},
                        {"fidelities", results}};
    // One fidelity: its fields at the top level as well (the earlier shape).
    if (results.size() == 1)
      for (const auto& [k, v] : results[0].items()) j[k] = v;
    std::printf("%s\n", j.dump().c_str());
  }
  return identical ? kExitOk : kExitFailed;
}

}  // namespace

void register_bench(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Measure tosses per second on this machine, per fidelity: one thread, then all threads\n"
      "(scaling; the counts must be identical), and where a toss's time goes, by phase:\n"
      "  draw     drawing the throw from (seed, toss index)\n"
      "  search   exact flight and the search for the next contact (with the contact set)\n"
      "  impacts  the impact law (paper: and its stop rule)\n"
      "  steps    fixed steps: sustained contact (impulse), the whole toss (stepped)\n"
      "  rest     rest checks (impulse), the quasi-static roll (static)\n"
      "The split comes from a separate one-thread run that reads the clock around each phase; its\n"
      "own rate is printed, so the cost of timing is visible. Wall clock: note the machine's load.\n\n"
      "Examples:\n"
      "  dicesim bench scenes/paper/die1.toml\n"
      "  dicesim bench scenes/paper/die1.toml --fidelities all --json\n"
      "  dicesim bench scenes/paper/die1.toml --fidelity impulse -n 20000 -j 1\n"
      "  dicesim bench tradeoff scenes/paper/die1.toml      # accuracy against speed (own --help)");
  args->scene.add_to(cmd);
  cmd->add_option("--fidelities", args->fidelities,
                  "Bench each of these in turn: a comma-separated list (static,paper,impulse,stepped,auto)\n"
                  "or 'all' (default: the scene's fidelity, or --fidelity)")
      ->type_name("LIST");
  args->tosses_opt = cmd->add_option("-n,--tosses", args->tosses,
                                     "Tosses per measurement (default: about a second of one core per fidelity:\n"
                                     "static 1000000, paper 400000, impulse 20000, stepped 2000)")
                         ->check(CLI::Range(1ULL, 1ULL << 40));
  cmd->add_option("--seed", args->seed, "Run seed")->capture_default_str();
  cmd->add_option("-j,--threads", args->threads, "Threads for the scaled measurement")->capture_default_str()->check(CLI::Range(1, 1024));
  cmd->add_flag("--json", args->json,
                "One JSON object on stdout: scene, shape, and per fidelity (\"fidelities\": [...]) tosses_per_s_1_thread,\n"
                "tosses_per_s (all threads), scaling_efficiency (N-thread rate / (N x 1-thread rate); null for -j 1),\n"
                "identical_counts, impacts_per_toss,\n"
                "search_steps_per_flight, fixed_steps_per_toss, located_steps_per_toss, located_capped_per_toss,\n"
                "nudges_per_toss, "
                "halved_steps_per_toss, curvature_capped_per_toss, support_search_capped_per_toss,\n"
                "slaps_per_toss, slap_no_arrival_per_toss,\n"
                "slap_rim_below_per_toss, flat_landed_per_toss, face_jumped_per_toss,\n"
                "face_jump_declined_per_toss, rim_struck_per_toss, rim_strike_declined_per_toss, dual_solves,\n"
                "exact_fallbacks,\n"
                "phases {name: {share, per_toss, us_each}},\n"
                "other_share; with one fidelity its fields also at the top level");
  cmd->callback([args, &exit_code] { exit_code = run_bench(*args); });
}

}  // namespace dicesim
