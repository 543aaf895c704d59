// The `dicesim` command line as a user meets it: output formats, exit codes, error messages.
#include <gtest/gtest.h>

#include "cli_runner.hpp"

#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace {

using dicesim::testing::CliRun;
using dicesim::testing::expect_bad_input;

CliRun cli(const std::string& args) { return dicesim::testing::run_dicesim(args); }

}  // namespace

TEST(Cli, TossJsonIsOneObjectWithEveryKey) {
  const CliRun r = cli("toss scenes/paper/die1.toml --tosses 3000 --seed 5 --threads 2 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);  // throws if there is anything but one object
  for (const char* k : {"scene", "fidelity", "seed", "threads", "tosses", "settled", "unresolved", "invalid", "faces",
                        "chi2_uniform", "elapsed_s", "tosses_per_s"})
    EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j["fidelity"], "paper");
  EXPECT_EQ(j["tosses"], 3000);
  EXPECT_EQ(j["settled"].get<int>() + j["unresolved"].get<int>() + j["invalid"].get<int>(), 3000);
  ASSERT_EQ(j["faces"].size(), 6u);
  int sum = 0;
  for (int i = 0; i < 6; ++i) {
    const auto& f = j["faces"][i];
    EXPECT_EQ(f["face"], i + 1);
    sum += f["count"].get<int>();
    EXPECT_LE(f["ci95"][0].get<double>(), f["p"].get<double>());
    EXPECT_GE(f["ci95"][1].get<double>(), f["p"].get<double>());
  }
  EXPECT_EQ(sum, j["settled"].get<int>());
  // Die 1 is loaded along z: only its sides 2-5 are alike, so no test against a fair die.
  EXPECT_TRUE(j["chi2_uniform"].is_null());
  ASSERT_EQ(j["chi2_alike"].size(), 1u);
  EXPECT_EQ(j["chi2_alike"][0]["outcomes"], nlohmann::json({2, 3, 4, 5}));
  EXPECT_TRUE(j["chi2_alike"][0].contains("statistic"));
  EXPECT_TRUE(j["chi2_alike"][0].contains("p_value"));
}

// A coin is fair when heads and tails are equally likely: that test leaves its edge landings out
// (1 dof), beside the uniform one over heads, tails and edge. A die has no such test (null). A
// coin's outcomes are named.
TEST(Cli, ACoinIsTestedHeadsAgainstTails) {
  const CliRun r = cli("toss scenes/coins/quarter.toml --tosses 2000 --seed 3 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  double heads = -1, tails = -1, edge = -1;
  for (const auto& f : j["faces"]) {  // the quarter's labels: heads 1, tails 2, edge 0
    const int label = f["face"];
    (label == 1 ? heads : label == 2 ? tails : edge) = f["count"].get<double>();
    EXPECT_EQ(f["name"], label == 1 ? "heads" : label == 2 ? "tails" : "edge");
  }
  ASSERT_GT(edge, 0.0) << "the test must have edge landings to leave out";
  const auto& c = j["chi2_heads_tails"];
  EXPECT_EQ(c["dof"], 1);
  EXPECT_NEAR(c["statistic"].get<double>(), (heads - tails) * (heads - tails) / (heads + tails), 1e-9);
  EXPECT_TRUE(j["chi2_uniform"].is_null()) << "heads, tails and edge are not alike: no test against all three equal";
  EXPECT_EQ(j["chi2_alike"].size(), 1u);
  EXPECT_EQ(j["chi2_alike"][0]["outcomes"], nlohmann::json({1, 2}));
  const CliRun table = cli("toss scenes/coins/quarter.toml --tosses 2000 --seed 3");
  EXPECT_NE(table.out.find("chi-square vs a fair coin (heads = tails, edge landings left out)"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("   heads\n"), std::string::npos) << table.out;
  // Edge landings counted as heads: no heads-against-tails test, and the grouped side is named so.
  const auto grouped = nlohmann::json::parse(cli("toss scenes/coins/quarter.toml --tosses 500 --json --set die.faces.edge=1").out);
  EXPECT_TRUE(grouped["chi2_heads_tails"].is_null());
  EXPECT_EQ(grouped["faces"][0]["name"], "heads/edge");
  const auto die = nlohmann::json::parse(cli("toss scenes/paper/die1.toml --tosses 1000 --json").out);
  EXPECT_TRUE(die["chi2_heads_tails"].is_null());
  EXPECT_FALSE(die["faces"][0].contains("name"));
}

TEST(Cli, CountsDoNotDependOnThreads) {
  const auto counts = [](const std::string& threads) {
    const CliRun r = cli("toss scenes/paper/die2.toml --tosses 5000 --seed 9 --json --threads " + threads);
    EXPECT_EQ(r.code, 0) << r.err;
    return nlohmann::json::parse(r.out)["faces"].dump();
  };
  EXPECT_EQ(counts("1"), counts("2"));
}

TEST(Cli, TableIsReadable) {
  const CliRun r = cli("toss scenes/fair.toml --tosses 1000");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("95% interval"), std::string::npos);
  EXPECT_NE(r.out.find("settled"), std::string::npos);
}

// The corner table says where its restitution and friction come from: the materials, or [floor].
TEST(Cli, InfoNamesTheFloorOverrides) {
  const CliRun plain = cli("info scenes/paper/die1.toml");
  ASSERT_EQ(plain.code, 0) << plain.err;
  EXPECT_NE(plain.out.find("friction: volume mix of the materials"), std::string::npos) << plain.out;
  const CliRun set = cli("info scenes/paper/die1.toml --set floor.friction=0.7 --set floor.restitution=0.4");
  ASSERT_EQ(set.code, 0) << set.err;
  EXPECT_NE(set.out.find("friction: [floor] friction for every contact"), std::string::npos) << set.out;
  EXPECT_NE(set.out.find("restitution: [floor] restitution for every contact"), std::string::npos) << set.out;
  EXPECT_NE(set.out.find("mu = 0.700"), std::string::npos);
  EXPECT_NE(set.out.find("e = 0.4000"), std::string::npos);
}

TEST(Cli, InfoJsonHasMassProperties) {
  const CliRun r = cli("info scenes/paper/die3.toml --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["mass"].get<double>(), 0.0);
  EXPECT_EQ(j["com"].size(), 3u);
  ASSERT_EQ(j["inertia"].size(), 3u);
  EXPECT_EQ(j["inertia"][0].size(), 3u);
  EXPECT_NE(j["inertia"][0][2].get<double>(), 0.0);  // the diagonal cut has products of inertia
  EXPECT_EQ(j["principal_moments"].size(), 3u);
}

// Issue 15: a cylinder's own fields (its "corners" are moving rim points, so that list is empty).
TEST(Cli, InfoJsonDescribesACylinder) {
  const CliRun r = cli("info scenes/coins/quarter.toml --json --set die.faces.edge=7");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("cylinder")) << r.out;
  const auto& c = j["cylinder"];
  EXPECT_NEAR(c["radius"].get<double>(), 0.01213, 1e-12);
  EXPECT_NEAR(c["height"].get<double>(), 0.00175, 1e-12);
  EXPECT_NEAR(c["rounding"].get<double>(), 0.0002, 1e-12);
  EXPECT_EQ(c["labels"]["heads"], 1);
  EXPECT_EQ(c["labels"]["tails"], 2);
  EXPECT_EQ(c["labels"]["edge"], 7);  // configurable: the scene's label, not a default
  ASSERT_EQ(c["rims"].size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const auto& rim = c["rims"][static_cast<std::size_t>(k)];
    const double sgn = k == 0 ? 1.0 : -1.0;
    EXPECT_EQ(rim["face"], k == 0 ? "heads" : "tails");
    EXPECT_NEAR(rim["radius"].get<double>(), 0.01213 - 0.0002, 1e-12);  // the core rim, swept by the rounding
    EXPECT_NEAR(rim["centre"][2].get<double>(), sgn * (0.00175 / 2 - 0.0002), 1e-12);
    EXPECT_NEAR(rim["centre"][0].get<double>(), 0.0, 1e-12);
    EXPECT_NEAR(rim["normal"][2].get<double>(), sgn, 1e-12);
    EXPECT_NEAR(rim["restitution"].get<double>(), 0.5, 1e-12);
    EXPECT_NEAR(rim["friction"].get<double>(), 0.3, 1e-12);
    EXPECT_NEAR(rim["rolling_resistance"].get<double>(), 3e-4, 1e-15);
    EXPECT_NEAR(rim["pivoting_resistance"].get<double>(), 3e-6, 1e-18);
  }
  ASSERT_EQ(j["faces"].size(), 3u);
  const char* names[] = {"heads", "tails", "edge"};
  for (std::size_t f = 0; f < 3; ++f) {
    EXPECT_EQ(j["faces"][f]["direction"], names[f]);
    EXPECT_EQ(j["faces"][f]["curved"], f == 2);
  }
  EXPECT_EQ(j["faces"][2]["label"], 7);
  // A polyhedron has none of it.
  const CliRun d = cli("info scenes/paper/die1.toml --json");
  ASSERT_EQ(d.code, 0) << d.err;
  EXPECT_FALSE(nlohmann::json::parse(d.out).contains("cylinder"));
}

TEST(Cli, HelpTeaches) {
  const CliRun r = cli("toss --help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("--tosses"), std::string::npos);
  EXPECT_NE(r.out.find("--set"), std::string::npos);
  EXPECT_NE(r.out.find("Example"), std::string::npos);
}

TEST(Cli, MissingFile) { expect_bad_input(cli("toss scenes/nope.toml"), {"scenes/nope.toml"}); }

TEST(Cli, UnknownKey) {
  expect_bad_input(cli("toss scenes/paper/die1.toml --set materials.steel.densty=1"), {"densty"});
}

TEST(Cli, NegativeDensity) {
  expect_bad_input(cli("toss scenes/paper/die1.toml --set materials.steel.density=-5"),
                   {"die1.toml", "materials.steel.density", "-5"});
}

TEST(Cli, RestitutionOutOfRange) {
  expect_bad_input(cli("toss scenes/paper/die1.toml --set materials.aluminium.restitution=1.5"),
                   {"materials.aluminium.restitution", "1.5"});
}

TEST(Cli, NotANumber) { expect_bad_input(cli("toss scenes/paper/die1.toml --set throw.height.mean=nan"), {"throw.height.mean"}); }

TEST(Cli, WrongType) { expect_bad_input(cli("toss scenes/paper/die1.toml --set sim.stop_speed='\"fast\"'"), {"sim.stop_speed"}); }

TEST(Cli, DieBelowTheFloor) {
  expect_bad_input(cli("toss scenes/paper/die1.toml --set throw.height.mean=0.001"), {"throw.height.mean", "floor"});
}

TEST(Cli, UnknownFidelity) { expect_bad_input(cli("toss scenes/paper/die1.toml --fidelity warp"), {"warp"}); }

TEST(Cli, BadOption) { expect_bad_input(cli("toss scenes/paper/die1.toml --tosses -3"), {}); }
