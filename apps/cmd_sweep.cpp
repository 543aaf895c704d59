// dicesim sweep: P(face) against one scene key, with common random numbers, as a table, CSV,
// JSON, a gnuplot picture with 95% bands, and (for sweep files that name a seed table) a
// Markdown table beside the seed's numbers.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "apps/commands.hpp"
#include "apps/fidelity_name.hpp"
#include "apps/gnuplot.hpp"
#include "apps/interrupt.hpp"
#include "apps/output_path.hpp"
#include "apps/provenance.hpp"
#include "apps/progress.hpp"
#include "apps/report.hpp"
#include "apps/sweep_workers.hpp"
#include "messages/wire.hpp"
#include "sim/body/outcome.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/key_unit.hpp"
#include "sim/study/compare.hpp"
#include "sim/study/shard.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/scene/scene_hash.hpp"
#include "sim/study/sweep.hpp"

namespace dicesim {
namespace {

namespace fs = std::filesystem;

struct SweepArgs {
  std::string input;  // a scene or a sweep file
  std::string param, values, value_template = "{}";
  double scale = 1.0, shift = 0.0;
  std::vector<std::string> overrides;
  std::string fidelity;      // non-empty: sim.fidelity at every point (as toss --fidelity)
  std::uint64_t tosses = 0;  // 0: the file's (or 10 000)
  std::uint64_t seed = 0;    // 0 given explicitly is a valid seed: track with the option
  CLI::Option* seed_opt = nullptr;
  CLI::Option* scale_opt = nullptr;
  CLI::Option* shift_opt = nullptr;
  CLI::Option* template_opt = nullptr;
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  int workers = 0;           // > 0: each point is a distributed run with this many local worker processes
  std::string lcm;           // the bus for distributed points (default: a private host-confined URL)
  bool json = false;
  std::string csv, plot, markdown;
  std::string points;        // --points I/N: shard I of N of the points
  bool distributed() const { return workers > 0 || !lcm.empty(); }
};

// A point compared with the seed's row at the same x.
struct SeedMatch {
  bool found = false;
  std::array<double, 6> p{};
  ChiSquare chi2;
};

SeedMatch match_seed(const SweepSpec& spec, const std::vector<ReferenceRow>& rows, const SweepPointResult& r) {
  SeedMatch m;
  const auto row = find_reference(rows, r.point.x);
  if (!row) return m;
  m.found = true;
  m.p = row->p;
  if (spec.seed_tosses > 0) {
    const auto est = face_estimates(r.counts, r.labels);
    std::vector<std::uint64_t> ours, theirs;
    for (std::size_t f = 0; f < est.size() && f < 6; ++f) {  // run_sweep checked: labels 1..6
      ours.push_back(est[f].count);
      theirs.push_back(static_cast<std::uint64_t>(std::llround(row->p[f] * static_cast<double>(spec.seed_tosses))));
    }
    m.chi2 = chi2_homogeneity(ours, theirs);
  }
  return m;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

bool has_categories(const SweepSpec& spec) { return spec.categorical; }

// What the plot needs beyond the counts: the x axis's label (with the key's unit), each outcome's
// name for the legend, and the question's reference probability (0: none).
struct PlotLabels {
  std::string x_label;
  std::vector<std::string> names;  // per outcome, label order
  double reference = 0.0;
  std::string reference_text;
};

// Outcomes alike by design: a regular solid (the d4-d20 presets, or a box of three equal edges) of
// one material (no regions), each face its own outcome. Only for such a die is 1/N the answer a
// fair die would give, so only then is it drawn; a coin's reference comes from its sweep file.
bool alike_by_design(const SceneDef& def, std::size_t outcomes, int faces) {
  const DieDef& d = def.die;
  const bool regular = d.shape == ShapeKind::D4 || d.shape == ShapeKind::D6 || d.shape == ShapeKind::D8 ||
                       d.shape == ShapeKind::D10 || d.shape == ShapeKind::D12 || d.shape == ShapeKind::D20 ||
                       (d.shape == ShapeKind::Box && d.size.x() == d.size.y() && d.size.y() == d.size.z());
  return regular && d.regions.empty() && static_cast<int>(outcomes) == faces;
}

// 1/3 rather than 0.333333 when the value is a simple fraction (denominators up to 20).
std::string fraction_text(double v) {
  for (int den = 1; den <= 20; ++den) {
    const double num = v * den;
    if (num >= 1.0 && std::abs(num - std::round(num)) < 1e-9 * den)
      return den == 1 ? short_text(v) : std::to_string(std::lround(num)) + "/" + std::to_string(den);
  }
  return short_text(v);
}

// The first point's die: the outcomes' labels and names are every point's (run_sweep checks).
DieModel first_point_model(const SweepSpec& spec, SceneDef* def = nullptr) {
  std::vector<std::string> all = spec.overrides;
  all.insert(all.end(), spec.points[0].overrides.begin(), spec.points[0].overrides.end());
  SceneDef d = load_scene(spec.scene, all);
  DieModel m = compile(d, spec.scene);
  if (def) *def = std::move(d);
  return m;
}

PlotLabels plot_labels(const SweepSpec& spec, const SweepArgs& a, bool file_mode) {
  PlotLabels pl;
  pl.x_label = spec.x_label;
  // A bare key (the CLI's --param) gets its unit from the scene schema; a sweep file's x_label is
  // its author's (with the unit of its own x, which scale and shift may have changed).
  if (!file_mode) {
    const std::string unit = key_unit(a.param);
    const bool plain = a.scale == 1.0 && a.shift == 0.0;
    if (!plain)
      pl.x_label = "x, where " + a.param + " = " + number_text(a.scale) + " x + " + number_text(a.shift) +
                   (unit.empty() ? "" : " (" + unit + ")");
    else if (!unit.empty())
      pl.x_label += " (" + unit + ")";
  }
  if (spec.points.empty()) return pl;
  SceneDef def;
  const DieModel m = first_point_model(spec, &def);
  pl.names = outcome_names(m);
  if (pl.names.empty())
    for (int l : m.outcome_labels) pl.names.push_back("face " + std::to_string(l));
  if (spec.reference > 0.0) {
    pl.reference = spec.reference;
    pl.reference_text = "reference " + fraction_text(spec.reference);
  } else if (alike_by_design(def, m.outcome_labels.size(), m.face_count())) {
    pl.reference = 1.0 / static_cast<double>(m.outcome_labels.size());
    pl.reference_text = "1/" + std::to_string(m.outcome_labels.size()) + " (alike by design)";
  }
  return pl;
}

// P(outcome) against x, one colour per outcome (label order; ten colours, then again with another
// point type), the 95% Wilson band shaded, the seed's values (if any) as open circles of the same
// colour, the question's reference line, and the share of tosses without an answer (unresolved +
// invalid, of all tosses) when there are any. y stays within [0, 1]; the legend outside the data.
void write_plot(const std::string& path, const SweepSpec& spec, const SweepResult& res,
                const std::vector<ReferenceRow>& seed_rows, const PlotLabels& pl) {
  std::ostringstream gp;
  gp << gnuplot_terminal(path);
  std::string title = spec.title;
  if (!spec.reproduces.empty()) title += " (seed: " + spec.reproduces + ")";
  std::uint64_t lost = 0;
  for (const SweepPointResult& r : res.points) lost += r.counts.unresolved + r.counts.invalid;
  const std::string fidelity = res.points.empty() ? "" : res.points[0].fidelity;
  // Three lines, centred on the picture, not on the plot (which the legend narrows: a title centred
  // there ran past the picture's left edge and was clipped).
  gp << "set tmargin 5\nset label 1 "
     << gnuplot_quote(title + "\n" + spec.scene + ", fidelity " + fidelity + ", " + std::to_string(spec.tosses) +
                      " tosses per point (seed " + std::to_string(spec.seed) + ", the same at every point)\nbands: 95% Wilson" +
                      (lost == 0 ? "; every toss settled" : "; unresolved + invalid: their share of all tosses"))
     << " at screen 0.5, screen 0.97 center front noenhanced\n";
  gp << "set xlabel " << gnuplot_quote(pl.x_label) << " noenhanced\n";
  double ymax = pl.reference;
  for (const SweepPointResult& r : res.points) {
    for (const FaceEstimate& f : face_estimates(r.counts, r.labels)) ymax = std::max(ymax, f.ci95.hi);
    if (r.counts.total() > 0)
      ymax = std::max(ymax, static_cast<double>(r.counts.unresolved + r.counts.invalid) / static_cast<double>(r.counts.total()));
  }
  // The seed's values too: its sec. 5.4 peak (0.26) was cut off by a range fitted to ours alone.
  for (const SweepPointResult& r : res.points)
    if (const auto row = find_reference(seed_rows, r.point.x))
      for (double p : row->p) ymax = std::max(ymax, p);
  ymax = std::min(1.0, 1.08 * ymax + 0.01);
  gp << "set yrange [0:" << number_text(ymax) << "]\nset offsets 0, 0, 0, 0\n";
  gp << "set ylabel 'P(outcome), of the settled tosses' noenhanced\nset grid\n"
        // Each name left-aligned right of its line's sample: right-aligned names stood far from short ones.
        "set key outside right top vertical Left reverse box opaque noenhanced\n"
        "set border 3\nset tics nomirror\n";
  const auto labels = res.points.empty() ? std::vector<FaceEstimate>{} : face_estimates(res.points[0].counts, res.points[0].labels);
  const int n = static_cast<int>(labels.size());
  const char* colours[10] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                             "#17becf", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22"};
  const int point_types[4] = {7, 5, 9, 13};
  for (int f = 0; f < n; ++f)
    gp << "set linetype " << f + 1 << " lc rgb '" << colours[f % 10] << "' lw 2 pt " << point_types[(f / 10) % 4]
       << " ps 0.6\n";
  if (n > 12) gp << "set key font ',8' spacing 0.8\n";
  if (has_categories(spec)) {
    gp << "set xtics (";
    for (std::size_t i = 0; i < spec.points.size(); ++i)
      gp << (i ? ", " : "") << gnuplot_quote(spec.points[i].label) << " " << number_text(spec.points[i].x);
    gp << ")\n";
    const auto [mn, mx] = std::minmax_element(spec.points.begin(), spec.points.end(),
                                              [](const SweepPoint& a, const SweepPoint& b) { return a.x < b.x; });
    gp << "set xrange [" << number_text(mn->x - 0.5) << ":" << number_text(mx->x + 0.5) << "]\n";
  }
  // Columns: x, then p lo hi per outcome, then the share without an answer.
  gp << "$d << EOD\n";
  for (const SweepPointResult& r : res.points) {
    gp << number_text(r.point.x);
    for (const FaceEstimate& f : face_estimates(r.counts, r.labels))
      gp << " " << number_text(f.p) << " " << number_text(f.ci95.lo) << " " << number_text(f.ci95.hi);
    const double total = static_cast<double>(std::max<std::uint64_t>(1, r.counts.total()));
    gp << " " << number_text(static_cast<double>(r.counts.unresolved + r.counts.invalid) / total) << "\n";
  }
  gp << "EOD\n";
  bool any_seed = false;
  gp << "$s << EOD\n";
  for (const SweepPointResult& r : res.points)
    if (const auto row = find_reference(seed_rows, r.point.x)) {
      any_seed = true;
      gp << number_text(r.point.x);
      for (double p : row->p) gp << " " << number_text(p);
      gp << "\n";
    }
  gp << "EOD\n";
  gp << "plot ";
  for (int f = 1; f <= n; ++f)
    gp << "$d using 1:" << 3 * f << ":" << 3 * f + 1 << " with filledcurves lt " << f
       << " fs transparent solid 0.18 noborder notitle, ";
  for (int f = 1; f <= n; ++f) {
    const std::size_t i = static_cast<std::size_t>(f - 1);
    gp << "$d using 1:" << 3 * f - 1 << " with linespoints lt " << f << " title "
       << gnuplot_quote(i < pl.names.size() ? pl.names[i] : "face " + std::to_string(labels[i].label));
    if (f < n) gp << ", ";
  }
  if (pl.reference > 0.0)
    gp << ", " << number_text(pl.reference) << " with lines dt 2 lw 1.5 lc rgb 'black' title " << gnuplot_quote(pl.reference_text);
  if (lost > 0)
    gp << ", $d using 1:" << 3 * n + 2 << " with linespoints dt 3 lw 1.5 pt 2 ps 0.6 lc rgb '#555555' title "
       << gnuplot_quote("unresolved + invalid");
  if (any_seed) {
    gp << ", ";
    for (int f = 1; f <= 6; ++f) gp << "$s using 1:" << f + 1 << " with points lt " << f << " pt 6 ps 1.1 notitle, ";
    gp << "NaN with points pt 6 ps 1.1 lc rgb 'black' title 'seed'";
  }
  gp << "\n";
  run_gnuplot(gp.str(), path);
}

std::string csv_text(const SweepResult& res, const Provenance& prov) {
  std::string out = provenance_csv_comment(prov) + "param,face,count,p,lo,hi\n";
  for (const SweepPointResult& r : res.points)
    for (const FaceEstimate& f : face_estimates(r.counts, r.labels))
      out += number_text(r.point.x) + "," + std::to_string(f.label) + "," + std::to_string(f.count) + "," +
             fmt("%.6f", f.p) + "," + fmt("%.6f", f.ci95.lo) + "," + fmt("%.6f", f.ci95.hi) + "\n";
  return out;
}

// The sweep's provenance: the base scene (every point's overrides but the swept key's) and its hash;
// the fidelity and why of the first point (each point also carries its own scene hash).
Provenance sweep_provenance(const SweepSpec& spec, const SweepResult& res, int threads) {
  Provenance p;
  p.scene = spec.scene;
  p.scene_sha256 = scene_sha256(spec.scene, spec.overrides);
  p.overrides = spec.overrides;
  if (!res.points.empty()) {
    p.fidelity = res.points[0].fidelity;
    p.fidelity_reason = res.points[0].fidelity_reason;
  }
  p.seed = spec.seed;
  p.tosses = spec.tosses;
  p.threads = threads;
  return p;
}

bool sweep_partial(const SweepSpec& spec, const SweepResult& res) {
  return res.points.size() < spec.points.size() || (!res.points.empty() && res.points.back().partial);
}

nlohmann::json json_report(const SweepSpec& spec, const SweepResult& res, const std::vector<ReferenceRow>& seed_rows,
                           int threads, int workers, const Provenance& prov) {
  nlohmann::json points = nlohmann::json::array();
  int compared = 0, rejected = 0;
  std::uint64_t tosses = 0;
  for (const SweepPointResult& r : res.points) {
    nlohmann::json faces = nlohmann::json::array();
    for (const FaceEstimate& f : face_estimates(r.counts, r.labels))
      faces.push_back({{"face", f.label}, {"count", f.count}, {"p", f.p}, {"ci95", {f.ci95.lo, f.ci95.hi}}});
    nlohmann::json p = {{"x", r.point.x},
                        {"label", r.point.label},
                        {"set", r.point.overrides},
                        {"settled", r.counts.settled},
                        {"unresolved", r.counts.unresolved},
                        {"invalid", r.counts.invalid},
                        {"corrections", corrections_json(r.counts.corrections)},
                        {"fidelity", r.fidelity},  // auto: each point's own pilot (its reason and numbers)
                        {"fidelity_reason", r.fidelity_reason},
                        {"pilot", pilot_json(r.pilot)},
                        {"faces", faces},
                        {"scene_sha256", r.scene_sha256}};
    if (r.partial) {
      p["partial"] = true;
      p["tosses"] = r.counts.total();
    }
    const SeedMatch m = match_seed(spec, seed_rows, r);
    if (m.found) {
      p["seed"] = {{"p", m.p}};
      if (spec.seed_tosses > 0) {
        p["seed"]["chi2"] = chi2_json(m.chi2);
        ++compared;
        if (m.chi2.p_value < 0.01) ++rejected;
      }
    }
    tosses += r.counts.total();
    points.push_back(p);
  }
  nlohmann::json j = {{"title", spec.title},
                      {"scene", spec.scene},
                      {"sweep_file", spec.source},
                      {"param", spec.x_label},
                      {"set", spec.overrides},
                      {"fidelity", res.points.empty() ? "" : res.points[0].fidelity},
                      {"seed", spec.seed},
                      {"tosses", spec.tosses},
                      {"threads", threads},
                      {"workers", workers},
                      {"points", points},
                      {"partial", sweep_partial(spec, res)},
                      {"points_requested", spec.points.size()},
                      {"elapsed_s", res.elapsed_s},
                      {"tosses_per_s", res.elapsed_s > 0 ? static_cast<double>(tosses) / res.elapsed_s : 0.0}};
  j["provenance"] = provenance_json(prov);
  if (!spec.seed_table.empty())
    j["seed_comparison"] = {{"table", spec.seed_table},
                            {"reproduces", spec.reproduces},
                            {"seed_tosses", spec.seed_tosses},
                            {"points_compared", compared},
                            {"rejected_at_1pct", rejected}};
  return j;
}

// names: a coin's side per outcome (P(edge), not P(0)); empty for a die (P(1)..).
std::string table_text(const SweepSpec& spec, const SweepResult& res, int threads, int workers, const Provenance& prov,
                       const std::vector<std::string>& names) {
  std::ostringstream out;
  out << spec.title << "  (" << spec.scene << ", fidelity " << (res.points.empty() ? "" : res.points[0].fidelity)
      << ", seed " << spec.seed << ", " << spec.tosses << " tosses per point, ";
  if (workers > 0) out << workers << " worker process" << (workers == 1 ? "" : "es") << ")\n";
  else out << threads << " thread" << (threads == 1 ? "" : "s") << ")\n";
  out << provenance_lines(prov);
  if (sweep_partial(spec, res)) {
    std::size_t whole = res.points.size();
    if (whole > 0 && res.points.back().partial) --whole;
    out << "interrupted after " << whole << " of " << spec.points.size() << " points";
    if (whole < res.points.size())
      out << " (point " << res.points.back().point.label << ": the first " << res.points.back().counts.total() << " of "
          << spec.tosses << " tosses)";
    }
  if (!res.points.empty() && res.points[0].fidelity_reason.rfind("auto", 0) == 0) {
    // auto: each point's pilot chose its model (--json: each point's reason and pilot).
    out << "auto, each point's pilot at " << spec.tosses << " tosses:";
    for (const SweepPointResult& r : res.points) out << " " << r.point.label << " " << r.fidelity << ";";
    out << "\n";
  }
  out << "\n";
  const auto first = res.points.empty() ? std::vector<FaceEstimate>{} : face_estimates(res.points[0].counts, res.points[0].labels);
  char line[512];
  std::snprintf(line, sizeof line, "%-14s", spec.x_label.size() <= 14 ? spec.x_label.c_str() : "x");
  out << line;
  std::vector<int> widths;
  for (std::size_t i = 0; i < first.size(); ++i) {
    const std::string head = "P(" + (i < names.size() ? names[i] : std::to_string(first[i].label)) + ")";
    widths.push_back(std::max<int>(7, static_cast<int>(head.size())));
    std::snprintf(line, sizeof line, "  %*s", widths.back(), head.c_str());
    out << line;
  }
  out << "   unresolved  invalid\n";
  double worst = 0.0;
  for (const SweepPointResult& r : res.points) {
    std::snprintf(line, sizeof line, "%-14s", r.point.label.c_str());
    out << line;
    const auto est = face_estimates(r.counts, r.labels);
    for (std::size_t i = 0; i < est.size(); ++i) {
      std::snprintf(line, sizeof line, "  %*.4f", i < widths.size() ? widths[i] : 7, est[i].p);
      out << line;
      worst = std::max(worst, est[i].ci95.half_width());
    }
    std::snprintf(line, sizeof line, "   %10llu  %7llu\n", static_cast<unsigned long long>(r.counts.unresolved),
                  static_cast<unsigned long long>(r.counts.invalid));
    out << line;
  }
  RunCorrections all;
  for (const SweepPointResult& r : res.points) {
    all.add(r.counts.corrections);
    if (r.counts.corrections.any()) out << "point " << r.point.label << ": " << corrections_line(r.counts.corrections);
  }
  if (all.any()) out << "whole sweep: " << corrections_line(all);
  out << "\np over settled tosses; widest 95% Wilson half-width " << fmt("%.4f", worst) << "; "
      << fmt("%.2f", res.elapsed_s) << " s\n";
  return out.str();
}

// Our table beside the seed's: each cell "ours (seed)", the last column the chi-square test of
// homogeneity of the two runs' counts (the seed's counts taken as p x its tosses per point).
std::string markdown_text(const SweepSpec& spec, const SweepResult& res, const std::vector<ReferenceRow>& seed_rows) {
  std::ostringstream md;
  const bool have_seed = !seed_rows.empty();  // run_sweep checked: then the labels are 1..6
  const std::vector<int> labels = res.points.empty() ? std::vector<int>{} : res.points[0].labels;
  const std::size_t n = labels.size();
  md << "| " << spec.x_label << " |";
  for (int l : labels) md << " P(" << l << ") |";
  if (have_seed && spec.seed_tosses > 0) md << " χ² p vs seed |";
  md << "\n|---|";
  for (std::size_t f = 0; f < n; ++f) md << "---|";
  if (have_seed && spec.seed_tosses > 0) md << "---|";
  md << "\n";
  int compared = 0, rejected = 0;
  std::vector<double> sum_ours(n, 0.0), sum_seed(n, 0.0);
  int n_seed = 0;
  double worst = 0.0;
  for (const SweepPointResult& r : res.points) {
    const SeedMatch m = match_seed(spec, seed_rows, r);
    md << "| " << r.point.label << " |";
    const auto est = face_estimates(r.counts, r.labels);
    for (std::size_t f = 0; f < n && f < est.size(); ++f) {
      const bool seed_has = m.found && f < m.p.size();
      md << " " << fmt("%.4f", est[f].p);
      if (seed_has) md << " (" << fmt("%.4f", m.p[f]) << ")";
      md << " |";
      worst = std::max(worst, est[f].ci95.half_width());
      if (seed_has) {
        sum_ours[f] += est[f].p;
        sum_seed[f] += m.p[f];
      }
    }
    if (m.found) ++n_seed;
    if (have_seed && spec.seed_tosses > 0) {
      if (m.found) {
        ++compared;
        const bool rej = m.chi2.p_value < 0.01;
        rejected += rej;
        md << " " << (m.chi2.p_value < 1e-4 ? std::string("<1e-4") : fmt("%.3g", m.chi2.p_value)) << (rej ? " ✗" : "") << " |";
      } else {
        md << " – |";
      }
    }
    md << "\n";
  }
  md << "\nOurs first, the seed's in parentheses; " << spec.tosses << " tosses per point (seed " << spec.seed
     << ", the same toss indices at every point); widest 95% Wilson half-width " << fmt("%.4f", worst) << ".";
  if (n_seed > 0) {
    md << " Mean over the " << n_seed << " matched points, ours (seed):";
    for (std::size_t f = 0; f < n; ++f)
      md << " P(" << labels[f] << ") " << fmt("%.4f", sum_ours[f] / n_seed) << " (" << fmt("%.4f", sum_seed[f] / n_seed) << ")"
         << (f + 1 < n ? "," : ".");
  }
  if (compared > 0)
    md << " χ² homogeneity (" << n - 1 << " dof; the seed's counts taken as p × " << spec.seed_tosses << "): " << rejected << " of "
       << compared << " points differ at the 1% level (✗).";
  md << "\n";
  return md.str();
}

int run_sweep_cmd(SweepArgs a) {
  if (!fs::is_regular_file(a.input)) throw SceneError(a.input, "", "", "cannot open file");
  check_fidelity_name(a.fidelity);
  if (!a.fidelity.empty()) a.overrides.push_back("sim.fidelity=\"" + a.fidelity + "\"");
  if (a.json && a.csv == "-") throw SceneError("dicesim sweep", "--csv", "-", "stdout carries the --json object; write the CSV to a file");
  const bool file_mode = is_sweep_file(a.input);
  SweepSpec spec;
  if (file_mode) {
    if (!a.param.empty() || !a.values.empty() || a.template_opt->count() || a.scale_opt->count() || a.shift_opt->count())
      throw SceneError(a.input, "--param/--values", "",
                       "a sweep file names its own parameter; give either a sweep file or SCENE --param KEY --values SPEC");
    spec = load_sweep_file(a.input);
    spec.overrides.insert(spec.overrides.end(), a.overrides.begin(), a.overrides.end());
  } else {
    if (a.param.empty() || a.values.empty())
      throw SceneError("dicesim sweep", "--param/--values", "",
                       "'" + a.input + "' is a scene, not a sweep file ([sweep] table): give --param KEY and --values SPEC");
    SweepParam p;
    p.key = a.param;
    p.values = parse_values(a.values);
    p.value_template = a.value_template;
    p.scale = a.scale;
    p.shift = a.shift;
    spec = sweep_from_param(a.input, p, a.overrides);
  }
  if (a.tosses) spec.tosses = a.tosses;
  if (a.seed_opt->count()) spec.seed = a.seed;
  if (!a.points.empty()) {
    // Every point tosses the same indices with the same seed (common random numbers): a point's
    // counts do not depend on which other points run, so shard I/N is a contiguous block of points.
    Shard shard;
    try {
      shard = parse_shard(a.points);
    } catch (const std::invalid_argument& e) {
      throw SceneError("dicesim sweep", "--points", a.points, e.what());
    }
    const IndexRange block = shard_range(spec.points.size(), shard);
    if (block.tosses == 0) throw SceneError("dicesim sweep", "--points", a.points, "this shard has no points (more shards than points)");
    spec.points = std::vector<SweepPoint>(spec.points.begin() + static_cast<std::ptrdiff_t>(block.first),
                                          spec.points.begin() + static_cast<std::ptrdiff_t>(block.first + block.tosses));
  }
  if (!a.plot.empty()) {
    const std::string ext = fs::path(a.plot).extension().string();
    if (ext != ".png" && ext != ".svg") throw SceneError("dicesim sweep", "--plot", a.plot, "must end in .png or .svg");
  }
  // Before any toss: a sweep must not run every point and then fail to write.
  check_output_path("dicesim sweep", "--csv", a.csv);
  check_output_path("dicesim sweep", "--plot", a.plot);
  check_output_path("dicesim sweep", "--markdown", a.markdown);
  const std::vector<ReferenceRow> seed_rows = spec.seed_table.empty() ? std::vector<ReferenceRow>{}
                                                                       : load_reference_table(spec.seed_table);

  const InterruptGuard interrupt;  // Ctrl-C / SIGTERM: the points done are printed, exit 130
  ProgressBar bar;
  SweepRunOptions opt;
  opt.threads = a.threads;
  opt.cancel = InterruptGuard::flag();
  opt.progress = [&bar](std::uint64_t done, std::uint64_t total) { bar.update(done, total); };
  std::unique_ptr<SweepOverLcm> lcm;
  if (a.distributed()) {
    std::string url = wire::resolve_url(a.lcm);
    if (a.lcm.empty() && url == wire::kDefaultUrl) url = private_lcm_url();
    lcm = std::make_unique<SweepOverLcm>(spec.scene, url, a.workers, InterruptGuard::flag());
    opt.run_point = lcm->runner();
  }
  const SweepResult res = run_sweep(spec, opt);
  bar.finish();
  lcm.reset();  // stops the local workers
  const bool interrupted = InterruptGuard::interrupted();
  const Provenance prov = sweep_provenance(spec, res, a.threads);

  if (!a.csv.empty()) {
    if (a.csv == "-") std::fputs(csv_text(res, prov).c_str(), stdout);
    else write_text(a.csv, csv_text(res, prov));
  }
  if (!a.markdown.empty()) write_text(a.markdown, markdown_text(spec, res, seed_rows));
  if (!a.plot.empty()) write_plot(a.plot, spec, res, seed_rows, plot_labels(spec, a, file_mode));
  if (a.json)
    std::printf("%s\n", json_report(spec, res, seed_rows, a.threads, a.workers, prov).dump().c_str());
  else if (a.csv != "-")
    std::fputs(table_text(spec, res, a.threads, a.workers, prov,
                          spec.points.empty() ? std::vector<std::string>{} : outcome_names(first_point_model(spec)))
                   .c_str(),
               stdout);
  if (interrupted) {
    std::fprintf(stderr, "dicesim: interrupted after %zu of %zu points\n", res.points.size(), spec.points.size());
    return kExitInterrupted;
  }
  return kExitOk;
}

}  // namespace

void register_sweep(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sweep",
      "P(face) against one scene key: every point is the scene with one --set KEY=VALUE, tossed with\n"
      "the same seed and toss indices (common random numbers: smooth curves, meaningful differences).\n"
      "Give a scene with --param and --values, or a sweep file (TOML with a [sweep] table, see\n"
      "scenes/paper/sweeps/README.md) that names the scene, key, values and the seed's table.\n\n"
      "Examples:\n"
      "  dicesim sweep scenes/paper/die1.toml --param throw.height.mean --values 0.4:4.2:0.2\n"
      "  dicesim sweep scenes/paper/die1.toml --param floor.restitution --values 0.1,0.5,0.9 -n 20000 --json\n"
      "  dicesim sweep scenes/paper/die1.toml --param floor.friction --values 0.1:0.7:0.2 --fidelity impulse\n"
      "  dicesim sweep scenes/paper/die1.toml --param throw.velocity.mean --template '[{}, 0, 0]' \\\n"
      "      --values 0.5:15:0.5 --csv vx.csv --plot vx.png\n"
      "  dicesim sweep scenes/paper/sweeps/volume-ratio.toml --plot ratio.png --markdown ratio.md\n"
      "  dicesim sweep scenes/paper/sweeps/height.toml --workers 4   # points as distributed runs\n\n"
      "Outputs: a table on stdout, or --json (one object); --csv FILE (columns param,face,count,p,lo,hi;\n"
      "'-' for stdout); --plot FILE.png|svg (gnuplot, 95% bands, the seed's values as circles);\n"
      "--markdown FILE (our table beside the seed's, with a chi-square test per point).");
  cmd->add_option("INPUT", a->input, "A scene file (with --param/--values) or a sweep file")->required();
  cmd->add_option("--param", a->param, "Scene key to sweep, e.g. throw.height.mean, floor.restitution")->type_name("KEY");
  cmd->add_option("--values", a->values,
                  "start:stop:step (stop included) or a list a,b,c; numbers may be fractions p/q")
      ->type_name("SPEC");
  a->template_opt = cmd->add_option("--template", a->value_template,
                                    "TOML value with {} where the number goes, e.g. '[{}, 0, 0]' for a vector key")
                        ->type_name("T");
  a->scale_opt = cmd->add_option("--scale", a->scale, "Scene value = scale * x + shift (default 1)")->type_name("A");
  a->shift_opt = cmd->add_option("--shift", a->shift, "(default 0)")->type_name("B");
  cmd->add_option("--set", a->overrides, "Override a scene key at every point, KEY=VALUE; repeatable")->type_name("KEY=VALUE");
  cmd->add_option("--fidelity", a->fidelity,
                  "Physical model at every point (the scene's sim.fidelity otherwise): static, paper, impulse, stepped, auto")
      ->type_name("F");
  cmd->add_option("-n,--tosses", a->tosses, "Tosses per point (default: the sweep file's, else 10000)")
      ->check(CLI::Range(1ULL, 1ULL << 40));
  a->seed_opt = cmd->add_option("--seed", a->seed, "Run seed (default: the sweep file's, else 1)");
  cmd->add_option("-j,--threads", a->threads, "Worker threads (default: all cores)")->capture_default_str()->check(CLI::Range(1, 1024));
  cmd->add_option("-w,--workers", a->workers,
                  "Toss every point as a distributed run over LCM with K local `dicesim worker` processes\n"
                  "(identical counts to the in-process sweep); workers started elsewhere on --lcm join too")
      ->type_name("K")
      ->check(CLI::Range(0, 256));
  cmd->add_option("--lcm", a->lcm,
                  "LCM URL for distributed points (implies a distributed sweep; default with --workers: a\n"
                  "private host-confined URL, or $LCM_DEFAULT_URL if set)")
      ->type_name("URL");
  cmd->add_flag("--json", a->json, "Print exactly one JSON object on stdout instead of the table");
  cmd->add_option("--points", a->points,
                  "Run only shard I of N of the points (I = 0..N-1, a contiguous block in order), for job arrays:\n"
                  "a point's counts are the same as in the whole sweep (docs/scaling-out.md)")
      ->type_name("I/N");
  cmd->add_option("--csv", a->csv, "Write CSV: param,face,count,p,lo,hi ('-': stdout)")->type_name("FILE");
  cmd->add_option("--plot", a->plot, "Write a plot, FILE.png or FILE.svg (needs gnuplot)")->type_name("FILE");
  cmd->add_option("--markdown", a->markdown, "Write a Markdown table (beside the seed's, for sweep files)")->type_name("FILE");
  cmd->callback([a, &exit_code] { exit_code = run_sweep_cmd(*a); });
}

}  // namespace dicesim
