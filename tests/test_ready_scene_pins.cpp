// Pins every ready scene's exact counts in every fidelity, so that a change of the physics on any
// of them is a visible decision (README, "Physics changes are visible decisions"). Dice 1-3 and
// the fair die are pinned at larger counts in test_paper_regression.cpp and
// test_impulse_regression.cpp; here they add only `static`. Each row: the counts in label order,
// the bounces, the unresolved and invalid tosses, and the four corrections (energy clamps,
// unconverged solves, overlap fixes, fallbacks), seed 20261122, 2 threads. The counts are small
// (a few hundred `impulse` tosses, a few dozen `stepped`) because a pin guards the bits, not the
// statistics. Regenerate: DICESIM_PRINT_PINS=1 build/tests/dicesim_tests
// --gtest_filter='ReadyScenes.*' prints every row as it is now; copy them only after checking
// that the change is intended, and say why in the commit.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "fidelity_test_util.hpp"

namespace {

using namespace dicesim;

struct Pin {
  const char* scene;
  Fidelity fidelity;
  std::uint64_t tosses;
  std::vector<std::uint64_t> counts;  // label order
  std::uint64_t bounces;
  std::uint64_t unresolved, invalid;
  std::array<std::uint64_t, 4> corrections;
};

const char* enum_name(Fidelity f) {
  switch (f) {
    case Fidelity::Static: return "Static";
    case Fidelity::Paper: return "Paper";
    case Fidelity::Impulse: return "Impulse";
    case Fidelity::Stepped: return "Stepped";
    case Fidelity::Auto: return "Auto";
  }
  return "?";
}

void check(const Pin& p) {
  const DieModel m = compile(dicesim::testing::with_fidelity(
      load_scene(std::string(DICESIM_SOURCE_DIR) + "/" + p.scene), p.fidelity));
  const RunCounts c = dicesim::testing::run(m, p.tosses, 20261122);
  const std::array<std::uint64_t, 4> corr = {c.corrections.energy_clamps, c.corrections.pgs_unconverged,
                                             c.corrections.overlap_fixes, c.corrections.fallbacks};
  const std::string what = std::string(to_string(p.fidelity)) + " " + p.scene;
  EXPECT_EQ(c.faces, p.counts) << what;
  EXPECT_EQ(c.bounces, p.bounces) << what;
  EXPECT_EQ(c.unresolved, p.unresolved) << what;
  EXPECT_EQ(c.invalid, p.invalid) << what;
  EXPECT_EQ(corr, p.corrections) << what;  // the target is 0; what they are today is pinned, so a change is seen
  if (::testing::Test::HasFailure() || std::getenv("DICESIM_PRINT_PINS")) {
    std::string counts;
    for (std::size_t k = 0; k < c.faces.size(); ++k)
      counts += (k ? ", " : "") + std::to_string(c.faces[k]);
    std::printf("      {\"%s\", Fidelity::%s, %llu, {%s}, %llu, %llu, %llu, {%llu, %llu, %llu, %llu}},\n", p.scene,
                enum_name(p.fidelity), (unsigned long long)p.tosses, counts.c_str(), (unsigned long long)c.bounces,
                (unsigned long long)c.unresolved, (unsigned long long)c.invalid, (unsigned long long)corr[0],
                (unsigned long long)corr[1], (unsigned long long)corr[2], (unsigned long long)corr[3]);
  }
}

// The polyhedral dice (d4 to d20, prisms, hollow and loaded dice, the seed's variants).
TEST(ReadyScenes, PolyhedralCountsArePinnedInEveryFidelity) {
  const Pin pins[] = {
      {"scenes/paper/die1.toml", Fidelity::Static, 4000, {506, 643, 677, 644, 649, 881}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/die2.toml", Fidelity::Static, 4000, {566, 660, 685, 651, 653, 785}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/die3.toml", Fidelity::Static, 4000, {784, 777, 684, 632, 549, 574}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/fair.toml", Fidelity::Static, 4000, {647, 668, 691, 652, 653, 689}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d4.toml", Fidelity::Static, 4000, {993, 1005, 1025, 977}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d4.toml", Fidelity::Paper, 4000, {1000, 968, 1018, 1014}, 4594, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d4.toml", Fidelity::Impulse, 400, {102, 103, 84, 111}, 5838, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d4.toml", Fidelity::Stepped, 40, {12, 10, 8, 10}, 748, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d6.toml", Fidelity::Static, 4000, {647, 668, 691, 652, 653, 689}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d6.toml", Fidelity::Paper, 4000, {640, 669, 652, 700, 667, 672}, 8737, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d6.toml", Fidelity::Impulse, 400, {61, 77, 68, 68, 69, 57}, 6825, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d6.toml", Fidelity::Stepped, 40, {10, 7, 6, 4, 6, 7}, 811, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d8.toml", Fidelity::Static, 4000, {481, 499, 491, 502, 512, 509, 495, 511}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d8.toml", Fidelity::Paper, 4000, {523, 453, 505, 514, 512, 490, 500, 503}, 5655, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d8.toml", Fidelity::Impulse, 400, {53, 40, 50, 50, 51, 46, 60, 50}, 5786, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d8.toml", Fidelity::Stepped, 40, {4, 8, 6, 5, 6, 4, 5, 2}, 765, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d10.toml", Fidelity::Static, 4000, {386, 383, 393, 405, 392, 419, 410, 406, 403, 403}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d10.toml", Fidelity::Paper, 4000, {380, 384, 399, 421, 413, 398, 416, 377, 425, 387}, 9143, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d10.toml", Fidelity::Impulse, 400, {39, 40, 44, 37, 42, 37, 28, 32, 46, 55}, 7771, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d10.toml", Fidelity::Stepped, 40, {2, 5, 5, 4, 2, 4, 4, 4, 6, 4}, 822, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d12.toml", Fidelity::Static, 4000, {331, 317, 308, 351, 359, 330, 339, 342, 314, 339, 331, 339}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d12.toml", Fidelity::Paper, 4000, {313, 332, 344, 348, 324, 333, 339, 355, 334, 311, 317, 350}, 17120, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d12.toml", Fidelity::Impulse, 400, {32, 42, 28, 32, 37, 40, 38, 32, 38, 34, 30, 17}, 8959, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d12.toml", Fidelity::Stepped, 40, {6, 2, 4, 3, 1, 5, 2, 3, 4, 4, 1, 5}, 1137, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d20.toml", Fidelity::Static, 4000, {220, 184, 207, 191, 178, 203, 198, 205, 184, 192, 206, 209, 191, 211, 196, 210, 190, 207, 204, 214}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d20.toml", Fidelity::Paper, 4000, {194, 194, 204, 192, 200, 200, 207, 185, 217, 188, 210, 204, 205, 217, 184, 212, 193, 200, 186, 208}, 10679, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d20.toml", Fidelity::Impulse, 400, {21, 16, 20, 19, 22, 22, 21, 28, 23, 16, 20, 18, 29, 12, 17, 15, 21, 26, 17, 17}, 7640, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/d20.toml", Fidelity::Stepped, 40, {0, 2, 3, 2, 2, 2, 3, 3, 1, 3, 4, 2, 1, 1, 0, 2, 2, 2, 2, 3}, 890, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/loaded-d20.toml", Fidelity::Static, 4000, {263, 253, 257, 217, 193, 244, 208, 226, 206, 152, 238, 180, 181, 193, 158, 182, 149, 167, 152, 181}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/loaded-d20.toml", Fidelity::Paper, 4000, {182, 186, 216, 205, 195, 210, 199, 189, 203, 237, 197, 215, 209, 208, 177, 216, 197, 207, 175, 177}, 11546, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/loaded-d20.toml", Fidelity::Impulse, 400, {26, 41, 36, 18, 33, 30, 24, 20, 16, 12, 24, 23, 18, 13, 11, 10, 16, 11, 12, 6}, 8135, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/loaded-d20.toml", Fidelity::Stepped, 40, {4, 2, 2, 5, 2, 4, 6, 1, 0, 0, 2, 0, 1, 3, 1, 1, 3, 1, 1, 1}, 948, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/binom3.toml", Fidelity::Static, 4000, {500, 523, 1499, 1478, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/binom3.toml", Fidelity::Paper, 4000, {28, 34, 100, 96, 550, 541, 251, 242, 77, 54, 246, 241, 248, 261, 527, 504}, 5456, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/binom3.toml", Fidelity::Impulse, 400, {18, 23, 161, 198, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, 6828, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/binom3.toml", Fidelity::Stepped, 40, {1, 3, 20, 16, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, 754, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/binom4.toml", Fidelity::Static, 4000, {243, 1020, 1452, 1019, 266, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/binom4.toml", Fidelity::Paper, 4000, {12, 39, 582, 50, 9, 467, 357, 367, 173, 154, 143, 131, 17, 25, 150, 172, 347, 330, 475}, 5982, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/binom4.toml", Fidelity::Impulse, 400, {12, 116, 149, 118, 5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, 6652, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/binom4.toml", Fidelity::Stepped, 40, {0, 7, 24, 9, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, 773, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/hollow-d6.toml", Fidelity::Static, 4000, {666, 664, 691, 653, 650, 676}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/hollow-d6.toml", Fidelity::Paper, 4000, {677, 661, 663, 676, 654, 669}, 6922, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/hollow-d6.toml", Fidelity::Impulse, 400, {76, 63, 67, 61, 69, 64}, 6518, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/hollow-d6.toml", Fidelity::Stepped, 40, {5, 3, 6, 12, 9, 5}, 869, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/prism3.toml", Fidelity::Static, 4000, {1313, 1306, 1298, 57, 26}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/prism3.toml", Fidelity::Paper, 4000, {946, 956, 1001, 546, 551}, 5332, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/prism3.toml", Fidelity::Impulse, 400, {140, 133, 127, 0, 0}, 6650, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/prism3.toml", Fidelity::Stepped, 40, {14, 13, 13, 0, 0}, 543, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/steel-cuboid.toml", Fidelity::Static, 4000, {1152, 412, 428, 398, 416, 1194}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/steel-cuboid.toml", Fidelity::Paper, 4000, {859, 565, 532, 577, 604, 863}, 8061, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/steel-cuboid.toml", Fidelity::Impulse, 400, {159, 13, 10, 10, 6, 202}, 6952, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/steel-cuboid.toml", Fidelity::Stepped, 40, {23, 2, 1, 1, 0, 13}, 800, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/plastic.toml", Fidelity::Static, 4000, {647, 668, 691, 652, 653, 689}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/plastic.toml", Fidelity::Paper, 4000, {673, 644, 648, 680, 675, 680}, 6679, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/plastic.toml", Fidelity::Impulse, 400, {66, 68, 73, 71, 66, 56}, 6424, 0, 0, {0, 0, 0, 0}},
      {"scenes/dice/plastic.toml", Fidelity::Stepped, 40, {11, 7, 3, 5, 8, 6}, 840, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-euler-uniform.toml", Fidelity::Static, 4000, {969, 440, 487, 450, 426, 1228}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-euler-uniform.toml", Fidelity::Paper, 4000, {631, 678, 662, 633, 586, 810}, 6539, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-euler-uniform.toml", Fidelity::Impulse, 400, {37, 61, 82, 52, 49, 119}, 6664, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-euler-uniform.toml", Fidelity::Stepped, 40, {4, 4, 9, 6, 9, 8}, 782, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-swapped-restitution.toml", Fidelity::Static, 4000, {506, 643, 677, 644, 649, 881}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-swapped-restitution.toml", Fidelity::Paper, 4000, {585, 633, 646, 698, 701, 737}, 6922, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-swapped-restitution.toml", Fidelity::Impulse, 400, {45, 59, 64, 54, 67, 111}, 6677, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-swapped-restitution.toml", Fidelity::Stepped, 40, {5, 8, 4, 7, 8, 8}, 836, 0, 0, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-variance-reading.toml", Fidelity::Static, 4000, {498, 635, 667, 635, 641, 873}, 0, 0, 51, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-variance-reading.toml", Fidelity::Paper, 4000, {513, 656, 687, 687, 666, 740}, 6615, 0, 51, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-variance-reading.toml", Fidelity::Impulse, 400, {32, 59, 66, 52, 61, 128}, 6696, 0, 2, {0, 0, 0, 0}},
      {"scenes/paper/variants/die1-seed-variance-reading.toml", Fidelity::Stepped, 40, {1, 9, 6, 7, 3, 14}, 842, 0, 0, {0, 0, 0, 0}},
  };
  for (const Pin& p : pins) check(p);
}

// The coins: the rim's curved contact has its own step (rim_step.cpp); guards that fire are
// counted (docs/fidelity.md, "Corrections"). The `impulse` rows are at a cylinder's default contact
// step, 0.2 ms (quarter-table.toml no longer sets its own 0.5 ms): why each row changed, when, is in
// `git log -p` of this file.
TEST(ReadyScenes, CoinCountsArePinnedInEveryFidelity) {
  const Pin pins[] = {
      {"scenes/coins/quarter.toml", Fidelity::Static, 4000, {235, 1852, 1913}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter.toml", Fidelity::Paper, 4000, {1892, 1025, 1083}, 8296, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter.toml", Fidelity::Impulse, 400, {2, 198, 200}, 8377, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter.toml", Fidelity::Stepped, 40, {0, 15, 25}, 362, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter-table.toml", Fidelity::Static, 4000, {0, 4000, 0}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter-table.toml", Fidelity::Paper, 4000, {1197, 1649, 1154}, 7575, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter-table.toml", Fidelity::Impulse, 400, {2, 212, 186}, 7345, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter-table.toml", Fidelity::Stepped, 40, {0, 20, 20}, 306, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/nickel-table.toml", Fidelity::Static, 4000, {0, 4000, 0}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/nickel-table.toml", Fidelity::Paper, 4000, {1224, 1592, 1184}, 7552, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/nickel-table.toml", Fidelity::Impulse, 400, {3, 225, 172}, 7154, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/nickel-table.toml", Fidelity::Stepped, 40, {1, 20, 19}, 307, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/euro-table.toml", Fidelity::Static, 4000, {0, 4000, 0}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/euro-table.toml", Fidelity::Paper, 4000, {1109, 1703, 1188}, 7870, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/euro-table.toml", Fidelity::Impulse, 400, {5, 213, 182}, 9147, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/euro-table.toml", Fidelity::Stepped, 40, {3, 17, 20}, 301, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/three-sided-coin.toml", Fidelity::Static, 4000, {1370, 1288, 1342}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/three-sided-coin.toml", Fidelity::Paper, 4000, {1366, 1311, 1323}, 11430, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/three-sided-coin.toml", Fidelity::Impulse, 400, {125, 136, 139}, 9223, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/three-sided-coin.toml", Fidelity::Stepped, 40, {13, 21, 6}, 422, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter-caught.toml", Fidelity::Static, 4000, {0, 4000, 0}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter-caught.toml", Fidelity::Paper, 4000, {0, 2019, 1981}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter-caught.toml", Fidelity::Impulse, 400, {0, 201, 199}, 0, 0, 0, {0, 0, 0, 0}},
      {"scenes/coins/quarter-caught.toml", Fidelity::Stepped, 40, {0, 23, 17}, 0, 0, 0, {0, 0, 0, 0}},
  };
  for (const Pin& p : pins) check(p);
}

// Several dice and obstacles (scenes/world/): `impulse` only, the one model that strikes bodies
// against each other (`static` reads dice alone and refuses obstacles). Counts are of the toss's
// outcomes (tuples or sums, label order); unresolved tosses have a die held still off its rest (leaning, or on an obstacle).
TEST(ReadyScenes, WorldCountsArePinned) {
  const Pin pins[] = {
      {"scenes/world/tray-2d6.toml", Fidelity::Impulse, 200, {5, 11, 14, 28, 35, 31, 21, 23, 20, 10, 1}, 4742, 1, 0, {0, 1, 0, 0}},
      {"scenes/world/loaded-pair.toml", Fidelity::Impulse, 200, {6, 4, 3, 4, 4, 7, 8, 6, 9, 3, 2, 10, 7, 3, 7, 3, 5, 15, 6, 5, 6, 5, 6, 4, 3, 6, 4, 8, 9, 6, 3, 5, 4, 5, 4, 2}, 4599, 3, 0, {0, 0, 0, 0}},
      {"scenes/world/craps.toml", Fidelity::Impulse, 100, {2, 6, 10, 10, 17, 17, 13, 10, 9, 5, 1}, 3153, 0, 0, {0, 0, 0, 0}},
      {"scenes/world/craps-controlled.toml", Fidelity::Impulse, 100, {0, 3, 0, 3, 0, 1, 2, 10, 6, 8, 2, 5, 1, 6, 1, 4, 2, 2, 1, 5, 1, 1, 3, 2, 1, 0, 4, 6, 4, 1, 1, 3, 6, 1, 3, 1}, 2831, 0, 0, {0, 0, 0, 0}},
      {"scenes/world/tower-3d6.toml", Fidelity::Impulse, 40, {0, 0, 2, 1, 6, 5, 3, 6, 3, 5, 4, 0, 1, 2, 1, 0}, 3341, 1, 0, {0, 3, 0, 0}},
  };
  for (const Pin& p : pins) check(p);
}

}  // namespace
