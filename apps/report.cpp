#include "apps/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "sim/body/outcome.hpp"
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

// Against every face equally likely: outcome k expected in proportion to its number of faces.
ChiSquare chi2_fair(const RunReport& r) {
  if (r.faces_per_label.size() != r.counts.faces.size()) return chi2_uniform(r.counts.faces);
  double faces = 0.0;
  for (int k : r.faces_per_label) faces += k;
  std::vector<double> p;
  for (int k : r.faces_per_label) p.push_back(k / faces);
  return chi2_against(r.counts.faces, p);
}

// A fair coin: heads and tails equally likely. Its edge landings are a matter of thickness, not of
// fairness, so they are left out (uniform over heads, tails and edge is no coin's expectation).
// Needs heads and tails each alone in its outcome: a grouped side ("heads/edge") has no test.
std::optional<ChiSquare> chi2_heads_tails(const RunReport& r) {
  const auto heads = std::find(r.names.begin(), r.names.end(), "heads");
  const auto tails = std::find(r.names.begin(), r.names.end(), "tails");
  if (heads == r.names.end() || tails == r.names.end() || r.names.size() != r.counts.faces.size()) return std::nullopt;
  const std::uint64_t two[2] = {r.counts.faces[static_cast<std::size_t>(heads - r.names.begin())],
                                r.counts.faces[static_cast<std::size_t>(tails - r.names.begin())]};
  return chi2_uniform(two);
}

double rate(const RunReport& r) { return r.elapsed_s > 0.0 ? static_cast<double>(r.tosses) / r.elapsed_s : 0.0; }

}  // namespace

nlohmann::json corrections_json(const RunCorrections& k) {
  return {{"energy_clamps", k.energy_clamps},
          {"pgs_unconverged", k.pgs_unconverged},
          {"overlap_fixes", k.overlap_fixes},
          {"fallbacks", k.fallbacks}};
}

std::string corrections_line(const RunCorrections& k) {
  if (!k.any()) return {};
  char line[320];
  std::snprintf(line, sizeof line,
                "corrections: %llu energy clamps, %llu unconverged contact solves, %llu overlap fixes, %llu fallbacks "
                "(each should be 0: the physics was repaired)\n",
                static_cast<unsigned long long>(k.energy_clamps), static_cast<unsigned long long>(k.pgs_unconverged),
                static_cast<unsigned long long>(k.overlap_fixes), static_cast<unsigned long long>(k.fallbacks));
  return line;
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
  const ChiSquare chi = chi2_fair(r);
  const auto coin = chi2_heads_tails(r);
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
          {"chi2_uniform", chi2_json(chi)},
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
    std::snprintf(line, sizeof line, "interrupted after %llu of %llu tosses (a complete prefix: the same counts as -n %llu)\n",
                  static_cast<unsigned long long>(r.tosses), static_cast<unsigned long long>(r.provenance.tosses),
                  static_cast<unsigned long long>(r.tosses));
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
  const auto coin = chi2_heads_tails(r);
  if (coin) chi_line("a fair coin (heads = tails, edge landings left out)", *coin);
  chi_line(coin ? "heads, tails and edge equally likely" : "a fair die", chi2_fair(r));
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
  for (const int k : m.face_outcome) ++r.faces_per_label[static_cast<std::size_t>(k)];
  r.names = outcome_names(m);
}

void print_report(const RunReport& r, bool json) {
  if (json)
    std::printf("%s\n", report_json(r).dump().c_str());
  else
    std::printf("%s", report_table(r).c_str());
}

}  // namespace dicesim
