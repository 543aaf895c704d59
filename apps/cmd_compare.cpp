// dicesim compare: are two results (two runs, or a run and a real experiment's face counts)
// statistically different? Chi-square homogeneity test and per-face differences with intervals.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "apps/commands.hpp"
#include "apps/report.hpp"
#include "sim/study/compare.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim {
namespace {

struct CompareArgs {
  std::string a, b;
  double alpha = 0.05;
  bool json = false;
};

// The provenance an input carries (a `dicesim toss --json` file's "provenance"), else null (a CSV of counts).
nlohmann::json input_provenance(const std::string& path) {
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_object() && j.contains("provenance") ? j["provenance"] : nlohmann::json(nullptr);
}

// What made the comparison: this build, and each input's own provenance (null when it has none).
nlohmann::json compare_provenance(const CompareArgs& a) {
  const Provenance self;
  return {{"version", self.version},
          {"dirty", self.dirty < 0 ? nlohmann::json(nullptr) : nlohmann::json(self.dirty == 1)},
          {"a", input_provenance(a.a)},
          {"b", input_provenance(a.b)}};
}

int run_compare(const CompareArgs& a) {
  const FaceCounts ca = read_face_counts(a.a), cb = read_face_counts(a.b);
  Comparison c;
  try {
    c = compare_counts(ca, cb);
  } catch (const std::invalid_argument& e) {
    throw SceneError(a.a + " vs " + a.b, "faces", "", e.what());
  }
  const bool differ = c.chi2.p_value < a.alpha;
  if (a.json) {
    nlohmann::json faces = nlohmann::json::array();
    for (const FaceDifference& f : c.faces)
      faces.push_back({{"face", f.label}, {"count_a", f.count_a}, {"count_b", f.count_b}, {"p_a", f.p_a}, {"p_b", f.p_b},
                       {"diff", f.diff}, {"ci95", {f.ci95.lo, f.ci95.hi}},
                       {"differs", f.ci95.lo > 0.0 || f.ci95.hi < 0.0}});
    const nlohmann::json j = {{"a", a.a}, {"b", a.b}, {"n_a", c.n_a}, {"n_b", c.n_b},
                              {"chi2", chi2_json(c.chi2)},
                              {"min_expected", c.min_expected}, {"alpha", a.alpha}, {"differ", differ}, {"faces", faces},
                              {"provenance", compare_provenance(a)}};
    std::printf("%s\n", j.dump().c_str());
    return kExitOk;
  }
  std::printf("A: %s (n = %llu)\nB: %s (n = %llu)\n", a.a.c_str(), static_cast<unsigned long long>(c.n_a), a.b.c_str(),
              static_cast<unsigned long long>(c.n_b));
  const nlohmann::json prov = compare_provenance(a);
  std::printf("dicesim %s\n", Provenance().version.c_str());
  for (const char* k : {"a", "b"})
    if (!prov[k].is_null())
      std::printf("%s made by dicesim %s from %s (scene sha256 %s, seed %s, fidelity %s)\n", k[0] == 'a' ? "A" : "B",
                  prov[k].value("version", "?").c_str(), prov[k].value("scene", "?").c_str(),
                  prov[k].value("scene_sha256", "?").c_str(), prov[k].contains("seed") ? prov[k]["seed"].dump().c_str() : "?",
                  prov[k].value("fidelity", "?").c_str());
  std::printf("\n");
  std::printf("face   count A     p A    count B     p B    p A - p B   95%% interval (Newcombe)\n");
  for (const FaceDifference& f : c.faces)
    std::printf("%4d %9llu  %7.4f %9llu  %7.4f   %+8.4f    [%+.4f, %+.4f]%s\n", f.label,
                static_cast<unsigned long long>(f.count_a), f.p_a, static_cast<unsigned long long>(f.count_b), f.p_b, f.diff,
                f.ci95.lo, f.ci95.hi, (f.ci95.lo > 0.0 || f.ci95.hi < 0.0) ? "  *" : "");
  std::printf("\nchi-square homogeneity: %.2f on %d dof, p = %.3g -> %s at the %g level\n", c.chi2.statistic, c.chi2.dof,
              c.chi2.p_value, differ ? "DIFFERENT" : "not distinguishable", a.alpha);
  if (c.min_expected < 5.0) std::printf("note: an expected count is %.2f (< 5): the chi-square p-value is rough\n", c.min_expected);
  std::printf("* the face's interval excludes 0 (per face, not corrected for %zu comparisons)\n", c.faces.size());
  return kExitOk;
}

}  // namespace

void register_compare(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Are two results statistically different? Each is the output of `dicesim toss --json`, or a CSV\n"
      "of observed face counts (face,count; e.g. a real experiment). Prints a chi-square test of\n"
      "homogeneity and each face's difference of proportions with a 95% Newcombe interval.\n"
      "Exit code 0 whatever the verdict (read it from the output); 2 for unreadable input.\n\n"
      "Examples:\n"
      "  dicesim toss scenes/paper/die1.toml -n 100000 --json > sim.json\n"
      "  dicesim compare sim.json data/seed-experiments/die1_counts.csv\n"
      "  dicesim compare run1.json run2.json --json");
  cmd->add_option("A", a->a, "First result: toss JSON or face,count CSV")->required();
  cmd->add_option("B", a->b, "Second result")->required();
  cmd->add_option("--alpha", a->alpha, "Significance level of the verdict")->capture_default_str()->check(CLI::Range(1e-12, 0.5));
  cmd->add_flag("--json", a->json, "Print exactly one JSON object on stdout");
  cmd->callback([a, &exit_code] { exit_code = run_compare(*a); });
}

}  // namespace dicesim
