// dicesim.toss and dicesim.sweep: Monte Carlo runs with the GIL released, and their results.
#include <chrono>
#include <cstdint>
#include <optional>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "aggregator/target.hpp"
#include "apps/report.hpp"
#include "python/bindings.hpp"
#include "sim/study/auto_pilot.hpp"
#include "sim/models/compile.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/study/sweep.hpp"

namespace dicesim::py {
namespace {

using Clock = std::chrono::steady_clock;

pb::object json_to_python(const nlohmann::json& j) { return pb::module_::import("json").attr("loads")(j.dump()); }

// One run's report; everything Python sees is read from report_json(), the function behind
// `dicesim toss --json`, so the faces, their labels and order, and any field it gains are the CLI's.
class Result {
 public:
  explicit Result(RunReport r) : report_(std::move(r)) {}

  const RunReport& report() const { return report_; }
  const nlohmann::json& json() {
    if (!json_) json_ = report_json(report_);
    return *json_;
  }
  const nlohmann::json& faces() { return json().at("faces"); }

  template <class T>
  pb::array_t<T> face_column(const char* key) {
    const nlohmann::json& f = faces();
    pb::array_t<T> out(static_cast<pb::ssize_t>(f.size()));
    auto o = out.template mutable_unchecked<1>();
    for (std::size_t i = 0; i < f.size(); ++i) o(static_cast<pb::ssize_t>(i)) = f[i].at(key).template get<T>();
    return out;
  }
  pb::array_t<double> ci95() {
    const nlohmann::json& f = faces();
    pb::array_t<double> out({static_cast<pb::ssize_t>(f.size()), pb::ssize_t{2}});
    auto o = out.mutable_unchecked<2>();
    for (std::size_t i = 0; i < f.size(); ++i) {
      o(static_cast<pb::ssize_t>(i), 0) = f[i].at("ci95")[0].get<double>();
      o(static_cast<pb::ssize_t>(i), 1) = f[i].at("ci95")[1].get<double>();
    }
    return out;
  }
  pb::object field(const char* key) {
    const nlohmann::json& j = json();
    return j.contains(key) ? json_to_python(j.at(key)) : pb::none();
  }

  // One row per face: face, count, p, lo, hi; the run's other fields in DataFrame.attrs.
  pb::object to_pandas() {
    pb::module_ pd = pb::module_::import("pandas");
    pb::dict cols;
    cols["face"] = face_column<std::int64_t>("face");
    cols["count"] = face_column<std::int64_t>("count");
    cols["p"] = face_column<double>("p");
    pb::array_t<double> ci = ci95();
    cols["lo"] = ci[pb::make_tuple(pb::slice(0, ci.shape(0), 1), 0)];
    cols["hi"] = ci[pb::make_tuple(pb::slice(0, ci.shape(0), 1), 1)];
    pb::object df = pd.attr("DataFrame")(cols);
    pb::dict attrs = json_to_python(json());
    attrs.attr("pop")("faces");
    df.attr("attrs").attr("update")(attrs);
    return df;
  }

 private:
  RunReport report_;
  std::optional<nlohmann::json> json_;
};

// `extra`: the overrides after the scene's own (fidelity=, a sweep point's key): with them the
// scene is loaded again for its provenance (the resolved scene's hash), as the CLI reports it.
RunReport make_report(const Scene& scene, const DieModel& model, std::uint64_t seed, int threads, std::uint64_t tosses,
                      const RunCounts& counts, double elapsed_s, const std::vector<std::string>& extra) {
  RunReport r;
  std::vector<std::string> overrides = scene.overrides();
  overrides.insert(overrides.end(), extra.begin(), extra.end());
  r.provenance = make_provenance(scene.origin(), overrides, scene.sha256_with(extra), model, seed, tosses, threads);
  r.scene = scene.origin();
  r.fidelity = to_string(model.fidelity);
  r.seed = seed;
  r.threads = threads;
  r.tosses = tosses;
  r.counts = counts;
  set_labels(r, model);
  r.elapsed_s = elapsed_s;
  return r;
}

// run_tosses checks `cancel` between chunks of n/64 tosses (64 to 16384): up to seconds for the
// slow fidelities (a `stepped` toss takes milliseconds). Those run in consecutive blocks of 64
// chunks of 64 tosses, so Ctrl-C stops them within one chunk; the indices are the same, so are the
// counts. (A block's tail, when one thread still works, idles about half a chunk per block: under
// 1% by estimate; measured CPU time equals the CLI's.) `paper` and `static` chunks last
// milliseconds: one run_tosses call, as the CLI makes.
constexpr std::uint64_t kSlowBlock = 64 * 64;

// Progress goes to `monitor` as (base + tosses done, monitor.total): `base` places a sweep's point.
RunCounts run_cancellable(const DieModel& model, RunConfig cfg, RunMonitor& monitor, bool report, std::uint64_t base = 0) {
  const std::uint64_t first = cfg.first, n = cfg.tosses;
  cfg.cancel = &monitor.cancel;
  const bool slow = model.fidelity == Fidelity::Impulse || model.fidelity == Fidelity::Stepped;
  if (!slow) {
    // run_tosses' reporter thread costs up to 100 ms at the end of a run: only when asked for.
    if (report) cfg.progress = [&monitor, base](std::uint64_t d, std::uint64_t) { monitor.report(base + d, monitor.total); };
    return run_tosses(model, cfg);
  }
  RunCounts total;
  for (std::uint64_t done = 0; done < n && !monitor.cancel;) {
    cfg.first = first + done;
    cfg.tosses = std::min(kSlowBlock, n - done);
    total.merge(run_tosses(model, cfg));
    done += cfg.tosses;
    monitor.report(base + done, monitor.total);
  }
  return total;
}

// Runs of at most one chunk of run_tosses (64 tosses) go on one thread anyway: they run on the
// calling thread, without the GIL but also without the waiting loop (no thread to start: the
// calling overhead stays in microseconds), and cannot be interrupted.
constexpr std::uint64_t kInlineTosses = 64;

Result do_toss(const pb::object& scene_given, const pb::object& n_given, std::uint64_t seed, int threads,
               std::optional<std::string> fidelity, std::optional<double> target_halfwidth, const pb::object& progress) {
  const std::shared_ptr<Scene> held = scene_arg(scene_given);
  Scene& scene = *held;
  const std::optional<std::uint64_t> n = count_arg(n_given, "n");
  if (n && (*n < 1 || *n > (1ULL << 40))) throw pb::value_error("n must be in [1, 2^40], got " + std::to_string(*n));
  if (target_halfwidth && !(*target_halfwidth >= 1e-6 && *target_halfwidth <= 0.5))
    throw pb::value_error("target_halfwidth must be in [1e-6, 0.5], got " + std::to_string(*target_halfwidth));
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) throw pb::type_error("progress must be callable or None");
  const int nthreads = resolve_threads(threads);
  std::shared_ptr<const DieModel> model = scene.model(fidelity);
  FidelityPilot pilot;
  if (model->fidelity_requested == Fidelity::Auto) {  // auto: the pilot at this call's precision (as `dicesim toss`)
    auto resolved = std::make_shared<DieModel>(*model);
    pb::gil_scoped_release nogil;
    pilot = resolve_auto(*resolved, target_halfwidth ? precision_of_target(*resolved, *target_halfwidth)
                                             : precision_of_run(*resolved, n.value_or(100000)),
                 nthreads);
    model = std::move(resolved);
  }

  RunConfig cfg;
  cfg.seed = seed;
  cfg.threads = nthreads;
  // With a target and no n, n is only a generous cap (as the CLI without --tosses).
  const std::uint64_t tosses = n.value_or(target_halfwidth ? 1'000'000'000ULL : 100000ULL);
  cfg.tosses = tosses;
  RunCounts counts;
  std::uint64_t done = tosses;
  const auto t0 = Clock::now();
  if (!target_halfwidth && tosses <= kInlineTosses && progress.is_none()) {
    pb::gil_scoped_release nogil;
    counts = run_tosses(*model, cfg);
  } else {
    RunMonitor monitor;
    monitor.total = tosses;
    run_interruptible(
        [&] {
          if (target_halfwidth) {  // blocks of 10000 tosses: chunks of 156, prompt at any fidelity
            cfg.cancel = &monitor.cancel;
            if (!progress.is_none()) cfg.progress = [&monitor](std::uint64_t d, std::uint64_t t) { monitor.report(d, t); };
            counts = agg::run_to_target(*model, cfg, tosses, *target_halfwidth, done);
          } else {
            counts = run_cancellable(*model, cfg, monitor, !progress.is_none());
          }
        },
        monitor, progress);
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  RunReport rep = make_report(scene, *model, seed, nthreads, done, counts, elapsed, fidelity_override(fidelity));
  rep.provenance.tosses = tosses;  // asked for (with a target: the cap), as the CLI's
  rep.pilot = pilot;
  return Result(std::move(rep));
}

// A sweep: one Result per value, every point tossed with the same seed and indices 0..n-1.
struct Sweep {
  std::string title;  // sweep files only
  std::string key;
  std::vector<double> values;
  std::vector<std::string> point_labels;
  std::vector<std::vector<std::string>> overrides;  // each point's extra overrides
  std::vector<std::shared_ptr<Result>> points;
  double elapsed_s = 0.0;

  pb::object to_pandas() {
    pb::module_ pd = pb::module_::import("pandas");
    pb::list frames;
    for (std::size_t i = 0; i < points.size(); ++i) {
      pb::object df = points[i]->to_pandas();
      df.attr("insert")(0, "x", values[i]);
      df.attr("insert")(1, "settled", points[i]->report().counts.settled);
      frames.append(df);
    }
    pb::object out = pd.attr("concat")(frames, pb::arg("ignore_index") = true);
    out.attr("attrs")["key"] = key;
    return out;
  }
};

// Tosses every point (its extra overrides after the scene's own) with the same seed and indices.
// Every point is loaded and compiled before the first toss: a bad value fails at once.
Sweep run_points(Scene& scene, Sweep out, std::uint64_t n, std::uint64_t seed, int threads, const pb::object& progress) {
  if (n < 1 || n > (1ULL << 40)) throw pb::value_error("n must be in [1, 2^40], got " + std::to_string(n));
  if (out.values.empty()) throw pb::value_error("values is empty");
  const int nthreads = resolve_threads(threads);
  std::vector<DieModel> models;
  std::vector<FidelityPilot> pilots;
  for (const std::vector<std::string>& extra : out.overrides) {
    models.push_back(compile(scene.load_with(extra), scene.origin()));
    pilots.push_back(resolve_auto(models.back(), precision_of_run(models.back(), n), nthreads));  // auto: per point, as `dicesim sweep`
  }

  RunMonitor monitor;
  monitor.total = n * models.size();
  std::vector<RunCounts> counts(models.size());
  std::vector<double> elapsed(models.size());
  const auto t0 = Clock::now();
  run_interruptible(
      [&] {
        for (std::size_t i = 0; i < models.size() && !monitor.cancel; ++i) {
          const auto ti = Clock::now();
          RunConfig cfg;
          cfg.seed = seed;
          cfg.first = 0;  // the same indices at every point: common random numbers
          cfg.tosses = n;
          cfg.threads = nthreads;
          counts[i] = run_cancellable(models[i], cfg, monitor, !progress.is_none(), n * i);
          monitor.report(n * (i + 1), monitor.total);
          elapsed[i] = std::chrono::duration<double>(Clock::now() - ti).count();
        }
      },
      monitor, progress);
  out.elapsed_s = std::chrono::duration<double>(Clock::now() - t0).count();
  for (std::size_t i = 0; i < models.size(); ++i)
  {
    RunReport report = make_report(scene, models[i], seed, nthreads, n, counts[i], elapsed[i], out.overrides[i]);
    report.pilot = pilots[i];
    out.points.push_back(std::make_shared<Result>(std::move(report)));
  }
  return out;
}

Sweep do_sweep(const pb::object& scene_given, const std::string& key, const pb::object& values, const pb::object& n_given,
               std::uint64_t seed, int threads, std::optional<std::string> fidelity, const std::string& value_template,
               double scale, double shift, const pb::object& progress) {
  const std::shared_ptr<Scene> held = scene_arg(scene_given);
  Scene& scene = *held;
  const std::optional<std::uint64_t> counted = count_arg(n_given, "n");
  if (!counted) throw pb::type_error("n must be a whole number, got None");
  const std::uint64_t n = *counted;
  SweepParam param;
  param.key = key;
  param.value_template = value_template;
  param.scale = scale;
  param.shift = shift;
  if (pb::isinstance<pb::str>(values))
    param.values = parse_values(values.cast<std::string>(), "dicesim.sweep", "values");  // "0.1:0.9:0.1", "1/30:1:1/30"
  else
    for (const pb::handle v : values) param.values.push_back(v.cast<double>());
  Sweep out;
  out.key = key;
  out.values = param.values;
  for (double x : param.values) {
    std::vector<std::string> extra = fidelity_override(fidelity);
    extra.push_back(param.override_for(x));
    out.overrides.push_back(std::move(extra));
    out.point_labels.push_back(short_text(x));
  }
  return run_points(scene, std::move(out), n, seed, threads, progress);
}

// A sweep file (scenes/paper/sweeps/*.toml), as `dicesim sweep FILE` runs it.
Sweep do_sweep_file(const std::string& path, const pb::object& n_given, std::optional<std::uint64_t> seed,
                    int threads, std::optional<std::string> fidelity, const pb::object& progress) {
  const std::optional<std::uint64_t> n = count_arg(n_given, "n");
  const SweepSpec spec = load_sweep_file(path);
  std::shared_ptr<Scene> scene = Scene::from_path(spec.scene, spec.overrides);
  Sweep out;
  out.title = spec.title;
  out.key = spec.x_label;
  for (const SweepPoint& p : spec.points) {
    std::vector<std::string> extra = fidelity_override(fidelity);
    extra.insert(extra.end(), p.overrides.begin(), p.overrides.end());
    out.values.push_back(p.x);
    out.point_labels.push_back(p.label);
    out.overrides.push_back(std::move(extra));
  }
  return run_points(*scene, std::move(out), n.value_or(spec.tosses), seed.value_or(spec.seed), threads, progress);
}

}  // namespace

void register_toss(pb::module_& m) {
  pb::class_<Result, std::shared_ptr<Result>>(
      m, "Result",
      "The outcome of a run: counts per face with probabilities and 95% Wilson intervals over the\n"
      "settled tosses, faces in ascending label order. to_dict() is exactly `dicesim toss --json`.")
      .def_property_readonly(
          "labels", [](Result& r) { return r.face_column<std::int64_t>("face"); }, "Face labels, ascending (int64).")
      .def_property_readonly(
          "counts", [](Result& r) { return r.face_column<std::int64_t>("count"); }, "Settled tosses per face (int64).")
      .def_property_readonly(
          "p", [](Result& r) { return r.face_column<double>("p"); }, "P(face) over the settled tosses (float64).")
      .def_property_readonly("ci95", &Result::ci95, "95% Wilson interval per face, shape (faces, 2): lo, hi.")
      .def_property_readonly(
          "settled", [](const Result& r) { return r.report().counts.settled; }, "Tosses that ended with a face.")
      .def_property_readonly(
          "unresolved", [](const Result& r) { return r.report().counts.unresolved; },
          "Tosses that hit a bounce or time cap, or chattered: no answer, counted.")
      .def_property_readonly(
          "invalid", [](const Result& r) { return r.report().counts.invalid; },
          "Tosses whose drawn throw was impossible (started below the floor, non-finite).")
      .def_property_readonly(
          "corrections", [](Result& r) { return r.field("corrections"); },
          "Counts of the guards, clamps and fallbacks applied inside the tosses, as `toss --json`'s\n"
          "'corrections' object (None if this build's report has none).")
      .def_property_readonly(
          "chi2_uniform", [](Result& r) { return r.field("chi2_uniform"); },
          "Pearson chi-square against a fair die: {'statistic', 'dof', 'p_value'}.")
      .def_property_readonly(
          "chi2_heads_tails", [](Result& r) { return r.field("chi2_heads_tails"); },
          "A coin's heads against tails, edge landings left out (1 dof): {'statistic', 'dof', 'p_value'};\n"
          "None for a die.")
      .def_property_readonly(
          "elapsed_s", [](const Result& r) { return r.report().elapsed_s; }, "Wall-clock time of the run (s).")
      .def_property_readonly(
          "tosses", [](const Result& r) { return r.report().tosses; }, "Tosses made (with a target: where it stopped).")
      .def_property_readonly(
          "seed", [](const Result& r) { return r.report().seed; }, "The run's seed.")
      .def_property_readonly(
          "threads", [](const Result& r) { return r.report().threads; }, "Threads used.")
      .def_property_readonly(
          "fidelity", [](const Result& r) { return r.report().fidelity; }, "The physical model used.")
      .def_property_readonly(
          "scene", [](const Result& r) { return r.report().scene; }, "The scene as named in the report.")
      .def("to_dict", [](Result& r) { return json_to_python(r.json()); },
           "The run as a dict: exactly the object `dicesim toss --json` prints.")
      .def("to_pandas", &Result::to_pandas,
           "A pandas DataFrame, one row per face: face, count, p, lo, hi (95% interval); the run's other\n"
           "fields in DataFrame.attrs. Needs pandas.")
      .def("__str__", [](const Result& r) { return report_table(r.report()); }, "The table `dicesim toss` prints.")
      .def("__repr__", [](const Result& r) {
        const RunReport& rep = r.report();
        return "<dicesim.Result " + rep.scene + ": " + rep.fidelity + ", seed " + std::to_string(rep.seed) + ", " +
               std::to_string(rep.tosses) + " tosses, settled " + std::to_string(rep.counts.settled) + ", unresolved " +
               std::to_string(rep.counts.unresolved) + ", invalid " + std::to_string(rep.counts.invalid) + ">";
      });

  m.def("toss", &do_toss, pb::arg("scene"), pb::arg("n") = pb::none(), pb::arg("seed") = 1, pb::arg("threads") = 0,
        pb::arg("fidelity") = pb::none(), pb::arg("target_halfwidth") = pb::none(), pb::arg("progress") = pb::none(),
        "Tosses the die n times (default 100000) and returns the counts per face: `dicesim toss`.\n"
        "Toss i draws its throw from (seed, i) only, so the same scene, fidelity, seed and n give\n"
        "the same counts as the command line, on any number of threads.\n\n"
        "scene: a Scene, or a path (str or os.PathLike) loaded as load_scene(path). n: an int, or a\n"
        "float that is a whole number (1e5).\n"
        "threads: 0 = all cores. fidelity: 'static', 'paper', 'impulse', 'stepped' or 'auto' (None:\n"
        "the scene's; another name is a SceneError naming it and the choices). target_halfwidth=H: stop at the first block of 10000 tosses (in index order)\n"
        "where every face's 95% half-width is <= H; n is then the most it may take (default 1e9).\n"
        "progress: a callable progress(done, total), called about every 0.1 s from this thread.\n\n"
        "The GIL is released while tossing (other Python threads run, and tosses in several threads\n"
        "run in parallel); Ctrl-C raises KeyboardInterrupt within about 20 ms of the next chunk of\n"
        "tosses (runs of at most 64 tosses are not interruptible).");

  pb::class_<Sweep>(m, "Sweep",
                    "The results of a sweep: points[i] is the Result at values[i] (the same seed and toss\n"
                    "indices at every point: common random numbers).")
      .def_readonly("title", &Sweep::title, "The sweep file's title ('' for dicesim.sweep).")
      .def_readonly("key", &Sweep::key, "The scene key swept (a sweep file's x_label).")
      .def_readonly("point_labels", &Sweep::point_labels, "Each point's label (the value, or a sweep file's label).")
      .def_property_readonly(
          "values", [](const Sweep& s) { return pb::array_t<double>(static_cast<pb::ssize_t>(s.values.size()), s.values.data()); },
          "The x values (float64).")
      .def_readonly("points", &Sweep::points, "One Result per value.")
      .def_readonly("overrides", &Sweep::overrides, "Each point's overrides after the scene's own.")
      .def_readonly("elapsed_s", &Sweep::elapsed_s, "Wall-clock time of the whole sweep (s).")
      .def("__len__", [](const Sweep& s) { return s.points.size(); })
      .def("__getitem__",
           [](const Sweep& s, std::ptrdiff_t i) {
             const auto n = static_cast<std::ptrdiff_t>(s.points.size());
             if (i < 0) i += n;
             if (i < 0 || i >= n) throw pb::index_error("sweep point index out of range");
             return s.points[static_cast<std::size_t>(i)];
           })
      .def("to_pandas", &Sweep::to_pandas,
           "Long form, one row per (value, face): x, settled, face, count, p, lo, hi. Needs pandas.")
      .def("__repr__", [](const Sweep& s) {
        return "<dicesim.Sweep " + s.key + ": " + std::to_string(s.points.size()) + " points>";
      });

  m.def("sweep", &do_sweep, pb::arg("scene"), pb::arg("key"), pb::arg("values"), pb::arg("n"), pb::arg("seed") = 1,
        pb::arg("threads") = 0, pb::arg("fidelity") = pb::none(), pb::arg("template") = "{}", pb::arg("scale") = 1.0,
        pb::arg("shift") = 0.0, pb::arg("progress") = pb::none(),
        "P(face) of the scene at each value of one key: `dicesim sweep SCENE --param KEY --values ...`.\n"
        "Every point is the scene with one more override KEY=VALUE, where VALUE is `template` with\n"
        "'{}' replaced by scale * x + shift, tossed n times with the same seed and toss indices.\n"
        "values: a sequence of numbers, or the CLI's text '0.1:0.9:0.1' / '1,2,5' / '1/30:1:1/30'.\n"
        "Every point is compiled before the first toss (bad input fails at once). GIL, Ctrl-C and\n"
        "progress(done, total) as in toss().");

  m.def("sweep_file", &do_sweep_file, pb::arg("path"), pb::arg("n") = pb::none(), pb::arg("seed") = pb::none(),
        pb::arg("threads") = 0, pb::arg("fidelity") = pb::none(), pb::arg("progress") = pb::none(),
        "A sweep file (TOML with a [sweep] table, e.g. scenes/paper/sweeps/volume-ratio.toml), as\n"
        "`dicesim sweep FILE` runs it: its scene, overrides, points, tosses and seed (n and seed\n"
        "override the file's). Returns a Sweep; raises SceneError for a bad file.");
}

}  // namespace dicesim::py
