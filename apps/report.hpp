// What a run prints: an aligned table for people, one JSON object for scripts.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/provenance.hpp"
#include "sim/body/die_model.hpp"
#include "sim/study/auto_pilot.hpp"
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
  // Per outcome, the index of the first outcome of its class of outcomes alike by design
  // (DieModel::outcome_alike); empty: unknown, no test. The rotations and the note say why.
  std::vector<int> alike;
  int symmetry_rotations = 1;
  std::string alike_note;
  double elapsed_s = 0.0;
  Provenance provenance;  // what made it ("provenance" in JSON, the header's lines in the table)
  // Interrupted (SIGINT/SIGTERM): `tosses` is the longest complete prefix 0..tosses-1 of the
  // `provenance.tosses` asked for, so the partial counts equal a fresh run of `tosses` tosses.
  bool partial = false;
  // How the fidelity was chosen: stated or auto and why (set_labels copies them from the model),
  // and auto's pilot (the caller sets it from resolve_auto: sim/study/auto_pilot.hpp).
  std::string fidelity_requested;
  std::string fidelity_reason;
  FidelityPilot pilot;
};

// {"scene", "fidelity", "seed", "threads", "tosses", "settled", "unresolved", "invalid",
//  "faces": [{"face", "count", "p", "ci95": [lo, hi]} (a coin's also "name": heads, tails, edge)],
//  "alike": {"groups": [[labels of outcomes alike by design], ...] (two or more each), "rotations", "note"},
//  "chi2_alike": [{"outcomes": [labels], "statistic", "dof", "p_value"}] (one per group: equal
//  probabilities within it), "chi2_uniform": the same when every outcome is alike (a fair die),
//  else null; "chi2_heads_tails": a coin's group of heads and tails (edge landings left out), else null,
//  "corrections": {"energy_clamps", "pgs_unconverged", "overlap_fixes", "fallbacks", "located_capped",
//  "support_search_capped", "rise_dropped", "contact_overlaps", "nudges"} (totals over the run; the table prints a line only when one is non-zero), "elapsed_s", "tosses_per_s"} -- p and
//  intervals over settled tosses; "partial": true when interrupted (then "tosses" is the complete
//  prefix run, "tosses_requested" what was asked), "tosses_requested", "provenance" (provenance.hpp); faces by label.
//  Outcomes not alike by design are never tested against each other (sim/body/symmetry.hpp says
//  when they are alike).
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
// Fills labels and faces_per_label from the model, and fidelity_requested and fidelity_reason.
void set_labels(RunReport& r, const DieModel& m);
// auto's pilot: {"seed", "halfwidth", "precision", "fraction", "threshold", "max_pairs", "cap", "tosses",
// "seconds", "candidates": [{"model", "pairs", "differing", "bound", "adequate"}]}, or null when none ran.
nlohmann::json pilot_json(const FidelityPilot& p);
// One line for a table's header: "auto chose paper: pilot of ..." (empty when no pilot ran).
std::string pilot_line(const FidelityPilot& p, const std::string& chosen);
std::string report_table(const RunReport& r);
// Prints the run on stdout: one JSON object (json) or the table.
void print_report(const RunReport& r, bool json);

}  // namespace dicesim
