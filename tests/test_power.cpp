// dicesim power: the count samplers, the simulated (exact) test against closed forms, the search
// for n, reproducibility, and the command line. Every tolerance below is a number of binomial
// standard deviations of a Monte Carlo fraction (fixed seeds: a correct implementation passes
// these bounds with probability > 0.9999 on any seed; a wrong one fails them by far).
#include <gtest/gtest.h>

#include <boost/math/distributions/binomial.hpp>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numeric>
#include <vector>

#include "cli_runner.hpp"
#include "scenes_for_tests.hpp"
#include "sim/models/compile.hpp"
#include "sim/study/power.hpp"

namespace dicesim {
namespace {

double mc_sd(double p, double reps) { return std::sqrt(std::max(p * (1.0 - p), 1e-4) / reps); }

// Chi-square of `draws` samples of Binomial(n, p) against Boost's pmf, bins with expectation < 5
// merged into their neighbours (tails together). Returns the p-value.
double binomial_gof(std::uint64_t n, double p, int draws, std::uint64_t seed) {
  CountStream rng(seed, 0, CountStream::kNull);
  std::vector<std::uint64_t> x(static_cast<std::size_t>(draws));
  for (auto& v : x) v = sample_binomial(n, p, rng);
  for (std::uint64_t v : x) EXPECT_LE(v, n);
  const boost::math::binomial_distribution<double> dist(static_cast<double>(n), p);
  // Bins around the mean +/- 8 sd: [lo, hi] plus the two tails.
  const double mean = static_cast<double>(n) * p, sd = std::sqrt(mean * (1 - p));
  const auto lo = static_cast<std::uint64_t>(std::max(0.0, std::floor(mean - 8 * sd - 1)));
  const auto hi = static_cast<std::uint64_t>(std::min(static_cast<double>(n), std::ceil(mean + 8 * sd + 1)));
  std::vector<double> expected, observed;
  double e_acc = lo > 0 ? boost::math::cdf(dist, static_cast<double>(lo - 1)) * draws : 0.0, o_acc = 0.0;
  for (std::uint64_t v : x) o_acc += v < lo ? 1 : 0;
  for (std::uint64_t k = lo; k <= hi; ++k) {
    e_acc += boost::math::pdf(dist, static_cast<double>(k)) * draws;
    o_acc += static_cast<double>(std::count(x.begin(), x.end(), k));
    if (e_acc >= 5.0) {
      expected.push_back(e_acc);
      observed.push_back(o_acc);
      e_acc = o_acc = 0.0;
    }
  }
  e_acc += hi < n ? boost::math::cdf(boost::math::complement(dist, static_cast<double>(hi))) * draws : 0.0;
  for (std::uint64_t v : x) o_acc += v > hi ? 1 : 0;
  expected.back() += e_acc;  // the remainder joins the last bin
  observed.back() += o_acc;
  double chi = 0.0;
  for (std::size_t i = 0; i < expected.size(); ++i) chi += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
  const int dof = static_cast<int>(expected.size()) - 1;
  if (dof < 1) return 1.0;
  return boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), chi));
}

TEST(Power, BinomialSamplerMatchesThePmfInEveryRegime) {
  struct Case {
    std::uint64_t n;
    double p;
  };
  // Inversion (n min(p, 1-p) < 10, also mirrored), BTRD at its threshold, near the box/tail edge
  // (km <= 15 and > 15 paths), huge n.
  const Case cases[] = {{1, 0.5},      {20, 0.3},     {1000, 0.004}, {15, 0.8},        {25, 0.4},
                        {100, 0.4},    {2000, 0.9},   {5000, 0.03},  {1000000, 0.3},   {1000000000, 0.001},
                        {300, 0.5},    {60, 0.85}};
  for (const Case& c : cases) {
    const double pv = binomial_gof(c.n, c.p, 40000, 11 + c.n);
    EXPECT_GT(pv, 1e-4) << "Binomial(" << c.n << ", " << c.p << ") draws do not follow its pmf";
  }
}

TEST(Power, StirlingTailIsLogFactorialsRemainder) {
  // long double lgamma: ~1e-18 relative, far below the 1e-13 the series promises above k = 9.
  for (int k : {0, 3, 9, 10, 11, 15, 40, 1000, 1000000}) {
    const long double kk = k;
    const long double exact = std::lgamma(kk + 1) - (kk + 0.5L) * std::log(kk + 1) + (kk + 1) -
                              0.5L * std::log(2 * 3.141592653589793238462643383279502884L);
    EXPECT_NEAR(stirling_tail(k), static_cast<double>(exact), 2e-13 + 1e-12 * std::fabs(static_cast<double>(exact)))
        << "k = " << k;
  }
}

TEST(Power, MultinomialKeepsTheTotalAndTheMeans) {
  const std::vector<double> p = {0.5, 0.0, 0.2, 0.25, 0.05};
  std::vector<double> sum(p.size(), 0.0);
  const int reps = 20000;
  const std::uint64_t n = 300;
  std::vector<std::uint64_t> c(p.size());
  for (int r = 0; r < reps; ++r) {
    CountStream rng(5, static_cast<std::uint64_t>(r), CountStream::kAlternative);
    sample_multinomial(n, p, rng, c);
    EXPECT_EQ(std::accumulate(c.begin(), c.end(), std::uint64_t{0}), n);
    EXPECT_EQ(c[1], 0u);
    for (std::size_t k = 0; k < p.size(); ++k) sum[k] += static_cast<double>(c[k]);
  }
  for (std::size_t k = 0; k < p.size(); ++k) {
    const double sd_mean = std::sqrt(n * p[k] * (1 - p[k]) / reps);
    EXPECT_NEAR(sum[k] / reps, n * p[k], 5 * sd_mean + 1e-12) << "cell " << k;
  }
}

TEST(Power, TwoOutcomesIsTheTwoSidedZTest) {
  // K = 2: Pearson's statistic is z^2, and the noncentral chi-square (1 dof) power is the
  // two-sided z test's, P(|Z + d| > z_{alpha/2}) with d = sqrt(n) (p1 - p0) / sqrt(p0 q0)...
  // under the approximation's variance p0 q0, which is what lambda = n w2 encodes.
  const std::vector<double> p0 = {0.4, 0.6}, p1 = {0.47, 0.53};
  const std::uint64_t n = 500;
  for (std::uint64_t x : {150u, 200u, 231u}) {
    const std::vector<std::uint64_t> counts = {x, n - x};
    const double z = (static_cast<double>(x) - n * 0.4) / std::sqrt(n * 0.4 * 0.6);
    EXPECT_NEAR(pearson_statistic(counts, p0), z * z, 1e-9 * (1 + z * z));
  }
  const boost::math::normal std_normal;
  const double zc = boost::math::quantile(boost::math::complement(std_normal, 0.025));
  const double d = std::sqrt(static_cast<double>(n)) * (0.47 - 0.4) / std::sqrt(0.4 * 0.6);
  const double z_power = boost::math::cdf(std_normal, -zc + d) + boost::math::cdf(std_normal, -zc - d);
  EXPECT_NEAR(approx_power(p0, p1, n, 0.05), z_power, 1e-9);
}

TEST(Power, SimulatedPowerEqualsTheExactBinomialPower) {
  // K = 2 at a given n and the simulated critical value c: the exact power P_1(T > c) is a sum of
  // binomial pmf terms (Boost.Math). The simulated fraction must agree within its binomial error.
  const std::vector<double> p0 = {0.5, 0.5}, p1 = {0.56, 0.44};
  PowerTarget t;
  t.replicates = 20000;
  t.seed = 3;
  for (std::uint64_t n : {60u, 400u, 1500u}) {
    const PowerAtN at = simulated_power(p0, p1, n, t);
    const boost::math::binomial_distribution<double> b0(static_cast<double>(n), 0.5), b1(static_cast<double>(n), 0.56);
    double exact_power = 0.0, exact_size = 0.0;
    for (std::uint64_t x = 0; x <= n; ++x) {
      const std::vector<std::uint64_t> counts = {x, n - x};
      if (pearson_statistic(counts, p0) > at.critical) {
        exact_power += boost::math::pdf(b1, static_cast<double>(x));
        exact_size += boost::math::pdf(b0, static_cast<double>(x));
      }
    }
    const double reps = static_cast<double>(t.replicates);
    EXPECT_NEAR(at.power, exact_power, 4.5 * mc_sd(exact_power, reps)) << "n = " << n;
    EXPECT_NEAR(at.size, exact_size, 4.5 * mc_sd(exact_size, reps)) << "n = " << n;
    EXPECT_LE(at.size, 0.05);  // at most floor(alpha R) null draws above c, by construction
  }
}

TEST(Power, SizeUnderH0IsAlphaOnFreshDraws) {
  // The critical value from one set of H0 draws rejects a fraction ~alpha of independent H0 draws
  // (K = 6, n = 300: the statistic takes thousands of values; ties do not cut the size).
  const std::vector<double> p0 = {0.1, 0.15, 0.2, 0.25, 0.12, 0.18};
  PowerTarget t;
  t.replicates = 8000;
  t.seed = 21;
  const PowerAtN at = simulated_power(p0, p0, 300, t);
  const int fresh = 40000;
  int above = 0;
  std::vector<std::uint64_t> c(p0.size());
  for (int r = 0; r < fresh; ++r) {
    CountStream rng(99, static_cast<std::uint64_t>(r), CountStream::kNull);
    sample_multinomial(300, p0, rng, c);
    above += pearson_statistic(c, p0) > at.critical ? 1 : 0;
  }
  const double size = static_cast<double>(above) / fresh;
  // The estimated critical value's own noise adds the 1/R term.
  const double sd = std::sqrt(0.05 * 0.95 * (1.0 / fresh + 1.0 / static_cast<double>(t.replicates)));
  EXPECT_NEAR(size, 0.05, 4 * sd);
  // And the asymptotic quantile is close at this n (the chi-square approximation holds here).
  const double asym = boost::math::quantile(boost::math::complement(boost::math::chi_squared(5), 0.05));
  EXPECT_NEAR(at.critical, asym, 0.05 * asym);
}

TEST(Power, ApproximationIsRightForALargeEffect) {
  // A d6 with two faces at 0.2: n = 642. The exact power at the approximation's n is the target
  // within MC error (4 sd of 20000 replicates) plus 0.02 for the approximation itself (measured
  // with 200000 replicates: 0.792, i.e. the approximation is 0.008 optimistic at this n).
  const std::vector<double> p0(6, 1.0 / 6), p1 = {0.2, 0.2, 0.15, 0.15, 0.15, 0.15};
  const auto n = approx_n(p0, p1, 0.05, 0.8);
  ASSERT_TRUE(n.has_value());
  EXPECT_GT(*n, 100u);
  EXPECT_LT(*n, 2000u);
  EXPECT_GE(approx_power(p0, p1, *n, 0.05), 0.8);
  EXPECT_LT(approx_power(p0, p1, *n - 1, 0.05), 0.8);
  PowerTarget t;
  t.replicates = 20000;
  t.seed = 8;
  const PowerAtN at = simulated_power(p0, p1, *n, t);
  EXPECT_NEAR(at.power, 0.8, 4 * mc_sd(0.8, 20000) + 0.02) << "n = " << *n;
}

TEST(Power, SearchFindsTheCrossingAndIsReproducible) {
  const std::vector<double> p0 = {0.3, 0.3, 0.4}, p1 = {0.33, 0.28, 0.39};
  PowerTarget t;
  t.replicates = 2000;
  t.seed = 4;
  const auto start = approx_n(p0, p1, 0.05, 0.8);
  ASSERT_TRUE(start.has_value());
  const ExactN e = exact_n(p0, p1, t, *start);
  ASSERT_TRUE(e.n.has_value());
  EXPECT_GE(e.at.power, 0.8);
  EXPECT_EQ(e.at.n, *e.n);
  EXPECT_LT(simulated_power(p0, p1, *e.n - 1, t).power, 0.8);  // bisection ends next to a failure
  // Common random numbers: the same n from any starting point that brackets the same crossing,
  // and bit-identical results on a repeat.
  const ExactN again = exact_n(p0, p1, t, *start);
  EXPECT_EQ(again.n, e.n);
  EXPECT_EQ(again.at.critical, e.at.critical);
  // Within 15% of the approximation at this n (thousands of throws).
  EXPECT_NEAR(static_cast<double>(*e.n), static_cast<double>(*start), 0.15 * static_cast<double>(*start));
  // No difference: never reached.
  EXPECT_FALSE(approx_n(p0, p0, 0.05, 0.8).has_value());
}

TEST(Power, ExactNHasTheWantedPowerOnFreshDraws) {
  // The whole procedure, checked from outside: at the n the search returns, throws drawn afresh
  // (another seed, 10x the replicates) from p1 reject H0 (at the search's critical value) with
  // the wanted power. The tolerance is 4 sd of the search's estimate and of the fresh fraction.
  const std::vector<double> p0(6, 1.0 / 6), p1 = {0.19, 0.16, 0.16, 0.16, 0.16, 0.17};
  PowerTarget t;
  t.seed = 31;
  const auto start = approx_n(p0, p1, t.alpha, t.power);
  ASSERT_TRUE(start.has_value());
  const ExactN e = exact_n(p0, p1, t, *start);
  ASSERT_TRUE(e.n.has_value());
  const int fresh = 10 * static_cast<int>(t.replicates);
  int rejected = 0;
  std::vector<std::uint64_t> c(p0.size());
  for (int r = 0; r < fresh; ++r) {
    CountStream rng(777, static_cast<std::uint64_t>(r), CountStream::kAlternative);
    sample_multinomial(*e.n, p1, rng, c);
    rejected += pearson_statistic(c, p0) > e.at.critical ? 1 : 0;
  }
  const double power = static_cast<double>(rejected) / fresh;
  const double sd = std::sqrt(0.8 * 0.2 * (1.0 / fresh + 1.0 / static_cast<double>(t.replicates)));
  EXPECT_NEAR(power, 0.8, 4 * sd) << "n = " << *e.n;
}

TEST(Power, ZeroCellsUnderH0) {
  // p0 rules a face out: one such throw rejects, so n is where one occurs with the wanted power.
  const std::vector<double> p0 = {0.5, 0.5, 0.0}, p1 = {0.45, 0.45, 0.1};
  EXPECT_TRUE(std::isinf(pearson_statistic(std::vector<std::uint64_t>{3, 4, 1}, p0)));
  EXPECT_EQ(gof_dof(p0), 1);
  const auto n = approx_n(p0, p1, 0.05, 0.8);
  ASSERT_TRUE(n.has_value());
  EXPECT_EQ(*n, static_cast<std::uint64_t>(std::ceil(std::log(0.2) / std::log(0.9))));  // 16
  PowerTarget t;
  t.seed = 2;
  const ExactN e = exact_n(p0, p1, t, *n);
  ASSERT_TRUE(e.n.has_value());
  EXPECT_LE(*e.n, *n);
}

TEST(Power, BiasAlternativesShiftOneFaceAndSumToOne) {
  const std::vector<double> p = {0.005, 0.2, 0.795};
  const auto alts = bias_alternatives(p, 0.01, {1, 2, 3});
  ASSERT_EQ(alts.size(), 5u);  // face 1 cannot go down by 0.01
  for (const BiasAlternative& a : alts) {
    EXPECT_NEAR(std::accumulate(a.p.begin(), a.p.end(), 0.0), 1.0, 1e-12);
    EXPECT_NEAR(a.p[a.face], p[a.face] + 0.01 * a.sign, 1e-15);
    for (std::size_t j = 0; j < p.size(); ++j) {  // the others keep their ratios
      if (j == a.face) continue;
      EXPECT_NEAR(a.p[j] / (1 - a.p[a.face]), p[j] / (1 - p[a.face]), 1e-12);
    }
  }
  EXPECT_FALSE(alts[0].sign < 0 && alts[0].face == 0);
}

PowerStudyConfig small_study(int threads) {
  PowerStudyConfig cfg;
  cfg.tosses = 20000;
  cfg.seed = 5;
  cfg.threads = threads;
  cfg.bootstrap = 200;
  cfg.target.replicates = 1000;
  return cfg;
}

TEST(Power, StudiesDoNotDependOnThreads) {
  const DieModel a = compile(testing::slab_scene(0.5), "slab");
  const DieModel b = compile(testing::slab_scene(0.4), "slab 0.4");
  const AgainstStudy s1 = power_against(a, b, small_study(1));
  const AgainstStudy s2 = power_against(a, b, small_study(2));
  EXPECT_EQ(s1.a.counts, s2.a.counts);
  EXPECT_EQ(s1.b.counts, s2.b.counts);
  ASSERT_TRUE(s1.estimate.exact.n.has_value());
  EXPECT_EQ(s1.estimate.exact.n, s2.estimate.exact.n);
  EXPECT_EQ(s1.estimate.n_approx, s2.estimate.n_approx);
  EXPECT_EQ(s1.estimate.n_range95, s2.estimate.n_range95);
  // The batches add up to one run over the same indices.
  RunConfig rc;
  rc.seed = 5;
  rc.tosses = 20000;
  EXPECT_EQ(s1.a.counts, run_tosses(a, rc));
  // The range: the exact n scaled by the approximation's bootstrap quantiles, around the estimate.
  ASSERT_TRUE(s1.estimate.n_range95[0] && s1.estimate.n_range95[1] && s1.estimate.n_range95_approx[1]);
  EXPECT_LE(*s1.estimate.n_range95[0], *s1.estimate.exact.n);
  EXPECT_GE(*s1.estimate.n_range95[1], *s1.estimate.exact.n);
  EXPECT_NEAR(static_cast<double>(*s1.estimate.n_range95[1]) / static_cast<double>(*s1.estimate.exact.n),
              static_cast<double>(*s1.estimate.n_range95_approx[1]) / static_cast<double>(*s1.estimate.n_approx), 1e-3);
  EXPECT_GT(s1.estimate.replicate_sd, 0.0);

  const BiasStudy d1 = power_detect_bias(a, 0.02, small_study(1));
  const BiasStudy d2 = power_detect_bias(a, 0.02, small_study(2));
  EXPECT_EQ(d1.hardest, d2.hardest);
  EXPECT_EQ(d1.estimate.exact.n, d2.estimate.exact.n);
  ASSERT_EQ(d1.alternatives.size(), d2.alternatives.size());
  for (std::size_t i = 0; i < d1.alternatives.size(); ++i) EXPECT_EQ(d1.alternatives[i].exact.n, d2.alternatives[i].exact.n);
  const BiasAlternative& hardest = d1.alternatives[d1.hardest];
  for (const BiasAlternative& alt : d1.alternatives)  // the hardest needs the most
    EXPECT_LE(alt.exact.n.value_or(kMaxThrows), hardest.exact.n.value_or(kMaxThrows));
  // Its n is searched again on fresh replicates: exactly exact_n on replicates R..2R-1.
  EXPECT_TRUE(d1.refreshed);
  PowerTarget fresh = small_study(1).target;
  fresh.seed = 5;
  fresh.first_replicate = fresh.replicates;
  EXPECT_EQ(d1.estimate.exact.n, exact_n(d1.a.p, hardest.p, fresh, *hardest.exact.n).n);
}

TEST(Power, DetectBiasIsNotBiasedUpByItsMaximum) {
  // A fair die: twelve alternatives nearly alike, so the largest of their twelve noisy searches
  // overstates the n of the one it picks. Over 200 seeds, against a third, independent search of
  // the same alternative (replicates 2R..3R-1): the selecting searches are higher on average by
  // many standard errors, the estimate (the fresh search) is not.
  SceneDef def = testing::fair_scene();
  def.sim.fidelity = Fidelity::Static;  // the fastest tosses: the searches are what is tested
  const DieModel fair = compile(def, "fair");
  PowerStudyConfig cfg = small_study(2);
  cfg.tosses = 50000;
  cfg.bootstrap = 20;
  cfg.target.replicates = 300;
  const int seeds = 200;
  std::vector<double> selecting, estimate;
  for (int k = 0; k < seeds; ++k) {
    cfg.seed = 100 + static_cast<std::uint64_t>(k);
    const BiasStudy s = power_detect_bias(fair, 0.05, cfg);
    const BiasAlternative& h = s.alternatives[s.hardest];
    ASSERT_TRUE(h.exact.n && s.estimate.exact.n);
    PowerTarget third = cfg.target;
    third.seed = cfg.seed;
    third.first_replicate = 2 * third.replicates;
    const auto n3 = exact_n(s.a.p, h.p, third, *h.exact.n).n;
    ASSERT_TRUE(n3);
    selecting.push_back(static_cast<double>(*h.exact.n) - static_cast<double>(*n3));
    estimate.push_back(static_cast<double>(*s.estimate.exact.n) - static_cast<double>(*n3));
  }
  auto mean_se = [](const std::vector<double>& d) {
    const double m = std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(d.size());
    double v = 0.0;
    for (double x : d) v += (x - m) * (x - m);
    return std::make_pair(m, std::sqrt(v / static_cast<double>(d.size() - 1) / static_cast<double>(d.size())));
  };
  const auto [ms, ses] = mean_se(selecting);
  const auto [me, see] = mean_se(estimate);
  EXPECT_GT(ms, 4 * ses) << "the premise: the maximum is biased up";
  EXPECT_LT(std::abs(me), 4 * see) << "the estimate: mean " << me << " +/- " << see;
}

// ---- Command line ----------------------------------------------------------------------------

using testing::expect_bad_input;
using testing::run_dicesim;

TEST(CliPower, BadInputExits2WithNothingOnStdout) {
  const std::string die1 = "power scenes/paper/die1.toml ";
  expect_bad_input(run_dicesim(die1 + "--against scenes/fair.toml --alpha 1.5"), {"--alpha", "1.5", "(0, 1)"});
  expect_bad_input(run_dicesim(die1 + "--against scenes/fair.toml --alpha 0"), {"--alpha", "(0, 1)"});
  expect_bad_input(run_dicesim(die1 + "--against scenes/fair.toml --power 0.04"), {"--power", "0.04", "(0.05, 1)"});
  expect_bad_input(run_dicesim(die1 + "--against scenes/fair.toml --power 1"), {"--power", "(0.05, 1)"});
  expect_bad_input(run_dicesim(die1 + "--detect-bias 0.6"), {"--detect-bias", "0.6", "(0, 0.5]"});
  expect_bad_input(run_dicesim(die1 + "--detect-bias 0"), {"--detect-bias", "(0, 0.5]"});
  expect_bad_input(run_dicesim(die1 + "--against scenes/fair.toml --tosses 999"), {"--tosses", "999"});
  expect_bad_input(run_dicesim(die1), {"--against", "--detect-bias", "exactly one"});
  expect_bad_input(run_dicesim(die1 + "--against scenes/fair.toml --detect-bias 0.01"), {"exactly one"});
  expect_bad_input(run_dicesim(die1 + "--against scenes/dice/d20.toml --tosses 1000"),
                   {"scenes/dice/d20.toml", "outcome labels", "scenes/paper/die1.toml"});
  expect_bad_input(run_dicesim(die1 + "--against scenes/nope.toml"), {"scenes/nope.toml"});
  expect_bad_input(run_dicesim(die1 + "--against scenes/fair.toml --set throw.nope=1"), {"throw.nope"});
}

TEST(CliPower, JsonIsOneObjectAndMatchesTheTable) {
  const std::string args =
      "power scenes/paper/die1.toml --against scenes/fair.toml --tosses 20000 --replicates 1000 --bootstrap 200";
  const auto r = run_dicesim(args + " -j 2 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"mode", "scene", "against", "labels", "p_a", "p_b", "p_a_ci95", "alpha", "power", "n_exact",
                          "n_approx", "n_range95", "n_range95_approx", "n_exact_replicate_sd", "replicates", "simulated_tosses", "elapsed_s", "difference", "exact"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["mode"], "against");
  EXPECT_EQ(j["simulated_tosses"], 40000);
  EXPECT_EQ(j["labels"].size(), 6u);
  ASSERT_TRUE(j["n_exact"].is_number_unsigned());
  EXPECT_TRUE(j["difference"]["significant"].get<bool>());  // Die 1 is far from fair
  EXPECT_GE(j["exact"]["power"].get<double>(), 0.8);
  // One thread: the same numbers.
  const auto one = nlohmann::json::parse(run_dicesim(args + " -j 1 --json").out);
  EXPECT_EQ(one["n_exact"], j["n_exact"]);
  EXPECT_EQ(one["n_range95"], j["n_range95"]);
  EXPECT_EQ(one["p_b"], j["p_b"]);
  const auto table = run_dicesim(args);
  ASSERT_EQ(table.code, 0) << table.err;
  EXPECT_NE(table.out.find(std::to_string(j["n_exact"].get<std::uint64_t>())), std::string::npos) << table.out;

  const auto bias = run_dicesim("power scenes/fair.toml --detect-bias 0.05 --tosses 5000 --replicates 500 --bootstrap 100 --json");
  ASSERT_EQ(bias.code, 0) << bias.err;
  const auto b = nlohmann::json::parse(bias.out);
  EXPECT_EQ(b["mode"], "detect_bias");
  EXPECT_EQ(b["alternatives"].size(), 12u);
  EXPECT_TRUE(b["hardest"].contains("face"));
}

}  // namespace
}  // namespace dicesim
