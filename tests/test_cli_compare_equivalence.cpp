// `dicesim compare --margin / --margin-rel`: equivalence verdicts per face and overall, as a user
// meets them (sim/study/equivalence.hpp computes them; tests/test_equivalence.cpp checks the numbers).
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"

namespace {

using dicesim::testing::CliRun;
using dicesim::testing::expect_bad_input;

CliRun cli(const std::string& args) { return dicesim::testing::run_dicesim(args); }

// A face,count CSV with labels first..first+k-1.
std::string counts_csv(const std::string& name, const std::vector<long long>& counts, int first = 1) {
  const std::string path = dicesim::testing::unique_temp(name);
  std::ofstream f(path);
  f << "face,count\n";
  for (std::size_t i = 0; i < counts.size(); ++i) f << first + static_cast<int>(i) << "," << counts[i] << "\n";
  return path;
}

TEST(CliCompareEquivalence, VerdictsPerFaceAndOverall) {
  const std::string a = counts_csv("eq_a.csv", std::vector<long long>(6, 166'667));
  const std::string b = counts_csv("eq_b.csv", std::vector<long long>(6, 166'667));
  const std::string c = counts_csv("eq_c.csv", {176'667, 156'667, 166'667, 166'667, 166'667, 166'667});
  const CliRun same = cli("compare " + a + " " + b + " --margin 0.002 --json");
  ASSERT_EQ(same.code, 0) << same.err;
  const auto j = nlohmann::json::parse(same.out);
  const auto& e = j["equivalence"];
  EXPECT_EQ(e["equivalent"], true);
  EXPECT_EQ(e["alpha"], 0.10);
  EXPECT_EQ(e["paired"], false);
  ASSERT_EQ(e["faces"].size(), 6u);
  EXPECT_EQ(e["faces"][0]["face"], 1);
  EXPECT_LT(e["faces"][0]["holm_p"].get<double>(), 0.10);
  EXPECT_EQ(j["alpha"], 0.05);  // the chi-square keeps its own level
  // One face 0.01 off (and another -0.01): not equivalent, a report all the same (exit 0).
  const CliRun off = cli("compare " + a + " " + c + " --margin 0.002 --json");
  ASSERT_EQ(off.code, 0) << off.err;
  const auto k = nlohmann::json::parse(off.out)["equivalence"];
  EXPECT_EQ(k["equivalent"], false);
  EXPECT_EQ(k["faces"][0]["equivalent"], false);
  EXPECT_EQ(k["faces"][2]["equivalent"], true);
  EXPECT_NEAR(k["faces"][0]["diff"].get<double>(), -0.01, 1e-6);
  // The table says it too.
  const CliRun table = cli("compare " + a + " " + c + " --margin 0.002");
  ASSERT_EQ(table.code, 0) << table.err;
  EXPECT_NE(table.out.find("NOT SHOWN EQUIVALENT"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("Holm"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("80% interval"), std::string::npos) << table.out;
  const CliRun table_same = cli("compare " + a + " " + b + " --margin 0.002");
  EXPECT_NE(table_same.out.find("overall: EQUIVALENT"), std::string::npos) << table_same.out;
  // Without a margin: no equivalence section.
  EXPECT_TRUE(nlohmann::json::parse(cli("compare " + a + " " + b + " --json").out)["equivalence"].is_null());
}

TEST(CliCompareEquivalence, RelativeMarginAndAlpha) {
  // A coin (edge 0, heads 1, tails 2) with the edge at 1% of 1e5: margin 0.2 p_edge.
  const std::string a = counts_csv("coin_a.csv", {1000, 49'500, 49'500}, 0);
  const std::string b = counts_csv("coin_b.csv", {1300, 49'350, 49'350}, 0);
  const CliRun same = cli("compare " + a + " " + a + " --margin-rel 0.2 --json");
  ASSERT_EQ(same.code, 0) << same.err;
  const auto j = nlohmann::json::parse(same.out)["equivalence"];
  EXPECT_EQ(j["equivalent"], true);
  EXPECT_NEAR(j["faces"][0]["margin"].get<double>(), 0.002, 1e-12);
  EXPECT_EQ(j["margin_rel"], 0.2);
  const CliRun off = cli("compare " + a + " " + b + " --margin-rel 0.2 --json");
  EXPECT_EQ(nlohmann::json::parse(off.out)["equivalence"]["equivalent"], false);
  // --alpha sets the equivalence level (and the chi-square's).
  const auto k = nlohmann::json::parse(cli("compare " + a + " " + a + " --margin-rel 0.2 --alpha 0.01 --json").out);
  EXPECT_EQ(k["equivalence"]["alpha"], 0.01);
  EXPECT_EQ(k["alpha"], 0.01);
}

TEST(CliCompareEquivalence, BadInput) {
  const std::string a = counts_csv("bad_a.csv", std::vector<long long>(6, 100));
  expect_bad_input(cli("compare " + a + " " + a + " --margin 0"), {"--margin"});
  expect_bad_input(cli("compare " + a + " " + a + " --margin 1.5"), {"--margin"});
  expect_bad_input(cli("compare " + a + " " + a + " --margin-rel -1"), {"--margin-rel"});
  expect_bad_input(cli("compare " + a + " " + a + " --margin 0.01 --margin-rel 0.2"), {"--margin", "excludes"});
  expect_bad_input(cli("compare " + a + " " + a + " --margin 0.01 --alpha 0.5"), {"--alpha", "below 0.5"});
}

}  // namespace

namespace {

// A run paired with a copy in which 15 tosses changed outcome (face 1 -> 2, the first 15 tosses
// that gave 1: d = 0.005 on faces 1 and 2): B's counts as a CSV, B's outcomes as `toss --outcomes`
// writes them. The paired test sees 15 discordant tosses in 3000 and is far narrower than the
// unpaired one. (Two real runs with the same seed at contact steps 3 ms and 0.3 ms differ in 7 of
// these 3000 tosses; made-up ones keep the test independent of the integrator.)
TEST(CliCompareEquivalence, PairedByTossIndex) {
  const std::string a = dicesim::testing::unique_temp("pa.json"), b = dicesim::testing::unique_temp("pb.csv");
  const std::string oa = dicesim::testing::unique_temp("pa.txt"), ob = dicesim::testing::unique_temp("pb.txt");
  ASSERT_EQ(cli("toss scenes/fair.toml -n 3000 --seed 3 --json --outcomes " + oa + " > " + a).code, 0);
  {
    std::ifstream in(oa);
    std::ofstream out(ob);
    std::vector<long long> n(6, 0);
    std::string line;
    int moved = 0;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') {
        out << line << "\n";
        continue;
      }
      int label = std::stoi(line);
      if (label == 1 && moved < 15) {
        label = 2;
        ++moved;
      }
      ASSERT_GE(label, 1);
      ++n[static_cast<std::size_t>(label - 1)];
      out << label << "\n";
    }
    ASSERT_EQ(moved, 15);
    std::ofstream csv(b);
    csv << "face,count\n";
    for (int f = 0; f < 6; ++f) csv << f + 1 << "," << n[static_cast<std::size_t>(f)] << "\n";
  }
  const CliRun paired = cli("compare " + a + " " + b + " --margin 0.01 --paired " + oa + " " + ob + " --json");
  ASSERT_EQ(paired.code, 0) << paired.err;
  const auto p = nlohmann::json::parse(paired.out)["equivalence"];
  EXPECT_EQ(p["paired"], true);
  EXPECT_EQ(p["pairs"], 3000);
  EXPECT_EQ(p["dropped"], 0);
  const auto u = nlohmann::json::parse(cli("compare " + a + " " + b + " --margin 0.01 --json").out)["equivalence"];
  EXPECT_EQ(u["paired"], false);
  for (std::size_t f = 0; f < 6; ++f) {
    EXPECT_DOUBLE_EQ(p["faces"][f]["diff"].get<double>(), u["faces"][f]["diff"].get<double>());
    EXPECT_LT(p["faces"][f]["se"].get<double>(), 0.5 * u["faces"][f]["se"].get<double>()) << f;
  }
  EXPECT_EQ(p["equivalent"], true);
  EXPECT_EQ(u["equivalent"], false);  // 3000 unpaired tosses cannot show 0.01 for six faces
  const CliRun table = cli("compare " + a + " " + b + " --margin 0.01 --paired " + oa + " " + ob);
  EXPECT_NE(table.out.find("paired by toss index over 3000 tosses"), std::string::npos) << table.out;
  // Bad input: --paired without a margin, the files swapped (B's outcomes are not A's counts), a
  // shard's outcomes.
  expect_bad_input(cli("compare " + a + " " + b + " --paired " + oa + " " + ob), {"--paired", "--margin"});
  expect_bad_input(cli("compare " + a + " " + b + " --margin 0.01 --paired " + ob + " " + oa), {"must equal A's count"});
  expect_bad_input(cli("toss scenes/fair.toml -n 100 --shard 0/2 --outcomes " + oa), {"--outcomes", "--shard"});
  expect_bad_input(cli("toss scenes/fair.toml -n 1e9 --outcomes " + oa), {"--outcomes", "100000000"});
  expect_bad_input(cli("toss scenes/fair.toml -n 10 --outcomes /nonexistent-dir/o.txt"), {"--outcomes", "cannot write"});
  std::ofstream(oa) << "1\n2\nseven\n";
  expect_bad_input(cli("compare " + a + " " + b + " --margin 0.01 --paired " + oa + " " + ob), {"line 3", "'seven'"});
}

}  // namespace
