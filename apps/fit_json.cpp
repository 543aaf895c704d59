#include "apps/fit_json.hpp"

#include "apps/report.hpp"
#include "sim/scene/scene_hash.hpp"

namespace dicesim {

Provenance fit_provenance(const std::string& scene, const FitOptions& opt, const std::string& fidelity,
                          const std::string& fidelity_reason, const std::vector<std::string>& own) {
  Provenance p;
  p.scene = scene;
  p.overrides = opt.overrides;
  p.overrides.insert(p.overrides.end(), own.begin(), own.end());
  try {
    p.scene_sha256 = scene_sha256(scene, p.overrides);
  } catch (const std::exception&) {  // not a file (a scene given as text): its hash is unknown
  }
  p.fidelity = fidelity;
  p.fidelity_reason = fidelity_reason;
  p.seed = opt.seed;
  p.tosses = opt.tosses;
  p.threads = opt.threads;
  return p;
}

nlohmann::json fit_json(const FitResult& r, const FitOptions& opt) {
  nlohmann::json params = nlohmann::json::array();
  for (const FitParamResult& p : r.params)
    params.push_back({{"key", p.key},
                      {"estimate", json_number(p.estimate)},
                      {"ci95", {json_number(p.ci95.lo), json_number(p.ci95.hi)}},
                      {"range", {json_number(p.lo), json_number(p.hi)}},
                      {"ci95_open", {p.lo_open, p.hi_open}},
                      {"ci95_profile", {json_number(p.ci95_profile.lo), json_number(p.ci95_profile.hi)}},
                      {"mc_sd", json_number(p.mc_sd)},
                      {"mc_large", p.mc_large},
                      {"fisher_halfwidth", json_number(p.fisher_halfwidth)},
                      {"box", {json_number(p.box_lo), json_number(p.box_hi)}},
                      {"identifiable", p.identifiable},
                      {"shift_z", json_number(p.shift_z)},
                      {"shift_z_level", json_number(p.shift_z_level)}});
  for (std::size_t i = 0; i < r.params.size(); ++i)
    if (!r.params[i].identifiable)
      params[i]["note"] = "not identifiable from these data: over its range it moves no outcome's probability by more "
                          "than the Monte Carlo noise";
  // "fitted": one entry per outcome of every data set (with several, "data" tells them apart).
  nlohmann::json fitted = nlohmann::json::array(), data = nlohmann::json::array();
  for (std::size_t s = 0; s < r.data.size(); ++s) {
    const FitDataResult& d = r.data[s];
    for (std::size_t k = 0; k < d.labels.size() && k < d.fitted.size(); ++k) {
      fitted.push_back({{"label", d.labels[k]}, {"p", json_number(d.fitted[k])}, {"observed", d.observed[k]}, {"data", s}});
      if (k < d.names.size()) fitted.back()["name"] = d.names[k];  // a coin's side
    }
    // Each data set's own scene as it was simulated (every data set's overrides, then its own): the
    // top-level provenance names the first only.
    std::vector<std::string> overrides = opt.overrides;
    overrides.insert(overrides.end(), d.overrides.begin(), d.overrides.end());
    nlohmann::json sha = nullptr;
    try {
      sha = scene_sha256(d.scene, overrides);
    } catch (const std::exception&) {  // not a file: its hash is unknown
    }
    data.push_back({{"scene", d.scene},
                    {"overrides", overrides},
                    {"scene_sha256", sha},
                    {"counts", d.source},
                    {"fitted_tosses", d.fitted_tosses},
                    {"gof", chi2_json(d.gof)}});
  }
  nlohmann::json rounds = nlohmann::json::array();
  for (const FitRound& fr : r.rounds)
    rounds.push_back({{"box_lo", fr.box_lo}, {"box_hi", fr.box_hi}, {"widened", fr.widened}, {"points", fr.points},
                      {"tosses_per_point", fr.tosses_per_point}, {"estimate", fr.estimate}});
  return {{"params", params},
          {"estimated", r.estimated},
          {"fitted", fitted},
          {"gof", chi2_json(r.gof)},
          {"data", data},
          {"loglik", json_number(r.loglik)},
          {"fidelity", r.fidelity},
          {"fidelity_reason", r.fidelity_reason},
          {"seed", opt.seed},
          {"rounds", rounds},
          {"simulated_tosses", r.simulated_tosses},
          {"elapsed_s", r.elapsed_s},
          {"partial", false},
          {"provenance", provenance_json(fit_provenance(r.data.empty() ? "" : r.data.front().scene, opt, r.fidelity,
                                                         r.fidelity_reason,
                                                         r.data.empty() ? std::vector<std::string>{} : r.data.front().overrides))}};
}

}  // namespace dicesim
