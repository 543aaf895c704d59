// dicesim power: how many throws a chi-square test needs to tell two dice apart (--against), or to
// detect any face moved by delta (--detect-bias). The computation is sim/study/power.hpp.
#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>

#include "apps/commands.hpp"
#include "apps/interrupt.hpp"
#include "apps/power_report.hpp"
#include "apps/progress.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene_hash.hpp"
#include "sim/study/auto_pilot.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/study/sweep.hpp"

namespace dicesim {
namespace {

struct PowerArgs {
  SceneArgs scene;
  std::string against;
  double detect_bias = 0.0;
  CLI::Option* detect_opt = nullptr;
  double alpha = 0.05, power = 0.8;
  std::uint64_t replicates = 4000;
  int bootstrap = 1000;
  std::uint64_t tosses = 100000;
  std::uint64_t seed = 1;
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool json = false;
};

std::string labels_text(const std::vector<int>& labels) {
  std::string t = "[";
  for (std::size_t i = 0; i < labels.size(); ++i) t += (i ? ", " : "") + std::to_string(labels[i]);
  return t + "]";
}

// Ranges CLI11's inclusive Range cannot say (open ends, one bound given by another option).
void check(const PowerArgs& a) {
  const std::string cmd = "dicesim power";
  const bool has_against = !a.against.empty(), has_bias = a.detect_opt->count() > 0;
  if (has_against == has_bias)
    throw SceneError(cmd, "--against/--detect-bias", "",
                     "give exactly one: --against SCENE2 (tell two dice apart) or --detect-bias D (the smallest shift of any face)");
  if (!(a.alpha > 0.0 && a.alpha < 1.0)) throw SceneError(cmd, "--alpha", number_text(a.alpha), "must be in (0, 1)");
  if (!(a.power > a.alpha && a.power < 1.0))
    throw SceneError(cmd, "--power", number_text(a.power), "must be in (alpha, 1) = (" + number_text(a.alpha) + ", 1)");
  if (has_bias && !(a.detect_bias > 0.0 && a.detect_bias <= 0.5))
    throw SceneError(cmd, "--detect-bias", number_text(a.detect_bias), "must be in (0, 0.5]");
}

int run_power(const PowerArgs& a) {
  check(a);
  const auto t0 = std::chrono::steady_clock::now();
  const SceneDef def = a.scene.load();
  DieModel model = compile(def, a.scene.path);
  // auto: each scene's pilot at the study's simulated tosses.
  resolve_auto(model, precision_of_run(model, a.tosses), a.threads);
  std::unique_ptr<DieModel> other;
  std::string against_sha256;
  if (!a.against.empty()) {
    SceneArgs b = a.scene;  // --set and --fidelity apply to both scenes
    b.path = a.against;
    const SceneDef def_b = b.load();
    against_sha256 = scene_sha256(b.path, b.applied_overrides());
    other = std::make_unique<DieModel>(compile(def_b, b.path));
    resolve_auto(*other, precision_of_run(*other, a.tosses), a.threads);
    if (other->outcome_labels != model.outcome_labels)
      throw SceneError(a.against, "outcome labels", labels_text(other->outcome_labels),
                       "must equal those of " + a.scene.path + " " + labels_text(model.outcome_labels) +
                           " (the test compares the same outcomes)");
  }

  ProgressBar bar(true);
  PowerRunInfo info;
  info.scene = a.scene.path;
  info.against = a.against;
  info.fidelity = to_string(model.fidelity);
  if (other) info.fidelity_against = to_string(other->fidelity);
  info.seed = a.seed;
  info.threads = a.threads;
  info.provenance = make_provenance(a.scene.path, a.scene.applied_overrides(), scene_sha256(a.scene.path, a.scene.applied_overrides()), model, a.seed, a.tosses, a.threads);
  info.against_sha256 = against_sha256;
  PowerStudyConfig& cfg = info.config;
  cfg.tosses = a.tosses;
  cfg.seed = a.seed;
  cfg.threads = a.threads;
  cfg.bootstrap = a.bootstrap;
  cfg.target.alpha = a.alpha;
  cfg.target.power = a.power;
  cfg.target.replicates = a.replicates;
  cfg.target.seed = a.seed;
  cfg.progress = [&bar](std::uint64_t done, std::uint64_t total) { bar.update(done, total); };
  const InterruptGuard interrupt;  // Ctrl-C / SIGTERM: what is done is printed, exit 130
  cfg.cancel = InterruptGuard::flag();
  // An interrupted study has no n: its state (tosses simulated) and that it is partial.
  auto interrupted = [&](std::uint64_t simulated) {
    bar.finish();
    if (a.json)
      std::printf("%s\n", nlohmann::json{{"partial", true},
                                         {"state", {{"simulated_tosses", simulated}}},
                                         {"n_exact", nullptr},
                                         {"provenance", provenance_json(info.provenance)}}
                              .dump()
                              .c_str());
    else
      std::printf("dicesim power: interrupted after %llu tosses simulated; no n (the study needs all of them)\n%s",
                  static_cast<unsigned long long>(simulated), provenance_lines(info.provenance).c_str());
    std::fprintf(stderr, "dicesim power: interrupted\n");
    return kExitInterrupted;
  };
  // The searches for n after the tosses (seconds for a d20's 40 alternatives): a line every 2 s.
  double last_line = 0.0;
  cfg.search_progress = [&](std::size_t done, std::size_t total) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (t < 1.0 || (t - last_line < 2.0 && done < total) || last_line < 0.0) return;
    bar.finish();
    std::fprintf(stderr, "dicesim power: searching n: %zu of %zu searches done (%.0f s)\n", done, total, t);
    last_line = done == total ? -1.0 : t;
  };

  std::string text;
  nlohmann::json j;
  if (other) {
    const AgainstStudy s = power_against(model, *other, cfg);
    if (s.cancelled || InterruptGuard::interrupted()) return interrupted(s.simulated_tosses);
    bar.finish();
    info.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (s.difference.p_value >= kPowerDifferenceLevel)
      std::fprintf(stderr,
                   "dicesim power: warning: the simulated dice do not differ significantly (chi-square p = %.3g): n "
                   "measures mostly the simulation's noise; toss more (--tosses) or compare dice that differ\n",
                   s.difference.p_value);
    if (a.json) j = power_json(info, s);
    else text = power_table(info, s);
  } else {
    const BiasStudy s = power_detect_bias(model, a.detect_bias, cfg);
    if (s.cancelled || InterruptGuard::interrupted()) return interrupted(s.simulated_tosses);
    bar.finish();
    info.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (a.json) j = power_json(info, s);
    else text = power_table(info, s);
  }
  if (a.json) std::printf("%s\n", j.dump().c_str());
  else std::fputs(text.c_str(), stdout);
  return kExitOk;
}

}  // namespace

void register_power(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<PowerArgs>();
  CLI::App* cmd = app.add_subcommand(
      "power",
      "How many throws does a chi-square test need? Plans an experiment with a real die.\n\n"
      "--against SCENE2: H0 is SCENE's face probabilities, the die you throw is SCENE2. Prints the\n"
      "number of throws n at which Pearson's goodness-of-fit test against H0 (K-1 dof) rejects with\n"
      "the wanted power: exact (multinomial counts simulated at n; the critical value simulated under\n"
      "H0, so the size is alpha without the asymptotic approximation) and the noncentral chi-square\n"
      "approximation. --detect-bias D: the alternatives are SCENE with one face's probability moved by\n"
      "+D or -D (the others rescaled in proportion); n is the largest over faces and signs.\n"
      "Both scenes' probabilities come from tosses (the same toss indices for both); their noise is\n"
      "carried into a 95% range of n by a bootstrap over 20 batches of tosses. Everything is a\n"
      "function of --seed: the same n on any number of threads.\n"
      "Exit code 0 also when the simulated dice do not differ significantly (a warning on stderr,\n"
      "\"significant\": false in --json): n is then mostly the simulation's noise.");
  cmd->footer(
      "\nExamples:\n"
      "  dicesim power scenes/paper/die1.toml --against scenes/fair.toml\n"
      "      throws to tell Die 1 from a fair die at alpha 0.05 with power 0.8\n"
      "  dicesim power scenes/fair.toml --detect-bias 0.01 --power 0.9 --json\n"
      "      throws to detect any face 1 percentage point off a fair die's\n"
      "  dicesim power scenes/paper/die1.toml --against scenes/paper/die2.toml -n 1000000 --replicates 10000\n"
      "      more tosses: a narrower range of n; more replicates: a less noisy exact n");
  a->scene.add_to(cmd);
  cmd->add_option("--against", a->against, "The die actually thrown (a scene with the same outcome labels)")
      ->type_name("SCENE2");
  a->detect_opt = cmd->add_option("--detect-bias", a->detect_bias,
                                  "Smallest shift of any face's probability to detect, in (0, 0.5]")
                      ->type_name("D");
  cmd->add_option("--alpha", a->alpha, "Size of the test, in (0, 1)")->capture_default_str();
  cmd->add_option("--power", a->power, "Wanted power, in (alpha, 1)")->capture_default_str();
  cmd->add_option("--replicates", a->replicates, "Simulated count vectors per hypothesis and n (exact n)")
      ->capture_default_str()
      ->check(CLI::Range(100ULL, 10000000ULL));
  cmd->add_option("--bootstrap", a->bootstrap, "Bootstrap resamples for the 95% range of n")
      ->capture_default_str()
      ->check(CLI::Range(100, 1000000));
  cmd->add_option("-n,--tosses", a->tosses, "Tosses per scene (the probabilities' precision)")
      ->capture_default_str()
      ->check(CLI::Range(1000ULL, 1ULL << 40));
  cmd->add_option("--seed", a->seed, "Seed of the tosses and of the simulated counts")->capture_default_str();
  cmd->add_option("-j,--threads", a->threads, "Worker threads (default: all cores)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  cmd->add_flag("--json", a->json, "Print exactly one JSON object on stdout instead of the table");
  cmd->callback([a, &exit_code] { exit_code = run_power(*a); });
}

}  // namespace dicesim
