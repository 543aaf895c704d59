// What a run prints: an aligned table for people, one JSON object for scripts.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "sim/body/die_model.hpp"
#include "sim/study/monte_carlo.hpp"

namespace dicesim {

struct RunReport {
  std::string scene;
  std::string fidelity;
  std::uint64_t seed = 0;
  int threads = 1;
  std::uint64_t tosses = 0;
  RunCounts counts;
  std::array<int, 6> labels{};  // face label per face index
  double elapsed_s = 0.0;
};

// {"scene", "fidelity", "seed", "threads", "tosses", "settled", "unresolved", "invalid",
//  "faces": [{"face", "count", "p", "ci95": [lo, hi]}], "chi2_uniform": {"statistic", "p_value"},
//  "corrections": {"energy_clamps", "pgs_unconverged", "overlap_fixes", "fallbacks"} (totals over
//  the run; the table prints a line only when one is non-zero), "elapsed_s", "tosses_per_s"} -- p and intervals over settled tosses, faces by label.
nlohmann::json report_json(const RunReport& r);
std::string report_table(const RunReport& r);
// Prints the run on stdout: one JSON object (json) or the table.
void print_report(const RunReport& r, bool json);

}  // namespace dicesim
