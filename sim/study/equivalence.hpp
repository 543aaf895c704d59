// Are two results the same to within a margin? Equivalence tests (TOST: two one-sided tests) per
// outcome, Holm-corrected across outcomes (issue 39: convergence shown by a verdict, not by "inside
// its own interval", which a small run passes by having wide intervals).
//
// Per outcome i, with d = p_a - p_b and a margin delta > 0: H0: |d| >= delta against H1: |d| < delta,
// rejected when both one-sided tests reject at level alpha: H0-: d <= -delta and H0+: d >= delta.
// Normal approximation with the unpooled (Wald) standard error se = sqrt(p_a q_a / n_a + p_b q_b / n_b):
// p- = 1 - Phi((d + delta) / se), p+ = Phi((d - delta) / se), the outcome's p = max(p-, p+). Equivalent
// to the (1 - 2 alpha) interval d -+ z se lying inside (-delta, delta). Wald is adequate at the sizes
// this is meant for (n p >~ 10 in both runs; 3e5 tosses of a d20 give n p ~ 15 000); an outcome that
// neither run ever saw (se = 0) has d = 0 exactly and is equivalent for any delta > 0.
// Across the k outcomes the p's are Holm-adjusted (step-down: the j-th smallest times k - j + 1,
// made monotone, capped at 1), which controls the family-wise error: the overall verdict
// "equivalent" (every outcome's adjusted p <= alpha) is wrong with probability <= alpha whatever
// the dependence between outcomes.
//
// Paired tosses (the same seed and toss indices in both runs): each toss gives a difference
// D_t = [outcome of A is i] - [outcome of B is i] in {-1, 0, 1}; its mean is d and its variance is
// estimated from the discordant counts (b_i: A is i and B is not; c_i: B is i and A is not):
// var D = (b_i + c_i) / n - d^2, se = sqrt(var D / n). Positively correlated pairs (the usual case:
// a small change of the integrator leaves most tosses' outcomes alone) make this se much smaller
// than the unpooled one; the unpaired test is then valid but conservative. (The normal
// approximation wants a fair number of discordant tosses; with very few the interval is narrow
// because the runs barely differ: |d| <= (b_i + c_i) / n holds exactly.)
// Pure computation: nothing here prints.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "sim/study/statistics.hpp"

namespace dicesim {

// The margin of outcome i given its pooled proportion p = (x_a + x_b) / (n_a + n_b).
using Margin = std::function<double(double p)>;
inline Margin absolute_margin(double delta) {
  return [delta](double) { return delta; };
}
// rel * p, p the pooled proportion (e.g. |delta edge| <= 0.2 p_edge).
inline Margin relative_margin(double rel) {
  return [rel](double p) { return rel * p; };
}

struct OutcomeEquivalence {
  double p_a = 0.0, p_b = 0.0;
  double diff = 0.0;        // p_a - p_b
  double se = 0.0;          // of diff (unpooled or paired)
  double margin = 0.0;      // delta of this outcome
  Interval ci;              // (1 - 2 alpha) interval of diff: inside (-margin, margin) iff tost_p < alpha
  double p_lower = 1.0;     // H0-: diff <= -margin
  double p_upper = 1.0;     // H0+: diff >= margin
  double tost_p = 1.0;      // max(p_lower, p_upper)
  double holm_p = 1.0;      // Holm-adjusted across the outcomes
  bool equivalent = false;  // holm_p <= alpha
};

struct Equivalence {
  double alpha = 0.10;
  bool paired = false;
  std::vector<OutcomeEquivalence> outcomes;  // in the input's order
  bool equivalent = false;                   // every outcome equivalent after Holm
};

// One outcome's TOST from its difference, standard error and margin (alpha sets ci only).
OutcomeEquivalence tost(double diff, double se, double margin, double alpha);

// Holm's step-down adjustment of p-values (same order as given).
std::vector<double> holm_adjust(const std::vector<double>& p);

// Two independent runs: counts a (n_a = sum a tosses) and b over the same outcomes, in the same
// order. Throws std::invalid_argument for different lengths, an empty run, a margin <= 0 or alpha
// outside (0, 0.5).
Equivalence equivalence_unpaired(const std::vector<std::uint64_t>& a, const std::vector<std::uint64_t>& b,
                                 const Margin& margin, double alpha = 0.10);

// Two runs over the same n toss indices: counts a and b (each summing to n) and, per outcome, the
// discordant counts a_only[i] (A gave i, B did not) and b_only[i] (B gave i, A did not); necessarily
// a[i] - b[i] == a_only[i] - b_only[i] (checked).
// Two runs' per-toss outcomes over the same toss indices (index i of both is toss i; an outcome
// index in [0, outcomes), or -1 for a toss that did not settle): the counts equivalence_paired
// takes, over the tosses settled in both (`dropped`: the others).
struct PairedCounts {
  std::vector<std::uint64_t> a, b, a_only, b_only;
  std::uint64_t pairs = 0, dropped = 0;
};
// Throws std::invalid_argument for different lengths or an index outside [-1, outcomes).
PairedCounts paired_counts(const std::vector<std::int16_t>& a, const std::vector<std::int16_t>& b, int outcomes);

Equivalence equivalence_paired(const std::vector<std::uint64_t>& a, const std::vector<std::uint64_t>& b,
                               const std::vector<std::uint64_t>& a_only, const std::vector<std::uint64_t>& b_only,
                               const Margin& margin, double alpha = 0.10);

}  // namespace dicesim
