// The frictions a new user meets in the first hour (issue 36), each through the real binary: a
// mistyped command, counts written as 1e5, --threads 0, help that tells the truth, watch saying
// where it listens, bench with one thread, a sweep point that fails.
#include <gtest/gtest.h>

#include "cli_runner.hpp"

#include <algorithm>
#include <thread>

#include <nlohmann/json.hpp>

namespace {

using dicesim::testing::CliRun;
using dicesim::testing::expect_bad_input;

CliRun cli(const std::string& args) { return dicesim::testing::run_dicesim(args); }

TEST(CliFirstHour, AnUnknownCommandIsNamedWithTheClosest) {
  expect_bad_input(cli("tos scenes/fair.toml"), {"unknown command 'tos'", "did you mean 'toss'?"});
  expect_bad_input(cli("swep scenes/fair.toml"), {"'swep'", "did you mean 'sweep'?"});
  const CliRun far = cli("xyzzyplugh");
  expect_bad_input(far, {"unknown command 'xyzzyplugh'", "Commands: toss"});
  EXPECT_EQ(far.err.find("did you mean"), std::string::npos) << far.err;
}

TEST(CliFirstHour, ACountIsAnyExactWholeNumber) {
  for (const char* n : {"1e3", "1000", "1_000", "1.0e3"}) {
    const CliRun r = cli(std::string("toss scenes/fair.toml --fidelity static --json -n ") + n);
    ASSERT_EQ(r.code, 0) << n << ": " << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["tosses"], 1000) << n;
  }
  expect_bad_input(cli("toss scenes/fair.toml -n 1.5"), {"'1.5' is not a whole number", "1e5"});
  expect_bad_input(cli("toss scenes/fair.toml -n 1e-3"), {"'1e-3' is not a whole number"});
  expect_bad_input(cli("toss scenes/fair.toml -n 1e300"), {"'1e300' is not a whole number"});
  // The other commands' -n take the same forms.
  EXPECT_EQ(cli("sweep scenes/fair.toml --fidelity static --param floor.restitution --values 0.5 -n 2e2 --json").code, 0);
}

TEST(CliFirstHour, ThreadsZeroIsAllCoresAsInPython) {
  const CliRun r = cli("toss scenes/fair.toml --fidelity static -n 300 --threads 0 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["threads"], static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  EXPECT_NE(cli("toss --help").out.find("0: all cores"), std::string::npos);
  EXPECT_NE(cli("sweep --help").out.find("0: all cores"), std::string::npos);
}

// -n's help used to say its default caps --target-halfwidth, which then ran 150 000 tosses.
TEST(CliFirstHour, TossHelpTellsWhatNMeansWithATarget) {
  const std::string help = cli("toss --help").out;
  EXPECT_NE(help.find("default 100000"), std::string::npos) << help;
  EXPECT_NE(help.find("without -n, as many as the target needs (up to 10^9)"), std::string::npos) << help;
}

// memq:// is LCM's in-process queue: no network is opened.
TEST(CliFirstHour, WatchSaysWhereItListens) {
  const CliRun r = cli("watch --lcm memq:// --timeout 0.3");
  EXPECT_EQ(r.code, 1) << r.err;  // timed out: nothing was heard
  EXPECT_NE(r.err.find("watching DICESIM_PROBABILITIES on memq:// for any run"), std::string::npos) << r.err;
  EXPECT_NE(cli("watch --lcm memq:// --timeout 0.1 --run 7").err.find("for run 7"), std::string::npos);
}

TEST(CliFirstHour, BenchWithOneThreadPrintsNoScaling) {
  const CliRun one = cli("bench scenes/fair.toml --fidelity static -n 2000 -j 1");
  ASSERT_EQ(one.code, 0) << one.err;
  EXPECT_EQ(one.out.find("1-thread rate"), std::string::npos) << one.out;
  EXPECT_EQ(one.out.find("efficiency"), std::string::npos) << one.out;
  const CliRun json = cli("bench scenes/fair.toml --fidelity static -n 2000 -j 1 --json");
  EXPECT_TRUE(nlohmann::json::parse(json.out)["scaling_efficiency"].is_null()) << json.out;
  const CliRun two = cli("bench scenes/fair.toml --fidelity static -n 2000 -j 2");
  EXPECT_NE(two.out.find("of 2 x the 1-thread rate"), std::string::npos) << two.out;
}

TEST(CliFirstHour, ASweepPointThatFailsIsNamed) {
  expect_bad_input(cli("sweep scenes/fair.toml --param floor.restitution --values 0.5,7 -n 100"),
                   {"floor.restitution", "(at sweep point floor.restitution = 7)"});
}

}  // namespace

TEST(CliFirstHour, TossHelpSaysWhichFidelity) {
  const std::string help = cli("toss --help").out;
  for (const char* f : {"Which fidelity", "auto     the cheapest model measured adequate", "impulse  a real, unfair die",
                        "stepped  the reference", "paper    only to reproduce", "static   a die placed",
                        "sim.contact_tol (leapfrog steps) is experimental: leave it 0"})
    EXPECT_NE(help.find(f), std::string::npos) << f << "\n" << help;
}

// `--steps 2e-3,1e-3` was read as one value and refused with CLI11's "could not be converted":
// commas separate the ladder as in sweep's --values (spaces too), and a bad entry is named with
// what is accepted.
TEST(CliFirstHour, TradeoffStepsTakeCommasAndSayWhatIsAccepted) {
  for (const char* steps : {"2e-3,1e-3", "2e-3 1e-3"}) {
    const CliRun r = cli(std::string("bench tradeoff scenes/fair.toml -n 20 --json --steps ") + steps);
    ASSERT_EQ(r.code, 0) << steps << ": " << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["rows"].size(), 6u) << steps;  // static, paper, then impulse and stepped at each step
    EXPECT_EQ(j["reference"]["setting"], "step=0.001") << steps;
  }
  expect_bad_input(cli("bench tradeoff scenes/fair.toml -n 20 --steps 2e-3,1e-3x"),
                   {"--steps", "'1e-3x' is not a step", "[1e-7, 0.01]", "commas or spaces"});
  expect_bad_input(cli("bench tradeoff scenes/fair.toml -n 20 --steps 2e-3,0.5"), {"'0.5' is not a step"});
}

// The sweep's table headed a coin's columns P(0), P(1), P(2) while its plot named the sides.
TEST(CliFirstHour, ACoinsSweepTableNamesItsSides) {
  const CliRun coin = cli("sweep scenes/coins/three-sided.toml -n 50 --fidelity static");
  ASSERT_EQ(coin.code, 0) << coin.err;
  EXPECT_NE(coin.out.find(" P(edge)  P(heads)  P(tails)   unresolved  invalid\n0.05             0.0600    0.5000"),
            std::string::npos)
      << coin.out;
  EXPECT_EQ(coin.out.find("P(0)"), std::string::npos) << coin.out;
  const CliRun die = cli("sweep scenes/fair.toml --param floor.restitution --values 0.3 -n 100 --fidelity static");
  EXPECT_NE(die.out.find("   P(1)     P(2)     P(3)     P(4)     P(5)     P(6)   unresolved"), std::string::npos) << die.out;
}
