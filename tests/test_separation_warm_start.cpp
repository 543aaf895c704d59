// The narrow phase's warm start (sim/dynamics/convex_distance.hpp, SeparationCache): a pair that
// moves a little between calls, started from the simplex its previous call ended with, gets the
// cold start's answer (distance, normal) in fewer GJK iterations; a cache left by another pair
// (or any valid indices) still gives the right answer; an overlapping pair takes the SAT either way
// and leaves in the cache the simplex that held the origin, from which it is known to overlap again
// at once. Cubes and a square pyramid (5 corners), random placements, fixed seeds.
#include "sim/dynamics/convex_distance.hpp"
#include "tests/random_geometry.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace dicesim {
namespace {

// A convex polytope with what PlacedHull needs (corners, outward face normals, edge directions,
// one per parallel class), in its own frame.
struct Shape {
  std::string name;
  std::vector<Vec3> corners, normals, edges;
  PlacedHull placed(const Mat3& R, const Vec3& x) const { return {corners, normals, edges, R, x}; }
};

// A cube of side `side` about its centre.
Shape cube(double side) {
  Shape s{"cube", {}, {}, {}};
  for (int i = 0; i < 8; ++i)
    s.corners.push_back(0.5 * side * Vec3(i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0));
  s.normals = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
  s.edges = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  return s;
}

// A square pyramid: base 1 x 1 at z = -1/4, apex at (0, 0, 3/4) (its centroid at the origin).
Shape pyramid() {
  Shape s{"pyramid", {}, {}, {}};
  s.corners = {{0.5, 0.5, -0.25}, {-0.5, 0.5, -0.25}, {-0.5, -0.5, -0.25}, {0.5, -0.5, -0.25}, {0, 0, 0.75}};
  // A side face through the apex and the base edge at x = 0.5: normal along (1, 0, 1/2).
  s.normals = {-Vec3::UnitZ(), Vec3(1, 0, 0.5).normalized(), Vec3(-1, 0, 0.5).normalized(), Vec3(0, 1, 0.5).normalized(),
               Vec3(0, -1, 0.5).normalized()};
  s.edges = {Vec3::UnitX(), Vec3::UnitY()};
  for (int k = 0; k < 4; ++k) s.edges.push_back((s.corners[4] - s.corners[static_cast<std::size_t>(k)]).normalized());
  return s;
}

using testing::random_rotation;
using testing::random_unit;
// A small turn: about a random axis by a normal angle of deviation `sigma`.
Mat3 small_rotation(std::mt19937_64& rng, double sigma) {
  std::normal_distribution<double> g(0.0, sigma);
  const Vec3 axis = random_unit(rng);
  return Eigen::AngleAxisd(g(rng), axis).toRotationMatrix();
}

// The warm answer is the cold one's: distance within 1e-9 relative (or 1e-15 absolute); separated by
// more than 1e-9, the same normal within 1e-6 and both GJK's.
void expect_same(const Separation& warm, const Separation& cold, const std::string& where) {
  EXPECT_NEAR(warm.distance, cold.distance, std::max(1e-9 * std::abs(cold.distance), 1e-15)) << where;
  if (cold.distance > 1e-9) {
    EXPECT_LE((warm.normal - cold.normal).norm(), 1e-6) << where << ": normals " << warm.normal.transpose() << " vs "
                                                         << cold.normal.transpose();
    EXPECT_FALSE(warm.sat) << where;
    EXPECT_FALSE(warm.degenerate) << where;
    // The witness points lie the distance apart along the normal.
    EXPECT_NEAR(warm.normal.dot(warm.point_b - warm.point_a), warm.distance, 1e-12) << where;
  }
}

bool valid(const SeparationCache& c, const Shape& a, const Shape& b) {
  if (c.n < 0 || c.n > 4) return false;
  for (int q = 0; q < c.n; ++q) {
    const auto i = static_cast<std::size_t>(q);
    if (c.ia[i] < 0 || c.ia[i] >= static_cast<int>(a.corners.size()) || c.ib[i] < 0 ||
        c.ib[i] >= static_cast<int>(b.corners.size()))
      return false;
  }
  return true;
}

// Random pairs (each kind of pair in turn), B drifting by small random turns and moves over 200 steps,
// one cache per pair kept across them: every step's answer is the cold start's, and the warm starts
// take fewer GJK iterations in all.
TEST(SeparationWarmStart, DriftingPairsMatchTheColdStartInFewerIterations) {
  const Shape shapes[] = {cube(1.0), pyramid()};
  std::mt19937_64 rng(20240541);
  std::uniform_real_distribution<double> gap(1.0, 2.2);
  std::normal_distribution<double> move(0.0, 0.01);
  long warm_iterations = 0, cold_iterations = 0;
  int steps = 0, separated = 0, overlapping = 0, cached = 0;
  for (int pair = 0; pair < 24; ++pair) {
    const Shape& sa = shapes[pair % 2];
    const Shape& sb = shapes[(pair / 2) % 2];
    const Mat3 Ra = random_rotation(rng);
    const Vec3 xa(0.3, -0.2, 0.1);
    Mat3 Rb = random_rotation(rng);
    Vec3 xb = xa + gap(rng) * random_unit(rng);
    SeparationCache cache;
    for (int step = 0; step < 200; ++step) {
      Rb = small_rotation(rng, 0.02) * Rb;
      xb += Vec3(move(rng), move(rng), move(rng));
      const PlacedHull a = sa.placed(Ra, xa), b = sb.placed(Rb, xb);
      cached += cache.n > 0;
      const Separation warm = separation(a, b, &cache);
      const Separation cold = separation(a, b);
      const std::string where = sa.name + "-" + sb.name + " pair " + std::to_string(pair) + " step " + std::to_string(step);
      expect_same(warm, cold, where);
      ASSERT_TRUE(valid(cache, sa, sb)) << where;
      if (cold.distance > 0.0 && !cold.sat) {
        ++separated;
        EXPECT_GT(cache.n, 0) << where;
      } else {
        ++overlapping;
        // The simplex that held the origin is kept: measured again where it is, the pair is known
        // to overlap at once.
        EXPECT_GT(cache.n, 0) << where;
        SeparationCache again = cache;
        const Separation repeat = separation(a, b, &again);
        EXPECT_EQ(repeat.iterations, 0) << where;
        expect_same(repeat, cold, where);
      }
      warm_iterations += warm.iterations;
      cold_iterations += cold.iterations;
      ++steps;
    }
  }
  std::printf("[ warm start ] %d steps (%d separated, %d overlapping, %d started from a cache): GJK iterations "
              "warm %ld (%.2f a step), cold %ld (%.2f a step)\n",
              steps, separated, overlapping, cached, warm_iterations, double(warm_iterations) / steps, cold_iterations,
              double(cold_iterations) / steps);
  RecordProperty("warm_iterations", std::to_string(warm_iterations));
  RecordProperty("cold_iterations", std::to_string(cold_iterations));
  EXPECT_GT(separated, steps / 2);
  EXPECT_GT(cached, steps / 2);
  EXPECT_LT(warm_iterations, cold_iterations);
}

// A cache from another pair entirely (its indices valid for this one: every index below 5), or any
// valid indices at all, starts a search that still ends at the right answer, and leaves this pair's
// simplex (the one that held the origin) in the cache.
TEST(SeparationWarmStart, ForeignCacheStillGivesTheRightAnswer) {
  const Shape c = cube(1.0), p = pyramid(), big = cube(1.7);
  std::mt19937_64 rng(777);
  std::uniform_real_distribution<double> gap(1.2, 3.0);
  // Caches left by cube pairs, kept when every index is below 5 (valid for a pyramid too).
  std::vector<SeparationCache> foreign;
  while (foreign.size() < 40) {
    SeparationCache cache;
    const Mat3 Ra = random_rotation(rng), Rb = random_rotation(rng);
    const PlacedHull a = big.placed(Ra, Vec3::Zero()), b = c.placed(Rb, gap(rng) * 1.3 * random_unit(rng));
    separation(a, b, &cache);
    if (cache.n == 0) continue;
    bool small = true;
    for (int q = 0; q < cache.n; ++q) small &= cache.ia[static_cast<std::size_t>(q)] < 5 && cache.ib[static_cast<std::size_t>(q)] < 5;
    if (small) foreign.push_back(cache);
  }
  // And made-up ones: one to three distinct corner pairs below 5.
  std::uniform_int_distribution<int> corner(0, 4), count(1, 3);
  while (foreign.size() < 120) {
    SeparationCache cache;
    cache.n = count(rng);
    for (int q = 0; q < cache.n; ++q) {
      auto& ia = cache.ia[static_cast<std::size_t>(q)];
      auto& ib = cache.ib[static_cast<std::size_t>(q)];
      bool repeat = true;
      while (repeat) {
        ia = corner(rng);
        ib = corner(rng);
        repeat = false;
        for (int r = 0; r < q; ++r)
          repeat |= cache.ia[static_cast<std::size_t>(r)] == ia && cache.ib[static_cast<std::size_t>(r)] == ib;
      }
    }
    foreign.push_back(cache);
  }
  const std::pair<const Shape*, const Shape*> pairs[] = {{&p, &p}, {&p, &c}, {&c, &p}, {&c, &c}};
  int k = 0;
  for (const SeparationCache& start : foreign)
    for (const auto& [sa, sb] : pairs) {
      const PlacedHull a = sa->placed(random_rotation(rng), Vec3(0.1, 0.2, -0.3));
      const PlacedHull b = sb->placed(random_rotation(rng), a.x + gap(rng) * random_unit(rng));
      SeparationCache cache = start;
      const Separation warm = separation(a, b, &cache);
      const Separation cold = separation(a, b);
      const std::string where = sa->name + "-" + sb->name + " case " + std::to_string(k++);
      expect_same(warm, cold, where);
      ASSERT_TRUE(valid(cache, *sa, *sb)) << where;
      EXPECT_GT(cache.n, 0) << where;
      // The cache it leaves is this pair's: started from it again, the same answer at once.
      const Separation again = separation(a, b, &cache);
      expect_same(again, cold, where + " again");
      EXPECT_LE(again.iterations, cold.iterations) << where;
    }
}

// Overlapping pairs take the SAT with or without a cache (a cache from the pair's separated past,
// an empty one, or made-up indices): the same depth and axis, and the cache left holding the
// simplex that held the origin.
TEST(SeparationWarmStart, OverlappingPairsTakeTheSatAndKeepTheirSimplex) {
  const Shape shapes[] = {cube(1.0), pyramid()};
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> near(0.0, 0.45);
  int tested = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Shape& sa = shapes[trial % 2];
    const Shape& sb = shapes[(trial / 2) % 2];
    const Mat3 Ra = random_rotation(rng), Rb = random_rotation(rng);
    const Vec3 xa(-0.2, 0.4, 0.05), dir = random_unit(rng);
    const PlacedHull a = sa.placed(Ra, xa), b = sb.placed(Rb, xa + near(rng) * dir);
    const Separation cold = separation(a, b);
    const std::string where = sa.name + "-" + sb.name + " trial " + std::to_string(trial);
    ASSERT_TRUE(cold.sat) << where;
    ASSERT_LE(cold.distance, 0.0) << where;
    ++tested;
    // The cache this pair had when B was still 3 away along the same direction.
    SeparationCache past;
    separation(a, sb.placed(Rb, xa + 3.0 * dir), &past);
    ASSERT_GT(past.n, 0) << where;
    SeparationCache made_up;
    made_up.n = 3;
    made_up.ia = {0, 1, 2};
    made_up.ib = {4, 3, 0};
    for (SeparationCache cache : {past, SeparationCache{}, made_up}) {
      const Separation warm = separation(a, b, &cache);
      EXPECT_TRUE(warm.sat) << where;
      EXPECT_NEAR(warm.distance, cold.distance, std::max(1e-9 * std::abs(cold.distance), 1e-15)) << where;
      EXPECT_LE((warm.normal - cold.normal).norm(), 1e-12) << where;
      EXPECT_GT(cache.n, 0) << where;
      EXPECT_TRUE(valid(cache, sa, sb)) << where;
    }
  }
  EXPECT_EQ(tested, 400);
}

}  // namespace
}  // namespace dicesim
