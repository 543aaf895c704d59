// `fidelity = "auto"` (sim/study/auto_pilot.hpp): a scene file that names no model runs auto, and
// auto takes a cheaper model only when a pilot of paired tosses shows it adequate at the run's
// precision.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "fidelity_test_util.hpp"
#include "sim/study/auto_pilot.hpp"

namespace {

using namespace dicesim;
using dicesim::testing::run_dicesim;

const std::string kScenes = std::string(DICESIM_SOURCE_DIR) + "/scenes/";

TEST(AutoFidelity, ASceneFileThatNamesNoModelRunsAuto) {
  const DieModel fair = compile(load_scene(kScenes + "fair.toml"));
  EXPECT_EQ(fair.fidelity_requested, Fidelity::Auto);
  EXPECT_EQ(fair.fidelity, Fidelity::Impulse);  // until a pilot measures: the reference
  EXPECT_EQ(fair.fidelity_reason.find("stated"), std::string::npos) << fair.fidelity_reason;
  // The seed's scenes state `paper` and keep it.
  const DieModel die1 = compile(load_scene(kScenes + "paper/die1.toml"));
  EXPECT_EQ(die1.fidelity_requested, Fidelity::Paper);
  EXPECT_EQ(die1.fidelity, Fidelity::Paper);
  EXPECT_NE(die1.fidelity_reason.find("stated"), std::string::npos);
}

// The 3-sided prism never rests on its end faces in `impulse` (friction tips it over); `paper`
// and `static` put 14% and 1% there. At the default command's precision (100000 tosses) the pilot
// rejects both after a few dozen pairs, and the run is `impulse`'s.
TEST(AutoFidelity, ThePrismsEndFacesUnderTheDefaultAreImpulses) {
  DieModel m = compile(load_scene(kScenes + "dice/prism3.toml"));
  const FidelityPilot pilot = resolve_auto(m, precision_of_run(m, 100000), 2);
  EXPECT_EQ(m.fidelity, Fidelity::Impulse) << m.fidelity_reason;
  ASSERT_TRUE(pilot.ran);
  ASSERT_EQ(pilot.candidates.size(), 2u);
  for (const PilotCandidate& c : pilot.candidates) {
    EXPECT_FALSE(c.adequate);
    EXPECT_LE(c.pairs, 256u) << to_string(c.model) << ": a clearly inadequate model is rejected after few pairs";
    EXPECT_GT(c.bound, pilot.threshold);
  }
  EXPECT_LE(pilot.tosses, 1000u);  // far below 5% of the run's 100000
  const RunCounts c = dicesim::testing::run(m, 300, 20261122);
  ASSERT_EQ(c.faces.size(), 5u);
  EXPECT_EQ(c.faces[3] + c.faces[4], 0u);  // labels 4 and 5: the end faces

  // The command: a scene that names no model, no --fidelity.
  const auto r = run_dicesim("toss scenes/dice/prism3.toml -n 300 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["fidelity"], "impulse");
  EXPECT_EQ(j["fidelity_requested"], "auto");
  EXPECT_EQ(j["faces"][3]["count"].get<int>() + j["faces"][4]["count"].get<int>(), 0) << r.out;
}

TEST(AutoFidelity, InfoSaysWhyTruthfully) {
  const auto fair = run_dicesim("info scenes/fair.toml");
  ASSERT_EQ(fair.code, 0) << fair.err;
  EXPECT_EQ(fair.out.find("stated"), std::string::npos) << fair.out;
  EXPECT_NE(fair.out.find("(chosen by auto)"), std::string::npos) << fair.out;
  EXPECT_NE(fair.out.find("pilot"), std::string::npos) << fair.out;
  EXPECT_NE(fair.out.find("differs from impulse in"), std::string::npos) << fair.out;
  const auto die1 = run_dicesim("info scenes/paper/die1.toml");
  ASSERT_EQ(die1.code, 0) << die1.err;
  EXPECT_NE(die1.out.find("stated: sim.fidelity = \"paper\""), std::string::npos) << die1.out;
  const auto j = nlohmann::json::parse(run_dicesim("info scenes/fair.toml --json").out);
  EXPECT_EQ(j["fidelity_requested"], "auto");
  EXPECT_FALSE(j["pilot"].is_null());
}

// A coin caught in the hand never touches the floor: `paper` flies it exactly as `impulse` does
// (torque-free flight to the catch), so every pair agrees and auto takes `paper`; `static` (the
// face up as thrown, no flight) is rejected. The JSON carries the pilot's numbers.
TEST(AutoFidelity, ACaughtCoinTakesTheCheaperModelTheMeasurementAllows) {
  const auto r = run_dicesim("toss scenes/coins/quarter-caught.toml -n 100000 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["fidelity"], "paper") << j["fidelity_reason"];
  const auto& p = j["pilot"];
  ASSERT_FALSE(p.is_null());
  ASSERT_EQ(p["candidates"].size(), 2u);
  EXPECT_EQ(p["candidates"][0]["model"], "static");
  EXPECT_FALSE(p["candidates"][0]["adequate"].get<bool>());
  EXPECT_EQ(p["candidates"][1]["model"], "paper");
  EXPECT_TRUE(p["candidates"][1]["adequate"].get<bool>());
  EXPECT_EQ(p["candidates"][1]["differing"], 0);
  EXPECT_EQ(p["candidates"][1]["pairs"], p["max_pairs"]);
  EXPECT_LT(p["candidates"][1]["bound"].get<double>(), p["threshold"].get<double>());
  EXPECT_LE(p["max_pairs"].get<std::uint64_t>(), p["cap"].get<std::uint64_t>());
  EXPECT_EQ(p["cap"].get<std::uint64_t>(), 5000u);  // 5% of the run's tosses
  // The choice is the pilot's, not the run seed's: the counts are those of `--fidelity paper`.
  const auto paper = nlohmann::json::parse(run_dicesim("toss scenes/coins/quarter-caught.toml -n 100000 --json --fidelity paper").out);
  EXPECT_EQ(j["faces"], paper["faces"]);
}

// Too small a run for any pilot to show a cheaper model adequate: impulse, and the reason says so.
TEST(AutoFidelity, ARunTooSmallForAPilotTakesImpulse) {
  DieModel m = compile(load_scene(kScenes + "coins/quarter-caught.toml"));
  const FidelityPilot pilot = resolve_auto(m, precision_of_run(m, 1000), 1);
  EXPECT_EQ(m.fidelity, Fidelity::Impulse);
  EXPECT_FALSE(pilot.ran);
  EXPECT_NE(m.fidelity_reason.find("no pilot"), std::string::npos) << m.fidelity_reason;
}

}  // namespace
