// dicesim calibrate-restitution: the coefficient of restitution, with a 95% interval, from drop
// measurements (speed pairs, or a height-against-time track).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "apps/commands.hpp"
#include "sim/study/restitution_fit.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim {
namespace {

struct CalibrateArgs {
  std::string pairs, track;
  std::vector<std::string> where;
  bool json = false;
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  const auto e = s.find_last_not_of(" \t\r\n");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (std::size_t c; (c = line.find(',', start)) != std::string::npos; start = c + 1) out.push_back(trim(line.substr(start, c - start)));
  out.push_back(trim(line.substr(start)));
  return out;
}

// A CSV with '#' comment lines and a header. Columns are found by name: `name` itself or
// `name_<unit>` (v_in, v_in_m_s). Rows failing a --where COL=VALUE filter are skipped.
struct Columns {
  std::vector<std::vector<double>> values;  // one vector per wanted column
  std::size_t rows = 0;
};

Columns read_columns(const std::string& path, const std::vector<std::string>& wanted, const std::vector<std::string>& where) {
  std::ifstream in(path);
  if (!in) throw SceneError(path, "", "", "cannot open file");
  std::string line;
  std::vector<std::string> header;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    header = split(t);
    break;
  }
  if (header.empty()) throw SceneError(path, "", "", "empty: expected a header line naming the columns");
  auto find = [&](const std::string& name) -> std::size_t {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name || header[i].rfind(name + "_", 0) == 0) return i;
    std::string list;
    for (const auto& h : header) list += (list.empty() ? "" : ", ") + h;
    throw SceneError(path, "column " + name, "", "not found; the header has: " + list);
  };
  std::vector<std::size_t> idx;
  for (const auto& w : wanted) idx.push_back(find(w));
  std::vector<std::pair<std::size_t, std::string>> filters;
  for (const auto& w : where) {
    const auto eq = w.find('=');
    if (eq == std::string::npos) throw SceneError("dicesim calibrate-restitution", "--where", w, "expected COLUMN=VALUE, e.g. material=steel");
    std::size_t col = header.size();
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == trim(w.substr(0, eq))) col = i;
    if (col == header.size()) throw SceneError(path, "column " + trim(w.substr(0, eq)), "", "not found (named by --where)");
    filters.emplace_back(col, trim(w.substr(eq + 1)));
  }
  Columns c;
  c.values.resize(wanted.size());
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const auto cells = split(t);
    if (cells.size() != header.size())
      throw SceneError(path, "line " + std::to_string(line_no), "'" + t + "'",
                       "has " + std::to_string(cells.size()) + " cells; the header has " + std::to_string(header.size()));
    bool keep = true;
    for (const auto& [col, value] : filters) keep = keep && cells[col] == value;
    if (!keep) continue;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const std::string& cell = cells[idx[k]];
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      if (cell.empty() || *end != '\0' || !std::isfinite(v))
        throw SceneError(path, "line " + std::to_string(line_no) + ", column " + header[idx[k]], "'" + cell + "'",
                         "must be a finite number");
      c.values[k].push_back(v);
    }
    ++c.rows;
  }
  return c;
}

std::string f4(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", v);
  return buf;
}

int run_calibrate(const CalibrateArgs& a) {
  if (a.pairs.empty() == a.track.empty())
    throw SceneError("dicesim calibrate-restitution", "--pairs/--track", "", "give exactly one of --pairs FILE.csv or --track FILE.csv");
  const std::string& file = a.pairs.empty() ? a.track : a.pairs;
  RestitutionEstimate e;
  TrackFit tf;
  try {
    if (!a.pairs.empty()) {
      const Columns c = read_columns(file, {"v_in", "v_out"}, a.where);
      e = restitution_from_pairs(c.values[0], c.values[1]);
    } else {
      const Columns c = read_columns(file, {"t", "z"}, a.where);
      tf = restitution_from_track(c.values[0], c.values[1]);
      e = tf.estimate;
    }
  } catch (const std::invalid_argument& err) {
    throw SceneError(file, a.pairs.empty() ? "--track" : "--pairs", "", err.what());
  }
  if (a.json) {
    nlohmann::json j = {{"restitution", e.restitution},
                        {"ci95", {e.ci95.lo, e.ci95.hi}},
                        {"n", e.n},
                        {"sd", e.sd},
                        {"method", a.pairs.empty() ? "track" : "pairs"},
                        {"file", file},
                        {"ratios", e.ratios}};
    if (!a.track.empty()) {
      nlohmann::json imps = nlohmann::json::array();
      for (const TrackImpact& i : tf.impacts)
        imps.push_back({{"t", i.t}, {"v_in", i.v_in}, {"v_out", i.v_out}, {"ratio", i.ratio}, {"g_before", i.g_before}, {"g_after", i.g_after}});
      j["impacts"] = imps;
    }
    std::printf("%s\n", j.dump().c_str());
    return kExitOk;
  }
  std::printf("%s  (%s)\n\n", file.c_str(), a.pairs.empty() ? "track: a parabola fitted to each flight" : "speed pairs");
  if (!a.track.empty()) {
    std::printf("impact   t (s)     v_in (m/s)  v_out (m/s)  ratio    g fitted before/after (m/s^2)\n");
    for (std::size_t k = 0; k < tf.impacts.size(); ++k) {
      const TrackImpact& i = tf.impacts[k];
      std::printf("%6zu  %8.4f  %10.4f  %11.4f  %6.4f   %.2f / %.2f\n", k + 1, i.t, i.v_in, i.v_out, i.ratio, i.g_before, i.g_after);
    }
  } else {
    std::printf("ratios v_out/v_in:");
    for (double r : e.ratios) std::printf(" %.4f", r);
    std::printf("\n");
  }
  std::printf("\nrestitution %s, 95%% interval [%s, %s] (Student t, n = %zu, sd %s)\n", f4(e.restitution).c_str(),
              f4(e.ci95.lo).c_str(), f4(e.ci95.hi).c_str(), e.n, f4(e.sd).c_str());
  return kExitOk;
}

}  // namespace

void register_calibrate(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<CalibrateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate-restitution",
      "Coefficient of restitution with a 95% interval from drop measurements (the seed's sec. 5.1).\n"
      "  --pairs FILE.csv  columns v_in,v_out: speeds just before and after each impact (signs ignored);\n"
      "                    the estimate is the mean of v_out/v_in.\n"
      "  --track FILE.csv  columns t,z: height of the die against time while it bounces; a parabola is\n"
      "                    fitted to each flight and the two around an impact give the speeds there.\n"
      "Columns may carry a unit suffix (v_in_m_s, t_s, z_m); '#' lines are comments.\n\n"
      "Examples:\n"
      "  dicesim calibrate-restitution --pairs data/seed-tables/table04_05_restitution_trials.csv --where material=steel\n"
      "  dicesim calibrate-restitution --track drop.csv --json\n"
      "JSON keys: restitution, ci95 [lo, hi], n, sd, method, ratios (and impacts for --track).");
  cmd->add_option("--pairs", a->pairs, "CSV of speed pairs (v_in,v_out)")->type_name("FILE.csv");
  cmd->add_option("--track", a->track, "CSV of a bouncing track (t,z)")->type_name("FILE.csv");
  cmd->add_option("--where", a->where, "Use only rows with COLUMN=VALUE, e.g. material=aluminium; repeatable")
      ->type_name("COL=VALUE");
  cmd->add_flag("--json", a->json, "Print exactly one JSON object on stdout");
  cmd->callback([a, &exit_code] { exit_code = run_calibrate(*a); });
}

}  // namespace dicesim
