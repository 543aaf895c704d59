#include "apps/fit_json.hpp"

#include <cmath>

namespace dicesim {

namespace {
nlohmann::json num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }
nlohmann::json chi2(const ChiSquare& c) {
  return {{"statistic", num(c.statistic)}, {"dof", c.dof}, {"p_value", num(c.p_value)}};
}
}  // namespace

nlohmann::json fit_json(const FitResult& r, const FitOptions& opt) {
  nlohmann::json params = nlohmann::json::array();
  for (const FitParamResult& p : r.params)
    params.push_back({{"key", p.key},
                      {"estimate", num(p.estimate)},
                      {"ci95", {num(p.ci95.lo), num(p.ci95.hi)}},
                      {"range", {num(p.lo), num(p.hi)}},
                      {"ci95_open", {p.lo_open, p.hi_open}},
                      {"ci95_profile", {num(p.ci95_profile.lo), num(p.ci95_profile.hi)}},
                      {"mc_sd", num(p.mc_sd)},
                      {"mc_large", p.mc_large},
                      {"fisher_halfwidth", num(p.fisher_halfwidth)}});
  // "fitted": one entry per outcome of every data set (with several, "data" tells them apart).
  nlohmann::json fitted = nlohmann::json::array(), data = nlohmann::json::array();
  for (std::size_t s = 0; s < r.data.size(); ++s) {
    const FitDataResult& d = r.data[s];
    for (std::size_t k = 0; k < d.labels.size(); ++k)
      fitted.push_back({{"label", d.labels[k]}, {"p", num(d.fitted[k])}, {"observed", d.observed[k]}, {"data", s}});
    data.push_back({{"scene", d.scene}, {"counts", d.source}, {"fitted_tosses", d.fitted_tosses}, {"gof", chi2(d.gof)}});
  }
  nlohmann::json rounds = nlohmann::json::array();
  for (const FitRound& fr : r.rounds)
    rounds.push_back({{"box_lo", fr.box_lo}, {"box_hi", fr.box_hi}, {"points", fr.points},
                      {"tosses_per_point", fr.tosses_per_point}, {"estimate", fr.estimate}});
  return {{"params", params},
          {"fitted", fitted},
          {"gof", chi2(r.gof)},
          {"data", data},
          {"loglik", num(r.loglik)},
          {"fidelity", r.fidelity},
          {"seed", opt.seed},
          {"rounds", rounds},
          {"simulated_tosses", r.simulated_tosses},
          {"elapsed_s", r.elapsed_s}};
}

}  // namespace dicesim
