// The JSON of a fit: what `dicesim fit --json` prints and what Python's dicesim.fit returns.
#pragma once

#include <nlohmann/json.hpp>

#include "apps/provenance.hpp"
#include "sim/study/fit.hpp"

namespace dicesim {

// {"params": [{"key", "estimate", "ci95": [lo, hi], ...}], "fitted": [{"label", "p", ...}],
//  "gof": {"statistic", "dof", "p_value"}, "simulated_tosses", "elapsed_s", ...}. NaN -> null.
// "provenance" (apps/provenance.hpp): the first data set's scene with opt.overrides and its own (not
// the fitted keys), "tosses" the last round's per grid point (opt.tosses; 0: automatic). Each entry
// of "data" names its own scene, "overrides" and "scene_sha256" (a joint fit's other scenes).
nlohmann::json fit_json(const FitResult& r, const FitOptions& opt);
// `own`: the data set's own overrides, applied after opt.overrides (FitData::overrides).
Provenance fit_provenance(const std::string& scene, const FitOptions& opt, const std::string& fidelity,
                          const std::string& fidelity_reason, const std::vector<std::string>& own = {});

}  // namespace dicesim
