#include "apps/power_report.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "apps/report.hpp"

namespace dicesim {
namespace {

using nlohmann::json;

json opt(const std::optional<std::uint64_t>& n) { return n ? json(*n) : json(nullptr); }

json intervals(const std::vector<Interval>& ci) {
  json a = json::array();
  for (const Interval& i : ci) a.push_back({i.lo, i.hi});
  return a;
}

json exact_json(const ExactN& e) {
  return {{"n", opt(e.n)},          {"power", e.at.power},           {"size", e.at.size},
          {"critical", json_number(e.at.critical)}, {"evaluations", e.evaluations}};
}

json common(const PowerRunInfo& info, const std::vector<int>& labels, const SimulatedDie& a, int dof,
            const PowerEstimate& est, std::uint64_t simulated) {
  const PowerStudyConfig& c = info.config;
  return {{"scene", info.scene},
          {"fidelity", info.fidelity},
          {"seed", info.seed},
          {"threads", info.threads},
          {"tosses", c.tosses},
          {"simulated_tosses", simulated},
          {"batches", c.batches},
          {"bootstrap", c.bootstrap},
          {"replicates", c.target.replicates},
          {"alpha", c.target.alpha},
          {"power", c.target.power},
          {"labels", labels},
          {"dof", dof},
          {"settled_a", a.counts.settled},
          {"p_a", a.p},
          {"p_a_ci95", intervals(a.ci95)},
          {"n_approx", opt(est.n_approx)},
          {"n_exact", opt(est.exact.n)},
          {"n_range95", {opt(est.n_range95[0]), opt(est.n_range95[1])}},
          {"n_range95_approx", {opt(est.n_range95_approx[0]), opt(est.n_range95_approx[1])}},
          {"n_exact_replicate_sd", est.replicate_sd},
          {"exact", exact_json(est.exact)},
          {"elapsed_s", info.elapsed_s},
          {"partial", false},
          {"against_sha256", info.against_sha256.empty() ? json(nullptr) : json(info.against_sha256)},
          {"provenance", provenance_json(info.provenance)}};
}

std::string format(const char* f, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, f);
  std::vsnprintf(buf, sizeof buf, f, ap);
  va_end(ap);
  return buf;
}

std::string n_text(const std::optional<std::uint64_t>& n) {
  return n ? std::to_string(*n) : std::string("not reached (no difference, or > 2^40)");
}

std::string head(const PowerRunInfo& info) {
  const PowerStudyConfig& c = info.config;
  return format("seed %llu, %llu tosses per scene (the same indices: common random numbers), %d thread%s\n",
                static_cast<unsigned long long>(info.seed), static_cast<unsigned long long>(c.tosses), info.threads,
                info.threads == 1 ? "" : "s");
}

std::string verdict(const PowerRunInfo& info, const PowerEstimate& e, int dof, const char* what) {
  const PowerStudyConfig& c = info.config;
  std::string t = format("\nthrows a chi-square goodness-of-fit test (%d dof) needs at alpha = %g for power %g%s:\n", dof,
                         c.target.alpha, c.target.power, what);
  t += format("  exact (simulated counts, %llu replicates):  %s", static_cast<unsigned long long>(c.target.replicates),
              n_text(e.exact.n).c_str());
  if (e.exact.n)
    t += format(" +/- %.0f   (at n: power %.3f, size %.3f, critical value %.3f)", e.replicate_sd, e.exact.at.power,
                e.exact.at.size, e.exact.at.critical);
  t += format("\n  noncentral chi-square approximation:       %s\n", n_text(e.n_approx).c_str());
  t += format("  95%% range from the tosses' own noise:      [%s, %s]  (bootstrap of %d batches, %d resamples)\n",
              n_text(e.n_range95[0]).c_str(), n_text(e.n_range95[1]).c_str(), c.batches, c.bootstrap);
  if (e.exact.n)
    t += format("  (+/- : the exact n's sd from its %llu replicates alone; the range: from the tosses alone)\n",
                static_cast<unsigned long long>(c.target.replicates));
  t += format("%.2f s\n", info.elapsed_s);
  return t;
}

}  // namespace

json power_json(const PowerRunInfo& info, const AgainstStudy& s) {
  json j = common(info, s.labels, s.a, s.dof, s.estimate, s.simulated_tosses);
  j["mode"] = "against";
  j["against"] = info.against;
  j["detect_bias"] = nullptr;
  j["fidelity_against"] = info.fidelity_against;
  j["settled_b"] = s.b.counts.settled;
  j["p_b"] = s.b.p;
  j["p_b_ci95"] = intervals(s.b.ci95);
  j["w2"] = json_number(s.w2);
  j["difference"] = {{"statistic", s.difference.statistic},
                     {"dof", s.difference.dof},
                     {"p_value", s.difference.p_value},
                     {"significant", s.difference.p_value < kPowerDifferenceLevel}};
  return j;
}

json power_json(const PowerRunInfo& info, const BiasStudy& s) {
  json j = common(info, s.labels, s.a, s.dof, s.estimate, s.simulated_tosses);
  j["mode"] = "detect_bias";
  j["against"] = nullptr;
  j["detect_bias"] = s.delta;
  j["fidelity_against"] = nullptr;
  json alts = json::array();
  for (const BiasAlternative& a : s.alternatives)
    alts.push_back({{"face", a.label},
                    {"sign", a.sign},
                    {"p_face", a.p[a.face]},
                    {"w2", json_number(a.w2)},
                    {"n_approx", opt(a.n_approx)},
                    {"n_exact", opt(a.exact.n)},
                    {"power_at_n", a.exact.at.power}});
  j["alternatives"] = alts;
  const BiasAlternative& h = s.alternatives.at(s.hardest);
  // n_exact_selecting: the search that made it the hardest; n_exact above is its fresh search.
  j["hardest"] = {{"face", h.label}, {"sign", h.sign}, {"n_exact_selecting", opt(h.exact.n)}, {"refreshed", s.refreshed}};
  return j;
}

std::string power_table(const PowerRunInfo& info, const AgainstStudy& s) {
  std::string t = format("H0:     %s  (fidelity %s)\nthrown: %s  (fidelity %s)\n", info.scene.c_str(), info.fidelity.c_str(),
                         info.against.c_str(), info.fidelity_against.c_str());
  t += provenance_lines(info.provenance);
  if (!info.against_sha256.empty()) t += "thrown scene sha256 " + info.against_sha256 + "\n";
  t += head(info);
  t += "\nface    p H0     95% interval          p thrown  95% interval         difference\n";
  for (std::size_t k = 0; k < s.labels.size(); ++k)
    t += format("%4d   %.5f  [%.5f, %.5f]     %.5f  [%.5f, %.5f]   %+.5f\n", s.labels[k], s.a.p[k], s.a.ci95[k].lo,
                s.a.ci95[k].hi, s.b.p[k], s.b.ci95[k].lo, s.b.ci95[k].hi, s.b.p[k] - s.a.p[k]);
  t += format("settled: %llu and %llu\n", static_cast<unsigned long long>(s.a.counts.settled),
              static_cast<unsigned long long>(s.b.counts.settled));
  const bool sig = s.difference.p_value < kPowerDifferenceLevel;
  t += format("\nthe simulated dice differ: chi-square %.2f on %d dof, p = %.3g -> %s\n", s.difference.statistic,
              s.difference.dof, s.difference.p_value,
              sig ? "significant" : "NOT significant: n below mostly measures the simulation's noise");
  t += format("effect w2 = sum (p thrown - p H0)^2 / p H0 = %.6g\n", s.w2);
  return t + verdict(info, s.estimate, s.dof, "");
}

std::string power_table(const PowerRunInfo& info, const BiasStudy& s) {
  std::string t = format("H0:     %s  (fidelity %s)\n", info.scene.c_str(), info.fidelity.c_str());
  t += provenance_lines(info.provenance);
  t += head(info);
  t += format("alternatives: one face moved by +/-%g, the others rescaled in proportion\n", s.delta);
  t += "\nface    p H0     95% interval        sign   p face   n approx    n exact  power at n\n";
  for (std::size_t k = 0; k < s.labels.size(); ++k) {
    bool first = true;
    for (std::size_t i = 0; i < s.alternatives.size(); ++i) {
      const BiasAlternative& a = s.alternatives[i];
      if (a.face != k) continue;
      const std::string left = first ? format("%4d   %.5f  [%.5f, %.5f]", s.labels[k], s.a.p[k], s.a.ci95[k].lo, s.a.ci95[k].hi)
                                     : std::string(37, ' ');
      t += format("%s    %c    %.5f %10s %10s    %.3f%s\n", left.c_str(), a.sign > 0 ? '+' : '-', a.p[k],
                  a.n_approx ? std::to_string(*a.n_approx).c_str() : "-", a.exact.n ? std::to_string(*a.exact.n).c_str() : "-",
                  a.exact.at.power, i == s.hardest ? "   <- hardest" : "");
      first = false;
    }
  }
  const BiasAlternative& h = s.alternatives.at(s.hardest);
  if (s.refreshed && s.estimate.exact.n)
    t += format("the hardest searched again on %llu fresh replicates (a maximum over searches is biased up): n exact %llu\n",
                static_cast<unsigned long long>(info.config.target.replicates),
                static_cast<unsigned long long>(*s.estimate.exact.n));
  return t + verdict(info, s.estimate, s.dof,
                     format(" against every alternative (hardest: face %d moved by %c%g)", h.label, h.sign > 0 ? '+' : '-',
                            s.delta)
                         .c_str());
}

}  // namespace dicesim
