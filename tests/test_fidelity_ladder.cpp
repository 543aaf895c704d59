// The fidelity ladder end to end: names, auto, fair dice, heavy face down, determinism, and the
// agreement of `impulse` with its reference `stepped` on the seed's three dice.
#include <gtest/gtest.h>

#include "fidelity_test_util.hpp"
#include "sim/models/compile.hpp"
#include "sim/study/agreement.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/study/statistics.hpp"

using namespace dicesim;
using namespace dicesim::testing;

namespace {
const std::string kScenes = std::string(DICESIM_SOURCE_DIR) + "/scenes/";
}

TEST(FidelityLadder, NamesRoundTrip) {
  for (Fidelity f : {Fidelity::Static, Fidelity::Paper, Fidelity::Impulse, Fidelity::Stepped, Fidelity::Auto})
    EXPECT_EQ(parse_fidelity(to_string(f)), f);
  EXPECT_FALSE(parse_fidelity("exact"));
  EXPECT_THROW(load_scene(kScenes + "fair.toml", {"sim.step=0"}), SceneError);
  EXPECT_THROW(load_scene(kScenes + "fair.toml", {"sim.contact_step=1"}), SceneError);
}

// Auto is no longer decided by the scene's features when it is compiled (frictionless once meant
// `paper`): compile keeps it requested and tosses `impulse` until a pilot at the run's precision
// shows a cheaper model adequate (test_auto_fidelity.cpp).
TEST(FidelityLadder, AutoIsMeasuredNotReadFromFeatures) {
  SceneDef s = with_fidelity(fair_scene(), Fidelity::Auto);
  s.materials["plastic"].friction = 0.0;
  const DieModel m = compile(s);
  EXPECT_EQ(m.fidelity, Fidelity::Impulse);
  EXPECT_EQ(m.fidelity_requested, Fidelity::Auto);
  EXPECT_NE(m.fidelity_reason.find("not yet measured"), std::string::npos) << m.fidelity_reason;
}

TEST(FidelityLadder, FairDieIsUniform) {
  struct Case {
    Fidelity f;
    std::uint64_t n;
  };
  for (const Case c : {Case{Fidelity::Static, 200000}, Case{Fidelity::Impulse, 6000}, Case{Fidelity::Stepped, 600}}) {
    SceneDef def = with_fidelity(fair_scene(), c.f);
    def.sim.step = 5e-4;
    const RunCounts r = run(compile(def), c.n, 5);
    EXPECT_EQ(r.settled, c.n) << to_string(c.f);
    EXPECT_GT(chi2_uniform(r.faces).p_value, 1e-3) << to_string(c.f);
  }
}

TEST(FidelityLadder, HeavyFaceDownAndMirrorSymmetry) {
  for (Fidelity f : {Fidelity::Static, Fidelity::Impulse}) {
    const RunCounts r = run(compile(with_fidelity(slab_scene(), f)), f == Fidelity::Static ? 200000 : 8000, 9);
    // Counts in label order: 1 = +z steel, 6 = -z aluminium, 2-5 the sides.
    EXPECT_LT(r.faces[0], r.faces[5]) << to_string(f);  // +z steel up less often than -z aluminium
    // Faces +x, -x, +y, -y alike: chi-square of the four against uniform.
    const std::array<std::uint64_t, 4> side = {r.faces[1], r.faces[2], r.faces[3], r.faces[4]};
    EXPECT_GT(chi2_uniform(side).p_value, 1e-3) << to_string(f);
  }
}

TEST(FidelityLadder, CountsDoNotDependOnThreads) {
  for (Fidelity f : {Fidelity::Static, Fidelity::Impulse, Fidelity::Stepped}) {
    SceneDef def = with_fidelity(slab_scene(), f);
    def.sim.step = 1e-3;
    const DieModel m = compile(def);
    const std::uint64_t n = f == Fidelity::Stepped ? 200 : 3000;
    EXPECT_EQ(run(m, n, 4, 1), run(m, n, 4, 2)) << to_string(f);
  }
}

// impulse (default contact step) against stepped at the reference step on Dice 1-3: a chi-square
// homogeneity test. CI-sized (1500 tosses each); bench tradeoff / docs/fidelity.md do 10^5.
TEST(FidelityLadder, ImpulseAgreesWithSteppedOnTheSeedDice) {
  for (const char* die : {"paper/die1.toml", "paper/die2.toml", "paper/die3.toml"}) {
    const SceneDef base = load_scene(kScenes + die);
    const RunCounts a = run(compile(with_fidelity(base, Fidelity::Impulse)), 1500, 21);
    const RunCounts b = run(compile(with_fidelity(base, Fidelity::Stepped)), 1500, 21);
    EXPECT_EQ(a.unresolved + b.unresolved, 0u) << die;
    // Three tests at once: 1e-3 each keeps the family's false-alarm rate at 0.3%.
    EXPECT_GT(agreement_of(a.faces, b.faces).chi2_p, 1e-3) << die;
  }
}

// `stepped` converges as the step shrinks: no growth of capped (unresolved) tosses. Under the old
// impact threshold (4 g h) a die sliding flat on a face, or spinning on a corner, had a corner
// arrive at a few g h every step, each one a counted impact, so the count grew like 1/h: Die 1
// had 0.4% unresolved at 0.1 ms and 4.5% at 0.05 ms (10^4 tosses; 11 of these 300). With the
// contact threshold (sim/contact_stepper.hpp) it has 0 in 10^5 at 0.2, 0.1 and 0.05 ms. The bound:
// at most 2 of 300 holds with probability > 0.995 for any rate <= 1e-3, and fails with
// probability > 0.9998 at the old build's 4.5% (Poisson mean 13.5).
TEST(FidelityLadder, SteppedFineStepsDoNotHitTheImpactCap) {
  SceneDef def = with_fidelity(load_scene(kScenes + "paper/die1.toml"), Fidelity::Stepped);
  def.sim.step = 5e-5;
  const RunCounts r = run(compile(def), 300, 1);
  EXPECT_EQ(r.invalid, 0u);
  EXPECT_LE(r.unresolved, 2u);
}
