// dicesim compare: are two results (two runs, or a run and a real experiment's face counts)
// statistically different? Chi-square homogeneity test and per-face differences with intervals;
// with --margin / --margin-rel, also are they the same to within that margin (equivalence tests,
// sim/study/equivalence.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "apps/commands.hpp"
#include "apps/report.hpp"
#include "sim/study/compare.hpp"
#include "sim/study/equivalence.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim {
namespace {

struct CompareArgs {
  std::string a, b;
  double alpha = 0.05;
  bool alpha_given = false;
  double margin = 0.0;      // > 0: equivalence to within |p_a - p_b| <= margin
  double margin_rel = 0.0;  // > 0: ... to within margin_rel * p (p pooled)
  std::vector<std::string> paired;  // --paired: A's and B's per-toss outcome files
  bool json = false;
  bool equivalence() const { return margin > 0.0 || margin_rel > 0.0; }
  // The chi-square's level (default 0.05), and the equivalence tests' (default 0.10).
  double chi2_alpha() const { return alpha_given || !equivalence() ? alpha : 0.05; }
  double tost_alpha() const { return alpha_given ? alpha : 0.10; }
};

// The tosses a paired test used (Equivalence::paired) and those dropped (not settled in both).
struct PairInfo {
  std::uint64_t pairs = 0, dropped = 0;
};

// One run's per-toss outcomes as indices into c's faces (label order); its settled counts must be
// the run's own (`which`: 0 for A, 1 for B), else it is not that run's file.
std::vector<std::int16_t> outcome_indices(const std::string& path, const Comparison& c, int which) {
  const std::vector<int> labels = read_toss_outcomes(path);
  std::vector<std::int16_t> idx;
  std::vector<std::uint64_t> n(c.faces.size(), 0);
  for (const int l : labels) {
    if (l < 0) {
      idx.push_back(-1);
      continue;
    }
    const auto it = std::find_if(c.faces.begin(), c.faces.end(), [l](const FaceDifference& f) { return f.label == l; });
    if (it == c.faces.end())
      throw SceneError(path, "outcome", std::to_string(l), "not a face label of the compared results");
    const auto i = static_cast<std::size_t>(it - c.faces.begin());
    ++n[i];
    idx.push_back(static_cast<std::int16_t>(i));
  }
  for (std::size_t i = 0; i < n.size(); ++i)
    if (n[i] != (which == 0 ? c.faces[i].count_a : c.faces[i].count_b))
      throw SceneError(path, "face " + std::to_string(c.faces[i].label), std::to_string(n[i]) + " tosses",
                       std::string("must equal ") + (which == 0 ? "A" : "B") + "'s count (" +
                           std::to_string(which == 0 ? c.faces[i].count_a : c.faces[i].count_b) +
                           "): --paired takes A's and B's own --outcomes files, in that order");
  return idx;
}

// The equivalence tests of c's faces: unpaired, or paired by toss index with --paired.
Equivalence equivalence_of(const Comparison& c, const CompareArgs& a, PairInfo& info) {
  const Margin margin = a.margin > 0.0 ? absolute_margin(a.margin) : relative_margin(a.margin_rel);
  if (!a.paired.empty()) {
    const std::vector<std::int16_t> ia = outcome_indices(a.paired[0], c, 0);  // A's first: its errors first
    const std::vector<std::int16_t> ib = outcome_indices(a.paired[1], c, 1);
    const PairedCounts p = paired_counts(ia, ib, static_cast<int>(c.faces.size()));
    info = {p.pairs, p.dropped};
    if (p.pairs == 0) throw SceneError(a.paired[0], "", "", "no toss settled in both runs");
    return equivalence_paired(p.a, p.b, p.a_only, p.b_only, margin, a.tost_alpha());
  }
  std::vector<std::uint64_t> ca, cb;
  for (const FaceDifference& f : c.faces) {
    ca.push_back(f.count_a);
    cb.push_back(f.count_b);
  }
  return equivalence_unpaired(ca, cb, margin, a.tost_alpha());
}

std::string margin_text(const CompareArgs& a) {
  char buf[96];
  if (a.margin > 0.0)
    std::snprintf(buf, sizeof buf, "|p A - p B| < %g", a.margin);
  else
    std::snprintf(buf, sizeof buf, "|p A - p B| < %g p (p pooled)", a.margin_rel);
  return buf;
}

nlohmann::json equivalence_json(const Equivalence& e, const Comparison& c, const CompareArgs& a, const PairInfo& info) {
  nlohmann::json faces = nlohmann::json::array();
  for (std::size_t i = 0; i < e.outcomes.size(); ++i) {
    const OutcomeEquivalence& o = e.outcomes[i];
    faces.push_back({{"face", c.faces[i].label}, {"diff", o.diff}, {"se", o.se}, {"margin", o.margin},
                     {"ci", {o.ci.lo, o.ci.hi}}, {"p_lower", o.p_lower}, {"p_upper", o.p_upper}, {"tost_p", o.tost_p},
                     {"holm_p", o.holm_p}, {"equivalent", o.equivalent}});
  }
  return {{"alpha", e.alpha},
          {"ci_level", 1.0 - 2.0 * e.alpha},
          {"margin", a.margin > 0.0 ? nlohmann::json(a.margin) : nlohmann::json(nullptr)},
          {"margin_rel", a.margin_rel > 0.0 ? nlohmann::json(a.margin_rel) : nlohmann::json(nullptr)},
          {"paired", e.paired},
          {"pairs", e.paired ? nlohmann::json(info.pairs) : nlohmann::json(nullptr)},
          {"dropped", e.paired ? nlohmann::json(info.dropped) : nlohmann::json(nullptr)},
          {"method", e.paired ? "TOST per face, normal approximation, variance of the paired per-toss difference; Holm across faces"
                              : "TOST per face, normal approximation, unpooled variance; Holm across faces"},
          {"equivalent", e.equivalent},
          {"faces", faces}};
}

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
  const bool differ = c.chi2.p_value < a.chi2_alpha();
  std::optional<Equivalence> eq;
  PairInfo pairs;
  if (!a.paired.empty() && !a.equivalence())
    throw SceneError("--paired", "", "", "needs --margin or --margin-rel (the paired test is an equivalence test)");
  if (a.equivalence()) {
    if (a.tost_alpha() >= 0.5)
      throw SceneError("--alpha", "", std::to_string(a.tost_alpha()), "with a margin it must be below 0.5 (two one-sided tests)");
    eq = equivalence_of(c, a, pairs);
  }
  if (a.json) {
    nlohmann::json faces = nlohmann::json::array();
    for (const FaceDifference& f : c.faces)
      faces.push_back({{"face", f.label}, {"count_a", f.count_a}, {"count_b", f.count_b}, {"p_a", f.p_a}, {"p_b", f.p_b},
                       {"diff", f.diff}, {"ci95", {f.ci95.lo, f.ci95.hi}},
                       {"differs", f.ci95.lo > 0.0 || f.ci95.hi < 0.0}});
    const nlohmann::json j = {{"a", a.a}, {"b", a.b}, {"n_a", c.n_a}, {"n_b", c.n_b},
                              {"chi2", chi2_json(c.chi2)},
                              {"min_expected", c.min_expected}, {"alpha", a.chi2_alpha()}, {"differ", differ}, {"faces", faces},
                              {"equivalence", eq ? equivalence_json(*eq, c, a, pairs) : nlohmann::json(nullptr)},
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
              c.chi2.p_value, differ ? "DIFFERENT" : "not distinguishable", a.chi2_alpha());
  if (c.min_expected < 5.0) std::printf("note: an expected count is %.2f (< 5): the chi-square p-value is rough\n", c.min_expected);
  std::printf("* the face's interval excludes 0 (per face, not corrected for %zu comparisons)\n", c.faces.size());
  if (eq) {
    std::printf("\nequivalence: %s per face, two one-sided tests at alpha %g, Holm over %zu faces\n", margin_text(a).c_str(),
                eq->alpha, eq->outcomes.size());
    std::printf("face  p A - p B   margin    %2.0f%% interval          TOST p    Holm p   verdict\n",
                100.0 * (1.0 - 2.0 * eq->alpha));
    for (std::size_t i = 0; i < eq->outcomes.size(); ++i) {
      const OutcomeEquivalence& o = eq->outcomes[i];
      std::printf("%4d  %+9.5f  %8.5f  [%+.5f, %+.5f]  %8.3g  %8.3g   %s\n", c.faces[i].label, o.diff, o.margin, o.ci.lo,
                  o.ci.hi, o.tost_p, o.holm_p, o.equivalent ? "equivalent" : "not shown");
    }
    std::printf("overall: %s at alpha %g (EQUIVALENT: every face equivalent after Holm)\n",
                eq->equivalent ? "EQUIVALENT" : "NOT SHOWN EQUIVALENT", eq->alpha);
    std::printf("note: the interval is the %g%% one (inside +-margin iff the face's TOST p < alpha, before Holm).\n",
                100.0 * (1.0 - 2.0 * eq->alpha));
    if (eq->paired)
      std::printf("note: paired by toss index over %llu tosses settled in both runs (%llu dropped).\n",
                  static_cast<unsigned long long>(pairs.pairs), static_cast<unsigned long long>(pairs.dropped));
    else
      std::printf("note: the tests treat the runs as independent; runs with the same seed pair their tosses, and for\n"
                  "      positively correlated pairs the unpaired test is conservative (it may miss an equivalence):\n"
                  "      give both runs --outcomes and compare them with --paired.\n");
  }
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
      "With --margin D (or --margin-rel F): are they the same to within D (or F times the face's\n"
      "pooled probability) on every face? Two one-sided tests per face (normal approximation,\n"
      "unpooled variance) at --alpha (default 0.10), Holm-corrected across the faces: EQUIVALENT\n"
      "only if every face is. Small runs cannot show equivalence: unpaired, a fair d6 needs about\n"
      "2 x 0.139 (z / D)^2 tosses per run (z ~ 2.1 for six faces; D = 0.002: ~3.2e5 each). Two runs\n"
      "with the same seed and --outcomes files, compared with --paired, need far fewer when few\n"
      "tosses change outcome between them.\n"
      "Exit code 0 whatever the verdict (read it from the output); 2 for unreadable input.\n\n"
      "Examples:\n"
      "  dicesim toss scenes/paper/die1.toml -n 100000 --json > sim.json\n"
      "  dicesim compare sim.json data/seed-experiments/die1_counts.csv\n"
      "  dicesim compare run1.json run2.json --json\n"
      "  dicesim compare stepped.json impulse.json --margin 0.002\n"
      "  dicesim compare a.json b.json --margin-rel 0.2 --json   # every face within 20% of its p\n"
      "  dicesim toss S.toml --seed 1 --json --outcomes a.txt > a.json   # (and b the same way)\n"
      "  dicesim compare a.json b.json --margin 0.002 --paired a.txt b.txt");
  cmd->add_option("A", a->a, "First result: toss JSON or face,count CSV")->required();
  cmd->add_option("B", a->b, "Second result")->required();
  cmd->add_option("--alpha", a->alpha,
                  "Significance level of the verdict (default 0.05 for the chi-square; with a margin, the\n"
                  "equivalence tests' level, default 0.10, and the chi-square's too)")
      ->check(CLI::Range(1e-12, 0.5))
      ->each([a](const std::string&) { a->alpha_given = true; });
  auto* margin = cmd->add_option("--margin", a->margin, "Equivalence margin on every face's p_A - p_B, in (0, 1)")
                     ->check(CLI::Range(1e-12, 0.999999));
  cmd->add_option("--margin-rel", a->margin_rel,
                  "Equivalence margin relative to each face's pooled probability p (margin = F p), in (0, 10]")
      ->check(CLI::Range(1e-12, 10.0))
      ->excludes(margin);
  cmd->add_option("--paired", a->paired,
                  "With a margin: A's and B's per-toss outcomes (`toss --outcomes FILE`, the same seed and\n"
                  "tosses): the test pairs toss i of A with toss i of B (far stronger for similar runs)")
      ->expected(2)
      ->type_name("A_OUT B_OUT");
  cmd->add_flag("--json", a->json, "Print exactly one JSON object on stdout");
  cmd->callback([a, &exit_code] { exit_code = run_compare(*a); });
}

}  // namespace dicesim
