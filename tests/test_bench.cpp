// `dicesim bench`: per-fidelity throughput and the phase split (its numbers are speeds, never
// asserted; what is tested is that the report is complete and the timing probe changes nothing).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/toss.hpp"
#include "sim/scene/scene.hpp"

namespace {

using namespace dicesim;

TEST(BenchProbe, TimingCountsPhasesAndChangesNoToss) {
  for (const char* fidelity : {"paper", "impulse"}) {
    const DieModel m = compile(load_scene(DICESIM_SOURCE_DIR "/scenes/paper/die1.toml",
                                          {std::string("sim.fidelity=\"") + fidelity + "\""}));
    TossProbe off, on;
    on.timing = true;
    constexpr int kTosses = 40;
    for (int i = 0; i < kTosses; ++i) {
      const TossResult plain = toss(m, 3, i);
      const TossResult a = toss(m, 3, i, &off);
      const TossResult b = toss(m, 3, i, &on);
      EXPECT_EQ(plain.face, b.face) << fidelity << " toss " << i;
      EXPECT_EQ(plain.bounces, b.bounces) << fidelity << " toss " << i;
      EXPECT_EQ(plain.t_end, b.t_end) << fidelity << " toss " << i;
      EXPECT_EQ(a.t_end, b.t_end) << fidelity << " toss " << i;
    }
    for (int k = 0; k < kPhaseCount; ++k) {
      EXPECT_EQ(off.phase_n[k], 0u) << "no timing, no phase counted";
      EXPECT_EQ(off.phase_s[k], 0.0);
    }
    const auto n = [&](Phase p) { return on.phase_n[static_cast<int>(p)]; };
    EXPECT_EQ(n(Phase::Draw), static_cast<std::uint64_t>(kTosses)) << fidelity;
    EXPECT_EQ(n(Phase::Search), on.flights) << fidelity;
    EXPECT_GT(n(Phase::Impact), 0u) << fidelity;
    if (std::string(fidelity) == "impulse") {
      EXPECT_GT(n(Phase::Steps), 0u);
      EXPECT_GT(n(Phase::Rest), 0u);
    } else {
      EXPECT_EQ(n(Phase::Steps), 0u);
    }
    for (int k = 0; k < kPhaseCount; ++k) EXPECT_GE(on.phase_s[k], 0.0);
  }
}

TEST(BenchCli, JsonReportsEachFidelityAndItsPhases) {
  const auto r = dicesim::testing::run_dicesim("bench scenes/paper/die1.toml --fidelities static,paper,impulse -n 300 -j 2 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["fidelities"].size(), 3u);
  const char* expected[3][3] = {{"static", "draw", "rest"}, {"paper", "search", "impacts"}, {"impulse", "steps", "rest"}};
  for (int i = 0; i < 3; ++i) {
    const auto& f = j["fidelities"][i];
    EXPECT_EQ(f["fidelity"], expected[i][0]);
    EXPECT_EQ(f["tosses"], 300);
    EXPECT_TRUE(f["identical_counts"].get<bool>()) << expected[i][0];
    EXPECT_GT(f["tosses_per_s_1_thread"].get<double>(), 0.0);
    EXPECT_GT(f["tosses_per_s"].get<double>(), 0.0);
    EXPECT_EQ(f["threads"], 2);
    double share = f["other_share"].get<double>();
    for (const char* p : {expected[i][1], expected[i][2]}) EXPECT_TRUE(f["phases"].contains(p)) << expected[i][0] << " " << p;
    for (const auto& [name, ph] : f["phases"].items()) {
      EXPECT_GT(ph["per_toss"].get<double>(), 0.0) << name;
      share += ph["share"].get<double>();
    }
    EXPECT_NEAR(share, 1.0, 1e-6) << expected[i][0] << ": phases and other make up the timed run";
  }
  EXPECT_EQ(j["fidelities"][1]["phases"]["draw"]["per_toss"], 1.0);
}

TEST(BenchCli, OneFidelityKeepsTheFlatShape) {
  const auto r = dicesim::testing::run_dicesim("bench scenes/paper/die1.toml -n 500 -j 1 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["fidelity"], "paper");
  for (const char* k : {"tosses_per_s_1_thread", "tosses_per_s", "scaling_efficiency", "impacts_per_toss", "time_split", "phases"})
    EXPECT_TRUE(j.contains(k)) << k;
}

TEST(BenchCli, UnknownFidelityIsBadInput) {
  dicesim::testing::expect_bad_input(dicesim::testing::run_dicesim("bench scenes/paper/die1.toml --fidelities paper,warp"),
                                     {"--fidelities", "warp"});
}

}  // namespace
