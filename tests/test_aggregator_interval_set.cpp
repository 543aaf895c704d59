// The interval set that de-duplicates toss indices: fresh sub-ranges, gaps, merging, removal.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "aggregator/interval_set.hpp"

using dicesim::agg::IntervalSet;

TEST(AggregatorIntervalSet, ReportsOnlyFreshSubranges) {
  IntervalSet s;
  EXPECT_EQ(s.add(10, 20), 10u);
  std::vector<IntervalSet::Range> fresh;
  const auto n = s.add(5, 25, [&](std::uint64_t a, std::uint64_t b) { fresh.emplace_back(a, b); });
  EXPECT_EQ(n, 10u);
  ASSERT_EQ(fresh.size(), 2u);
  EXPECT_EQ(fresh[0], IntervalSet::Range(5, 10));
  EXPECT_EQ(fresh[1], IntervalSet::Range(20, 25));
  EXPECT_EQ(s.ranges(), 1u);  // merged
  EXPECT_EQ(s.size(), 20u);
  EXPECT_EQ(s.add(5, 25), 0u);  // a full duplicate adds nothing
}

TEST(AggregatorIntervalSet, GapsCoversAndRunEnd) {
  IntervalSet s;
  s.add(0, 10);
  s.add(20, 30);
  s.add(30, 35);  // touching ranges merge
  EXPECT_EQ(s.ranges(), 2u);
  EXPECT_TRUE(s.covers(0, 10));
  EXPECT_FALSE(s.covers(0, 11));
  EXPECT_TRUE(s.covers(22, 35));
  EXPECT_EQ(s.run_end(0), 10u);
  EXPECT_EQ(s.run_end(12), 12u);
  const auto g = s.gaps(5, 40);
  ASSERT_EQ(g.size(), 2u);
  EXPECT_EQ(g[0], IntervalSet::Range(10, 20));
  EXPECT_EQ(g[1], IntervalSet::Range(35, 40));
  EXPECT_TRUE(s.gaps(20, 35).empty());
}

TEST(AggregatorIntervalSet, RemoveSplits) {
  IntervalSet s;
  s.add(0, 100);
  s.remove(10, 20);
  EXPECT_EQ(s.size(), 90u);
  EXPECT_FALSE(s.contains(15));
  EXPECT_TRUE(s.contains(9));
  EXPECT_TRUE(s.contains(20));
  s.remove(0, 1000);
  EXPECT_TRUE(s.empty());
  EXPECT_EQ(s.size(), 0u);
}

// Against a std::set of indices, with random overlapping adds and removes.
TEST(AggregatorIntervalSet, MatchesANaiveSet) {
  std::mt19937_64 rng(7);
  IntervalSet s;
  std::set<std::uint64_t> ref;
  for (int step = 0; step < 3000; ++step) {
    const std::uint64_t a = rng() % 500, b = a + rng() % 40;
    if (rng() % 4 == 0) {
      s.remove(a, b);
      for (auto i = a; i < b; ++i) ref.erase(i);
    } else {
      std::uint64_t fresh = 0;
      for (auto i = a; i < b; ++i) fresh += ref.insert(i).second ? 1 : 0;
      ASSERT_EQ(s.add(a, b), fresh);
    }
    ASSERT_EQ(s.size(), ref.size());
  }
  for (std::uint64_t i = 0; i < 560; ++i) ASSERT_EQ(s.contains(i), ref.count(i) == 1) << i;
}
