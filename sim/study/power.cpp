#include "sim/study/power.hpp"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/non_central_chi_squared.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <tuple>

#include "sim/log.hpp"
#include "sim/study/compare.hpp"

namespace dicesim {

// ---- Count draws -------------------------------------------------------------------------------

CountStream::CountStream(std::uint64_t seed, std::uint64_t replicate, std::uint32_t tag) {
  key_ = {{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32)}};
  ctr_ = {{static_cast<std::uint32_t>(replicate), static_cast<std::uint32_t>(replicate >> 32), 0u, tag}};
}

double CountStream::uniform() {
  if (left_ == 0) refill();
  --left_;
  return buf_[left_];
}

void CountStream::refill() {
  r123::Philox4x32 gen;
  const auto out = gen(ctr_, key_);
  ++ctr_.v[2];
  // 53 bits each, centred in their cell: never 0 or 1 (the samplers divide by and log them).
  auto unit = [](std::uint32_t a, std::uint32_t b) {
    const std::uint64_t bits = (static_cast<std::uint64_t>(a >> 5) << 26) | (b >> 6);
    return (static_cast<double>(bits) + 0.5) * 0x1.0p-53;
  };
  buf_[0] = unit(out.v[0], out.v[1]);
  buf_[1] = unit(out.v[2], out.v[3]);
  left_ = 2;
}

// fc(k) = log k! - (k + 1/2) log(k + 1) + (k + 1) - log(2 pi)/2, Stirling's error term (BTRD's
// "fc"). Exact values (30 digits, mpmath) below 10; the asymptotic series above, to its x^-9 term
// (x = k + 1): the first omitted one, 691 / (360360 x^11), is < 1e-14 there.
double stirling_tail(double k) {
  static constexpr double kTable[10] = {0.081061466795327258, 0.041340695955409294, 0.027677925684998339,
                                        0.020790672103765093, 0.016644691189821192, 0.013876128823070748,
                                        0.01189670994589177,  0.010411265261972096, 0.0092554621827127329,
                                        0.0083305634333628713};
  if (k < 10) return kTable[static_cast<int>(k)];
  const double x = k + 1.0, x2 = x * x;
  return (1.0 / 12 - (1.0 / 360 - (1.0 / 1260 - (1.0 / 1680 - 1.0 / (1188 * x2)) / x2) / x2) / x2) / x;
}

namespace {

// q^n by repeated squaring: IEEE multiplications only (std::pow is libm's, chosen by CPU).
double pow_int(double q, std::uint64_t n) {
  double r = 1.0;
  for (double b = q; n != 0; n >>= 1, b *= b)
    if (n & 1) r *= b;
  return r;
}

// p <= 0.5, n p < 10: walk the pmf from 0 (at most a few dozen steps on average).
std::uint64_t binomial_inversion(std::uint64_t n, double p, CountStream& rng) {
  const double q = 1.0 - p, s = p / q, a = (static_cast<double>(n) + 1.0) * s;
  const double r0 = pow_int(q, n);
  for (;;) {
    double u = rng.uniform(), r = r0;
    std::uint64_t x = 0;
    // The computed pmf may sum to a hair below 1: a u beyond it draws again (never a bias one
    // can see: the probability is ~1e-15) instead of running on towards n.
    while (u > r && r > 0.0 && x < n) {
      u -= r;
      ++x;
      r *= a / static_cast<double>(x) - s;
    }
    if (u <= r) return x;
  }
}

// Hormann (1993), "The generation of binomial random variates", algorithm BTRD, for p <= 0.5 and
// n p >= 10. Written from the paper's steps (the numbers are its constants).
std::uint64_t binomial_btrd(std::uint64_t n, double p, CountStream& rng) {
  const double nd = static_cast<double>(n);
  const double q = 1.0 - p;
  const double m = std::floor((nd + 1.0) * p);  // the mode
  const double r = p / q, nr = (nd + 1.0) * r, npq = nd * p * q, sq = std::sqrt(npq);
  const double b = 1.15 + 2.53 * sq;
  const double a = -0.0873 + 0.0248 * b + 0.01 * p;
  const double c = nd * p + 0.5;
  const double alpha = (2.83 + 5.1 / b) * sq;
  const double vr = 0.92 - 4.2 / b;
  const double urvr = 0.86 * vr;
  for (;;) {
    // Step 1: the box in the middle of the hat accepts at once (most draws).
    double v = rng.uniform();
    double u;
    if (v <= urvr) {
      u = v / vr - 0.43;
      return static_cast<std::uint64_t>(std::floor((2.0 * a / (0.5 - std::fabs(u)) + b) * u + c));
    }
    // Step 2: a point under the rest of the hat.
    if (v >= vr) {
      u = rng.uniform() - 0.5;
    } else {
      u = v / vr - 0.93;
      u = (u < 0.0 ? -0.5 : 0.5) - u;
      v = rng.uniform() * vr;
    }
    // Step 3.0
    const double us = 0.5 - std::fabs(u);
    const double k = std::floor((2.0 * a / us + b) * u + c);
    if (k < 0.0 || k > nd) continue;
    v = v * alpha / (a / (us * us) + b);
    const double km = std::fabs(k - m);
    if (km <= 15.0) {
      // Step 3.1: f(k)/f(m) by the pmf's recurrence.
      double f = 1.0;
      if (m < k) {
        for (double i = m + 1.0; i <= k; i += 1.0) f *= nr / i - r;
      } else if (m > k) {
        for (double i = k + 1.0; i <= m; i += 1.0) v *= nr / i - r;
      }
      if (v <= f) return static_cast<std::uint64_t>(k);
      continue;
    }
    // Step 3.2: squeeze on the log scale.
    v = log_fixed(v);
    const double rho = (km / npq) * (((km / 3.0 + 0.625) * km + 1.0 / 6.0) / npq + 0.5);
    const double t = -km * km / (2.0 * npq);
    if (v < t - rho) return static_cast<std::uint64_t>(k);
    if (v > t + rho) continue;
    // Steps 3.3, 3.4: the exact log ratio f(k)/f(m) with Stirling's tails.
    const double nm = nd - m + 1.0;
    const double h = (m + 0.5) * log_fixed((m + 1.0) / (r * nm)) + stirling_tail(m) + stirling_tail(nd - m);
    const double nk = nd - k + 1.0;
    if (v <= h + (nd + 1.0) * log_fixed(nm / nk) + (k + 0.5) * log_fixed(nk * r / (k + 1.0)) - stirling_tail(k) -
                 stirling_tail(nd - k))
      return static_cast<std::uint64_t>(k);
  }
}

}  // namespace

std::uint64_t sample_binomial(std::uint64_t n, double p, CountStream& rng) {
  if (n == 0 || !(p > 0.0)) return 0;
  if (p >= 1.0) return n;
  const bool flip = p > 0.5;  // both samplers want p <= 1/2
  const double pp = flip ? 1.0 - p : p;
  const std::uint64_t k = static_cast<double>(n) * pp < 10.0 ? binomial_inversion(n, pp, rng) : binomial_btrd(n, pp, rng);
  return flip ? n - k : k;
}

void sample_multinomial(std::uint64_t n, std::span<const double> p, CountStream& rng, std::span<std::uint64_t> out) {
  // The remaining mass as a sum of the remaining cells (not 1 - the cells so far: no cancellation).
  double rest = 0.0;
  for (double x : p) rest += x;
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (k + 1 == p.size() || n == 0) {
      out[k] = n;
      for (std::size_t j = k + 1; j < p.size(); ++j) out[j] = 0;
      return;
    }
    const double share = rest > 0.0 ? std::min(1.0, p[k] / rest) : 1.0;
    out[k] = sample_binomial(n, share, rng);
    n -= out[k];
    rest -= p[k];
    if (rest < 0.0) rest = 0.0;
  }
}

double pearson_statistic(std::span<const std::uint64_t> counts, std::span<const double> p0) {
  std::uint64_t n = 0;
  for (std::uint64_t c : counts) n += c;
  const double nd = static_cast<double>(n);
  double t = 0.0;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    if (p0[k] <= 0.0) {
      if (counts[k] > 0) return std::numeric_limits<double>::infinity();
      continue;
    }
    const double e = nd * p0[k], d = static_cast<double>(counts[k]) - e;
    t += d * d / e;
  }
  return t;
}

int gof_dof(std::span<const double> p0) {
  int cells = 0;
  for (double x : p0) cells += x > 0.0 ? 1 : 0;
  return cells - 1;
}

namespace {

// Mass of p1 where p0 has none, and w2 over the cells where p0 has some.
struct Effect {
  double q = 0.0;
  double w2 = 0.0;
};
Effect effect(std::span<const double> p0, std::span<const double> p1) {
  Effect e;
  for (std::size_t k = 0; k < p0.size(); ++k) {
    if (p0[k] <= 0.0) {
      e.q += p1[k];
    } else {
      const double d = p1[k] - p0[k];
      e.w2 += d * d / p0[k];
    }
  }
  return e;
}

// lambda at which the noncentral chi-square's power is `power`, per (dof, alpha, power); the root
// search costs milliseconds and the bootstrap asks for the same one a thousand times.
double required_lambda(int dof, double alpha, double power) {
  static std::mutex mu;
  static std::map<std::tuple<int, double, double>, double> cache;
  std::lock_guard lock(mu);
  const auto key = std::make_tuple(dof, alpha, power);
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  const boost::math::chi_squared null(dof);
  const double crit = boost::math::quantile(boost::math::complement(null, alpha));
  const double lambda =
      boost::math::non_central_chi_squared_distribution<double>::find_non_centrality(dof, crit, 1.0 - power);
  cache.emplace(key, lambda);
  return lambda;
}

// approx_n as a double (+inf: no difference, or too large), for sorting bootstrap resamples.
double approx_n_real(std::span<const double> p0, std::span<const double> p1, double alpha, double power) {
  const Effect e = effect(p0, p1);
  const int dof = gof_dof(p0);
  double n = std::numeric_limits<double>::infinity();
  if (e.q >= 1.0) return 1.0;
  if (e.q > 0.0) n = std::ceil(std::log1p(-power) / std::log1p(-e.q));
  if (dof >= 1 && e.w2 > 0.0) n = std::min(n, std::ceil(required_lambda(dof, alpha, power) / e.w2));
  return std::max(1.0, n);
}

std::optional<std::uint64_t> to_throws(double n) {
  if (!(n <= static_cast<double>(kMaxThrows))) return std::nullopt;
  return static_cast<std::uint64_t>(n);
}

}  // namespace

double effect_w2(std::span<const double> p0, std::span<const double> p1) {
  const Effect e = effect(p0, p1);
  return e.q > 0.0 ? std::numeric_limits<double>::infinity() : e.w2;
}

std::optional<std::uint64_t> approx_n(std::span<const double> p0, std::span<const double> p1, double alpha,
                                      double power) {
  return to_throws(approx_n_real(p0, p1, alpha, power));
}

double approx_power(std::span<const double> p0, std::span<const double> p1, std::uint64_t n, double alpha) {
  const Effect e = effect(p0, p1);
  const int dof = gof_dof(p0);
  const double nd = static_cast<double>(n);
  const double zero_cells = e.q > 0.0 ? 1.0 - std::exp(nd * std::log1p(-std::min(e.q, 1.0))) : 0.0;
  if (dof < 1) return zero_cells;
  const boost::math::chi_squared null(dof);
  const double crit = boost::math::quantile(boost::math::complement(null, alpha));
  const double lambda = nd * e.w2;
  const double chi = lambda > 0.0
                         ? boost::math::cdf(boost::math::complement(
                               boost::math::non_central_chi_squared_distribution<double>(dof, lambda), crit))
                         : alpha;
  return std::max(zero_cells, chi);
}

PowerAtN simulated_power(std::span<const double> p0, std::span<const double> p1, std::uint64_t n,
                         const PowerTarget& target) {
  const std::size_t k = p0.size();
  const std::uint64_t reps = target.replicates;
  std::vector<std::uint64_t> counts(k);
  std::vector<double> null_stats(reps);
  for (std::uint64_t r = 0; r < reps; ++r) {
    CountStream rng(target.seed, target.first_replicate + r, CountStream::kNull);
    sample_multinomial(n, p0, rng, counts);
    null_stats[r] = pearson_statistic(counts, p0);
  }
  std::sort(null_stats.begin(), null_stats.end());
  // At most floor(alpha R) null draws may lie above the critical value: the size is alpha when the
  // statistic has no ties there, and below it when it does (a discrete statistic, small n).
  const auto allowed = std::min<std::uint64_t>(reps - 1, static_cast<std::uint64_t>(std::floor(target.alpha * static_cast<double>(reps))));
  PowerAtN at;
  at.n = n;
  at.critical = null_stats[reps - 1 - allowed];
  const auto above_null = static_cast<std::uint64_t>(null_stats.end() - std::upper_bound(null_stats.begin(), null_stats.end(), at.critical));
  at.size = static_cast<double>(above_null) / static_cast<double>(reps);
  std::uint64_t above = 0;
  for (std::uint64_t r = 0; r < reps; ++r) {
    CountStream rng(target.seed, target.first_replicate + r, CountStream::kAlternative);
    sample_multinomial(n, p1, rng, counts);
    above += pearson_statistic(counts, p0) > at.critical ? 1 : 0;
  }
  at.power = static_cast<double>(above) / static_cast<double>(reps);
  return at;
}

ExactN exact_n(std::span<const double> p0, std::span<const double> p1, const PowerTarget& target, std::uint64_t start,
               const std::atomic<bool>* cancel) {
  ExactN out;
  PowerAtN at, hi_at;
  auto stop = [&] { return cancel && cancel->load(std::memory_order_relaxed); };
  auto reaches = [&](std::uint64_t n) {
    at = simulated_power(p0, p1, n, target);
    ++out.evaluations;
    return at.power >= target.power;
  };
  // lo: the largest n known to fall short (0 always does); hi: the smallest known to reach.
  std::uint64_t lo = 0, hi = std::clamp<std::uint64_t>(start, 1, kMaxThrows);
  if (reaches(hi)) {
    hi_at = at;
    while (hi > 1 && !stop()) {
      const std::uint64_t cand = hi / 2;
      if (!reaches(cand)) {
        lo = cand;
        break;
      }
      hi = cand;
      hi_at = at;
    }
  } else {
    lo = hi;
    for (;;) {
      if (lo >= kMaxThrows || stop()) {
        out.at = at;
        return out;
      }
      const std::uint64_t cand = std::min(kMaxThrows, lo * 2);
      if (reaches(cand)) {
        hi = cand;
        hi_at = at;
        break;
      }
      lo = cand;
    }
  }
  while (hi - lo > 1) {
    if (stop()) {
      out.at = hi_at;
      return out;
    }
    const std::uint64_t mid = lo + (hi - lo) / 2;
    if (reaches(mid)) {
      hi = mid;
      hi_at = at;
    } else {
      lo = mid;
    }
  }
  out.n = hi;
  out.at = hi_at;
  return out;
}

// ---- Studies -----------------------------------------------------------------------------------

namespace {

// Runs fn(0..count-1) on up to `threads` threads; each task is alone deterministic. `done` is
// called after each task, under a lock.
void parallel_for(std::size_t count, int threads, const std::function<void(std::size_t)>& fn,
                  const std::function<void(std::size_t, std::size_t)>& done = {}) {
  std::atomic<std::size_t> next{0};
  std::mutex mu;
  std::size_t finished = 0;
  auto work = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < count;) {
      fn(i);
      if (done) {
        std::lock_guard lock(mu);
        done(++finished, count);
      }
    }
  };
  const std::size_t extra = std::min<std::size_t>(count, static_cast<std::size_t>(std::max(1, threads))) - (count > 0 ? 1 : 0);
  std::vector<std::jthread> pool;
  for (std::size_t t = 0; t < extra; ++t) pool.emplace_back(work);
  work();
}

std::vector<double> probabilities(const RunCounts& c) {
  std::vector<double> p(c.faces.size(), 0.0);
  if (c.settled == 0) return p;
  for (std::size_t k = 0; k < p.size(); ++k) p[k] = static_cast<double>(c.faces[k]) / static_cast<double>(c.settled);
  return p;
}

// Tosses indices 0..tosses-1 of `m` in cfg.batches contiguous batches (the same counts as one run).
SimulatedDie toss_batches(const DieModel& m, const PowerStudyConfig& cfg, std::uint64_t done_before,
                          std::uint64_t total_all) {
  SimulatedDie d;
  d.counts = RunCounts(m.outcomes());
  const std::uint64_t nb = std::clamp<std::uint64_t>(static_cast<std::uint64_t>(std::max(1, cfg.batches)), 1, cfg.tosses);
  for (std::uint64_t b = 0; b < nb; ++b) {
    const std::uint64_t lo = cfg.tosses * b / nb, hi = cfg.tosses * (b + 1) / nb;
    RunConfig rc;
    rc.seed = cfg.seed;
    rc.first = lo;
    rc.tosses = hi - lo;
    rc.threads = cfg.threads;
    rc.cancel = cfg.cancel;
    if (cfg.progress) {
      const std::uint64_t base = done_before + lo;
      rc.progress = [&cfg, base, total_all](std::uint64_t done, std::uint64_t) { cfg.progress(base + done, total_all); };
    }
    d.batches.push_back(run_tosses(m, rc));
    d.counts.merge(d.batches.back());
  }
  if (d.counts.settled == 0 && !(cfg.cancel && cfg.cancel->load()))
    throw std::runtime_error("no toss settled in " + std::to_string(cfg.tosses) + " (all unresolved or invalid)");
  d.p = probabilities(d.counts);
  for (std::uint64_t c : d.counts.faces) d.ci95.push_back(wilson_interval(c, d.counts.settled));
  return d;
}

// Bootstrap resample r: which batches it draws (with replacement). The same for both dice of a
// pairing, so a resample keeps the tosses paired.
std::vector<std::size_t> resample_batches(std::uint64_t seed, std::uint64_t r, std::size_t batches) {
  CountStream rng(seed, r, CountStream::kBootstrap);
  std::vector<std::size_t> idx(batches);
  for (auto& i : idx) i = std::min(batches - 1, static_cast<std::size_t>(rng.uniform() * static_cast<double>(batches)));
  return idx;
}

std::vector<double> resampled_p(const SimulatedDie& d, const std::vector<std::size_t>& idx) {
  RunCounts c(static_cast<int>(d.counts.faces.size()));
  for (std::size_t i : idx) c.merge(d.batches[i]);
  return probabilities(c);
}

// The 2.5% and 97.5% quantiles of bootstrap values of the approximate n (+inf: not reached), and
// the range of n they give: the exact n scaled by quantile / point (the approximation at the
// unresampled probabilities). Why scaled, not searched again at the quantile resamples: a search
// carries the replicates' own noise (2-3% of n at 4000), which the ratio exact / approx shares
// between nearby p; measured with 10^6 tosses of Die 1 against a fair die, searches at the ends
// gave [2199, 2426] around an exact n of 2183, outside its own range.
void set_range(PowerEstimate& e, std::vector<double> boot, double point) {
  std::sort(boot.begin(), boot.end());
  const std::size_t count = boot.size();
  const auto lo = std::min(count - 1, static_cast<std::size_t>(std::floor(0.025 * static_cast<double>(count))));
  const auto hi = std::min(count - 1, static_cast<std::size_t>(std::max(1.0, std::ceil(0.975 * static_cast<double>(count)))) - 1);
  const std::array<double, 2> q = {boot[lo], boot[hi]};
  for (int i = 0; i < 2; ++i) {
    e.n_range95_approx[i] = to_throws(q[i]);
    if (e.exact.n && std::isfinite(point) && point > 0.0)
      e.n_range95[i] = to_throws(std::round(static_cast<double>(*e.exact.n) * q[i] / point));
  }
}

// The exact n's own Monte Carlo noise: the power's binomial sd over the approximation's slope.
double replicate_sd(std::span<const double> p0, std::span<const double> p1, const ExactN& e, const PowerTarget& t) {
  if (!e.n) return 0.0;
  const double n = static_cast<double>(*e.n);
  const auto lo = static_cast<std::uint64_t>(std::max(1.0, std::floor(0.97 * n))), hi = static_cast<std::uint64_t>(std::ceil(1.03 * n)) + 1;
  const double slope = (approx_power(p0, p1, hi, t.alpha) - approx_power(p0, p1, lo, t.alpha)) / static_cast<double>(hi - lo);
  if (!(slope > 0.0)) return 0.0;
  return std::sqrt(t.power * (1.0 - t.power) / static_cast<double>(t.replicates)) / slope;
}

void check_config(const PowerStudyConfig& cfg) {
  const PowerTarget& t = cfg.target;
  if (!(t.alpha > 0.0 && t.alpha < 1.0)) throw std::invalid_argument("power: alpha must be in (0, 1)");
  if (!(t.power > t.alpha && t.power < 1.0)) throw std::invalid_argument("power: power must be in (alpha, 1)");
  if (t.replicates < 100) throw std::invalid_argument("power: replicates must be >= 100");
  if (cfg.tosses < 1) throw std::invalid_argument("power: tosses must be >= 1");
  if (cfg.bootstrap < 1) throw std::invalid_argument("power: bootstrap must be >= 1");
}

bool cancelled(const PowerStudyConfig& cfg) { return cfg.cancel && cfg.cancel->load(); }

std::uint64_t start_of(std::optional<std::uint64_t> n) { return n.value_or(kMaxThrows); }

}  // namespace

AgainstStudy power_against(const DieModel& a, const DieModel& b, const PowerStudyConfig& cfg_in) {
  check_config(cfg_in);
  if (a.outcome_labels != b.outcome_labels) throw std::invalid_argument("power: the two dice have different outcome labels");
  PowerStudyConfig cfg = cfg_in;
  cfg.target.seed = cfg.seed;
  AgainstStudy s;
  s.labels = a.outcome_labels;
  s.a = toss_batches(a, cfg, 0, 2 * cfg.tosses);
  if (cancelled(cfg)) {
    s.cancelled = true;
    return s;
  }
  s.b = toss_batches(b, cfg, cfg.tosses, 2 * cfg.tosses);
  if (cancelled(cfg)) {
    s.cancelled = true;
    return s;
  }
  s.simulated_tosses = 2 * cfg.tosses;
  s.w2 = effect_w2(s.a.p, s.b.p);
  s.dof = gof_dof(s.a.p);
  s.difference = chi2_homogeneity(s.a.counts.faces, s.b.counts.faces);
  s.estimate.n_approx = approx_n(s.a.p, s.b.p, cfg.target.alpha, cfg.target.power);

  if (s.w2 > 0.0) s.estimate.exact = exact_n(s.a.p, s.b.p, cfg.target, start_of(s.estimate.n_approx), cfg.cancel);
  if (cfg.search_progress) cfg.search_progress(1, 1);
  s.estimate.replicate_sd = replicate_sd(s.a.p, s.b.p, s.estimate.exact, cfg.target);

  // Bootstrap over batches, paired (the same batches of both dice): the approximate n's spread.
  const std::size_t nb = s.a.batches.size();
  std::vector<double> boot(static_cast<std::size_t>(cfg.bootstrap));
  for (std::size_t r = 0; r < boot.size(); ++r) {
    const auto idx = resample_batches(cfg.seed, r, nb);
    boot[r] = approx_n_real(resampled_p(s.a, idx), resampled_p(s.b, idx), cfg.target.alpha, cfg.target.power);
  }
  set_range(s.estimate, std::move(boot), approx_n_real(s.a.p, s.b.p, cfg.target.alpha, cfg.target.power));
  s.cancelled = cancelled(cfg);
  return s;
}

std::vector<BiasAlternative> bias_alternatives(std::span<const double> p, double delta, const std::vector<int>& labels) {
  std::vector<BiasAlternative> alts;
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (!(p[k] < 1.0)) continue;  // nothing to rescale
    for (int sign : {+1, -1}) {
      const double pk = p[k] + sign * delta;
      if (pk < 0.0 || pk > 1.0) continue;
      BiasAlternative alt;
      alt.face = k;
      alt.label = labels[k];
      alt.sign = sign;
      alt.p.resize(p.size());
      const double scale = (1.0 - pk) / (1.0 - p[k]);
      for (std::size_t j = 0; j < p.size(); ++j) alt.p[j] = j == k ? pk : p[j] * scale;
      alts.push_back(std::move(alt));
    }
  }
  return alts;
}

BiasStudy power_detect_bias(const DieModel& a, double delta, const PowerStudyConfig& cfg_in) {
  check_config(cfg_in);
  if (!(delta > 0.0 && delta <= 0.5)) throw std::invalid_argument("power: delta must be in (0, 0.5]");
  PowerStudyConfig cfg = cfg_in;
  cfg.target.seed = cfg.seed;
  BiasStudy s;
  s.labels = a.outcome_labels;
  s.delta = delta;
  s.a = toss_batches(a, cfg, 0, cfg.tosses);
  if (cancelled(cfg)) {
    s.cancelled = true;
    return s;
  }
  s.simulated_tosses = cfg.tosses;
  s.dof = gof_dof(s.a.p);
  s.alternatives = bias_alternatives(s.a.p, delta, s.labels);
  if (s.alternatives.empty()) throw std::invalid_argument("power: no face can move by delta inside [0, 1]");
  for (BiasAlternative& alt : s.alternatives) {
    alt.w2 = effect_w2(s.a.p, alt.p);
    alt.n_approx = approx_n(s.a.p, alt.p, cfg.target.alpha, cfg.target.power);
  }

  // Every alternative's exact n: independent searches, each alone reproducible.
  const std::size_t na = s.alternatives.size();
  parallel_for(na, cfg.threads, [&](std::size_t i) {
    BiasAlternative& alt = s.alternatives[i];
    alt.exact = exact_n(s.a.p, alt.p, cfg.target, start_of(alt.n_approx), cfg.cancel);
  }, cfg.search_progress);

  // The hardest: the largest exact n (not reached counts as the largest), ties by the approximation.
  auto key = [](const BiasAlternative& alt) {
    const double inf = std::numeric_limits<double>::infinity();
    return std::make_pair(alt.exact.n ? static_cast<double>(*alt.exact.n) : inf,
                          alt.n_approx ? static_cast<double>(*alt.n_approx) : inf);
  };
  for (std::size_t i = 1; i < na; ++i)
    if (key(s.alternatives[s.hardest]) < key(s.alternatives[i])) s.hardest = i;
  const BiasAlternative& h = s.alternatives[s.hardest];
  s.estimate.n_approx = h.n_approx;
  s.estimate.exact = h.exact;
  if (na > 1 && h.exact.n && !cancelled(cfg)) {
    // The largest of several noisy searches overstates the n it picked (by up to about one
    // replicate sd when alternatives are alike): that one is searched again on fresh replicates.
    PowerTarget fresh = cfg.target;
    fresh.first_replicate = cfg.target.replicates;
    s.estimate.exact = exact_n(s.a.p, h.p, fresh, *h.exact.n, cfg.cancel);
    s.refreshed = true;
  }
  s.estimate.replicate_sd = replicate_sd(s.a.p, h.p, s.estimate.exact, cfg.target);

  // Bootstrap of the largest approximate n over the alternatives (rebuilt on each resample).
  auto worst_approx = [&](std::span<const double> p) {
    double worst = 0.0;
    for (const BiasAlternative& alt : bias_alternatives(p, delta, s.labels))
      worst = std::max(worst, approx_n_real(p, alt.p, cfg.target.alpha, cfg.target.power));
    return worst;
  };
  std::vector<double> boot(static_cast<std::size_t>(cfg.bootstrap));
  for (std::size_t r = 0; r < boot.size(); ++r)
    boot[r] = worst_approx(resampled_p(s.a, resample_batches(cfg.seed, r, s.a.batches.size())));
  set_range(s.estimate, std::move(boot), worst_approx(s.a.p));
  s.cancelled = cancelled(cfg);
  return s;
}

}  // namespace dicesim
