// What a run prints: an aligned table for people, one JSON object for scripts.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sim/body/die_model.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/study/statistics.hpp"

namespace dicesim {

struct RunReport {
  std::string scene;
  std::string fidelity;
  std::uint64_t seed = 0;
  int threads = 1;
  std::uint64_t tosses = 0;
  RunCounts counts;
  std::vector<int> labels;          // label of each counts.faces entry (the model's outcome_labels)
  std::vector<int> faces_per_label; // faces showing each label (empty: one each); a fair die's expectation
  // Per outcome (counts.faces order), a coin's side names: "heads", "tails", "edge" ("heads/tails"
  // when labels group them). Empty for a die.
  std::vector<std::string> names;
  double elapsed_s = 0.0;
};

// {"scene", "fidelity", "seed", "threads", "tosses", "settled", "unresolved", "invalid",
//  "faces": [{"face", "count", "p", "ci95": [lo, hi]} (a coin's also "name": heads, tails, edge)], "chi2_uniform": {"statistic", "dof", "p_value"},
//  "chi2_heads_tails": a coin's heads against tails, edge landings left out (1 dof; null for a die),
//  "corrections": {"energy_clamps", "pgs_unconverged", "overlap_fixes", "fallbacks", "located_capped",
//  "support_search_capped", "rise_dropped", "depth_held", "nudges"} (totals over the run; the table
//  prints a line only when one is non-zero), "elapsed_s", "tosses_per_s"} -- p and
//  intervals over settled tosses, faces by label (N outcomes; chi-square on N - 1 dof against every
//  face equally likely, grouped labels weighted by their faces).
nlohmann::json report_json(const RunReport& r);
// A number, or null when it is not finite (JSON has no NaN or infinity; Python then sees None).
nlohmann::json json_number(double v);
// {"statistic", "dof", "p_value"}: every command's chi-square test, written one way.
nlohmann::json chi2_json(const ChiSquare& c);
// Every kind of RunCorrections by name (corrections.hpp for_each): the run's totals (toss, run, sweep points).
nlohmann::json corrections_json(const RunCorrections& k);
// "corrections: N energy clamps, ... M nudges (each should be 0: ...)", or "" when all are 0 (the
// four repairs of the law always, the sustained phase's guards when non-zero).
std::string corrections_line(const RunCorrections& k);
// Fills labels and faces_per_label from the model.
void set_labels(RunReport& r, const DieModel& m);
std::string report_table(const RunReport& r);
// Prints the run on stdout: one JSON object (json) or the table.
void print_report(const RunReport& r, bool json);

}  // namespace dicesim
