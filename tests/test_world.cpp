// Several dice and obstacles in one toss (issue 41): independence and the sum's law, walls that hold,
// a pyramid that a fast-spinning die never passes through, and how much a controlled craps throw
// still decides without and with the backboard.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_runner.hpp"
#include "fidelity_test_util.hpp"
#include "sim/body/world.hpp"
#include "sim/dynamics/convex_distance.hpp"
#include "sim/scene/scene.hpp"
#include "sim/study/statistics.hpp"

namespace {

using namespace dicesim;

const std::string kWorld = std::string(DICESIM_SOURCE_DIR) + "/scenes/world/";

DieModel world_model(const std::string& toml, const std::vector<std::string>& overrides = {}) {
  return compile(parse_scene(toml, kWorld + "test.toml", overrides));
}

// Two fair d6 thrown 0.6 m apart, each its own throw: they never meet, so their faces are
// independent, and each is fair.
const char* kApart = R"(
name = "apart"
[[dice]]
scene = "../dice/d6.toml"
offset = [0.0, -0.3, 0.0]
[[dice]]
scene = "../dice/d6.toml"
offset = [0.0, 0.3, 0.0]
[sim]
fidelity = "impulse"
)";

TEST(World, TwoFairDiceThrownApartHaveIndependentFaces) {
  const DieModel m = world_model(kApart);
  ASSERT_TRUE(m.world);
  ASSERT_EQ(m.outcomes(), 36);
  EXPECT_EQ(m.outcome_labels.front(), 11);
  EXPECT_EQ(m.outcome_labels.back(), 66);
  const std::uint64_t n = 3600;
  const RunCounts c = dicesim::testing::run(m, n, 41);
  // Dice that wander together and come to rest leaning on each other (cocked) have no answer.
  EXPECT_LE(c.unresolved, n / 500);
  EXPECT_EQ(c.invalid, 0u);
  // Pearson's contingency chi-square on the 6 x 6 table, (6 - 1)^2 = 25 degrees of freedom.
  std::array<double, 6> row{}, col{};
  double total = 0.0;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) {
      const double x = static_cast<double>(c.faces[static_cast<std::size_t>(6 * a + b)]);
      row[static_cast<std::size_t>(a)] += x;
      col[static_cast<std::size_t>(b)] += x;
      total += x;
    }
  double chi2 = 0.0;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) {
      const double e = row[static_cast<std::size_t>(a)] * col[static_cast<std::size_t>(b)] / total;
      const double d = static_cast<double>(c.faces[static_cast<std::size_t>(6 * a + b)]) - e;
      chi2 += d * d / e;
    }
  const double p = chi2_p_value(chi2, 25);
  std::printf("2d6 apart, %llu tosses: contingency chi2 %.1f (25 dof), p %.3f\n", (unsigned long long)n, chi2, p);
  EXPECT_GT(p, 0.001);  // at a fixed seed: a dependence (a shared stream, say) gives p ~ 0
  const ChiSquare first = chi2_uniform(std::vector<std::uint64_t>(
      {static_cast<std::uint64_t>(row[0]), static_cast<std::uint64_t>(row[1]), static_cast<std::uint64_t>(row[2]),
       static_cast<std::uint64_t>(row[3]), static_cast<std::uint64_t>(row[4]), static_cast<std::uint64_t>(row[5])}));
  EXPECT_GT(first.p_value, 0.001);
}

// The tray scene: two fair dice from one hand, striking each other and the walls. Their sum must
// follow 1, 2, ..., 6, ..., 1 / 36.
TEST(World, TheSumOfTwoFairDiceInATrayIsTriangular) {
  const DieModel m = compile(load_scene(kWorld + "tray-2d6.toml"));
  ASSERT_EQ(m.outcomes(), 11);
  const std::uint64_t n = 3600;
  const RunCounts c = dicesim::testing::run(m, n, 41);
  std::vector<double> p;
  for (int s = 2; s <= 12; ++s) p.push_back((6.0 - std::abs(s - 7)) / 36.0);
  const ChiSquare x = chi2_against(c.faces, p);
  std::printf("tray 2d6, %llu tosses: sum chi2 %.1f, p %.3f; unresolved %llu, overlaps %llu\n", (unsigned long long)n,
              x.statistic, x.p_value, (unsigned long long)c.unresolved,
              (unsigned long long)c.corrections.contact_overlaps);
  EXPECT_GT(x.p_value, 0.001);
  // A die held still off its rest (leaning on a wall or the other die, or left on a wall's top) is
  // unresolved: 0.44 % at seed 41 today (docs/world.md, "What it leaves out").
  EXPECT_LE(c.unresolved, n / 100);
}

// The fair 16 mm d6 of scenes/dice/d6.toml, stated here: a scene parsed from text resolves
// `extends` against the working directory.
const std::string kPlasticD6 = R"(
[materials.plastic]
density = 1180.0
restitution = 0.5
friction = 0.3
[die]
shape = "d6"
size = 0.016
rounding = 0.0015
material = "plastic"
)";

// A die dropped into the corner of two walls, moving toward it: it bounces off and rests on the
// floor, never inside either wall.
TEST(World, ADieDroppedOntoAWallCornerNeverEndsInsideTheWall) {
  const std::string scene = std::string(R"(
name = "corner"
[materials.wood]
density = 700.0
restitution = 0.5
friction = 0.4
[[obstacles]]
kind = "plane"
material = "wood"
point = [0, 0, 0]
normal = [1, 0, 0]
[[obstacles]]
kind = "plane"
material = "wood"
point = [0, 0, 0]
normal = [0, 1, 0]
[throw.height]
mean = 0.2
sd = 0.05
[throw.velocity]
mean = [-1.0, -1.0, 0.0]
sd = [0.3, 0.3, 0.3]
[throw.spin]
sd = [30, 30, 30]
[sim]
fidelity = "impulse"
)") + kPlasticD6;
  // The release 3 cm out from each wall (the die's bounding radius is 11 mm).
  DieModel m = world_model(scene);
  auto w = std::make_shared<World>(*m.world);
  w->offsets[0] = Vec3(0.03, 0.03, 0.0);
  m.world = w;
  const DieModel& d = w->dice[0];
  int settled = 0, struck = 0;
  for (std::uint64_t i = 0; i < 400; ++i) {
    RigidState end;
    TossProbe probe;
    probe.final_state = &end;
    const TossResult r = toss(m, 7, i, &probe);
    ASSERT_NE(r.status, TossStatus::Invalid) << i;
    settled += r.status == TossStatus::Settled;
    struck += probe.interactions > 0;
    for (const Vec3& v : d.vertices) {
      const Vec3 x = end.position + end.R * v;
      // Inside by more than the floor allows a held corner to sink in a step (1e-4 r) is inside.
      EXPECT_GT(x.x() - d.rounding, -1e-4 * d.bounding_radius) << "toss " << i;
      EXPECT_GT(x.y() - d.rounding, -1e-4 * d.bounding_radius) << "toss " << i;
    }
    EXPECT_EQ(r.corrections.contact_overlaps, 0u) << i << " overlap " << probe.max_overlap;
  }
  EXPECT_EQ(settled, 400);
  EXPECT_GT(struck, 300);  // the walls were hit, not missed
}

// A d6 spinning at 1000 rad/s thrown at a pyramid 40 cm tall: conservative advancement bounds every
// point's speed, so the die bounces off its face (or is deflected around it) and never ends inside
// or behind it.
TEST(World, APyramidHitAt1000RadPerSecondIsNeverTunnelled) {
  const std::string scene = std::string(R"(
name = "pyramid"
[materials.stone]
density = 2500.0
restitution = 0.5
friction = 0.3
[[obstacles]]
kind = "polyhedron"
material = "stone"
vertices = [[0.1, -0.1, 0.0], [0.3, -0.1, 0.0], [0.3, 0.1, 0.0], [0.1, 0.1, 0.0], [0.2, 0.0, 0.4]]
[throw.height]
mean = 0.06
sd = 0.01
[throw.velocity]
mean = [3.0, 0.0, 0.0]
sd = [0.3, 0.02, 0.1]
[throw.spin]
kind = "random-axis"
mean = 1000
sd = 20
[sim]
fidelity = "impulse"
)") + kPlasticD6;
  const DieModel m = world_model(scene);
  const World& w = *m.world;
  const PlacedHull pyramid{w.pieces[0].corners, w.pieces[0].face_normals, w.pieces[0].edge_dirs, Mat3::Identity(),
                           Vec3::Zero()};
  int hit = 0;
  for (std::uint64_t i = 0; i < 300; ++i) {
    RigidState end;
    TossProbe probe;
    probe.final_state = &end;
    const TossResult r = toss(m, 11, i, &probe);
    ASSERT_NE(r.status, TossStatus::Invalid) << i;
    hit += probe.interactions > 0;
    // Behind it: past its front and within its width (a die deflected sideways may roll around it).
    const bool behind = end.position.x() > 0.1 && std::abs(end.position.y()) < 0.1;
    EXPECT_FALSE(behind) << "toss " << i << " ended behind the pyramid, at y " << end.position.y();
    EXPECT_GT(point_distance(pyramid, end.position), 0.0) << "toss " << i;
    EXPECT_EQ(r.corrections.contact_overlaps, 0u) << i << " overlap " << probe.max_overlap;
  }
  EXPECT_EQ(hit, 300);
}

// A dice setter's throw (craps-controlled.toml): both dice set with the same face up, backspin,
// little scatter. The mutual information between the face set up (each of the six, equally often)
// and the first die's face read, without the backboard and with it. Plug-in estimates with the
// Miller-Madow correction (the plug-in's bias, (6 - 1)^2 / (2 N ln 2) = 0.020 bits at N = 900,
// subtracted). Measured at seed 1: 0.087 bits without, 0.017 with. The assertions leave a margin of
// several standard errors of such an estimate (~0.01 bits here).
double mutual_information_bits(const std::array<std::array<double, 6>, 6>& n) {
  double total = 0.0;
  std::array<double, 6> row{}, col{};
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) {
      row[static_cast<std::size_t>(a)] += n[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)];
      col[static_cast<std::size_t>(b)] += n[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)];
      total += n[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)];
    }
  double mi = 0.0;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) {
      const double x = n[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)];
      if (x > 0.0) mi += x / total * std::log2(x * total / (row[static_cast<std::size_t>(a)] * col[static_cast<std::size_t>(b)]));
    }
  return mi - 25.0 / (2.0 * total * std::log(2.0));
}

TEST(World, TheBackboardRandomisesAControlledCrapsThrow) {
  // The orientation that puts each face of a standard d6 up: 1 (+z), 2 (+x), 3 (+y), 4 (-y), 5 (-x), 6 (-z).
  const std::array<Vec3, 6> set_up = {Vec3(0, 0, 0),   Vec3(0, 90, 90),  Vec3(0, 90, 0),
                                      Vec3(0, -90, 0), Vec3(0, 90, -90), Vec3(0, 180, 0)};
  const std::uint64_t per_face = 150;
  double mi[2] = {};
  int hit_board = 0;
  for (int board = 0; board < 2; ++board) {
    std::array<std::array<double, 6>, 6> n{};
    for (int f = 0; f < 6; ++f) {
      SceneDef d = load_scene(kWorld + "craps-controlled.toml");
      if (!board) d.obstacles.clear();
      d.throw_.orientation.euler_deg = set_up[static_cast<std::size_t>(f)];
      const DieModel m = compile(d);
      for (std::uint64_t i = 0; i < per_face; ++i) {
        TossProbe probe;
        const TossResult r = toss(m, 1, i, &probe);
        hit_board += board && probe.interactions > 0;
        if (r.status != TossStatus::Settled) continue;
        const int first = r.face / 10;  // a tuple's label: the first die's face, then the second's
        ASSERT_GE(first, 1);
        ASSERT_LE(first, 6);
        n[static_cast<std::size_t>(f)][static_cast<std::size_t>(first - 1)] += 1.0;
      }
    }
    mi[board] = mutual_information_bits(n);
  }
  std::printf("controlled craps throw, 6 x %llu tosses: I(face set; face read) %.3f bits without the backboard, "
              "%.3f with it (%d of %llu struck it or the other die)\n",
              (unsigned long long)per_face, mi[0], mi[1], hit_board, (unsigned long long)(6 * per_face));
  EXPECT_GT(mi[0], 0.05);  // the setting shows without the board
  EXPECT_LT(mi[1], 0.04);  // and is mostly gone with it
  EXPECT_GT(hit_board, static_cast<int>(5 * per_face));
}

// The CLI on a world scene: `toss --json` reports the toss's outcomes (sums here) and how they were
// made; `info` says it is a world; `show`, which draws one die, refuses it as bad input.
TEST(World, TheCliTossesAWorldAndShowRefusesIt) {
  const dicesim::testing::CliRun toss = dicesim::testing::run_dicesim("toss scenes/world/tray-2d6.toml -n 40 --json");
  ASSERT_EQ(toss.code, 0) << toss.err;
  EXPECT_NE(toss.out.find("\"face\":12"), std::string::npos) << toss.out;  // the sums 2 .. 12 are the labels
  EXPECT_NE(toss.out.find("\"fidelity\":\"impulse\""), std::string::npos);
  const dicesim::testing::CliRun info = dicesim::testing::run_dicesim("info scenes/world/craps.toml");
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_NE(info.out.find("2 dice"), std::string::npos) << info.out;
  dicesim::testing::expect_bad_input(dicesim::testing::run_dicesim("show scenes/world/craps.toml -o -"),
                                     {"scenes/world/craps.toml", "draws one die alone"});
}

}  // namespace

// An instant whose strikes reach their cap (16 Gauss-Seidel sweeps over its contacts, slow contacts
// still approaching, left to the window) is a multi-contact solve not converged: a correction every
// report carries (pgs_unconverged), not only the bench's probe. The dice tower's wedged dice reach it.
TEST(World, CappedSweepsAreReportedAsCorrections) {
  const DieModel m = compile(load_scene(kWorld + "tower-3d6.toml"));
  std::uint64_t capped = 0, unconverged = 0;
  for (std::uint64_t i = 0; i < 40; ++i) {
    TossProbe probe;
    const TossResult r = toss(m, 20261122, i, &probe);
    capped += probe.sweeps_capped;
    unconverged += r.corrections.pgs_unconverged;
  }
  ASSERT_GT(capped, 0u);  // the case is met
  EXPECT_GE(unconverged, capped);
}

// After a patch's solve the witness point is struck on its own only if it still approaches by more
// than rounding (1e-10 of the speeds involved, as the floor's law allows). At zero, every tray toss
// struck ~2 witness points approaching at 1e-16 to 1e-14 of the speeds: noise, counted as strikes.
TEST(World, WitnessStrikesAreApproachesNotRounding) {
  const DieModel m = compile(load_scene(kWorld + "tray-2d6.toml"));
  TossProbe probe;
  for (std::uint64_t i = 0; i < 100; ++i) toss(m, 20261122, i, &probe);
  ASSERT_GT(probe.interactions, 500u);  // the dice strike the tray and each other
  EXPECT_LE(probe.witness_strikes, 5u);
}
