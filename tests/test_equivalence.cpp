// Equivalence tests (TOST per outcome, Holm across outcomes): sim/study/equivalence.hpp.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "scenes_for_tests.hpp"
#include "sim/models/compile.hpp"
#include "sim/study/equivalence.hpp"
#include "sim/study/monte_carlo.hpp"

namespace dicesim {
namespace {

using Counts = std::vector<std::uint64_t>;

// A fair d6's counts over n tosses (n divisible by 6).
Counts fair(std::uint64_t n) { return Counts(6, n / 6); }

TEST(Equivalence, OneOutcomeByHand) {
  // d = 0.001, se = 0.001, delta = 0.002: p- = 1 - Phi(3) = 0.0013499, p+ = Phi(-1) = 0.1586553.
  const OutcomeEquivalence o = tost(0.001, 0.001, 0.002, 0.10);
  EXPECT_NEAR(o.p_lower, 0.0013499, 1e-7);
  EXPECT_NEAR(o.p_upper, 0.1586553, 1e-7);
  EXPECT_DOUBLE_EQ(o.tost_p, o.p_upper);
  // The 80% (1 - 2 alpha) interval: d -+ 1.2815516 se.
  EXPECT_NEAR(o.ci.lo, 0.001 - 0.0012815516, 1e-9);
  EXPECT_NEAR(o.ci.hi, 0.001 + 0.0012815516, 1e-9);
  // No variance: decided by the difference alone.
  EXPECT_EQ(tost(0.0, 0.0, 0.002, 0.10).tost_p, 0.0);
  EXPECT_EQ(tost(0.003, 0.0, 0.002, 0.10).tost_p, 1.0);
  EXPECT_THROW(tost(0.0, 0.001, 0.0, 0.10), std::invalid_argument);
}

TEST(Equivalence, HolmStepDown) {
  // Sorted 0.005, 0.01, 0.03, 0.04 times 4, 3, 2, 1: 0.02, 0.03, 0.06, 0.04 -> monotone 0.06.
  const std::vector<double> adj = holm_adjust({0.01, 0.04, 0.03, 0.005});
  ASSERT_EQ(adj.size(), 4u);
  EXPECT_NEAR(adj[0], 0.03, 1e-15);
  EXPECT_NEAR(adj[1], 0.06, 1e-15);
  EXPECT_NEAR(adj[2], 0.06, 1e-15);
  EXPECT_NEAR(adj[3], 0.02, 1e-15);
  EXPECT_EQ(holm_adjust({0.5, 0.6})[1], 1.0);  // capped at 1
}

TEST(Equivalence, IdenticalLargeRunsAreEquivalent) {
  // 10^6 tosses each, identical fair counts: se = sqrt(2 (1/6)(5/6) / 1e6) = 5.27e-4, z = 3.79.
  const Equivalence e = equivalence_unpaired(fair(1'000'002), fair(1'000'002), absolute_margin(0.002));
  EXPECT_TRUE(e.equivalent);
  for (const OutcomeEquivalence& o : e.outcomes) {
    EXPECT_LT(o.holm_p, 0.10);
    EXPECT_NEAR(o.se, 5.2705e-4, 1e-7);
  }
}

TEST(Equivalence, AOnePercentDifferenceIsNotEquivalent) {
  Counts a = fair(1'000'002), b = a;
  a[0] += 10'000;  // p_a(1) 0.1750 against 0.1667: d = +0.0083 (and -0.0017 on the others)
  a[1] -= 10'000;
  const Equivalence e = equivalence_unpaired(a, b, absolute_margin(0.002));
  EXPECT_FALSE(e.equivalent);
  EXPECT_FALSE(e.outcomes[0].equivalent);
  EXPECT_FALSE(e.outcomes[1].equivalent);
  EXPECT_GT(e.outcomes[0].tost_p, 0.5);
  EXPECT_TRUE(e.outcomes[2].equivalent);  // the untouched faces still are
}

TEST(Equivalence, HolmTurnsTheVerdict) {
  // Identical fair d6 runs of 3e5 tosses: each face alone passes (z = 0.002 / 9.62e-4 = 2.08,
  // p = 0.0188 < 0.10) but Holm multiplies the smallest of six equal p's by 6: 0.113 > 0.10.
  // (So an unpaired test at the 3e5 tosses cannot call a d6 equivalent at 0.002 even
  // when the two runs agree exactly: pair the tosses, or toss more.)
  const Equivalence e = equivalence_unpaired(fair(300'000), fair(300'000), absolute_margin(0.002));
  for (const OutcomeEquivalence& o : e.outcomes) {
    EXPECT_NEAR(o.tost_p, 0.01876, 1e-4);
    EXPECT_LT(o.tost_p, 0.10);
    EXPECT_NEAR(o.holm_p, 6.0 * o.tost_p, 1e-12);
    EXPECT_FALSE(o.equivalent);
  }
  EXPECT_FALSE(e.equivalent);
  // A d20 at the same size passes: p = 0.05, se = 5.63e-4, z = 3.55.
  const Equivalence d20 = equivalence_unpaired(Counts(20, 15'000), Counts(20, 15'000), absolute_margin(0.002));
  EXPECT_TRUE(d20.equivalent);
}

TEST(Equivalence, PairedTossesUseTheDiscordantCounts) {
  // The same 3e5 toss indices; 1 000 tosses per face changed away from it and 1 000 to it:
  // var D = 2000 / 3e5, se = sqrt(var / 3e5) = 1.49e-4, z = 13.4: equivalent, where the unpaired
  // test (above) is not.
  const Counts a = fair(300'000), b = a, moved(6, 1000);
  const Equivalence e = equivalence_paired(a, b, moved, moved, absolute_margin(0.002));
  EXPECT_TRUE(e.paired);
  EXPECT_TRUE(e.equivalent);
  EXPECT_NEAR(e.outcomes[0].se, 1.4907e-4, 1e-8);
  // 2 400 tosses moved from face 1 to face 2: d = +-0.008, not equivalent.
  Counts a2 = a, a_only(6, 0), b_only(6, 0);
  a2[0] += 2400;
  a2[1] -= 2400;
  a_only[0] = 2400;
  b_only[1] = 2400;
  const Equivalence f = equivalence_paired(a2, b, a_only, b_only, absolute_margin(0.002));
  EXPECT_FALSE(f.equivalent);
  EXPECT_FALSE(f.outcomes[0].equivalent);
  EXPECT_TRUE(f.outcomes[2].equivalent);
  // Discordant counts that cannot be: a[i] - b[i] != a_only[i] - b_only[i].
  EXPECT_THROW(equivalence_paired(a2, b, moved, moved, absolute_margin(0.002)), std::invalid_argument);
}

TEST(Equivalence, PairedCountsFromPerTossOutcomes) {
  // Toss 0: both 0; 1: 0 -> 1; 2: 2 -> 0; 3: B did not settle (dropped); 4: both 1.
  const PairedCounts p = paired_counts({0, 0, 2, 1, 1}, {0, 1, 0, -1, 1}, 3);
  EXPECT_EQ(p.pairs, 4u);
  EXPECT_EQ(p.dropped, 1u);
  EXPECT_EQ(p.a, (Counts{2, 1, 1}));
  EXPECT_EQ(p.b, (Counts{2, 2, 0}));
  EXPECT_EQ(p.a_only, (Counts{1, 0, 1}));
  EXPECT_EQ(p.b_only, (Counts{1, 1, 0}));
  EXPECT_NO_THROW(equivalence_paired(p.a, p.b, p.a_only, p.b_only, absolute_margin(0.5)));
  EXPECT_THROW(paired_counts({0, 1}, {0}, 3), std::invalid_argument);
  EXPECT_THROW(paired_counts({0, 3}, {0, 1}, 3), std::invalid_argument);
}

TEST(Equivalence, RelativeMarginOnARareOutcome) {
  // A coin's edge at 1% of 1e5 tosses, margin 0.2 p_edge = 0.002 (pooled p): se = 4.45e-4.
  const Counts a{49'500, 49'500, 1000};
  EXPECT_TRUE(equivalence_unpaired(a, a, relative_margin(0.2)).equivalent);
  const Counts b{49'350, 49'350, 1300};  // the edge 30% more often
  const Equivalence e = equivalence_unpaired(a, b, relative_margin(0.2));
  EXPECT_FALSE(e.equivalent);
  EXPECT_FALSE(e.outcomes[2].equivalent);
  EXPECT_NEAR(e.outcomes[2].margin, 0.2 * 2300.0 / 200'000.0, 1e-15);
  // An edge neither run saw (a small run): equivalent, though its relative margin is 0.
  const Equivalence none = equivalence_unpaired({500, 500, 0}, {510, 490, 0}, relative_margin(0.2));
  EXPECT_TRUE(none.outcomes[2].equivalent);
  EXPECT_EQ(none.outcomes[2].margin, 0.0);
  EXPECT_TRUE(none.equivalent);  // heads and tails within 20 % of 0.5: z = 4.1 and 5.0 at 1000 tosses
}

// run_tosses' per-toss outcomes (what `toss --outcomes` writes): the counts they add up to, the
// same on any number of threads.
TEST(RunTosses, PerTossOutcomesAreTheCountsOnAnyThreads) {
  const DieModel m = compile(testing::fair_scene());
  std::vector<std::int16_t> one, two;
  RunConfig cfg;
  cfg.seed = 7;
  cfg.tosses = 700;
  cfg.threads = 1;
  cfg.outcomes = &one;
  const RunCounts c1 = run_tosses(m, cfg);
  cfg.threads = 2;
  cfg.outcomes = &two;
  const RunCounts c2 = run_tosses(m, cfg);
  ASSERT_EQ(one.size(), 700u);
  EXPECT_EQ(one, two);
  EXPECT_EQ(c1, c2);
  Counts n(6, 0);
  for (const std::int16_t o : one) {
    ASSERT_GE(o, 0);
    ++n[static_cast<std::size_t>(o)];
  }
  EXPECT_EQ(n, c1.faces);
}

TEST(Equivalence, BadInputThrows) {
  EXPECT_THROW(equivalence_unpaired({1, 2}, {1, 2, 3}, absolute_margin(0.01)), std::invalid_argument);
  EXPECT_THROW(equivalence_unpaired({0, 0}, {1, 2}, absolute_margin(0.01)), std::invalid_argument);
  EXPECT_THROW(equivalence_unpaired({1, 2}, {1, 2}, absolute_margin(0.01), 0.5), std::invalid_argument);
  EXPECT_THROW(equivalence_unpaired({1, 2}, {1, 2}, absolute_margin(-0.01)), std::invalid_argument);
}

}  // namespace
}  // namespace dicesim
