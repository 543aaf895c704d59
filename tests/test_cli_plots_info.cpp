// What a plot says (read from its gnuplot script: DICESIM_PLOT_SCRIPT) and what `info` shows a
// maker: units, outcome names, y within [0, 1], reference lines, the run in the title, tosses
// without an answer; a coin's edge as a curved side; each region's volume and mass.
#include <gtest/gtest.h>

#include "cli_runner.hpp"

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
  EXPECT_TRUE(has(gp, "set key outside")) << gp;
  // Die 1 (steel over aluminium) is unfair by design: no 1/6 line.
  const std::string die1 = plot_script("sweep scenes/paper/die1.toml --param floor.restitution --values 0.3,0.6 -n 200", "die1-e");
  EXPECT_FALSE(has(die1, "alike by design")) << die1;
  EXPECT_TRUE(has(die1, "set xlabel \"floor.restitution\"")) << "dimensionless: no unit";
}

TEST(CliPlots, ACoinsSweepNamesItsSidesAndDrawsItsQuestion) {
  const std::string gp = plot_script("sweep scenes/coins/three-sided.toml -n 100 --fidelity static", "three-sided");
  for (const char* side : {"title \"edge\"", "title \"heads\"", "title \"tails\""}) EXPECT_TRUE(has(gp, side)) << side << gp;
  EXPECT_FALSE(has(gp, "face 0")) << gp;
  EXPECT_TRUE(has(gp, "reference 1/3") || has(gp, "reference 0.333333")) << gp;
  EXPECT_TRUE(has(gp, "set yrange [0:")) << gp;
}

TEST(CliPlots, TossesWithoutAnAnswerAreShown) {
  // A one-bounce cap leaves most paper tosses unresolved: the plot draws their share.
  const std::string gp = plot_script(
      "sweep scenes/fair.toml --param throw.height.mean --values 0.5,1 -n 200 --fidelity paper --set sim.max_bounces=1", "capped");
  EXPECT_TRUE(has(gp, "unresolved + invalid (of all tosses)")) << gp;
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
