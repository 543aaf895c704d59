// The JSON of a fit: what `dicesim fit --json` prints and what Python's dicesim.fit returns.
#pragma once

#include <nlohmann/json.hpp>

#include "sim/study/fit.hpp"

namespace dicesim {

// {"params": [{"key", "estimate", "ci95": [lo, hi], ...}], "fitted": [{"label", "p", ...}],
//  "gof": {"statistic", "dof", "p_value"}, "simulated_tosses", "elapsed_s", ...}. NaN -> null.
nlohmann::json fit_json(const FitResult& r, const FitOptions& opt);

}  // namespace dicesim
