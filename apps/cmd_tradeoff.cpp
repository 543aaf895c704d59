// dicesim bench tradeoff: the fidelity ladder's speed against its accuracy, measured. The same toss
// indices go through every fidelity and a ladder of its accuracy settings; the reference is
// `stepped` at its finest step.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/commands.hpp"
#include "apps/gnuplot.hpp"
#include "apps/number_forms.hpp"
#include "sim/models/compile.hpp"
#include "sim/study/agreement.hpp"
#include "sim/body/die_model.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/models/toss.hpp"

namespace dicesim {
namespace {

struct TradeoffArgs {
  SceneArgs scene;
  std::uint64_t tosses = 20000;
  std::uint64_t seed = 1;
  int threads = 1;
  bool json = false;
  std::string csv, plot, from_csv;
  std::vector<double> steps = {2e-3, 1e-3, 5e-4, 2e-4};  // the last one is the reference
};

struct Setting {
  Fidelity fidelity;
  std::string label;  // e.g. "step=0.0005"
  double step = 0.0;  // sim.step (stepped) or sim.contact_step (impulse); 0: not used
};

struct Row {
  Setting setting;
  std::vector<std::int32_t> faces;  // per toss index: outcome index, -1 if not settled
  std::vector<std::uint64_t> counts;  // per outcome, label order
  std::vector<int> labels;            // the model's outcome labels
  std::uint64_t settled = 0, unresolved = 0, invalid = 0;
  double seconds = 0.0;
  double tosses_per_s = 0.0;
  double same_face = 0.0;
  Agreement vs_ref;
};

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

void run_row(const SceneDef& base, const TradeoffArgs& a, Row& row) {
  SceneDef sd = base;
  sd.sim.fidelity = row.setting.fidelity;
  if (row.setting.fidelity == Fidelity::Stepped) sd.sim.step = row.setting.step;
  if (row.setting.fidelity == Fidelity::Impulse) sd.sim.contact_step = row.setting.step;
  const DieModel m = compile(sd, a.scene.path);
  row.faces.assign(a.tosses, -1);
  std::vector<std::array<std::uint64_t, 3>> status(static_cast<std::size_t>(a.threads));
  const auto t0 = std::chrono::steady_clock::now();
  {
    std::vector<std::jthread> pool;
    for (int k = 0; k < a.threads; ++k)
      pool.emplace_back([&, k] {
        for (std::uint64_t i = static_cast<std::uint64_t>(k); i < a.tosses; i += static_cast<std::uint64_t>(a.threads)) {
          const TossResult r = toss(m, a.seed, i);
          if (r.status == TossStatus::Settled) row.faces[i] = r.outcome;
          ++status[static_cast<std::size_t>(k)][static_cast<int>(r.status)];
        }
      });
  }
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  row.tosses_per_s = static_cast<double>(a.tosses) / row.seconds;
  for (const auto& s : status) {
    row.settled += s[0];
    row.unresolved += s[1];
    row.invalid += s[2];
  }
  row.labels = m.outcome_labels;
  row.counts.assign(m.outcome_labels.size(), 0);
  for (std::int32_t f : row.faces)
    if (f >= 0) ++row.counts[static_cast<std::size_t>(f)];
}

void write_csv(std::FILE* out, const std::vector<Row>& rows) {
  std::fprintf(out, "fidelity,setting,tosses_per_s,same_face,tv,tv_noise,chi2_p,settled,unresolved,invalid\n");
  for (const Row& r : rows)
    std::fprintf(out, "%s,%s,%.6g,%.6f,%.6g,%.6g,%.6g,%llu,%llu,%llu\n", to_string(r.setting.fidelity),
                 r.setting.label.c_str(), r.tosses_per_s, r.same_face, r.vs_ref.tv, r.vs_ref.tv_noise, r.vs_ref.chi2_p,
                 static_cast<unsigned long long>(r.settled), static_cast<unsigned long long>(r.unresolved),
                 static_cast<unsigned long long>(r.invalid));
}

}  // namespace

// The gnuplot program drawing the rows of a CSV written above; throws std::runtime_error if gnuplot fails.
void plot_tradeoff_csv(const std::string& csv, const std::string& png, const std::string& title) {
  const std::string script =
      gnuplot_terminal(png, 1000, 620) +
      "set datafile separator ','\n"
      // Centred on the picture (centred on the plot, its second line ran past the left edge).
      "set tmargin 4\nset label 1 " + gnuplot_quote(title) + " at screen 0.5, screen 0.975 center front noenhanced\n"
      "set logscale xy\n"
      "set xlabel 'tosses per second (all threads; depends on the machine and its load)'\nset format x '10^{%L}'\n"
      "set ylabel 'distance from the reference (stepped, finest step)'\n"
      // Below the axes: inside, at any fixed place, the rows of a slower machine ran under it.
      "set key below horizontal Left reverse font ',9'\n"
      "set grid\nset yrange [1e-3:2]\n"
      // One colour per fidelity (its rows are a ladder of one setting); each point labelled by its
      // setting's value only, turned: impulse's labels below its points, the others' above, so that
      // the close ladders of impulse and stepped (both near the noise level) do not overprint.
      "val(s) = strstrt(s, '=') > 0 ? s[strstrt(s, '=') + 1:] : ''\n"
      "tv(f) = (strcol(1) eq f && column(5) > 0) ? column(5) : 1/0\n"
      "other(f) = (strcol(1) ne f && column(5) > 0) ? column(5) : 1/0\n"
      "plot for [f in 'static paper impulse stepped'] '" + csv + "' skip 1 using 3:(tv(f)) with points pt 7 ps 1.3 "
      "title f, "
      "'' skip 1 using 3:(other('impulse')):(val(strcol(2))) with labels rotate by 35 left offset char 0.6,0.5 font ',8' "
      "notitle, "
      "'' skip 1 using 3:(tv('impulse')):(val(strcol(2))) with labels rotate by -35 left offset char 0.6,-0.5 "
      "font ',8' notitle, "
      "'' skip 1 using 3:6 with points pt 6 ps 1.5 lc rgb 'gray40' title 'noise level of the total variation', "
      "'' skip 1 using 3:(1 - column(4) > 0 ? 1 - column(4) : 1/0) with points pt 5 ps 0.8 lc rgb 'gray70' "
      "title '1 - same face fraction'\n";
  run_gnuplot(script, png);
}

namespace {

int run_tradeoff(const TradeoffArgs& a) {
  const SceneDef base = a.scene.load();
  (void)compile(base, a.scene.path);  // bad scenes fail before any work
  if (!a.from_csv.empty()) {  // redraw an earlier run's rows: no tossing
    if (a.plot.empty()) throw SceneError("dicesim bench tradeoff", "--from-csv", a.from_csv, "needs --plot FILE.png");
    if (!std::ifstream(a.from_csv)) throw SceneError("dicesim bench tradeoff", "--from-csv", a.from_csv, "must be a readable file");
    plot_tradeoff_csv(a.from_csv, a.plot,
                      a.scene.path + ": accuracy against speed\nrows from " + a.from_csv +
                          "; point labels: each row's setting (a step in s; paper: its stop speed in m/s)");
    return kExitOk;
  }
  std::vector<Row> rows;
  const auto row = [](Setting s) {
    Row r;
    r.setting = std::move(s);
    return r;
  };
  rows.push_back(row({Fidelity::Static, "-", 0.0}));
  rows.push_back(row({Fidelity::Paper, "stop_speed=" + num(base.sim.stop_speed), 0.0}));
  for (double s : a.steps) rows.push_back(row({Fidelity::Impulse, "contact_step=" + num(s), s}));
  for (double s : a.steps) rows.push_back(row({Fidelity::Stepped, "step=" + num(s), s}));
  for (Row& r : rows) {
    if (!a.json) std::fprintf(stderr, "  %-8s %-20s ...\r", to_string(r.setting.fidelity), r.setting.label.c_str());
    run_row(base, a, r);
  }
  const Row& ref = rows.back();
  for (Row& r : rows) {
    std::uint64_t same = 0, ref_settled = 0;
    for (std::uint64_t i = 0; i < a.tosses; ++i) {
      if (ref.faces[i] < 0) continue;
      ++ref_settled;
      if (r.faces[i] == ref.faces[i]) ++same;
    }
    r.same_face = ref_settled ? static_cast<double>(same) / static_cast<double>(ref_settled) : 0.0;
    r.vs_ref = agreement_of(r.counts, ref.counts);
  }

  const auto row_json = [&](const Row& r) {
    nlohmann::json p = nlohmann::json::object();
    for (std::size_t f = 0; f < r.counts.size(); ++f)
      p[std::to_string(r.labels[f])] = r.settled ? static_cast<double>(r.counts[f]) / r.settled : 0.0;
    return nlohmann::json{{"fidelity", to_string(r.setting.fidelity)}, {"setting", r.setting.label},
                          {"tosses_per_s", r.tosses_per_s}, {"same_face", r.same_face},
                          {"tv", r.vs_ref.tv}, {"tv_noise", r.vs_ref.tv_noise}, {"chi2_p", r.vs_ref.chi2_p},
                          {"settled", r.settled}, {"unresolved", r.unresolved}, {"invalid", r.invalid},
                          {"seconds", r.seconds}, {"probabilities", p}};
  };
  if (a.json) {
    nlohmann::json j = {{"scene", a.scene.path}, {"tosses", a.tosses}, {"seed", a.seed}, {"threads", a.threads},
                        {"reference", row_json(ref)}, {"rows", nlohmann::json::array()}};
    for (const Row& r : rows) j["rows"].push_back(row_json(r));
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::fprintf(stderr, "%60s\r", "");
    std::printf("%s: %llu tosses (indices 0..%llu, seed %llu), %d thread%s; reference: stepped %s\n\n",
                a.scene.path.c_str(), static_cast<unsigned long long>(a.tosses),
                static_cast<unsigned long long>(a.tosses - 1), static_cast<unsigned long long>(a.seed), a.threads,
                a.threads == 1 ? "" : "s", ref.setting.label.c_str());
    std::printf("%-8s %-20s %12s %10s %9s %9s %9s %10s\n", "fidelity", "setting", "tosses/s", "same_face", "tv",
                "tv_noise", "chi2_p", "unresolved");
    for (const Row& r : rows)
      std::printf("%-8s %-20s %12.0f %10.4f %9.5f %9.5f %9.3g %10llu\n", to_string(r.setting.fidelity),
                  r.setting.label.c_str(), r.tosses_per_s, r.same_face, r.vs_ref.tv, r.vs_ref.tv_noise, r.vs_ref.chi2_p,
                  static_cast<unsigned long long>(r.unresolved));
    std::printf("\nsame_face: fraction of toss indices whose face equals the reference's; tv: total-variation\n"
                "distance of the probability vectors; tv_noise: its expected size from sampling alone;\n"
                "chi2_p: chi-square homogeneity p-value against the reference (small: a real difference).\n");
  }
  if (!a.csv.empty()) {
    std::FILE* f = std::fopen(a.csv.c_str(), "w");
    if (!f) throw SceneError(a.csv, "--csv", a.csv, "cannot write this file");
    write_csv(f, rows);
    std::fclose(f);
  }
  if (!a.plot.empty()) {
    const std::string tmp = a.plot + ".csv.tmp";
    std::FILE* f = std::fopen(tmp.c_str(), "w");
    if (!f) throw SceneError(a.plot, "--plot", a.plot, "cannot write next to this file");
    write_csv(f, rows);
    std::fclose(f);
    const std::string title = a.scene.path + ": accuracy against speed\n" + std::to_string(a.tosses) +
                              " tosses per row (the same indices in each, seed " + std::to_string(a.seed) + "), " +
                              std::to_string(a.threads) + (a.threads == 1 ? " thread" : " threads") +
                              "; point labels: each row's setting (a step in s; paper: its stop speed in m/s)";
    try {
      plot_tradeoff_csv(tmp, a.plot, title);
    } catch (...) {
      std::remove(tmp.c_str());
      throw;
    }
    std::remove(tmp.c_str());
  }
  return kExitOk;
}

}  // namespace

int run_bench_tradeoff(int argc, char** argv) {
  auto a = std::make_shared<TradeoffArgs>();
  CLI::App app{
      "Speed against accuracy along the fidelity ladder: the same toss indices through static, paper,\n"
      "impulse (a ladder of contact steps) and stepped (a ladder of steps); the reference is stepped at\n"
      "its finest step. Per row: tosses/s, same_face, tv, tv_noise, chi2_p.\n\n"
      "Example:  dicesim bench tradeoff scenes/paper/die1.toml --tosses 20000 --plot die1.png",
      "dicesim bench tradeoff"};
  a->scene.add_to(&app);
  app.add_option("-n,--tosses", a->tosses, "Tosses per row")->capture_default_str()->check(CLI::Range(1ULL, 1ULL << 32));
  app.add_option("--seed", a->seed, "Run seed")->capture_default_str();
  app.add_option("-j,--threads", a->threads, "Threads (tosses/s is for all of them together)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  // Commas as in sweep's --values (`--steps 1e-3,5e-4,2e-4`); spaces work too.
  app.add_option("--steps", a->steps, "Ladder of steps (s) for impulse's contact_step and stepped's step, each in "
                                      "[1e-7, 0.01], separated by commas or spaces; the last one is the reference")
      ->capture_default_str()
      ->delimiter(',')
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            char* end = nullptr;
            const double x = std::strtod(v.c_str(), &end);
            if (v.empty() || *end != '\0' || !(x >= 1e-7 && x <= 1e-2))
              return "'" + v + "' is not a step: each is a number of seconds in [1e-7, 0.01], the list separated by "
                               "commas or spaces (--steps 2e-3,1e-3,5e-4)";
            return {};
          },
          "STEP", "step"));
  app.add_flag("--json", a->json, "One JSON object {scene, tosses, reference, rows} on stdout");
  app.add_option("--csv", a->csv, "Also write the rows as CSV to this file")->type_name("FILE");
  app.add_option("--plot", a->plot, "Also draw accuracy against speed as PNG (gnuplot)")->type_name("FILE.png");
  app.add_option("--from-csv", a->from_csv, "Toss nothing: draw --plot from the rows of an earlier --csv")
      ->type_name("ROWS.csv");
  int exit_code = kExitOk;
  app.callback([a, &exit_code] { exit_code = run_tradeoff(*a); });
  accept_number_forms(app);
  return parse_and_run(app, argc, argv, exit_code);
}

}  // namespace dicesim
