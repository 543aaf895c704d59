// Pins the `paper` fidelity's counts on the ready scenes, so that work on other fidelities or on
// speed cannot change its answers unnoticed. The numbers are exact: toss i depends only on
// (scene, seed, i) and the build keeps IEEE semantics (no -ffast-math, no FMA contraction).
// They were produced by this code on x86-64 (glibc libm); a deliberate change to the paper
// physics, or a platform whose libm rounds sin/cos differently, needs them regenerated: run the
// test and copy the "actual" values after checking the change is intended.
#include <gtest/gtest.h>

#include "fidelity_test_util.hpp"

namespace {

using namespace dicesim;

using dicesim::testing::check_pinned;
using dicesim::testing::Golden;

TEST(PaperRegression, CountsArePinned) {
  const Golden golden[] = {
      {"scenes/paper/die1.toml", {3367, 3364, 3323, 3419, 2817, 3710}, 33436},
      {"scenes/paper/die2.toml", {3326, 3373, 3369, 3394, 2990, 3548}, 33593},
      {"scenes/paper/die3.toml", {3113, 3635, 3348, 3341, 3558, 3005}, 33626},
      {"scenes/fair.toml", {3380, 3372, 3268, 3359, 3262, 3359}, 34138},
  };
  for (const Golden& g : golden) check_pinned(g, Fidelity::Paper, 20000);
}

}  // namespace
