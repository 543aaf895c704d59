#include "sim/study/auto_pilot.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>
#include <vector>

#include <boost/math/special_functions/beta.hpp>

#include "sim/models/toss.hpp"
#include "sim/study/statistics.hpp"

namespace dicesim {
namespace {

// One-sided upper 95% Clopper-Pearson limit of a binomial proportion, k of n.
double upper95(std::uint64_t k, std::uint64_t n) {
  if (n == 0 || k >= n) return 1.0;
  return boost::math::ibeta_inv(static_cast<double>(k + 1), static_cast<double>(n - k), 0.95);
}

// A toss's answer as the pilot compares it: the outcome if settled, else its status.
int answer(const TossResult& r) { return r.status == TossStatus::Settled ? r.outcome : -1 - static_cast<int>(r.status); }

// Answers of tosses [from, to) of `m` under the pilot's seed, appended to `out`; split over threads
// when the block is long enough to pay for starting them (`per_toss_s`: this model's last measured
// seconds per toss, updated here). Which thread tosses an index never changes its answer.
void toss_range(const DieModel& m, std::uint64_t from, std::uint64_t to, int threads, std::vector<int>& out,
                double& per_toss_s) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t base = out.size();
  out.resize(base + (to - from));
  const std::uint64_t n = to - from;
  constexpr double kWorthThreads = 5e-3;  // s of single-thread work: thread start-up is negligible beside it
  const auto t = per_toss_s * static_cast<double>(n) < kWorthThreads ? 1 : static_cast<std::uint64_t>(std::max(1, threads));
  struct Timer {
    std::chrono::steady_clock::time_point t0;
    double& out;
    std::uint64_t n, t;
    ~Timer() {
      out = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * static_cast<double>(t) /
            static_cast<double>(n);
    }
  } timer{t0, per_toss_s, n, t};
  auto work = [&](std::uint64_t k) {
    for (std::uint64_t i = from + k; i < to; i += t) out[base + (i - from)] = answer(toss(m, kPilotSeed, i));
  };
  if (t == 1 || n < 2 * t) {
    for (std::uint64_t k = 0; k < t; ++k) work(k);
    return;
  }
  std::vector<std::jthread> pool;
  for (std::uint64_t k = 1; k < t; ++k) pool.emplace_back(work, k);
  work(0);
}

double fair_face_sd(const DieModel& m) {
  const double q = 1.0 / std::max(2, m.outcomes());
  return std::sqrt(q * (1.0 - q));
}

std::string num(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

}  // namespace

AutoPrecision precision_of_run(const DieModel& m, std::uint64_t tosses) {
  AutoPrecision p;
  p.tosses = tosses;
  p.halfwidth = kZ95 * fair_face_sd(m) / std::sqrt(static_cast<double>(std::max<std::uint64_t>(tosses, 1)));
  p.what = "a fair die's face at " + std::to_string(tosses) + " tosses";
  return p;
}

AutoPrecision precision_of_target(const DieModel& m, double halfwidth) {
  AutoPrecision p;
  p.halfwidth = halfwidth;
  const double sd = fair_face_sd(m);
  p.tosses = static_cast<std::uint64_t>(std::ceil(kZ95 * kZ95 * sd * sd / (halfwidth * halfwidth)));
  p.what = "the target half-width (about " + std::to_string(p.tosses) + " tosses of a fair die)";
  return p;
}

FidelityPilot resolve_auto(DieModel& m, const AutoPrecision& precision, int threads) {
  FidelityPilot pl;
  if (m.fidelity_requested != Fidelity::Auto) return pl;
  if (m.world) {  // several dice or obstacles: no cheaper model strikes one body against another
    m.fidelity = Fidelity::Impulse;
    m.fidelity_reason = "auto: `impulse`: several dice or obstacles, which only `impulse` strikes against each other (no pilot)";
    return pl;
  }
  const auto t0 = std::chrono::steady_clock::now();
  pl.ran = true;
  pl.halfwidth = precision.halfwidth;
  pl.precision = precision.what;
  pl.fraction = kAutoFraction;
  pl.threshold = kAutoFraction * precision.halfwidth;
  pl.seed = kPilotSeed;
  pl.cap = static_cast<std::uint64_t>(kPilotCapShare * static_cast<double>(precision.tosses));
  // Zero differences in n pairs pass when 1 - 0.05^(1/n) < threshold.
  const double n0 = pl.threshold > 0.0 && pl.threshold < 1.0 ? std::ceil(std::log(0.05) / std::log1p(-pl.threshold)) : 1e300;
  const std::uint64_t want = n0 < 1e15 ? static_cast<std::uint64_t>(std::ceil(1.1 * n0)) : ~0ULL;
  pl.max_pairs = std::min(want, pl.cap);
  const std::string judged = "the run's half-width " + num("%.3g", pl.halfwidth) + " (" + pl.precision + ")";
  if (upper95(0, pl.max_pairs) >= pl.threshold) {  // not even zero differences could pass
    m.fidelity = Fidelity::Impulse;
    pl.max_pairs = 0;
    pl.ran = false;
    m.fidelity_reason = "auto: `impulse`: no pilot, since showing a cheaper model's bias below half " + judged + " needs at least " +
                        std::to_string(static_cast<std::uint64_t>(n0)) + " paired tosses, more than the " +
                        std::to_string(pl.cap) + " a pilot may take (5% of the run's tosses)";
    return pl;
  }
  // The most differences the full size allows.
  std::uint64_t k_max = 0;
  while (upper95(k_max + 1, pl.max_pairs) < pl.threshold) ++k_max;

  std::vector<int> ref;  // impulse answers, shared by the candidates
  double impulse_per_toss = 0.0;
  DieModel impulse = m;
  impulse.fidelity = Fidelity::Impulse;
  Fidelity chosen = Fidelity::Impulse;
  for (Fidelity f : {Fidelity::Static, Fidelity::Paper}) {
    DieModel cheap = m;
    cheap.fidelity = f;
    PilotCandidate c;
    c.model = f;
    std::vector<int> mine;
    double per_toss = 0.0;
    std::uint64_t block = 32;
    while (c.pairs < pl.max_pairs && c.differing <= k_max) {
      const std::uint64_t to = std::min(pl.max_pairs, c.pairs + block);
      if (ref.size() < to) {
        pl.tosses += to - ref.size();
        toss_range(impulse, ref.size(), to, threads, ref, impulse_per_toss);
      }
      toss_range(cheap, c.pairs, to, threads, mine, per_toss);
      pl.tosses += to - c.pairs;
      for (std::uint64_t i = c.pairs; i < to; ++i) c.differing += mine[i] != ref[i] ? 1 : 0;
      c.pairs = to;
      block = std::min<std::uint64_t>(block * 2, 4096);
    }
    c.bound = upper95(c.differing, c.pairs);
    c.adequate = c.pairs == pl.max_pairs && c.differing <= k_max && c.bound < pl.threshold;
    pl.candidates.push_back(c);
    if (c.adequate) {
      chosen = f;
      break;
    }
  }
  pl.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  m.fidelity = chosen;

  std::string tried;
  for (const PilotCandidate& c : pl.candidates) {
    if (!tried.empty()) tried += "; ";
    tried += std::string(to_string(c.model)) + " differed from impulse in " + std::to_string(c.differing) + " of " +
             std::to_string(c.pairs) + " paired tosses (bias bound " + num("%.3g", c.bound) + (c.adequate ? ": adequate" : ": not adequate") + ")";
  }
  const std::string rule = "the bound (upper 95% limit of the share of differing outcomes) must be below " +
                           num("%.3g", pl.threshold) + ", half " + judged;
  if (chosen == Fidelity::Impulse)
    m.fidelity_reason = "auto: `impulse`, no cheaper model shown adequate at this precision: " + tried + "; " + rule;
  else
    m.fidelity_reason = std::string("auto: `") + to_string(chosen) + "`, the cheapest model shown adequate at this precision: " +
                        tried + "; " + rule;
  return pl;
}

void resolve_auto_unmeasured(DieModel& m, const std::string& why) {
  if (m.fidelity_requested != Fidelity::Auto) return;
  m.fidelity = Fidelity::Impulse;
  m.fidelity_reason = why;
}

}  // namespace dicesim
