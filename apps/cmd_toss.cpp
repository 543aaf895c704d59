// dicesim toss: Monte Carlo probabilities of each face, in this process.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "aggregator/target.hpp"
#include "apps/commands.hpp"
#include "apps/interrupt.hpp"
#include "apps/progress.hpp"
#include "apps/report.hpp"
#include "apps/shard_file.hpp"
#include "sim/body/die_model.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene_hash.hpp"
#include "sim/study/auto_pilot.hpp"
#include "sim/study/monte_carlo.hpp"

namespace dicesim {
namespace {

struct TossArgs {
  SceneArgs scene;
  std::uint64_t tosses = 100000;
  std::uint64_t seed = 1;
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool json = false;
  double target_halfwidth = 0.0;
  CLI::Option* tosses_opt = nullptr;
  std::string shard;  // --shard I/N
  std::string out;    // --out FILE: the shard file for `dicesim merge`
  std::string outcomes;  // --outcomes FILE: each toss's outcome label (paired `compare`)
};

// Each toss's outcome label, one line per toss index (sim/study/compare.hpp's read_toss_outcomes).
bool write_outcomes(std::ofstream& f, const DieModel& m, const TossArgs& a, const std::vector<std::int16_t>& o) {
  f << "# dicesim toss --outcomes: " << a.scene.path << ", fidelity " << to_string(m.fidelity) << ", seed " << a.seed
    << ", tosses 0.." << o.size() << " (one line per toss index: its outcome label, -1 if it did not settle)\n";
  for (const std::int16_t i : o) f << (i < 0 ? -1 : m.outcome_labels[static_cast<std::size_t>(i)]) << '\n';
  return static_cast<bool>(f.flush());
}

int run_toss(const TossArgs& a) {
  const SceneDef def = a.scene.load();
  DieModel model = compile(def, a.scene.path);
  // auto: the pilot judges the cheaper models at this run's precision (its N, or the target).
  const FidelityPilot pilot = resolve_auto(model,
               a.target_halfwidth > 0.0 ? precision_of_target(model, a.target_halfwidth) : precision_of_run(model, a.tosses),
               a.threads);
  Shard shard;
  if (!a.shard.empty()) {
    try {
      shard = parse_shard(a.shard);
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "dicesim: error: --shard %s\n", e.what());
      return kExitBadInput;
    }
  }
  if ((!a.shard.empty() || !a.out.empty()) && a.target_halfwidth > 0.0) {
    std::fprintf(stderr, "dicesim: error: --shard/--out and --target-halfwidth exclude each other (a shard tosses a fixed block)\n");
    return kExitBadInput;
  }
  if (!a.outcomes.empty() && (!a.shard.empty() || a.target_halfwidth > 0.0)) {
    std::fprintf(stderr, "dicesim: error: --outcomes excludes --shard and --target-halfwidth (it records tosses 0..N-1)\n");
    return kExitBadInput;
  }
  if (!a.outcomes.empty() && a.tosses > 100'000'000ULL) {
    std::fprintf(stderr, "dicesim: error: --outcomes with -n %llu: at most 100000000 tosses (a line per toss, kept in memory)\n",
                 static_cast<unsigned long long>(a.tosses));
    return kExitBadInput;
  }
  std::ofstream outcomes_file;  // opened now: a path that cannot be written is bad input, not a lost run
  if (!a.outcomes.empty()) {
    outcomes_file.open(a.outcomes);
    if (!outcomes_file) {
      std::fprintf(stderr, "dicesim: error: --outcomes %s: cannot write it\n", a.outcomes.c_str());
      return kExitBadInput;
    }
  }
  std::ofstream out_file;
  if (!a.out.empty()) {
    out_file.open(a.out);
    if (!out_file) {
      std::fprintf(stderr, "dicesim: error: --out %s: cannot write it\n", a.out.c_str());
      return kExitBadInput;
    }
  }
  // The whole run is a.tosses; this process tosses its block (all of it without --shard).
  const IndexRange block = shard_range(a.tosses, shard);
  std::vector<std::string> overrides = a.scene.overrides;
  if (!a.scene.fidelity.empty()) overrides.push_back("sim.fidelity=\"" + a.scene.fidelity + "\"");
  const ShardHeader header = a.out.empty() ? ShardHeader{} : make_shard_header(a.scene.path, overrides, model, a.tosses, shard);

  const InterruptGuard interrupt;
  ProgressBar bar;
  RunConfig cfg;
  cfg.cancel = InterruptGuard::flag();
  cfg.seed = a.seed;
  cfg.first = block.first;
  cfg.tosses = block.tosses;
  cfg.threads = a.threads;
  cfg.progress = [&bar](std::uint64_t done, std::uint64_t total) { bar.update(done, total); };
  std::vector<std::int16_t> outcomes;
  if (!a.outcomes.empty()) cfg.outcomes = &outcomes;

  const auto t0 = std::chrono::steady_clock::now();
  std::uint64_t tosses = block.tosses;
  const bool target = a.target_halfwidth > 0.0;
  // With a target and no explicit --tosses, N is only a generous cap.
  const std::uint64_t cap = target && a.tosses_opt->count() == 0 ? 1'000'000'000ULL : a.tosses;
  const RunCounts counts = target ? agg::run_to_target(model, cfg, cap, a.target_halfwidth, tosses) : run_tosses(model, cfg);
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  bar.finish();
  if (target)
    std::fprintf(stderr, "dicesim: target half-width %g %s after %llu tosses (widest: %.5f)\n", a.target_halfwidth,
                 agg::halfwidth_reached(counts, a.target_halfwidth) ? "reached" : "NOT reached",
                 static_cast<unsigned long long>(tosses), agg::max_halfwidth(counts));

  // Interrupted before the end: the counts are the longest complete prefix (monte_carlo.hpp). A
  // signal after the last toss, or once the target was reached, leaves the answer whole.
  const bool partial = InterruptGuard::interrupted() && counts.total() < (target ? cap : block.tosses) &&
                       !(target && agg::halfwidth_reached(counts, a.target_halfwidth));
  if (partial) tosses = counts.total();
  RunReport r;
  r.provenance = make_provenance(a.scene.path, a.scene.applied_overrides(), scene_sha256(a.scene.path, a.scene.applied_overrides()), model, a.seed, target ? cap : a.tosses, a.threads);
  r.partial = partial;
  r.scene = a.scene.path;
  r.fidelity = to_string(model.fidelity);
  r.seed = a.seed;
  r.threads = a.threads;
  r.tosses = tosses;
  r.counts = counts;
  set_labels(r, model);
  r.pilot = pilot;
  r.elapsed_s = elapsed;
  if (!a.out.empty() && !partial) {  // an interrupted shard is no shard: nothing for merge
    out_file << shard_json(r, header).dump() << '\n';
    if (!out_file.flush()) {
      std::fprintf(stderr, "dicesim: failed: cannot write --out %s\n", a.out.c_str());
      return kExitFailed;
    }
  }
  if (!a.outcomes.empty() && !partial && !write_outcomes(outcomes_file, model, a, outcomes)) {
    std::fprintf(stderr, "dicesim: failed: cannot write --outcomes %s\n", a.outcomes.c_str());
    return kExitFailed;
  }
  print_report(r, a.json);
  if (partial) std::fprintf(stderr, "dicesim: interrupted after %llu of %llu tosses\n", static_cast<unsigned long long>(tosses),
                            static_cast<unsigned long long>(r.provenance.tosses));
  return partial ? kExitInterrupted : kExitOk;
}

}  // namespace

void register_toss(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<TossArgs>();
  CLI::App* cmd = app.add_subcommand(
      "toss",
      "Toss the die N times and print each face's probability with a 95% Wilson interval.\n"
      "Toss i draws its throw from (seed, i) only: the same scene, fidelity, seed and N give\n"
      "identical counts on any number of threads. Ctrl-C (or SIGTERM) prints the tosses done so far,\n"
      "the longest complete prefix 0..N-1 of the indices (the counts of `-n N`), marked partial; exit 130.\n\n"
      "Examples:\n"
      "  dicesim toss scenes/paper/die1.toml\n"
      "  dicesim toss scenes/paper/die1.toml --tosses 1000000 --threads 2 --json\n"
      "  dicesim toss scenes/fair.toml --set throw.height.mean=0.5 --set sim.stop_speed=0.01\n"
      "  dicesim toss scenes/paper/die3.toml --target-halfwidth 0.002   # as many tosses as that takes\n"
      "  dicesim toss scenes/paper/die1.toml -n 1000000 --shard 3/16 --out part-3.json   # then: dicesim merge part-*.json");
  cmd->footer(
      "\nWhich fidelity (--fidelity; scenes/README.md, docs/fidelity.md):\n"
      "  auto     the cheapest model measured adequate for this scene at this run's precision, else\n"
      "           impulse (`dicesim info SCENE` says which and why)\n"
      "  impulse  a real, unfair die or coin: friction, rolling, tipping to rest; its accuracy knob is\n"
      "           sim.contact_step (default 3 ms for polyhedra, 0.2 ms for cylinders, each measured\n"
      "           converged). sim.contact_tol (leapfrog steps) is experimental: leave it 0\n"
      "  stepped  the reference (fixed 0.2 ms steps), ~6x slower than impulse: to check a new die\n"
      "  paper    only to reproduce the seed's tables (frictionless corners, a rebound-speed stop)\n"
      "  static   a die placed, not thrown (random orientation, quasi-static roll); instant");
  args->scene.add_to(cmd);
  args->tosses_opt = cmd->add_option("-n,--tosses", args->tosses, "Number of tosses (default 100000). With --target-halfwidth: the most it may take when\n"
                                     "given; without -n, as many as the target needs (up to 10^9).\n"
                                     "Any exact whole number: 100000, 1e5, 100_000")
                         ->check(CLI::Range(1ULL, 1ULL << 40));
  cmd->add_option("--seed", args->seed, "Run seed (with the toss index, the only source of randomness)")
      ->capture_default_str();
  cmd->add_option("-j,--threads", args->threads, "Worker threads (default: all cores)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--target-halfwidth", args->target_halfwidth,
                  "Stop when every face's 95% half-width is <= H, judged every 10000 tosses in index order\n"
                  "(deterministic: the same stopping point on any number of threads or workers)")
      ->type_name("H")
      ->check(CLI::Range(1e-6, 0.5));
  cmd->add_option("--shard", args->shard,
                  "Toss shard I of N (I = 0..N-1) of the --tosses run: the contiguous index block\n"
                  "[floor(T*I/N), floor(T*(I+1)/N)) of T tosses. `dicesim merge` adds N shards' --out files\n"
                  "into the counts of one toss of all T (docs/scaling-out.md)")
      ->type_name("I/N");
  cmd->add_option("--out", args->out,
                  "Also write the report as a shard file for `dicesim merge` (the --json report plus a \"shard\"\n"
                  "object: version, scene hash, model fingerprint, block, raw counts); stdout is unchanged")
      ->type_name("FILE");
  cmd->add_option("--outcomes", args->outcomes,
                  "Also write each toss's outcome label, one line per toss index (-1: not settled), for\n"
                  "`dicesim compare A.json B.json --margin D --paired A.txt B.txt` on two runs with the same seed")
      ->type_name("FILE");
  cmd->add_flag("--json", args->json, "Print exactly one JSON object on stdout instead of the table");
  cmd->callback([args, &exit_code] { exit_code = run_toss(*args); });
}

}  // namespace dicesim
