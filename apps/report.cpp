#include "apps/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "sim/body/outcome.hpp"
#include "sim/body/world.hpp"
#include "sim/study/statistics.hpp"

namespace dicesim {
namespace {

struct FaceRow {
  int label;
  std::string name;  // a coin's side; empty for a die
  std::uint64_t count;
  double p;
  Interval ci;
};

std::vector<FaceRow> face_rows(const RunReport& r) {
  std::vector<FaceRow> rows;
  for (std::size_t i = 0; i < r.counts.faces.size() && i < r.labels.size(); ++i) {
    const std::uint64_t c = r.counts.faces[i];
    const double p = r.counts.settled ? static_cast<double>(c) / static_cast<double>(r.counts.settled) : 0.0;
    rows.push_back({r.labels[i], i < r.names.size() ? r.names[i] : "", c, p, wilson_interval(c, r.counts.settled)});
  }
  std::sort(rows.begin(), rows.end(), [](const FaceRow& a, const FaceRow& b) { return a.label < b.label; });
  return rows;
}

// The classes of outcomes alike by design with two or more outcomes, each tested against equal
// probabilities within it (outcomes in label order).
struct AlikeTest {
  std::vector<int> labels;
  std::vector<std::string> names;  // a coin's sides
  ChiSquare chi;
};

std::vector<AlikeTest> alike_tests(const RunReport& r) {
  std::vector<AlikeTest> tests;
  if (r.alike.size() != r.counts.faces.size() || r.labels.size() != r.counts.faces.size()) return tests;
  for (std::size_t first = 0; first < r.alike.size(); ++first) {
    if (r.alike[first] != static_cast<int>(first)) continue;
    AlikeTest t;
    std::vector<std::uint64_t> counts;
    for (std::size_t k = first; k < r.alike.size(); ++k)
      if (r.alike[k] == static_cast<int>(first)) {
        t.labels.push_back(r.labels[k]);
        if (k < r.names.size()) t.names.push_back(r.names[k]);
        counts.push_back(r.counts.faces[k]);
      }
    if (counts.size() < 2) continue;
    t.chi = chi2_uniform(counts);
    tests.push_back(std::move(t));
  }
  return tests;
}

// Every outcome alike: the one test against a fair die.
std::optional<ChiSquare> chi2_fair(const RunReport& r, const std::vector<AlikeTest>& tests) {
  if (tests.size() == 1 && tests.front().labels.size() == r.counts.faces.size()) return tests.front().chi;
  return std::nullopt;
}

// A fair coin: heads and tails alike, edge landings left out (a matter of thickness, not of
// fairness). Needs heads and tails each alone in its outcome and the coin turned over onto itself.
std::optional<ChiSquare> chi2_heads_tails(const std::vector<AlikeTest>& tests) {
  for (const AlikeTest& t : tests)
    if (t.names == std::vector<std::string>{"heads", "tails"}) return t.chi;
  return std::nullopt;
}

std::string labels_text(const std::vector<int>& labels) {
  std::string s;
  for (const int l : labels) s += (s.empty() ? "" : ", ") + std::to_string(l);
  return s;
}

double rate(const RunReport& r) { return r.elapsed_s > 0.0 ? static_cast<double>(r.tosses) / r.elapsed_s : 0.0; }

}  // namespace

nlohmann::json corrections_json(const RunCorrections& k) {
  nlohmann::json j = nlohmann::json::object();
  k.for_each([&](const char* name, std::uint64_t n) { j[name] = n; });
  return j;
}

std::string corrections_line(const RunCorrections& k) {
  if (!k.any()) return {};
  // The four repairs of the law always, then the sustained phase's guards that fired.
  char line[320];
  std::snprintf(line, sizeof line,
                "corrections: %llu energy clamps, %llu unconverged contact solves, %llu overlap fixes, %llu fallbacks",
                static_cast<unsigned long long>(k.energy_clamps), static_cast<unsigned long long>(k.pgs_unconverged),
                static_cast<unsigned long long>(k.overlap_fixes), static_cast<unsigned long long>(k.fallbacks));
  std::string out = line;
  int i = 0;
  k.for_each([&](const char* name, std::uint64_t n) {
    if (i++ < 4 || n == 0) return;
    out += ", " + std::to_string(n) + " " + name;
  });
  return out + " (each should be 0: the physics was repaired or a guard fired; docs/fidelity.md)\n";
}

nlohmann::json json_number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json chi2_json(const ChiSquare& c) {
  return {{"statistic", json_number(c.statistic)}, {"dof", c.dof}, {"p_value", json_number(c.p_value)}};
}

nlohmann::json report_json(const RunReport& r) {
  nlohmann::json faces = nlohmann::json::array();
  for (const FaceRow& f : face_rows(r)) {
    faces.push_back({{"face", f.label}, {"count", f.count}, {"p", f.p}, {"ci95", {f.ci.lo, f.ci.hi}}});
    if (!f.name.empty()) faces.back()["name"] = f.name;
  }
  const std::vector<AlikeTest> tests = alike_tests(r);
  const auto fair = chi2_fair(r, tests);
  const auto coin = chi2_heads_tails(tests);
  nlohmann::json groups = nlohmann::json::array(), chi_alike = nlohmann::json::array();
  for (const AlikeTest& t : tests) {
    groups.push_back(t.labels);
    chi_alike.push_back(chi2_json(t.chi));
    chi_alike.back()["outcomes"] = t.labels;
  }
  return {{"scene", r.scene},
          {"fidelity", r.fidelity},
          {"fidelity_requested", r.fidelity_requested},
          {"fidelity_reason", r.fidelity_reason},
          {"pilot", pilot_json(r.pilot)},
          {"seed", r.seed},
          {"threads", r.threads},
          {"tosses", r.tosses},
          {"partial", r.partial},
          {"tosses_requested", r.partial ? r.provenance.tosses : r.tosses},
          {"settled", r.counts.settled},
          {"unresolved", r.counts.unresolved},
          {"invalid", r.counts.invalid},
          {"faces", faces},
          {"alike", {{"groups", groups}, {"rotations", r.symmetry_rotations}, {"note", r.alike_note}}},
          {"chi2_alike", chi_alike},
          {"chi2_uniform", fair ? chi2_json(*fair) : nlohmann::json(nullptr)},
          {"chi2_heads_tails", coin ? chi2_json(*coin) : nlohmann::json(nullptr)},
          {"bounces_per_toss", r.tosses ? static_cast<double>(r.counts.bounces) / static_cast<double>(r.tosses) : 0.0},
          {"corrections", corrections_json(r.counts.corrections)},
          {"elapsed_s", r.elapsed_s},
          {"tosses_per_s", rate(r)},
          {"provenance", provenance_json(r.provenance)}};
}

std::string report_table(const RunReport& r) {
  std::string out;
  char line[320];
  std::snprintf(line, sizeof line, "%s  (fidelity %s, seed %llu, %llu tosses, %d thread%s)\n", r.scene.c_str(),
                r.fidelity.c_str(), static_cast<unsigned long long>(r.seed), static_cast<unsigned long long>(r.tosses),
                r.threads, r.threads == 1 ? "" : "s");
  out += line;
  out += provenance_lines(r.provenance);
  if (r.partial) {
    // With --fidelity of the model run: auto would judge a shorter run at its own precision.
    std::snprintf(line, sizeof line,
                  "interrupted after %llu of %llu tosses (a complete prefix: the same counts as -n %llu --fidelity %s)\n",
                  static_cast<unsigned long long>(r.tosses), static_cast<unsigned long long>(r.provenance.tosses),
                  static_cast<unsigned long long>(r.tosses), r.fidelity.c_str());
    out += line;
  }
  if (r.fidelity_requested == "auto" && r.pilot.ran)  // how auto chose (the reason is in the provenance lines)
    out += pilot_line(r.pilot, r.fidelity);
  out += "\n";
  out += "face       count        p     95% interval (Wilson)\n";
  for (const FaceRow& f : face_rows(r)) {
    std::snprintf(line, sizeof line, "%4d  %10llu   %.5f   [%.5f, %.5f]%s%s\n", f.label,
                  static_cast<unsigned long long>(f.count), f.p, f.ci.lo, f.ci.hi, f.name.empty() ? "" : "   ", f.name.c_str());
    out += line;
  }
  std::snprintf(line, sizeof line, "\nsettled %llu, unresolved %llu, invalid %llu (p and intervals over settled tosses)\n",
                static_cast<unsigned long long>(r.counts.settled), static_cast<unsigned long long>(r.counts.unresolved),
                static_cast<unsigned long long>(r.counts.invalid));
  out += line;
  out += corrections_line(r.counts.corrections);
  auto chi_line = [&](const char* against, const ChiSquare& c) {
    std::snprintf(line, sizeof line, "chi-square vs %s: %.2f on %d dof, p = %.3g\n", against, c.statistic, c.dof, c.p_value);
    out += line;
  };
  const std::vector<AlikeTest> tests = alike_tests(r);
  const auto fair = chi2_fair(r, tests);
  if (fair) {
    chi_line("a fair die (every outcome alike by its symmetry)", *fair);
  } else if (const auto coin = chi2_heads_tails(tests)) {
    chi_line("a fair coin (heads = tails, edge landings left out)", *coin);
  } else if (!tests.empty()) {
    out += "chi-square within the outcomes alike by the die's symmetry (equal by design; the groups are not alike):\n";
    for (const AlikeTest& t : tests) {
      std::snprintf(line, sizeof line, "  %-24s %.2f on %d dof, p = %.3g\n", labels_text(t.labels).c_str(), t.chi.statistic,
                    t.chi.dof, t.chi.p_value);
      out += line;
    }
  } else if (r.alike.empty()) {
    out += "no chi-square test: which outcomes are alike by design is not known here (the run's model is not at hand)\n";
  } else {
    out += "no chi-square test: no two outcomes are alike by design (" + r.alike_note + ")\n";
  }
  std::snprintf(line, sizeof line, "%.3f s, %.0f tosses/s, %.2f impacts per toss\n", r.elapsed_s, rate(r),
                r.tosses ? static_cast<double>(r.counts.bounces) / static_cast<double>(r.tosses) : 0.0);
  out += line;
  return out;
}

nlohmann::json pilot_json(const FidelityPilot& p) {
  if (!p.ran) return nullptr;
  nlohmann::json c = nlohmann::json::array();
  for (const PilotCandidate& k : p.candidates)
    c.push_back({{"model", to_string(k.model)}, {"pairs", k.pairs}, {"differing", k.differing}, {"bound", k.bound},
                 {"adequate", k.adequate}});
  return {{"seed", p.seed},           {"halfwidth", p.halfwidth}, {"precision", p.precision}, {"fraction", p.fraction},
          {"threshold", p.threshold}, {"max_pairs", p.max_pairs}, {"cap", p.cap},             {"tosses", p.tosses},
          {"seconds", p.seconds},     {"candidates", c}};
}

namespace {
std::string format_seconds(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g s", s);
  return b;
}
}  // namespace

std::string pilot_line(const FidelityPilot& p, const std::string& chosen) {
  if (!p.ran) return {};
  std::string out = "auto chose " + chosen + ": pilot of " + std::to_string(p.tosses) + " tosses (" +
                    format_seconds(p.seconds) + ")";
  char b[200];
  for (const PilotCandidate& k : p.candidates) {
    std::snprintf(b, sizeof b, "; %s differed from impulse in %llu of %llu pairs, bias <= %.3g%s", to_string(k.model),
                  static_cast<unsigned long long>(k.differing), static_cast<unsigned long long>(k.pairs), k.bound,
                  k.adequate ? " (adequate)" : "");
    out += b;
  }
  std::snprintf(b, sizeof b, "; adequate: bias < %.3g, half the half-width %.3g\n", p.threshold, p.halfwidth);
  return out + b;
}

void set_labels(RunReport& r, const DieModel& m) {
  r.fidelity_requested = to_string(m.fidelity_requested);
  r.fidelity_reason = m.fidelity_reason;
  r.labels = m.outcome_labels;
  r.faces_per_label.assign(m.outcome_labels.size(), 0);
  if (m.world)  // several dice: the face tuples that read each outcome
    r.faces_per_label = m.world->faces_per_outcome;
  else
    for (const int k : m.face_outcome) ++r.faces_per_label[static_cast<std::size_t>(k)];
  r.names = outcome_names(m);
  r.alike = m.outcome_alike;
  r.symmetry_rotations = m.symmetry_rotations;
  r.alike_note = m.alike_note;
}

void print_report(const RunReport& r, bool json) {
  if (json)
    std::printf("%s\n", report_json(r).dump().c_str());
  else
    std::printf("%s", report_table(r).c_str());
}

}  // namespace dicesim
