// What a plot says (read from its gnuplot script: DICESIM_PLOT_SCRIPT) and what `info` shows a
// maker: units, outcome names, y within [0, 1], reference lines, the run in the title, tosses
// without an answer; a coin's edge as a curved side; each region's volume and mass.
#include <gtest/gtest.h>

#include "cli_runner.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;
using dicesim::testing::CliRun;

CliRun cli(const std::string& args) { return dicesim::testing::run_dicesim(args); }

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool has(const std::string& text, const std::string& what) { return text.find(what) != std::string::npos; }

// Runs `args --plot PNG` keeping the script; returns it (empty if the run failed).
std::string plot_script(const std::string& args, const std::string& name) {
  const std::string png = dicesim::testing::unique_temp(name + ".png"), gp = dicesim::testing::unique_temp(name + ".gp");
  ::setenv("DICESIM_PLOT_SCRIPT", gp.c_str(), 1);
  const CliRun r = cli(args + " --plot " + png);
  ::unsetenv("DICESIM_PLOT_SCRIPT");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(png) && fs::file_size(png) > 5000) << png;
  return read(gp);
}

}  // namespace

TEST(CliPlots, ASweepOfAKeyHasItsUnitTheRunAndTheReference) {
  const std::string gp = plot_script(
      "sweep scenes/fair.toml --param throw.height.mean --values 0.3,0.6 -n 300 --fidelity paper", "fair-height");
  EXPECT_TRUE(has(gp, "set xlabel \"throw.height.mean (m)\"")) << gp;
  EXPECT_TRUE(has(gp, "scenes/fair.toml, fidelity paper, 300 tosses per point")) << gp;
  EXPECT_TRUE(has(gp, "set yrange [0:")) << gp;
  EXPECT_FALSE(has(gp, "graph 0.04")) << "offsets pushed the y axis below 0";
  EXPECT_TRUE(has(gp, "title \"face 1\"")) << gp;
  EXPECT_TRUE(has(gp, "0.1666") && has(gp, " with lines dt 2")) << gp;
  EXPECT_TRUE(has(gp, "1/6 (alike by design)")) << gp;
  EXPECT_TRUE(has(gp, "set key outside right top vertical Left reverse")) << gp;
  // Centred on the picture: centred on the plot, which the legend narrows, its second line ran
  // past the left edge and was clipped.
  EXPECT_FALSE(has(gp, "set title")) << gp;
  EXPECT_TRUE(has(gp, "set label 1 \"throw.height.mean\\nscenes/fair.toml, fidelity paper, 300 tosses per point")) << gp;
  EXPECT_TRUE(has(gp, "\" at screen 0.5, screen 0.97 center front")) << gp;
  // Die 1 (steel over aluminium) is unfair by design: no 1/6 line.
  const std::string die1 = plot_script("sweep scenes/paper/die1.toml --param floor.restitution --values 0.3,0.6 -n 200", "die1-e");
  EXPECT_FALSE(has(die1, "alike by design")) << die1;
  EXPECT_TRUE(has(die1, "set xlabel \"floor.restitution\"")) << "dimensionless: no unit";
}

TEST(CliPlots, ACoinsSweepNamesItsSidesAndDrawsItsQuestion) {
  const std::string gp = plot_script("sweep scenes/coins/three-sided.toml -n 100 --fidelity static", "three-sided");
  for (const char* side : {"title \"edge\"", "title \"heads\"", "title \"tails\""}) EXPECT_TRUE(has(gp, side)) << side << gp;
  EXPECT_FALSE(has(gp, "face 0")) << gp;
  EXPECT_TRUE(has(gp, "title \"reference 1/3\"")) << gp;
  EXPECT_TRUE(has(gp, "set yrange [0:")) << gp;
}

// The y range held our points but not the seed's circles: Table 8's P(6) = 0.26 at k = 19/30 (the
// seed's peak, the point of the comparison) was drawn above the picture's top.
TEST(CliPlots, TheSeedsValuesAreInsideTheYRange) {
  const std::string gp = plot_script("sweep scenes/paper/sweeps/volume-ratio.toml -n 2000", "ratio");
  const std::size_t at = gp.find("set yrange [0:");
  ASSERT_NE(at, std::string::npos) << gp;
  const double ymax = std::stod(gp.substr(at + 14));
  // The largest value of a data block's columns (after x): ours (p, lo, hi per face; then the share
  // without an answer) or the seed's (p per face).
  const auto block_max = [&](const std::string& name, int* rows) {
    const std::size_t from = gp.find(name + " << EOD\n");
    EXPECT_NE(from, std::string::npos) << name;
    const std::size_t start = from + name.size() + 8;
    std::istringstream lines(gp.substr(start, gp.find("EOD\n", start) - start));
    double most = 0.0, v = 0.0;
    *rows = 0;
    for (std::string line; std::getline(lines, line); ++*rows) {
      std::istringstream fields(line);
      fields >> v;  // x
      while (fields >> v) most = std::max(most, v);
    }
    return most;
  };
  int ours_rows = 0, seed_rows = 0;
  const double ours = block_max("$d", &ours_rows), seed = block_max("$s", &seed_rows);
  EXPECT_EQ(seed_rows, 30) << "one seed row per point of Table 8";
  ASSERT_GT(seed, ours) << "the seed's peak must stand above our bands for this test to see anything";
  EXPECT_GT(ymax, seed) << gp;
}

TEST(CliPlots, TossesWithoutAnAnswerAreShown) {
  // A one-bounce cap leaves most paper tosses unresolved: the plot draws their share.
  const std::string gp = plot_script(
      "sweep scenes/fair.toml --param throw.height.mean --values 0.5,1 -n 200 --fidelity paper --set sim.max_bounces=1", "capped");
  EXPECT_TRUE(has(gp, "title \"unresolved + invalid\"")) << gp;
  EXPECT_TRUE(has(gp, "unresolved + invalid: their share of all tosses")) << gp;
  // 1.5 m: no draw starts below the floor (at 0.5 m a few of 100 do, and count as invalid).
  const std::string clean = plot_script("sweep scenes/fair.toml --param throw.height.mean --values 1.5 -n 100 --fidelity static", "clean");
  EXPECT_TRUE(has(clean, "every toss settled")) << clean;
}

TEST(CliPlots, AFitProfileHasUnitsTheRunAndItsLegendBelow) {
  const std::string data = dicesim::testing::unique_temp("counts.csv");
  std::ofstream(data) << "1,80\n2,83\n3,84\n4,85\n5,81\n6,87\n";
  const std::string gp = plot_script("fit scenes/paper/die1.toml --data " + data +
                                         " --param materials.steel.density=3000:20000 --fidelity static -n 2000",
                                     "profile");
  EXPECT_TRUE(has(gp, "set xlabel \"materials.steel.density (kg/m^3)\"")) << gp;
  EXPECT_TRUE(has(gp, "scenes/paper/die1.toml, fidelity static")) << gp;
  EXPECT_TRUE(has(gp, "500 observed tosses")) << gp;
  EXPECT_TRUE(has(gp, "set key below")) << gp;
  // The dashed bounds named in the legend with their unit (the picture gave no numbers for them).
  EXPECT_TRUE(has(gp, "title \"95% interval [")) << gp;
  EXPECT_TRUE(has(gp, "] kg/m^3 (cut 3.84)\"")) << gp;
}

// The key sat at a fixed place inside the axes, where a loaded machine's slower rows ran under it;
// the title did not say how many tosses, which seed or how many threads.
TEST(CliPlots, ATradeoffSaysItsRunAndKeepsItsLegendOffTheData) {
  const std::string csv = dicesim::testing::unique_temp("tradeoff.csv");
  const std::string gp = plot_script("bench tradeoff scenes/fair.toml -n 20 --steps 2e-3,1e-3 --csv " + csv, "tradeoff");
  EXPECT_TRUE(has(gp, "\"scenes/fair.toml: accuracy against speed\\n20 tosses per row (the same indices in each, seed 1), 1 thread;"))
      << gp;
  EXPECT_TRUE(has(gp, "set key below")) << gp;
  EXPECT_FALSE(has(gp, "set key at graph")) << gp;
  EXPECT_FALSE(has(gp, "set title")) << "centred on the plot, the title was clipped: " << gp;
  EXPECT_TRUE(has(gp, "tosses per second (all threads; depends on the machine and its load)")) << gp;
  // The same program redraws the CSV without tossing.
  const std::string again = plot_script("bench tradeoff scenes/fair.toml --from-csv " + csv, "tradeoff-again");
  EXPECT_TRUE(has(again, "rows from " + csv)) << again;
  EXPECT_TRUE(has(again, "set key below")) << again;
  dicesim::testing::expect_bad_input(cli("bench tradeoff scenes/fair.toml --from-csv /no/such.csv --plot x.png"),
                                     {"--from-csv", "/no/such.csv", "must be a readable file"});
  dicesim::testing::expect_bad_input(cli("bench tradeoff scenes/fair.toml --from-csv " + csv), {"--from-csv", "needs --plot"});
}

TEST(CliInfo, ACoinsEdgeIsACurvedSideNotAZeroNormal) {
  const CliRun r = cli("info scenes/coins/quarter.toml");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(has(r.out, "(+0.0000, +0.0000, +0.0000)")) << r.out;
  EXPECT_TRUE(has(r.out, "any, perpendicular to axis")) << r.out;
  EXPECT_FALSE(has(r.out, "\ncorners (")) << "a coin has no corners: " << r.out;
  EXPECT_TRUE(has(r.out, "rims (no corners")) << r.out;
  const auto j = nlohmann::json::parse(cli("info scenes/coins/quarter.toml --json").out);
  EXPECT_TRUE(j["faces"][2]["normal"].is_null());
  EXPECT_TRUE(j["faces"][2]["area"].is_null());
  EXPECT_EQ(j["faces"][0]["normal"].size(), 3u);
}

// Die 1: a 30 mm cube, the top half (z >= 0) steel and the rest aluminium. Each part's
// volume is half the cube, its mass that times its density.
TEST(CliInfo, EachRegionHasItsVolumeAndMass) {
  const CliRun r = cli("info scenes/paper/die1.toml --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto& parts = j["parts"];
  ASSERT_EQ(parts.size(), 2u) << parts;
  EXPECT_EQ(parts[0]["part"], "base");
  EXPECT_EQ(parts[1]["part"], "region 0");
  double volume = 0.0, mass = 0.0;
  for (const auto& p : parts) {
    volume += p["volume"].get<double>();
    mass += p["mass"].get<double>();
    EXPECT_NEAR(p["mass"].get<double>(), p["volume"].get<double>() * p["density"].get<double>(), 1e-12);
  }
  EXPECT_NEAR(volume, j["volume"].get<double>(), 1e-15);
  EXPECT_NEAR(mass, j["mass"].get<double>(), 1e-9 * mass);
  EXPECT_NEAR(parts[0]["volume"].get<double>(), parts[1]["volume"].get<double>(), 1e-12 * volume);
  const CliRun text = cli("info scenes/paper/die1.toml");
  EXPECT_TRUE(has(text.out, "region 0")) << text.out;
  EXPECT_TRUE(has(text.out, "volume (cm^3)")) << text.out;
}

// binom4's back face is two triangles that both read 3: `info` says that their outcome settles below
// the pass to another outcome (rest.hpp), which the table's per-basin escape does not show; the
// JSON carries both passes. A die whose basins all read differently prints no such line.
TEST(CliInfo, BasinsReadTheSameShowTheirOutcomesPass) {
  const CliRun r = cli("info scenes/dice/binom4.toml");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "face 5: a neighbouring basin also reads 3; the lowest pass to another outcome is 0.00792")) << r.out;
  const auto j = nlohmann::json::parse(cli("info scenes/dice/binom4.toml --json").out);
  EXPECT_GT(j["rest"][5]["outcome_escape_height"].get<double>(), j["rest"][5]["escape_height"].get<double>() + 1e-3);
  EXPECT_FALSE(has(cli("info scenes/dice/binom3.toml").out, "a neighbouring basin also reads"));
}
