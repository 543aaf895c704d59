// dicesim fit: scene keys fitted to observed counts (simulation-based maximum likelihood,
// sim/study/fit.hpp), with profile-likelihood intervals, the fitted probabilities and the
// goodness of fit, as a table or JSON, and the profiles as a picture.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include "apps/commands.hpp"
#include "apps/fidelity_name.hpp"
#include "apps/fit_json.hpp"
#include "apps/fit_parts.hpp"
#include "apps/gnuplot.hpp"
#include "apps/interrupt.hpp"
#include "apps/output_path.hpp"
#include "sim/scene/key_unit.hpp"
#include "apps/progress.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/study/fit.hpp"
#include "sim/study/sweep.hpp"

namespace dicesim {
namespace {

namespace fs = std::filesystem;

struct FitArgs {
  SceneArgs scene;
  std::vector<std::string> data, scenes, params;
  std::uint64_t tosses = 0;  // automatic
  int rounds = 3;
  std::uint64_t seed = 1;
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool json = false;
  std::string plot;
  std::string points;  // --points I/N: one shard's pass of a fit sharded by point (with --parts DIR)
  std::string parts;
  std::string merge;   // --merge DIR: the fit from its parts
};

// One shard's pass (fit --points I/N --parts DIR): tosses this shard's block of the first stage not
// yet counted in DIR, writes it as a part, and goes on while the stage it finished is then whole
// (the other shards' parts already there); stops at a stage that waits for other shards.
int run_fit_pass(const std::vector<FitParam>& params, const std::vector<FitData>& data, FitOptions opt, const FitArgs& a) {
  Shard shard;
  try {
    shard = parse_shard(a.points);
  } catch (const std::invalid_argument& e) {
    throw SceneError("dicesim fit", "--points", a.points, e.what());
  }
  std::error_code ec;
  std::filesystem::create_directories(a.parts, ec);
  if (!std::filesystem::is_directory(a.parts)) throw SceneError("dicesim fit", "--parts", a.parts, "cannot create this directory");
  const nlohmann::json identity = fit_identity(params, data, opt);
  opt.toss_shard = shard;
  std::vector<std::string> written;
  nlohmann::json status = {{"shard", a.points}, {"parts", a.parts}};
  const InterruptGuard interrupt;
  opt.cancel = InterruptGuard::flag();
  for (;;) {
    const FitParts parts = read_fit_parts(a.parts, identity, shard.count);
    opt.given = &parts.points;
    try {
      (void)run_fit(params, data, opt);
      status["complete"] = true;
      break;
    } catch (const FitStageIncomplete& inc) {
      if (!inc.tossed.empty()) written.push_back(write_fit_part(a.parts, identity, shard, inc));
      if (!inc.tossed.empty() && inc.missing.empty()) continue;  // that stage is whole now: on to the next
      status["complete"] = false;
      status["stage"] = inc.stage;
      status["label"] = inc.label;
      status["stage_points"] = inc.stage_points;
      status["missing"] = inc.missing;
      break;
    } catch (const std::runtime_error&) {
      if (!InterruptGuard::interrupted()) throw;
      // The block being tossed is lost (no part written); the parts written stay valid.
      std::fprintf(stderr, "dicesim fit: interrupted; %zu part%s written, the block in progress not (run the pass again)\n",
                   written.size(), written.size() == 1 ? "" : "s");
      return kExitInterrupted;
    }
  }
  status["written"] = written;
  if (a.json) {
    std::printf("%s\n", nlohmann::json{{"fit_pass", status}}.dump().c_str());
    return kExitOk;
  }
  std::printf("dicesim fit: shard %s of a fit sharded by point, parts in %s\n", a.points.c_str(), a.parts.c_str());
  for (const std::string& w : written) std::printf("  wrote %s\n", w.c_str());
  if (status["complete"].get<bool>())
    std::printf("every stage is counted: `dicesim fit ... --merge %s` (the same arguments) prints the fit\n", a.parts.c_str());
  else
    std::printf("stage %d (%s) waits for %zu of its %zu points from other shards: run every shard's pass again once they "
                "have finished (a fit takes at most rounds + %d + 1 passes)\n",
                status["stage"].get<int>(), status["label"].get<std::string>().c_str(), status["missing"].size(),
                status["stage_points"].get<std::size_t>(), kFitMaxWidenings);
  return kExitOk;
}

void write_profile_plot(const std::string& path, const FitResult& r) {
  std::ostringstream gp;
  const int d = static_cast<int>(r.params.size());
  gp << gnuplot_terminal(path, 480 * d + 60, 420);
  std::string scenes;
  std::uint64_t observed = 0;
  for (const FitDataResult& data : r.data) {
    if (scenes.find(data.scene) == std::string::npos) scenes += (scenes.empty() ? "" : ", ") + data.scene;
    for (const auto c : data.observed) observed += c;
  }
  gp << "set multiplot layout 1," << d << " title "
     << gnuplot_quote("profile likelihood: " + scenes + ", fidelity " + r.fidelity + "\n" + std::to_string(observed) +
                      " observed tosses, " + std::to_string(r.simulated_tosses) + " simulated")
     << " noenhanced\n";
  // The legend below the axes: at the top centre it covered the profile's minimum.
  gp << "set grid\nset border 3\nset tics nomirror\nset ylabel '2 (l_max - l_profile)' noenhanced\n"
        "set key below horizontal Left reverse noenhanced\n";
  for (const FitParamResult& p : r.params) {
    const std::string unit = key_unit(p.key);
    gp << "set xlabel " << gnuplot_quote(unit.empty() ? p.key : p.key + " (" + unit + ")") << " noenhanced\n";
    gp << "set yrange [0:8]\n";
    if (!p.identifiable) {  // its profile is flat: no interval, no estimate
      gp << "$p << EOD\n";
      for (const auto& row : p.profile) gp << number_text(row[0]) << " " << number_text(row[1]) << "\n";
      gp << "EOD\nplot $p using 1:2 with lines lw 2 title 'profile (not identifiable)'\n";
      continue;
    }
    gp << "set arrow from " << number_text(p.ci95.lo) << ",0 to " << number_text(p.ci95.lo) << ",3.841 nohead dt 2\n";
    gp << "set arrow from " << number_text(p.ci95.hi) << ",0 to " << number_text(p.ci95.hi) << ",3.841 nohead dt 2\n";
    gp << "$p << EOD\n";
    for (const auto& row : p.profile) gp << number_text(row[0]) << " " << number_text(row[1]) << "\n";
    gp << "EOD\n";
    // The legend says what the dashed bounds are: the interval's numbers, in the key's unit.
    const std::string in_unit = unit.empty() ? "" : " " + unit;
    gp << "plot $p using 1:2 with lines lw 2 title 'profile', 3.841 with lines dt 3 lw 1.5 lc rgb 'black' title "
       << gnuplot_quote("95% interval [" + short_text(p.ci95.lo) + ", " + short_text(p.ci95.hi) + "]" + in_unit +
                        " (cut 3.84)")
       << ", '+' using (" << number_text(p.estimate) << "):(0) with points pt 7 ps 1.2 title "
       << gnuplot_quote("estimate " + short_text(p.estimate) + in_unit) << "\n";
    gp << "unset arrow\n";
  }
  gp << "unset multiplot\n";
  run_gnuplot(gp.str(), path);
}

void print_text(const FitResult& r, const FitArgs& a, const FitOptions& opt) {
  std::printf("dicesim fit: %zu parameter%s, %zu data set%s, fidelity %s, seed %llu\n", r.params.size(),
              r.params.size() == 1 ? "" : "s", r.data.size(), r.data.size() == 1 ? "" : "s", r.fidelity.c_str(),
              static_cast<unsigned long long>(a.seed));
  std::fputs(provenance_lines(fit_provenance(a.scene.path, opt, r.fidelity, r.fidelity_reason)).c_str(), stdout);
  for (const FitDataResult& d : r.data) {
    std::uint64_t n = 0;
    for (const auto c : d.observed) n += c;
    std::printf("  %s on %s: %llu observed tosses\n", d.source.c_str(), d.scene.c_str(), static_cast<unsigned long long>(n));
  }
  if (!r.estimated) {  // no estimate: say which key the simulated probabilities do not feel
    std::printf("\n");
    for (const FitParamResult& p : r.params) {
      if (p.identifiable)
        std::printf("%s: moves the outcomes (up to %.3g standard errors); refit without the keys below\n", p.key.c_str(),
                    p.shift_z);
      else
        std::printf("%s: not identifiable from these data: over %g..%g it moves no outcome's probability by more than "
                    "the Monte Carlo noise (largest change %.3g standard errors; %.3g needed)\n",
                    p.key.c_str(), p.lo, p.hi, p.shift_z, p.shift_z_level);
    }
    std::printf("no estimate (%llu tosses simulated in %.1f s)\n", static_cast<unsigned long long>(r.simulated_tosses),
                r.elapsed_s);
    return;
  }
  std::printf("\n%-28s %12s   %-27s %12s %14s\n", "parameter", "estimate", "95% interval", "MC sd", "ideal 95% +-");
  for (const FitParamResult& p : r.params) {
    char iv[64];
    std::snprintf(iv, sizeof iv, "[%.6g, %.6g]", p.ci95.lo, p.ci95.hi);
    if (!p.identifiable) {
      std::printf("%-28s not identifiable from these data (moves no outcome beyond the Monte Carlo noise over %g..%g)\n",
                  p.key.c_str(), p.lo, p.hi);
      continue;
    }
    std::printf("%-28s %12.6g   %-27s %12.3g %14.4g\n", p.key.c_str(), p.estimate, iv, p.mc_sd, p.fisher_halfwidth);
  }
  for (const FitParamResult& p : r.params) {
    if (!p.identifiable) continue;
    if (p.mc_large)
      std::printf("note: %s's Monte Carlo sd is over half the data's: the interval may be too narrow (raise --tosses)\n",
                  p.key.c_str());
    if (p.lo_open && p.box_lo <= p.lo)
      std::printf("note: %s's interval reaches the range's low end %g: the data do not bound it there (widen --param)\n",
                  p.key.c_str(), p.lo);
    else if (p.lo_open)
      std::printf("note: %s's interval reaches %g, the low end of the last (narrowed, then widened) box: open there; "
                  "the data may not bound it (raise --rounds or --tosses)\n", p.key.c_str(), p.box_lo);
    if (p.hi_open && p.box_hi >= p.hi)
      std::printf("note: %s's interval reaches the range's high end %g: the data do not bound it there (widen --param)\n",
                  p.key.c_str(), p.hi);
    else if (p.hi_open)
      std::printf("note: %s's interval reaches %g, the high end of the last (narrowed, then widened) box: open there; "
                  "the data may not bound it (raise --rounds or --tosses)\n", p.key.c_str(), p.box_hi);
  }
  for (const FitDataResult& d : r.data) {
    std::uint64_t n = 0;
    for (const auto c : d.observed) n += c;
    std::printf("\n%s: fitted (simulated at the estimate, %llu tosses)\n", d.source.c_str(),
                static_cast<unsigned long long>(d.fitted_tosses));
    std::printf("%8s %10s %10s %10s\n", "outcome", "observed", "expected", "p fitted");
    for (std::size_t k = 0; k < d.labels.size(); ++k)
      std::printf("%8d %10llu %10.1f %10.4f%s%s\n", d.labels[k], static_cast<unsigned long long>(d.observed[k]),
                  d.fitted[k] * static_cast<double>(n), d.fitted[k], k < d.names.size() ? "   " : "",
                  k < d.names.size() ? d.names[k].c_str() : "");
    std::printf("chi-square %.2f on %d dof, p = %.3g\n", d.gof.statistic, d.gof.dof, d.gof.p_value);
  }
  if (r.gof.dof > 0)
    std::printf("\ngoodness of fit (all data, %zu fitted): chi-square %.2f on %d dof, p = %.3g\n", r.params.size(),
                r.gof.statistic, r.gof.dof, r.gof.p_value);
  else {  // e.g. a coin's heads and tails, one key: the fit can match them exactly
    const std::size_t keys = r.params.size();
    const int free = r.gof.dof + static_cast<int>(keys);
    std::printf("\ngoodness of fit (all data): none possible, %zu fitted key%s for %d free outcome frequenc%s "
                "(chi-square %.2f)\n", keys, keys == 1 ? "" : "s", free, free == 1 ? "y" : "ies", r.gof.statistic);
  }
  std::printf("%zu rounds, %llu tosses simulated in %.1f s (95%% interval: profile likelihood of the surrogate, widened\n"
              "by the Monte Carlo sd in quadrature; ideal: the Fisher information's, for comparison)\n",
              r.rounds.size(), static_cast<unsigned long long>(r.simulated_tosses), r.elapsed_s);
}

int run_fit_cmd(const FitArgs& a) {
  if (a.scenes.size() + 1 != a.data.size() && !(a.scenes.empty() && a.data.size() == 1))
    throw SceneError("dicesim fit", "--scene", std::to_string(a.scenes.size()) + " given",
                     "the first --data is SCENE's; each further --data needs its --scene (" +
                         std::to_string(a.data.size() - 1) + " expected)");
  std::vector<FitParam> params;
  for (const std::string& p : a.params) params.push_back(parse_fit_param(p));
  std::vector<FitData> data;
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    FitData d;
    d.scene = i == 0 ? a.scene.path : a.scenes[i - 1];
    d.source = a.data[i];
    d.observed = read_face_counts(a.data[i]);
    data.push_back(std::move(d));
  }
  if (!a.plot.empty()) {
    const std::string ext = fs::path(a.plot).extension().string();
    if (ext != ".png" && ext != ".svg") throw SceneError("dicesim fit", "--plot", a.plot, "must end in .png or .svg");
  }
  check_output_path("dicesim fit", "--plot", a.plot);  // before any toss
  FitOptions opt;
  opt.overrides = a.scene.overrides;
  check_fidelity_name(a.scene.fidelity);
  if (!a.scene.fidelity.empty()) opt.overrides.push_back("sim.fidelity=\"" + a.scene.fidelity + "\"");
  opt.seed = a.seed;
  opt.threads = a.threads;
  opt.tosses = a.tosses;
  opt.rounds = a.rounds;
  if (!a.points.empty() || !a.parts.empty()) {
    if (a.points.empty() || a.parts.empty())
      throw SceneError("dicesim fit", a.points.empty() ? "--parts" : "--points", a.points.empty() ? a.parts : a.points,
                       "a shard's pass needs both --points I/N and --parts DIR");
    if (!a.merge.empty()) throw SceneError("dicesim fit", "--merge", a.merge, "not with --points: a pass tosses, --merge reads");
    if (!a.plot.empty()) throw SceneError("dicesim fit", "--plot", a.plot, "needs the whole fit: give it with --merge DIR");
    return run_fit_pass(params, data, opt, a);
  }
  FitParts merged;
  if (!a.merge.empty()) {  // every point from the parts: the fit of one unsharded run
    merged = read_fit_parts(a.merge, fit_identity(params, data, opt), 0);
    opt.given = &merged.points;
  }
  ProgressBar bar;
  // Where the fit was when interrupted: a fit has no estimate before a round's whole grid is tossed.
  struct State {
    std::string stage;
    std::uint64_t done = 0, total = 0;
  } state;
  std::mutex state_mu;  // run_fit's threads report at once
  opt.progress = [&bar, &state, &state_mu](const std::string& stage, std::uint64_t done, std::uint64_t total) {
    {
      std::lock_guard lock(state_mu);
      if (done >= state.done || stage != state.stage) state = {stage, done, total};
    }
    bar.update(done, total);
  };
  const InterruptGuard interrupt;
  opt.cancel = InterruptGuard::flag();
  FitResult r;
  try {
    r = run_fit(params, data, opt);
  } catch (const FitStageIncomplete& inc) {
    bar.finish();
    throw ShardError(missing_parts_message(a.merge, merged.count, inc));
  } catch (const std::runtime_error&) {
    bar.finish();
    if (!InterruptGuard::interrupted()) throw;
    const Provenance prov = fit_provenance(a.scene.path, opt, "", "");
    if (a.json) {
      std::printf("%s\n", nlohmann::json{{"partial", true},
                                         {"state", {{"stage", state.stage}, {"tosses_done", state.done}, {"tosses_total", state.total}}},
                                         {"estimate", nullptr},
                                         {"provenance", provenance_json(prov)}}
                              .dump()
                              .c_str());
    } else {
      std::printf("dicesim fit: interrupted in %s, after %llu of %llu tosses; no estimate (a round's whole grid is needed)\n",
                  state.stage.empty() ? "its checks" : state.stage.c_str(), static_cast<unsigned long long>(state.done),
                  static_cast<unsigned long long>(state.total));
      std::fputs(provenance_lines(prov).c_str(), stdout);
    }
    std::fprintf(stderr, "dicesim fit: interrupted\n");
    return kExitInterrupted;
  }
  bar.finish();
  if (!a.plot.empty() && r.estimated) write_profile_plot(a.plot, r);
  if (!a.plot.empty() && !r.estimated) std::fprintf(stderr, "dicesim fit: no profile to plot (%s not written)\n", a.plot.c_str());
  if (a.json)
    std::printf("%s\n", fit_json(r, opt).dump().c_str());
  else
    print_text(r, a, opt);
  return kExitOk;
}

}  // namespace

void register_fit(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<FitArgs>();
  CLI::App* cmd = app.add_subcommand(
      "fit",
      "From counts back to the die: fit one to three numeric scene keys to observed face counts.\n"
      "Simulation-based maximum likelihood: a grid of the keys' values is tossed with the same seed\n"
      "and toss indices at every point (common random numbers), log P(outcome) is fitted by a smooth\n"
      "polynomial, the likelihood of the counts is maximised, and each key's 95% interval is where\n"
      "its profile likelihood is within 1.92 of the maximum, widened by the simulation's own error.\n"
      "Each round narrows the grid around the estimate and doubles its tosses. Several data sets\n"
      "(dice, heights) fit shared keys jointly. The fitted probabilities are simulated at the\n"
      "estimate, with the chi-square goodness of fit. docs/fitting.md has the method and its checks.");
  cmd->footer(
      "\nCounts: a CSV face,count (header and '#' comments allowed) or `dicesim toss --json` output.\n"
      "Examples:\n"
      "  dicesim fit scenes/paper/die1.toml --data data/seed-experiments/die1_counts.csv \\\n"
      "      --param floor.restitution=0.2:0.9 --fidelity impulse\n"
      "  dicesim fit scenes/paper/die1.toml --data data/seed-experiments/die1_counts.csv \\\n"
      "      --data data/seed-experiments/die2_counts.csv --scene scenes/paper/die2.toml \\\n"
      "      --param floor.restitution=0.2:0.9 --param floor.friction=0.05:1 --fidelity impulse --json\n"
      "  dicesim fit scenes/paper/die1.toml --data my_counts.csv \\\n"
      "      --param materials.steel.density=2000:20000 --fidelity static --plot profile.svg\n"
      "Sharded by point (e.g. a Slurm array of 4, each pass after the last; the same arguments each time):\n"
      "  for pass in 1 2 3 4; do for i in 0 1 2 3; do dicesim fit ARGS --points $i/4 --parts parts/; done; done\n"
      "  dicesim fit ARGS --merge parts/\n"
      "Exit codes: 0 fitted, 1 failed, 2 bad input (file, key, value or range named).");
  a->scene.add_to(cmd);
  cmd->add_option("--data", a->data, "Observed counts (CSV face,count or toss JSON); repeatable: the first is SCENE's")
      ->required()
      ->type_name("COUNTS");
  cmd->add_option("--scene", a->scenes, "The scene of the next --data after the first (in order); repeatable")
      ->type_name("SCENE2");
  cmd->add_option("--param", a->params, "A numeric scene key to fit and its range, KEY=LO:HI; 1 to 3 of them")
      ->required()
      ->type_name("KEY=LO:HI");
  cmd->add_option("-n,--tosses", a->tosses,
                  "Tosses per grid point and data set in the last round (earlier rounds: half, a quarter, ...).\n"
                  "Default: 20 per observed toss of the largest data set, at least 40000 (fewer make the\n"
                  "intervals too narrow once the simulation's noise rivals the data's: docs/fitting.md)")
      ->check(CLI::Range(1000ULL, 1ULL << 34));
  cmd->add_option("--rounds", a->rounds, "Rounds of the adaptive design (each narrows the grid)")
      ->capture_default_str()
      ->check(CLI::Range(1, 10));
  cmd->add_option("--seed", a->seed, "Run seed (with the toss index, the only source of randomness)")->capture_default_str();
  cmd->add_option("-j,--threads", a->threads, "Worker threads (default: all cores)")->capture_default_str()->check(CLI::Range(1, 1024));
  cmd->add_flag("--json", a->json, "Print exactly one JSON object on stdout instead of the table");
  cmd->add_option("--plot", a->plot, "Write the profile likelihood(s) as a picture (.png or .svg; needs gnuplot)")
      ->type_name("FILE");
  cmd->add_option("--points", a->points,
                  "Shard the fit by point, for job arrays: toss shard I of N's block of the first stage (a round's\n"
                  "design, then the fitted point) not yet counted in --parts DIR and write it there as a part. A\n"
                  "stage needs the ones before it, so run the N shards' passes again after each other (at most\n"
                  "rounds + 5 passes; a pass with nothing left to toss says so), then --merge DIR")
      ->type_name("I/N");
  cmd->add_option("--parts", a->parts, "With --points: the directory shared by the shards' part files (created)")
      ->type_name("DIR");
  cmd->add_option("--merge", a->merge,
                  "Print the fit from the part files in DIR, exactly as one unsharded fit with the same arguments\n"
                  "prints it; refuses (exit 2, naming the file) parts of another fit, missing and overlapping parts")
      ->type_name("DIR");
  cmd->callback([a, &exit_code] { exit_code = run_fit_cmd(*a); });
}

}  // namespace dicesim
