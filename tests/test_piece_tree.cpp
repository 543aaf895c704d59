// The obstacles' broad phase (sim/body/piece_tree.hpp): the pieces it visits near a sphere are
// exactly those brute force over every box finds, with a fixed reach and with one that shrinks; its
// order does not depend on the order it was given the pieces in; and the craps backboard's tree
// holds every polyhedron piece once.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "sim/body/piece_tree.hpp"
#include "sim/body/world.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene.hpp"

namespace {

using namespace dicesim;

constexpr double kInf = std::numeric_limits<double>::infinity();

// Random boxes in the unit cube, some thin, some long, a few on top of each other (equal centres).
struct Boxes {
  std::vector<Vec3> lo, hi;
  std::vector<int> include;  // all but every seventh (as planes are left out)
};

// Uniform in [0, 1)^3, drawn x, y, z in turn (a constructor's arguments have no order).
Vec3 uniform3(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double x = u(rng), y = u(rng), z = u(rng);
  return {x, y, z};
}

Boxes random_boxes(std::mt19937_64& rng, int n) {
  Boxes b;
  for (int p = 0; p < n; ++p) {
    if (p % 11 == 10) {  // a copy of the one before: ties in the split
      b.lo.push_back(b.lo.back());
      b.hi.push_back(b.hi.back());
    } else {
      const Vec3 c = uniform3(rng);
      const Vec3 s = uniform3(rng), t = uniform3(rng);
      const Vec3 half(0.1 * s.x() * t.x(), 0.1 * s.y(), 0.3 * s.z() * t.z() * t.y());
      b.lo.push_back(c - half);
      b.hi.push_back(c + half);
    }
    if (p % 7 != 3) b.include.push_back(p);
  }
  return b;
}

struct Query {
  Vec3 centre;
  double radius, reach;
};

Query random_query(std::mt19937_64& rng) {
  const Vec3 c = 1.4 * uniform3(rng) - Vec3::Constant(0.2), s = uniform3(rng);
  return {c, 0.05 * s.x(), 0.2 * s.y()};
}

// Brute force: every included piece and its gap, those within `reach`.
std::vector<std::pair<int, double>> brute(const Boxes& b, const Query& q, double reach) {
  std::vector<std::pair<int, double>> out;
  for (const int p : b.include) {
    const auto k = static_cast<std::size_t>(p);
    const double gap = PieceTree::box_gap(b.lo[k], b.hi[k], q.centre, q.radius);
    if (gap <= reach) out.emplace_back(p, gap);
  }
  return out;
}

TEST(PieceTree, VisitsExactlyThePiecesBruteForceFindsWithinAFixedReach) {
  std::mt19937_64 rng(20240541);
  const Boxes b = random_boxes(rng, 500);
  const PieceTree tree(b.lo, b.hi, b.include);
  ASSERT_EQ(tree.size(), static_cast<int>(b.include.size()));
  std::size_t found = 0;
  for (int i = 0; i < 2000; ++i) {
    const Query q = random_query(rng);
    std::vector<std::pair<int, double>> visited;
    tree.visit_near(q.centre, q.radius, q.reach, [&](int p, double gap) { visited.emplace_back(p, gap); });
    std::sort(visited.begin(), visited.end());  // brute's order is by index; each piece once
    ASSERT_EQ(visited, brute(b, q, q.reach)) << "query " << i;
    found += visited.size();
  }
  EXPECT_GT(found, 2000u);  // the queries do find pieces (not a vacuous match of empty sets)
}

TEST(PieceTree, AShrinkingReachFindsTheNearestGap) {
  std::mt19937_64 rng(41);
  const Boxes b = random_boxes(rng, 500);
  const PieceTree tree(b.lo, b.hi, b.include);
  std::size_t visits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Query q = random_query(rng);
    double nearest = kInf;
    tree.visit_near(q.centre, q.radius, kInf, [&](int, double gap) {
      ++visits;
      nearest = std::min(nearest, gap);
      return std::min(nearest, gap + 0.01);
    });
    double want = kInf;
    for (const auto& [p, gap] : brute(b, q, kInf)) want = std::min(want, gap);
    ASSERT_EQ(nearest, want) << "query " << i;
  }
  // Near first: the shrinking reach prunes almost every piece (brute force visits 429 per query).
  EXPECT_LT(visits, 2000u * 10u);
}

TEST(PieceTree, OrderDoesNotDependOnTheOrderThePiecesCameIn) {
  std::mt19937_64 rng(7);
  Boxes b = random_boxes(rng, 300);
  const PieceTree forward(b.lo, b.hi, b.include);
  std::reverse(b.include.begin(), b.include.end());
  const PieceTree backward(b.lo, b.hi, b.include);
  EXPECT_TRUE(std::equal(forward.pieces().begin(), forward.pieces().end(), backward.pieces().begin(),
                         backward.pieces().end()));
  for (int i = 0; i < 200; ++i) {
    const Query q = random_query(rng);
    std::vector<int> a, c;
    forward.visit_near(q.centre, q.radius, q.reach, [&](int p, double) { a.push_back(p); });
    backward.visit_near(q.centre, q.radius, q.reach, [&](int p, double) { c.push_back(p); });
    ASSERT_EQ(a, c) << "query " << i;
  }
}

TEST(PieceTree, EmptyAndSinglePiece) {
  const std::vector<Vec3> lo{Vec3(0, 0, 0)}, hi{Vec3(1, 1, 1)};
  int calls = 0;
  PieceTree().visit_near(Vec3::Zero(), 0.0, kInf, [&](int, double) { ++calls; });
  PieceTree(lo, hi, std::vector<int>{}).visit_near(Vec3::Zero(), 0.0, kInf, [&](int, double) { ++calls; });
  EXPECT_EQ(calls, 0);
  const PieceTree one(lo, hi, std::vector<int>{0});
  // 2 from the box's face x = 1, radius 0.5: gap 1.5.
  one.visit_near(Vec3(3, 0.5, 0.5), 0.5, 1.5, [&](int p, double gap) {
    ++calls;
    EXPECT_EQ(p, 0);
    EXPECT_DOUBLE_EQ(gap, 1.5);
  });
  one.visit_near(Vec3(3, 0.5, 0.5), 0.5, 1.49, [&](int, double) { ++calls; });
  EXPECT_EQ(calls, 1);
  // Inside the box: 0 - radius.
  EXPECT_DOUBLE_EQ(PieceTree::box_gap(lo[0], hi[0], Vec3(0.5, 0.5, 0.5), 0.25), -0.25);
  EXPECT_THROW(PieceTree(lo, hi, std::vector<int>{0, 0}), std::invalid_argument);
  EXPECT_THROW(PieceTree(lo, hi, std::vector<int>{1}), std::out_of_range);
}

// The craps scene, compiled as a toss compiles it: the tree holds every polyhedron piece (the
// board and its pyramids) once and no plane, and finds what brute force finds near the board.
TEST(PieceTree, CrapsBackboardHoldsEveryPolyhedronOnce) {
  const DieModel m = compile(load_scene(std::string(DICESIM_SOURCE_DIR) + "/scenes/world/craps.toml"));
  ASSERT_TRUE(m.world);
  const World& w = *m.world;
  std::vector<int> polyhedra;
  for (std::size_t p = 0; p < w.pieces.size(); ++p)
    if (!w.pieces[p].plane) polyhedra.push_back(static_cast<int>(p));
  ASSERT_GT(polyhedra.size(), 300u);  // the board and its pyramids
  std::vector<int> held(w.piece_tree.pieces().begin(), w.piece_tree.pieces().end());
  std::sort(held.begin(), held.end());
  EXPECT_EQ(held, polyhedra);
  std::vector<int> visited;
  w.piece_tree.visit_near(Vec3::Zero(), 0.0, kInf, [&](int p, double) { visited.push_back(p); });
  std::sort(visited.begin(), visited.end());
  EXPECT_EQ(visited, polyhedra);

  // A die's bounding sphere at random points within 5 cm of the board's boxes.
  Vec3 lo = w.piece_lo[static_cast<std::size_t>(polyhedra[0])], hi = lo;
  for (const int p : polyhedra) {
    lo = lo.cwiseMin(w.piece_lo[static_cast<std::size_t>(p)]);
    hi = hi.cwiseMax(w.piece_hi[static_cast<std::size_t>(p)]);
  }
  lo -= Vec3::Constant(0.05);
  hi += Vec3::Constant(0.05);
  std::mt19937_64 rng(321);
  const double radius = w.dice[0].bounding_radius;
  for (int i = 0; i < 500; ++i) {
    const Vec3 c = lo + (hi - lo).cwiseProduct(uniform3(rng));
    const double reach = 0.02 * (i % 5);
    std::vector<int> got, want;
    w.piece_tree.visit_near(c, radius, reach, [&](int p, double) { got.push_back(p); });
    for (const int p : polyhedra) {
      const auto k = static_cast<std::size_t>(p);
      if (PieceTree::box_gap(w.piece_lo[k], w.piece_hi[k], c, radius) <= reach) want.push_back(p);
    }
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, want) << "query " << i;
  }
}

}  // namespace
