#include "sim/models/compile.hpp"
#include "sim/scene/scene_hash.hpp"
#include "sim/study/sweep.hpp"
#include "sim/study/auto_pilot.hpp"

#include "sim/body/outcome.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <toml++/toml.h>

#include "sim/body/die_model.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim {
namespace {

namespace fs = std::filesystem;
constexpr std::size_t kMaxValues = 100000;

std::string trim_space(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  const auto e = s.find_last_not_of(" \t\r\n");
  return b == std::string_view::npos ? "" : std::string(s.substr(b, e - b + 1));
}

// A finite number or a fraction p/q; nullopt otherwise.
std::optional<double> parse_number(std::string_view text) {
  const std::string t = trim_space(text);
  if (t.empty()) return std::nullopt;
  const auto slash = t.find('/');
  auto one = [](std::string_view s) -> std::optional<double> {
    const std::string u = trim_space(s);
    if (u.empty()) return std::nullopt;
    double v = 0.0;
    const char* b = u.data();
    if (*b == '+') ++b;
    const auto [p, ec] = std::from_chars(b, u.data() + u.size(), v);
    if (ec != std::errc() || p != u.data() + u.size() || !std::isfinite(v)) return std::nullopt;
    return v;
  };
  if (slash == std::string::npos) return one(t);
  const auto num = one(std::string_view(t).substr(0, slash));
  const auto den = one(std::string_view(t).substr(slash + 1));
  if (!num || !den || *den == 0.0) return std::nullopt;
  const double v = *num / *den;
  if (!std::isfinite(v)) return std::nullopt;
  return v;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in || fs::is_directory(path)) throw SceneError(path, "", "", "cannot open file");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Resolves `p` against the folder of `file` unless it is absolute.
std::string relative_to(const std::string& file, const std::string& p) {
  if (fs::path(p).is_absolute()) return p;
  return (fs::path(file).parent_path() / p).lexically_normal().string();
}

// A strict reader of one table of a sweep file: every key is checked, unknown keys are errors.
class Table {
 public:
  Table(const toml::table* t, std::string path, std::string file) : t_(t), path_(std::move(path)), file_(std::move(file)) {}

  std::string key_of(std::string_view k) const { return path_.empty() ? std::string(k) : path_ + "." + std::string(k); }
  [[noreturn]] void fail(std::string_view k, const std::string& value, const std::string& why) const {
    throw SceneError(file_, key_of(k), value, why);
  }
  const toml::node* get(std::string_view k) {
    seen_.push_back(std::string(k));
    return t_ ? t_->get(k) : nullptr;
  }
  std::optional<std::string> str(std::string_view k) {
    const toml::node* n = get(k);
    if (!n) return std::nullopt;
    if (!n->is_string()) fail(k, describe(*n), "must be a string");
    return n->as_string()->get();
  }
  std::optional<double> num(std::string_view k) {
    const toml::node* n = get(k);
    if (!n) return std::nullopt;
    if (n->is_integer()) return static_cast<double>(n->as_integer()->get());
    if (n->is_floating_point() && std::isfinite(n->as_floating_point()->get())) return n->as_floating_point()->get();
    fail(k, describe(*n), "must be a finite number");
  }
  std::optional<std::uint64_t> count(std::string_view k, std::uint64_t lo, std::uint64_t hi) {
    const toml::node* n = get(k);
    if (!n) return std::nullopt;
    if (!n->is_integer() || n->as_integer()->get() < static_cast<std::int64_t>(lo) ||
        static_cast<std::uint64_t>(n->as_integer()->get()) > hi)
      fail(k, describe(*n), "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return static_cast<std::uint64_t>(n->as_integer()->get());
  }
  std::vector<std::string> strings(std::string_view k) {
    const toml::node* n = get(k);
    std::vector<std::string> out;
    if (!n) return out;
    if (!n->is_array()) fail(k, describe(*n), "must be an array of strings \"KEY=VALUE\"");
    for (const auto& e : *n->as_array()) {
      if (!e.is_string()) fail(k, describe(*n), "must be an array of strings \"KEY=VALUE\"");
      out.push_back(e.as_string()->get());
    }
    return out;
  }
  void finish(const std::vector<std::string_view>& allowed) const {
    if (!t_) return;
    for (const auto& [k, v] : *t_) {
      if (std::find(allowed.begin(), allowed.end(), k.str()) != allowed.end()) continue;
      std::string list;
      for (auto a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      fail(k.str(), describe(v), "unknown key '" + std::string(k.str()) + "'" +
                                     (path_.empty() ? "" : " in [" + path_ + "]") + "; allowed: " + list);
    }
  }
  static std::string describe(const toml::node& n) {
    std::ostringstream os;
    n.visit([&](const auto& v) { os << v; });
    return os.str();
  }
  const std::string& file() const { return file_; }

 private:
  const toml::table* t_;
  std::string path_, file_;
  std::vector<std::string> seen_;
};

}  // namespace

std::string number_text(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  // TOML needs a digit before an exponent and accepts "1e-05"; "inf"/"nan" never reach here.
  return s;
}

static std::string short12(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.12g", v);
  return buf;
}

std::string short_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::vector<double> parse_values(const std::string& spec, const std::string& origin, const std::string& key) {
  const std::string form = "expected start:stop:step (e.g. 0.4:4.2:0.2) or a list a,b,c; numbers may be fractions p/q";
  auto bad = [&](const std::string& why) { return SceneError(origin, key, "'" + spec + "'", why); };
  const std::string s = trim_space(spec);
  if (s.empty()) throw bad("is empty: " + form);
  std::vector<double> out;
  if (s.find(':') != std::string::npos) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    for (std::size_t c; (c = s.find(':', start)) != std::string::npos; start = c + 1) parts.push_back(s.substr(start, c - start));
    parts.push_back(s.substr(start));
    if (parts.size() != 3) throw bad(form);
    std::array<double, 3> v{};
    for (int i = 0; i < 3; ++i) {
      const auto n = parse_number(parts[static_cast<std::size_t>(i)]);
      if (!n) throw bad("'" + trim_space(parts[static_cast<std::size_t>(i)]) + "' is not a finite number: " + form);
      v[static_cast<std::size_t>(i)] = *n;
    }
    const double a = v[0], b = v[1], step = v[2];
    if (step == 0.0) throw bad("step must not be 0");
    if ((b - a) / step < -1e-9) throw bad("step " + number_text(step) + " does not lead from " + number_text(a) + " to " + number_text(b));
    const double span = (b - a) / step;
    if (span > static_cast<double>(kMaxValues)) throw bad("more than " + std::to_string(kMaxValues) + " values");
    const auto n = static_cast<std::size_t>(std::floor(span + 1e-9)) + 1;
    for (std::size_t i = 0; i < n; ++i) {
      double x = a + static_cast<double>(i) * step;
      // The last value lands on stop up to rounding: use stop itself (1/30 * 30 is 1, not 1.0000000000000002).
      if (std::abs(x - b) <= 1e-9 * std::abs(step)) x = b;
      // 0.04 + 20 * 0.04 is 0.8400000000000001: when a 12-digit decimal lies within a few ulps,
      // that decimal is what was meant (19/30 has no such decimal and stays as computed).
      else if (const double r = std::strtod(short12(x).c_str(), nullptr); std::abs(r - x) <= 4e-16 * std::abs(x)) x = r;
      out.push_back(x);
    }
  } else {
    std::size_t start = 0;
    for (;;) {
      const std::size_t c = s.find(',', start);
      const std::string item = s.substr(start, c == std::string::npos ? std::string::npos : c - start);
      const auto n = parse_number(item);
      if (!n) throw bad("'" + trim_space(item) + "' is not a finite number: " + form);
      out.push_back(*n);
      if (out.size() > kMaxValues) throw bad("more than " + std::to_string(kMaxValues) + " values");
      if (c == std::string::npos) break;
      start = c + 1;
    }
  }
  return out;
}

std::string SweepParam::override_for(double x) const {
  double v = scale * x + shift;
  // 0.03 * (1/15) - 0.015 is -0.013999999999999999: write -0.014 when that is within a few ulps.
  if (const double r = std::strtod(short12(v).c_str(), nullptr); std::abs(r - v) <= 4e-16 * std::abs(v)) v = r;
  std::string value = value_template;
  const auto at = value.find("{}");
  if (at != std::string::npos) value.replace(at, 2, number_text(v));
  return key + "=" + value;
}

SweepSpec sweep_from_param(const std::string& scene, const SweepParam& param, const std::vector<std::string>& overrides) {
  if (param.key.empty()) throw SceneError("dicesim sweep", "--param", "", "a scene key is required, e.g. throw.height.mean");
  if (param.values.empty()) throw SceneError("dicesim sweep", "--values", "", "at least one value is required");
  if (param.value_template.find("{}") == std::string::npos)
    throw SceneError("dicesim sweep", "--template", "'" + param.value_template + "'", "must contain {} where the value goes");
  SweepSpec s;
  s.scene = scene;
  s.overrides = overrides;
  s.x_label = param.key;
  s.title = param.key;
  for (double x : param.values) s.points.push_back({x, short_text(x), {param.override_for(x)}});
  return s;
}

bool is_sweep_file(const std::string& path) {
  try {
    const toml::table t = toml::parse(read_file(path), std::string_view(path));
    return t.contains("sweep");
  } catch (...) {
    return false;
  }
}

SweepSpec load_sweep_file(const std::string& path) {
  toml::table root;
  try {
    root = toml::parse(read_file(path), std::string_view(path));
  } catch (const toml::parse_error& e) {
    throw SceneError(path, "", "", "TOML syntax error at line " + std::to_string(e.source().begin.line) + ": " +
                                       std::string(e.description()));
  }
  Table top(&root, "", path);
  const toml::node* sw = top.get("sweep");
  top.finish({"sweep"});
  if (!sw || !sw->is_table()) throw SceneError(path, "sweep", "", "a sweep file needs a [sweep] table");
  Table t(sw->as_table(), "sweep", path);

  SweepSpec s;
  s.source = path;
  const auto scene = t.str("scene");
  if (!scene || scene->empty()) t.fail("scene", "", "required: the base scene, a path relative to this file");
  s.scene = relative_to(path, *scene);
  if (!fs::is_regular_file(s.scene)) t.fail("scene", "\"" + *scene + "\"", "cannot open scene file '" + s.scene + "'");
  s.title = t.str("title").value_or(fs::path(path).stem().string());
  s.reproduces = t.str("reproduces").value_or("");
  s.reading = t.str("reading").value_or("");
  s.notes = t.str("notes").value_or("");
  s.x_label = t.str("x_label").value_or("");
  s.tosses = t.count("tosses", 1, 1ULL << 40).value_or(10000);
  s.seed = t.count("seed", 0, ~0ULL >> 1).value_or(1);
  s.overrides = t.strings("set");
  if (const auto st = t.str("seed_table")) {
    s.seed_table = relative_to(path, *st);
    if (!fs::is_regular_file(s.seed_table)) t.fail("seed_table", "\"" + *st + "\"", "cannot open '" + s.seed_table + "'");
  }
  s.seed_tosses = t.count("seed_tosses", 1, 1ULL << 40).value_or(0);
  if (const auto ref = t.num("reference")) {
    if (!(*ref > 0.0 && *ref < 1.0)) t.fail("reference", number_text(*ref), "must be a probability in (0, 1), e.g. 0.3333333333333333");
    s.reference = *ref;
  }

  const toml::node* param = t.get("param");
  const toml::node* points = t.get("points");
  t.finish({"title", "reproduces", "scene", "tosses", "seed", "set", "seed_table", "seed_tosses", "x_label", "reading",
            "notes", "reference", "param", "points"});
  if ((param != nullptr) == (points != nullptr))
    t.fail(param ? "points" : "param", "", "give exactly one of [sweep.param] (a key and values) or [[sweep.points]]");

  if (param) {
    if (!param->is_table()) t.fail("param", Table::describe(*param), "must be a table: key, values, template, scale, shift");
    Table p(param->as_table(), "sweep.param", path);
    SweepParam sp;
    const auto key = p.str("key");
    if (!key || key->empty()) p.fail("key", "", "required: the scene key to sweep, e.g. throw.height.mean");
    sp.key = *key;
    const toml::node* v = p.get("values");
    if (!v) p.fail("values", "", "required: \"start:stop:step\", \"a,b,c\" or an array of numbers");
    if (v->is_string()) {
      sp.values = parse_values(v->as_string()->get(), path, "sweep.param.values");
    } else if (v->is_array() && !v->as_array()->empty()) {
      for (const auto& e : *v->as_array()) {
        if (e.is_integer()) sp.values.push_back(static_cast<double>(e.as_integer()->get()));
        else if (e.is_floating_point() && std::isfinite(e.as_floating_point()->get())) sp.values.push_back(e.as_floating_point()->get());
        else p.fail("values", Table::describe(*v), "must be an array of finite numbers");
      }
    } else {
      p.fail("values", Table::describe(*v), "must be \"start:stop:step\", \"a,b,c\" or a non-empty array of numbers");
    }
    sp.value_template = p.str("template").value_or("{}");
    if (sp.value_template.find("{}") == std::string::npos)
      p.fail("template", "\"" + sp.value_template + "\"", "must contain {} where the value goes");
    sp.scale = p.num("scale").value_or(1.0);
    sp.shift = p.num("shift").value_or(0.0);
    p.finish({"key", "values", "template", "scale", "shift"});
    for (double x : sp.values) s.points.push_back({x, short_text(x), {sp.override_for(x)}});
    if (s.x_label.empty()) s.x_label = sp.key;
  } else {
    if (!points->is_array_of_tables() || points->as_array()->empty())
      t.fail("points", "", "must be an array of tables [[sweep.points]] with x, label and set");
    std::size_t i = 0;
    for (const auto& e : *points->as_array()) {
      Table p(e.as_table(), "sweep.points[" + std::to_string(i++) + "]", path);
      const auto x = p.num("x");
      if (!x) p.fail("x", "", "required: the point's position on the x axis");
      SweepPoint pt;
      pt.x = *x;
      pt.label = p.str("label").value_or(short_text(*x));
      pt.overrides = p.strings("set");
      p.finish({"x", "label", "set"});
      s.points.push_back(std::move(pt));
    }
    s.categorical = true;
  }
  return s;
}

SweepResult run_sweep(const SweepSpec& spec, const SweepRunOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  // Every point is loaded and compiled before the first toss: a bad value fails at once.
  std::vector<DieModel> models;
  std::vector<FidelityPilot> pilots;
  std::vector<std::vector<std::string>> overrides;
  std::vector<std::string> hashes;
  models.reserve(spec.points.size());
  for (const SweepPoint& p : spec.points) {
    std::vector<std::string> all = spec.overrides;
    all.insert(all.end(), p.overrides.begin(), p.overrides.end());
    // A point that fails says which point: its key and value may differ from the one that broke.
    const std::string where = "sweep point " + spec.x_label + " = " + p.label;
    try {
      models.push_back(compile(load_scene(spec.scene, all), spec.scene));
      hashes.push_back(scene_sha256(spec.scene, all));
    } catch (const SceneError& e) {
      throw SceneError(e.file(), e.key(), e.value(), e.allowed() + " (at " + where + ")");
    } catch (const std::exception& e) {
      throw std::runtime_error(where + ": " + e.what());
    }
    // auto: each point's own pilot at the sweep's tosses per point (a point's scene is its own);
    // the choice is passed on as an override, so that workers of a distributed sweep toss it too.
    pilots.push_back(resolve_auto(models.back(), precision_of_run(models.back(), spec.tosses), opt.threads));
    if (models.back().fidelity_requested == Fidelity::Auto)
      all.push_back(std::string("sim.fidelity=\"") + to_string(models.back().fidelity) + "\"");
    // One table: the same outcomes at every point (a sweep of die.sides is a sweep per die).
    const std::vector<int>& labels = models.back().outcome_labels;
    auto text = [](const std::vector<int>& v) {
      std::string s;
      for (std::size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + std::to_string(v[i]);
      return s;
    };
    if (labels != models.front().outcome_labels)
      throw SceneError(spec.source.empty() ? spec.scene : spec.source, "point " + spec.x_label + " = " + p.label, text(labels),
                       "every point of a sweep must have the same outcome labels as the first (" +
                           text(models.front().outcome_labels) + ")");
    if (!spec.seed_table.empty() && labels != std::vector<int>{1, 2, 3, 4, 5, 6})
      throw SceneError(spec.source.empty() ? spec.scene : spec.source, "seed_table", spec.seed_table,
                       "compares P1..P6: the die must have six outcomes labelled 1..6 (this one: " + text(labels) + ")");
    overrides.push_back(std::move(all));
  }
  SweepResult out;
  const std::uint64_t total = spec.tosses * spec.points.size();
  for (std::size_t i = 0; i < models.size(); ++i) {
    if (opt.cancel && opt.cancel->load()) break;
    RunConfig cfg;
    cfg.seed = spec.seed;
    cfg.first = 0;  // the same indices at every point: common random numbers
    cfg.tosses = spec.tosses;
    cfg.threads = opt.threads;
    cfg.cancel = opt.cancel;
    const std::uint64_t before = spec.tosses * i;
    SweepPointResult r;
    r.point = spec.points[i];
    if (opt.run_point) {
      r.counts = opt.run_point(models[i], overrides[i], cfg, [&opt, before, total](std::uint64_t done) {
        if (opt.progress) opt.progress(before + done, total);
      });
    } else {
      // run_tosses' progress reporter wakes every ~100 ms and is joined at the end of the run, which
      // would add up to 0.1 s per point: only long points report from inside, the others per point.
      constexpr std::uint64_t kLongPoint = 200000;
      if (opt.progress && spec.tosses >= kLongPoint)
        cfg.progress = [&opt, before, total](std::uint64_t done, std::uint64_t) { opt.progress(before + done, total); };
      r.counts = run_tosses(models[i], cfg);
    }
    const bool cancelled = opt.cancel && opt.cancel->load();
    // A cancelled point is kept when its counts are a complete prefix (run_tosses in this process)
    // and not empty; a distributed point's partial counts are not a prefix: dropped.
    const bool complete = r.counts.total() >= spec.tosses;
    if (cancelled && !complete && (opt.run_point || r.counts.total() == 0)) break;
    r.partial = !complete;
    r.labels = models[i].outcome_labels;
    r.fidelity = to_string(models[i].fidelity);
    r.fidelity_reason = models[i].fidelity_reason;
    r.scene_sha256 = hashes[i];
    r.pilot = pilots[i];
    out.points.push_back(std::move(r));
    if (cancelled) break;
    if (opt.progress) opt.progress(before + spec.tosses, total);
  }
  out.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

std::vector<FaceEstimate> face_estimates(const RunCounts& counts, const std::vector<int>& labels) {
  std::vector<FaceEstimate> f(labels.size());
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const std::uint64_t c = i < counts.faces.size() ? counts.faces[i] : 0;
    f[i].label = labels[i];
    f[i].count = c;
    f[i].p = counts.settled ? static_cast<double>(c) / static_cast<double>(counts.settled) : 0.0;
    f[i].ci95 = wilson_interval(c, counts.settled);
  }
  std::sort(f.begin(), f.end(), [](const FaceEstimate& a, const FaceEstimate& b) { return a.label < b.label; });
  return f;
}

std::vector<ReferenceRow> load_reference_table(const std::string& path) {
  std::istringstream in(read_file(path));
  std::vector<ReferenceRow> rows;
  std::string line;
  bool header = false;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim_space(line);
    if (t.empty() || t[0] == '#') continue;
    if (!header) {
      header = true;
      continue;
    }
    std::vector<std::string> cells;
    std::size_t start = 0;
    for (std::size_t c; (c = t.find(',', start)) != std::string::npos; start = c + 1) cells.push_back(t.substr(start, c - start));
    cells.push_back(t.substr(start));
    if (cells.size() < 7)
      throw SceneError(path, "line " + std::to_string(line_no), "'" + t + "'", "expected x,P1,P2,P3,P4,P5,P6");
    ReferenceRow r;
    for (std::size_t k = 0; k < 7; ++k) {
      const auto v = parse_number(cells[k]);
      if (!v) throw SceneError(path, "line " + std::to_string(line_no), "'" + cells[k] + "'", "not a finite number");
      if (k == 0) r.x = *v;
      else r.p[k - 1] = *v;
    }
    rows.push_back(r);
  }
  return rows;
}

std::optional<ReferenceRow> find_reference(const std::vector<ReferenceRow>& rows, double x) {
  for (const ReferenceRow& r : rows)
    if (std::abs(r.x - x) <= 1e-4 * std::max(1.0, std::abs(x))) return r;
  return std::nullopt;
}

}  // namespace dicesim
