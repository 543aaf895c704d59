// dicesim.fit: scene keys fitted to observed counts, with the GIL released; returns the same
// object as `dicesim fit --json` (apps/fit_json.hpp), as a dict.
#include <pybind11/stl.h>

#include "apps/fit_json.hpp"
#include "python/bindings.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/study/fit.hpp"

namespace dicesim::py {
namespace {

// A scene argument: a Scene loaded from a file (its overrides come along) or a path.
std::pair<std::string, std::vector<std::string>> scene_of(const pb::handle& h) {
  if (pb::isinstance<Scene>(h)) {
    const Scene& s = h.cast<const Scene&>();
    if (!s.from_file())
      throw pb::value_error("fit needs scenes loaded from files (the fit loads them again at each value); '" + s.origin() +
                            "' came from TOML text");
    return {s.origin(), s.overrides()};
  }
  if (pb::isinstance<pb::str>(h)) return {h.cast<std::string>(), {}};
  throw pb::type_error("a scene must be a dicesim.Scene or a path");
}

// Observed counts: a counts file (CSV face,count or `dicesim toss --json`) or a dict {label: count}.
FaceCounts counts_of(const pb::handle& h, std::string& source) {
  if (pb::isinstance<pb::str>(h)) {
    source = h.cast<std::string>();
    return read_face_counts(source);
  }
  if (pb::isinstance<pb::dict>(h)) {
    source = "counts";
    FaceCounts c;
    for (const auto& [k, v] : h.cast<pb::dict>()) {
      c.labels.push_back(k.cast<int>());
      const long long n = v.cast<long long>();
      if (n < 0) throw pb::value_error("counts must be >= 0, got " + std::to_string(n) + " for " + std::to_string(c.labels.back()));
      c.counts.push_back(static_cast<std::uint64_t>(n));
    }
    return c;
  }
  throw pb::type_error("data must be a counts file path or a dict {label: count}");
}

pb::object do_fit(const pb::object& scene, const pb::object& data, const pb::object& params, const pb::object& n_given, int rounds,
                  std::uint64_t seed, int threads, std::optional<std::string> fidelity, const pb::object& progress) {
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) throw pb::type_error("progress must be callable or None");
  // One data set, or lists of scenes and data of the same length.
  const bool many = pb::isinstance<pb::list>(data) || pb::isinstance<pb::tuple>(data);
  std::vector<pb::object> scenes, datas;
  if (many) {
    for (const pb::handle d : data) datas.push_back(pb::reinterpret_borrow<pb::object>(d));
    if (pb::isinstance<pb::list>(scene) || pb::isinstance<pb::tuple>(scene)) {
      for (const pb::handle s : scene) scenes.push_back(pb::reinterpret_borrow<pb::object>(s));
    } else {
      scenes.assign(datas.size(), scene);
    }
    if (scenes.size() != datas.size())
      throw pb::value_error("scene and data must be lists of the same length (" + std::to_string(scenes.size()) + " and " +
                            std::to_string(datas.size()) + ")");
  } else {
    scenes.push_back(scene);
    datas.push_back(data);
  }
  std::vector<FitData> sets;
  for (std::size_t i = 0; i < datas.size(); ++i) {
    FitData d;
    auto [path, overrides] = scene_of(scenes[i]);
    d.scene = path;
    d.overrides = overrides;
    d.observed = counts_of(datas[i], d.source);
    sets.push_back(std::move(d));
  }
  std::vector<FitParam> ps;
  if (pb::isinstance<pb::dict>(params)) {
    for (const auto& [k, v] : params.cast<pb::dict>()) {
      const auto range = v.cast<std::pair<double, double>>();
      ps.push_back({k.cast<std::string>(), range.first, range.second});  // run_fit checks the range
    }
  } else {
    for (const pb::handle p : params) ps.push_back(parse_fit_param(p.cast<std::string>(), "dicesim.fit"));
  }
  FitOptions opt;
  opt.overrides = fidelity_override(fidelity);
  opt.seed = seed;
  opt.threads = resolve_threads(threads);
  opt.tosses = count_arg(n_given, "n").value_or(0);
  opt.rounds = rounds;
  RunMonitor monitor;
  opt.cancel = &monitor.cancel;
  opt.progress = [&monitor](const std::string&, std::uint64_t d, std::uint64_t t) { monitor.report(d, t); };
  FitResult r;
  run_interruptible([&] { r = run_fit(ps, sets, opt); }, monitor, progress);
  return pb::module_::import("json").attr("loads")(fit_json(r, opt).dump());
}

}  // namespace

void register_fit(pb::module_& m) {
  m.def("fit", &do_fit, pb::arg("scene"), pb::arg("data"), pb::arg("params"), pb::arg("n") = 0, pb::arg("rounds") = 3,
        pb::arg("seed") = 1, pb::arg("threads") = 0, pb::arg("fidelity") = pb::none(), pb::arg("progress") = pb::none(),
        "Fit one to three numeric scene keys to observed counts: `dicesim fit`. Returns the dict that\n"
        "`dicesim fit --json` prints: params (key, estimate, ci95, ...), fitted (label, p, observed),\n"
        "gof (statistic, dof, p_value), simulated_tosses, elapsed_s.\n"
        "scene: a Scene loaded from a file, or a path; data: a counts file (CSV face,count or toss JSON)\n"
        "or a dict {label: count}. Several data sets fit shared keys jointly: lists of scenes and data\n"
        "of the same length (or one scene for every data set).\n"
        "params: {key: (lo, hi)} or ['KEY=LO:HI', ...]. n: tosses per grid point in the last round\n"
        "(0: automatic, 20 per observed toss, at least 40000).\n"
        "    dicesim.fit('scenes/paper/die1.toml', 'data/seed-experiments/die1_counts.csv',\n"
        "                {'materials.steel.density': (3000, 20000)}, fidelity='impulse')\n"
        "GIL, Ctrl-C and progress(done, total) as in toss(). Bad input raises SceneError.");
}

}  // namespace dicesim::py
