// dicesim.power: throws a chi-square test needs (sim/study/power.hpp), with the GIL released.
// Returns the dict of `dicesim power --json` (apps/power_report.hpp builds both).
#include <chrono>
#include <optional>

#include <pybind11/stl.h>

#include "apps/power_report.hpp"
#include "python/bindings.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/study/auto_pilot.hpp"

namespace dicesim::py {
namespace {

std::string labels_text(const std::vector<int>& labels) {
  std::string t = "[";
  for (std::size_t i = 0; i < labels.size(); ++i) t += (i ? ", " : "") + std::to_string(labels[i]);
  return t + "]";
}

pb::object do_power(const pb::object& scene_given, const pb::object& against_given, std::optional<double> detect_bias,
                    const pb::object& n_given,
                    double alpha, double power, std::uint64_t replicates, int bootstrap, std::uint64_t seed, int threads,
                    std::optional<std::string> fidelity, const pb::object& progress) {
  const std::shared_ptr<Scene> held = scene_arg(scene_given);
  Scene& scene = *held;
  // against, like scene, may be a path: power('die.toml', against='scenes/fair.toml').
  const std::shared_ptr<Scene> against = against_given.is_none() ? nullptr : scene_arg(against_given);
  const std::optional<std::uint64_t> counted = count_arg(n_given, "n");
  if (!counted) throw pb::type_error("n must be a whole number, got None");
  const std::uint64_t n = *counted;
  if ((against != nullptr) == detect_bias.has_value())
    throw pb::value_error("give exactly one of against (a Scene or a path) or detect_bias (a shift in (0, 0.5])");
  if (!(alpha > 0.0 && alpha < 1.0)) throw pb::value_error("alpha must be in (0, 1), got " + std::to_string(alpha));
  if (!(power > alpha && power < 1.0))
    throw pb::value_error("power must be in (alpha, 1) = (" + std::to_string(alpha) + ", 1), got " + std::to_string(power));
  if (detect_bias && !(*detect_bias > 0.0 && *detect_bias <= 0.5))
    throw pb::value_error("detect_bias must be in (0, 0.5], got " + std::to_string(*detect_bias));
  if (n < 1000 || n > (1ULL << 40)) throw pb::value_error("n must be in [1000, 2^40], got " + std::to_string(n));
  if (replicates < 100 || replicates > 10000000)
    throw pb::value_error("replicates must be in [100, 10^7], got " + std::to_string(replicates));
  if (bootstrap < 100 || bootstrap > 1000000) throw pb::value_error("bootstrap must be in [100, 10^6], got " + std::to_string(bootstrap));
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) throw pb::type_error("progress must be callable or None");

  std::shared_ptr<const DieModel> model = scene.model(fidelity);
  // auto: each scene's pilot at the study's simulated tosses (as `dicesim power`).
  auto resolved = [&](std::shared_ptr<const DieModel> m) -> std::shared_ptr<const DieModel> {
    if (m->fidelity_requested != Fidelity::Auto) return m;
    auto r = std::make_shared<DieModel>(*m);
    resolve_auto(*r, precision_of_run(*r, n), resolve_threads(threads));
    return r;
  };
  model = resolved(model);
  std::shared_ptr<const DieModel> other;
  if (against) {
    other = resolved(against->model(fidelity));
    if (other->outcome_labels != model->outcome_labels)
      throw SceneError(against->origin(), "outcome labels", labels_text(other->outcome_labels),
                       "must equal those of " + scene.origin() + " " + labels_text(model->outcome_labels) +
                           " (the test compares the same outcomes)");
  }
  PowerRunInfo info;
  info.scene = scene.origin();
  info.fidelity = to_string(model->fidelity);
  if (other) {
    info.against = against->origin();
    info.fidelity_against = to_string(other->fidelity);
  }
  info.seed = seed;
  info.threads = resolve_threads(threads);
  {
    const std::vector<std::string> extra = fidelity_override(fidelity);
    std::vector<std::string> overrides = scene.overrides();
    overrides.insert(overrides.end(), extra.begin(), extra.end());
    info.provenance = make_provenance(scene.origin(), overrides, scene.sha256_with(extra), *model, seed, n, info.threads);
    if (against) info.against_sha256 = against->sha256_with(extra);
  }
  PowerStudyConfig& cfg = info.config;
  cfg.tosses = n;
  cfg.seed = seed;
  cfg.threads = info.threads;
  cfg.bootstrap = bootstrap;
  cfg.target = {alpha, power, replicates, seed};

  RunMonitor monitor;
  monitor.total = other ? 2 * n : n;
  cfg.cancel = &monitor.cancel;
  cfg.progress = [&monitor](std::uint64_t d, std::uint64_t t) { monitor.report(d, t); };
  nlohmann::json j;
  const auto t0 = std::chrono::steady_clock::now();
  run_interruptible(
      [&] {
        if (other) {
          const AgainstStudy s = power_against(*model, *other, cfg);
          info.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          if (!s.cancelled) j = power_json(info, s);
        } else {
          const BiasStudy s = power_detect_bias(*model, *detect_bias, cfg);
          info.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          if (!s.cancelled) j = power_json(info, s);
        }
      },
      monitor, progress);
  return pb::module_::import("json").attr("loads")(j.dump());
}

}  // namespace

void register_power(pb::module_& m) {
  m.def("power", &do_power, pb::arg("scene"), pb::kw_only(), pb::arg("against").none(true) = pb::none(),
        pb::arg("detect_bias") = pb::none(), pb::arg("n") = 100000, pb::arg("alpha") = 0.05, pb::arg("power") = 0.8,
        pb::arg("replicates") = 4000, pb::arg("bootstrap") = 1000, pb::arg("seed") = 1, pb::arg("threads") = 0,
        pb::arg("fidelity") = pb::none(), pb::arg("progress") = pb::none(),
        "Throws a chi-square goodness-of-fit test needs: `dicesim power` as a dict (its --json).\n\n"
        "power(scene, against=other): H0 is scene's face probabilities, the die thrown is `other`.\n"
        "power(scene, detect_bias=0.01): any one face moved by +/-0.01 (the others rescaled).\n"
        "n tosses per scene give the probabilities (the same toss indices for both); 'n_exact' is\n"
        "the number of throws by simulated multinomial counts (replicates per hypothesis and n),\n"
        "'n_approx' the noncentral chi-square approximation's, 'n_range95' the range of n_exact from\n"
        "the tosses' own noise (a paired bootstrap of toss batches), 'n_exact_replicate_sd' its noise\n"
        "from the replicates. Everything is a function of seed, on any number of threads.\n"
        "Bad arguments raise ValueError; scenes with different outcome labels raise SceneError.\n\n"
        "    d = dicesim.power('scenes/paper/die1.toml', against='scenes/fair.toml')\n"
        "    d['n_exact'], d['n_range95']");
}

}  // namespace dicesim::py
