// From counts back to the die: scene parameters fitted to observed tosses by simulation-based
// maximum likelihood.
//
// The observed counts n_k of a data set are multinomial with the die's outcome probabilities
// p_k(theta), theta = one to three numeric scene keys. p(theta) is known only by simulation, so:
//  1. Design: a grid over a box of theta; every point is tossed with the same seed and toss
//     indices (common random numbers: two points differ only through theta, so the estimates are
//     smooth in theta and their differences precise).
//  2. Surrogate: per data set and outcome, log p_k(theta) is fitted by a polynomial (weighted
//     least squares, weights from each point's binomial variance); p~ = softmax of the fits.
//  3. Likelihood: l(theta) = sum over data sets and outcomes of n_k log p~_k(theta); the estimate
//     maximises it over the box, and each parameter's 95% interval is where its profile
//     (the others maximised) is within chi2_1(0.95)/2 = 1.92 of the maximum.
//  4. Adaptive: the next round's box is the interval widened 2.5x (clipped to LO..HI) with twice
//     the tosses, so the last surrogate is local and precise; `rounds` rounds in all.
//  5. Monte Carlo error: each point's tosses are split into batches of consecutive indices; the
//     estimate is refitted without each batch in turn (a jackknife that keeps the common random
//     numbers: the same batch leaves every point), and its standard deviation is added to the
//     interval in quadrature.
// The fitted probabilities are then simulated at the estimate, with Pearson's chi-square of the
// counts against them. Randomness comes only from (seed, toss index): the same inputs give the
// same fit on any number of threads. Pure computation: nothing here prints.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/study/compare.hpp"
#include "sim/study/shard.hpp"
#include "sim/study/statistics.hpp"

namespace dicesim {

struct FitParam {
  std::string key;  // a numeric scene key, as for --set (e.g. floor.restitution)
  double lo = 0.0;
  double hi = 1.0;
};

// "KEY=LO:HI" (LO < HI, both finite). Throws SceneError naming `origin`, "--param" and the text.
FitParam parse_fit_param(const std::string& text, const std::string& origin = "dicesim fit");

// ---- A fit sharded by point (`dicesim fit --points I/N`, `--merge`) ----
// A fit tosses in stages: each round's design (a round refitted in a widened box is a stage of its
// own), then the fitted probabilities at the estimate. A stage's points are known only once the
// stages before it are counted, so a sharded fit runs in passes: in each pass, shard I of N tosses
// its block of the first stage not yet counted (the stage's points in order -- data set s's design
// point j is s * J + j -- cut as shard_range cuts toss indices). Every point tosses indices
// 0..tosses-1 with the fit's seed whatever else is tossed, so the points given back replay the
// fit exactly: the same estimate, intervals and fitted probabilities as one unsharded fit.
struct FitPointCounts {
  int stage = 0;
  std::size_t point = 0;      // in its stage
  std::vector<double> theta;  // the fitted keys' values, in --param order
  std::uint64_t tosses = 0;
  std::vector<std::vector<std::uint64_t>> faces;  // [batch][outcome, in label order]
  std::vector<std::uint64_t> settled;             // [batch]
  std::string origin;         // where it was read (a part file), for messages
};

// Thrown by run_fit when FitOptions::given lacks a point of a stage: with toss_shard set, after
// tossing that shard's block of the stage (`tossed`: a pass's part); without, nothing tossed (a
// merge of incomplete parts).
struct FitStageIncomplete : std::runtime_error {
  FitStageIncomplete() : std::runtime_error("a stage of the sharded fit is not counted") {}
  int stage = 0;
  std::string label;                 // "round 2/3", "fitted"
  std::size_t stage_points = 0;
  std::vector<std::size_t> missing;  // points of the stage neither given nor tossed by this pass
  std::vector<FitPointCounts> tossed;
};

// One data set: observed counts of one die in one scene.
struct FitData {
  std::string scene;                   // scene file
  std::vector<std::string> overrides;  // after FitOptions::overrides
  std::string source;                  // where the counts came from, for messages (e.g. the CSV)
  FaceCounts observed;
};

struct FitOptions {
  std::vector<std::string> overrides;  // every data set's, before its own (--set, sim.fidelity)
  std::uint64_t seed = 1;
  int threads = 1;
  // Tosses per design point and data set in the last round; round r of R takes tosses / 2^(R-1-r).
  // 0: automatic, fit_auto_tosses(data).
  std::uint64_t tosses = 0;
  int rounds = 3;
  int batches = 16;  // for the Monte Carlo error (jackknife); each point's tosses in this many
  // (stage, tosses done, tosses in the whole fit), from any thread, about every few hundred tosses.
  std::function<void(const std::string&, std::uint64_t, std::uint64_t)> progress;
  const std::atomic<bool>* cancel = nullptr;  // stops at the next job: run_fit then throws
  // Sharded by point (FitPointCounts): points counted by earlier passes, taken instead of tossed
  // (their keys' values and tosses must be the fit's: SceneError naming the origin). nullptr: an
  // ordinary fit, every point tossed here. With `given`, the first stage not wholly given throws
  // FitStageIncomplete, after tossing toss_shard's block of it when toss_shard.count > 0.
  const std::vector<FitPointCounts>* given = nullptr;
  Shard toss_shard{0, 0};
};

// The automatic tosses per point: 20 per observed toss of the largest data set, at least 40 000.
// Fewer leave the surrogate noisy enough to overstate its slope, and the intervals too narrow
// (docs/fitting.md, "Coverage").
inline constexpr std::uint64_t kAutoTossesMin = 40000, kAutoTossesPerObserved = 20;
std::uint64_t fit_auto_tosses(const std::vector<FitData>& data);

// Design points per parameter and polynomial degree of the surrogate, by number of parameters.
int fit_grid_points(int params);
int fit_surrogate_degree(int params);

struct FitParamResult {
  std::string key;
  double lo = 0.0, hi = 0.0;    // the range searched
  double estimate = 0.0;
  Interval ci95;                // profile likelihood, widened by the Monte Carlo error
  Interval ci95_profile;        // the surrogate's profile likelihood alone
  double mc_sd = 0.0;           // Monte Carlo standard deviation of the estimate (jackknife)
  double fisher_halfwidth = 0;  // the ideal 95% half-width, 1.96 sqrt((I^-1)_ii), NaN if I is singular
  // The confidence set reaches the end of the box searched: the data do not bound it there. That
  // box is LO..HI, or a narrowed one that was widened as far as kFitMaxWidenings allow (box_lo,
  // box_hi: the last round's box). Never an end cut off by a narrowed box and called closed.
  bool lo_open = false;
  bool hi_open = false;
  double box_lo = 0.0, box_hi = 0.0;
  // Whether the key moves some outcome's probability by more than the Monte Carlo noise over its
  // range (round 1's design: every pair of points differing in this key alone, every outcome;
  // |difference| / its batch standard error against a Bonferroni-corrected 95% normal level).
  // false: "not identifiable from these data", no estimate or interval (NaN; the other keys are
  // fitted with it free over its range, and the ideal half-widths leave it out).
  bool identifiable = true;
  double shift_z = 0.0;         // the largest |difference| / standard error found
  double shift_z_level = 0.0;   // the level it must exceed
  bool mc_large = false;        // mc_sd above half the profile's sd: raise the tosses
  std::vector<std::array<double, 2>> profile;  // (value, 2 (l_max - l_profile)) over the last box
};

struct FitDataResult {
  std::string scene, source;
  std::vector<std::string> overrides;   // the data set's own (FitData::overrides)
  std::vector<int> labels;              // the die's outcomes, ascending
  std::vector<std::string> names;       // a coin's side per label (outcome_names); empty for a die
  std::vector<std::uint64_t> observed;  // per label
  std::vector<double> fitted;           // simulated at the estimate, per label
  std::uint64_t fitted_tosses = 0;
  ChiSquare gof;                        // this data set against `fitted`, dof = outcomes - 1
};

// A narrowed box whose confidence set reaches its edge is widened and the round refitted, at most
// this many times in a fit; after that the end is reported open.
inline constexpr int kFitMaxWidenings = 4;

struct FitRound {
  std::vector<double> box_lo, box_hi;   // per parameter
  bool widened = false;                 // its set reached a narrowed edge: refitted in a wider box
  std::uint64_t points = 0, tosses_per_point = 0;
  std::vector<double> estimate;
};

struct FitResult {
  std::vector<FitParamResult> params;
  std::vector<FitDataResult> data;
  ChiSquare gof;  // all data sets together, dof = sum(outcomes - 1) - parameters
  std::string fidelity;  // the first data set's model's (after --fidelity / sim.fidelity)
  std::string fidelity_reason;  // why (auto in a fit: impulse, no pilot)
  double loglik = 0.0;
  std::uint64_t simulated_tosses = 0;
  double elapsed_s = 0.0;
  std::vector<FitRound> rounds;
  bool estimated = true;  // false: no key is identifiable (FitParamResult::identifiable); the fit
                          // stopped after round 1 with no estimate, interval or fitted probabilities
};

// Validates first (1-3 distinct parameters, every scene loading at each parameter's LO and HI,
// observed labels exactly the die's outcomes, counts not all zero: SceneError naming the file or key), then
// fits. Throws std::runtime_error("cancelled") if `cancel` was set.
FitResult run_fit(const std::vector<FitParam>& params, const std::vector<FitData>& data, const FitOptions& opt);

}  // namespace dicesim
