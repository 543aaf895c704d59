// What `dicesim power` prints: a table for people, one JSON object for scripts. Shared by the CLI
// and the Python module (dicesim.power returns this JSON as a dict), so it lives in dicesim_report.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/provenance.hpp"
#include "sim/study/power.hpp"

namespace dicesim {

struct PowerRunInfo {
  std::string scene;            // H0's scene
  std::string against;          // the thrown die's scene (--against), else empty
  std::string fidelity;         // of the scene
  std::string fidelity_against; // of the other scene (--against)
  std::uint64_t seed = 1;
  int threads = 1;
  PowerStudyConfig config;      // tosses, batches, bootstrap, alpha, power, replicates
  double elapsed_s = 0.0;
  Provenance provenance;        // of the scene (H0); "tosses" per scene
  std::string against_sha256;   // the other scene's resolved hash (--against), else empty
};

// Level at which the simulated difference of two scenes is called significant (below it, n is
// mostly the simulation's noise: a warning on stderr and "significant": false).
inline constexpr double kPowerDifferenceLevel = 0.05;

// One object for both modes:
// {"mode": "against" | "detect_bias", "scene", "against" (or null), "detect_bias" (delta or null),
//  "fidelity", "fidelity_against" (or null), "seed", "threads", "tosses" (per scene), "simulated_tosses",
//  "batches", "bootstrap", "replicates", "alpha", "power", "labels", "dof",
//  "settled_a", "p_a", "p_a_ci95": [[lo, hi]...], and with --against "settled_b", "p_b", "p_b_ci95",
//  "w2" (sum (p_b - p_a)^2 / p_a; null if infinite), "difference": {"statistic", "dof", "p_value",
//  "significant"};
//  "provenance" (apps/provenance.hpp), "against_sha256" (or null), "partial": false (an interrupted
//  `dicesim power` prints {"partial": true, "state", "provenance"} instead: cmd_power.cpp),
//  "n_approx", "n_exact", "n_range95": [lo, hi] (n_exact scaled by the bootstrap quantiles of the
//  approximate n), "n_range95_approx" (those quantiles), "n_exact_replicate_sd" (null n: not
//  reached by 2^40 throws),
//  "exact": {"n", "power", "size", "critical", "evaluations"} (the simulated test at n_exact),
//  with --detect-bias "hardest": {"face", "sign"} and "alternatives": [{"face", "sign", "p_face", "w2",
//  "n_approx", "n_exact", "power_at_n"}], and "elapsed_s"}.
nlohmann::json power_json(const PowerRunInfo& info, const AgainstStudy& s);
nlohmann::json power_json(const PowerRunInfo& info, const BiasStudy& s);
std::string power_table(const PowerRunInfo& info, const AgainstStudy& s);
std::string power_table(const PowerRunInfo& info, const BiasStudy& s);

}  // namespace dicesim
