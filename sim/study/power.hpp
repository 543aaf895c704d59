// Planning experiments: how many throws a chi-square test needs to tell two dice apart.
//
// H0: the die follows p0 (K outcomes). The thrown die follows p1. The test is Pearson's
// goodness of fit of n throws against p0 (K - 1 dof). Two answers:
//  - approx: the noncentral chi-square approximation, lambda = n * w2 with
//    w2 = sum (p1 - p0)^2 / p0 (Boost.Math);
//  - exact: multinomial counts simulated at n. The critical value is the (1 - alpha) quantile of
//    the statistic simulated under H0 (not the asymptotic quantile), power is the fraction of
//    draws from p1 above it; n is searched by doubling from the approximation, then bisection.
// Replicate r of an evaluation draws only from Philox4x32-10 keyed by the seed, with r in the
// counter, and draws the same uniforms at every n (common random numbers): power(n) is then
// nearly monotone and the search reproducible on any thread count.
//
// p0 and p1 come from simulated tosses of one or two scenes (power_against, power_detect_bias):
// their Monte Carlo error is carried into a 95% range of n by a bootstrap over toss batches.
// Pure computation: nothing here prints.
#pragma once

#include <Random123/philox.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "sim/body/die_model.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/study/statistics.hpp"

namespace dicesim {

// Uniforms for count draws: Philox4x32-10 keyed by `seed`, counter (replicate, block, tag). The
// tag separates the H0 draws, the H1 draws and the bootstrap from each other and from the tosses
// (whose counters end in 0 or 0xD1CE).
class CountStream {
 public:
  static constexpr std::uint32_t kNull = 0x504F0000u, kAlternative = 0x504F0001u, kBootstrap = 0x504F0002u;
  CountStream(std::uint64_t seed, std::uint64_t replicate, std::uint32_t tag);
  double uniform();  // on (0, 1), 53 random bits

 private:
  void refill();
  r123::Philox4x32::key_type key_;
  r123::Philox4x32::ctr_type ctr_;
  double buf_[2] = {0.0, 0.0};
  int left_ = 0;
};

// Binomial(n, p), exactly: inversion (the pmf's recurrence from 0) when n min(p, 1-p) < 10, else
// Hormann's BTRD (transformed rejection with decomposition, 1993). Only IEEE arithmetic and
// sim/log.hpp's logarithm: the same draws on every machine.
std::uint64_t sample_binomial(std::uint64_t n, double p, CountStream& rng);
// BTRD's Stirling tail fc(k) = log k! - (k + 1/2) log(k + 1) + (k + 1) - log(2 pi)/2 (exposed for
// its test: the sampler's pmf test reaches the steps that use it too rarely to see a wrong one).
double stirling_tail(double k);
// Multinomial(n, p) as a chain of binomials: cell k gets Binomial(rest, p_k / (p_k + ... + p_K)).
void sample_multinomial(std::uint64_t n, std::span<const double> p, CountStream& rng, std::span<std::uint64_t> out);

// Pearson's statistic of `counts` against p0. A cell with p0 = 0 is left out when empty and makes
// the statistic +inf when not (such a throw is impossible under H0).
double pearson_statistic(std::span<const std::uint64_t> counts, std::span<const double> p0);
// Cells with p0 > 0, minus 1.
int gof_dof(std::span<const double> p0);
// w2 = sum (p1 - p0)^2 / p0 over cells with p0 > 0; +inf if p1 puts mass where p0 has none.
double effect_w2(std::span<const double> p0, std::span<const double> p1);

struct PowerTarget {
  double alpha = 0.05;                // size of the test, in (0, 1)
  double power = 0.8;                 // wanted power, in (alpha, 1)
  std::uint64_t replicates = 4000;    // simulated count vectors per hypothesis and n
  std::uint64_t seed = 1;             // of the count draws
  // Replicate r draws from counter first_replicate + r: another first_replicate (e.g. R) gives
  // draws independent of the default ones under the same seed.
  std::uint64_t first_replicate = 0;
};

// The largest n considered: beyond it n is reported as not reached.
inline constexpr std::uint64_t kMaxThrows = 1ULL << 40;

struct PowerAtN {
  std::uint64_t n = 0;
  double critical = 0.0;  // reject H0 when the statistic is > critical
  double size = 0.0;      // fraction of H0 draws above critical (<= alpha; below it when ties)
  double power = 0.0;     // fraction of H1 draws above critical
};

// The exact test at n, simulated. Deterministic in (p0, p1, n, target).
PowerAtN simulated_power(std::span<const double> p0, std::span<const double> p1, std::uint64_t n,
                         const PowerTarget& target);
// The noncentral chi-square approximation of the power at n.
double approx_power(std::span<const double> p0, std::span<const double> p1, std::uint64_t n, double alpha);
// The smallest n of the approximation. When p1 puts mass q where p0 has none, n is capped by the
// n at which such a throw occurs with the wanted power (1 - (1 - q)^n >= power). nullopt: w2 = 0
// (no difference) or n > kMaxThrows.
std::optional<std::uint64_t> approx_n(std::span<const double> p0, std::span<const double> p1, double alpha,
                                      double power);

struct ExactN {
  std::optional<std::uint64_t> n;  // nullopt: not reached by kMaxThrows
  PowerAtN at;                     // the test at n (at the largest n tried if not reached)
  int evaluations = 0;
};
// The smallest n (to the search's resolution: power is monotone only up to MC noise) whose
// simulated power reaches target.power. `start` (e.g. the approximation) seeds the bracket.
// Returns early (n = nullopt) once *cancel is set.
ExactN exact_n(std::span<const double> p0, std::span<const double> p1, const PowerTarget& target,
               std::uint64_t start, const std::atomic<bool>* cancel = nullptr);

// ---- Studies: p0 and p1 from simulated tosses ------------------------------------------------

struct PowerStudyConfig {
  std::uint64_t tosses = 100000;  // per scene, indices 0..tosses-1 (common random numbers)
  std::uint64_t seed = 1;         // of the tosses and of the count draws
  int threads = 1;
  int batches = 20;               // contiguous index batches, resampled by the bootstrap
  int bootstrap = 1000;           // bootstrap resamples for the 95% range of n
  PowerTarget target;             // its seed is overwritten with `seed`
  // (tosses done, tosses total) while tossing; the search that follows takes a fraction of that.
  std::function<void(std::uint64_t, std::uint64_t)> progress;
  // (searches done, searches total) after each search for an exact n; from any thread, one at a time.
  std::function<void(std::size_t, std::size_t)> search_progress;
  const std::atomic<bool>* cancel = nullptr;
};

// One scene's tosses: totals and the per-batch counts the bootstrap resamples.
struct SimulatedDie {
  RunCounts counts;
  std::vector<RunCounts> batches;
  std::vector<double> p;          // faces / settled, label order
  std::vector<Interval> ci95;     // Wilson
};

struct PowerEstimate {
  std::optional<std::uint64_t> n_approx;
  ExactN exact;
  // How much n moves with the tosses' own noise: the 2.5% and 97.5% quantiles of the approximate n
  // over a paired bootstrap of the toss batches (n_range95_approx), and the exact n scaled by them
  // (n_range95 = n_exact * quantile / n_approx at the tosses' probabilities). nullopt: not reached
  // (no difference in those resamples).
  std::array<std::optional<std::uint64_t>, 2> n_range95, n_range95_approx;
  // The exact n's own noise from the finite replicates (not in the range): the power's binomial
  // sd sqrt(P (1 - P) / R) over the slope d power / d n of the approximation at n_exact.
  double replicate_sd = 0.0;
};

struct AgainstStudy {
  std::vector<int> labels;
  SimulatedDie a, b;
  double w2 = 0.0;
  int dof = 0;
  // Homogeneity test of the two runs' counts (conservative: the tosses are paired, and paired
  // tosses are positively correlated). Not significant: n mostly measures simulation noise.
  ChiSquare difference;
  PowerEstimate estimate;
  std::uint64_t simulated_tosses = 0;
  bool cancelled = false;
};

// H0 = a's probabilities, thrown die = b. The outcome labels must be equal (the caller checks).
AgainstStudy power_against(const DieModel& a, const DieModel& b, const PowerStudyConfig& cfg);

struct BiasAlternative {
  std::size_t face = 0;  // index in label order
  int label = 0;
  int sign = +1;         // p'_face = p_face + sign * delta
  std::vector<double> p;
  double w2 = 0.0;
  std::optional<std::uint64_t> n_approx;
  ExactN exact;
};

struct BiasStudy {
  std::vector<int> labels;
  SimulatedDie a;
  double delta = 0.0;
  int dof = 0;
  std::vector<BiasAlternative> alternatives;  // skipped signs (p' outside [0, 1]) left out
  std::size_t hardest = 0;                    // index into alternatives: the largest exact n
  // n = the hardest alternative's, with its range. With several alternatives its exact n is
  // searched again on fresh replicates (refreshed), since the maximum of noisy searches is biased up.
  PowerEstimate estimate;
  bool refreshed = false;
  std::uint64_t simulated_tosses = 0;
  bool cancelled = false;
};

// The alternatives of --detect-bias: face k moved by +/-delta, the others rescaled in proportion
// (a sign leaving [0, 1], or a face with p = 1, is skipped).
std::vector<BiasAlternative> bias_alternatives(std::span<const double> p, double delta, const std::vector<int>& labels);

// Every alternative's exact n is searched (on cfg.threads threads, each alone reproducible); the
// hardest one's again on replicates R..2R-1, for the estimate.
BiasStudy power_detect_bias(const DieModel& a, double delta, const PowerStudyConfig& cfg);

}  // namespace dicesim
