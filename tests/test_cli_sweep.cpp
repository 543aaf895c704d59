// `dicesim sweep`, `calibrate-restitution` and `compare` as a user meets them: outputs, exit
// codes, error messages, plots.
#include <gtest/gtest.h>

#include "cli_runner.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;

using dicesim::testing::CliRun;
using dicesim::testing::expect_bad_input;

CliRun cli(const std::string& args) { return dicesim::testing::run_dicesim(args); }
std::string tmp(const std::string& name) { return dicesim::testing::unique_temp(name); }

// A sweep point's faces: labels 1..n in order, their counts summing to the settled tosses.
void expect_faces_one_to(const nlohmann::json& p, int n) {
  ASSERT_EQ(p["faces"].size(), static_cast<std::size_t>(n));
  int sum = 0;
  for (int f = 0; f < n; ++f) {
    EXPECT_EQ(p["faces"][f]["face"], f + 1);
    sum += p["faces"][f]["count"].get<int>();
  }
  EXPECT_EQ(sum, p["settled"].get<int>());
}

TEST(CliSweep, JsonHasEveryPointAndFace) {
  const CliRun r = cli("sweep scenes/paper/die1.toml --param floor.restitution --values 0.2,0.8 -n 400 --seed 3 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["param"], "floor.restitution");
  EXPECT_EQ(j["tosses"], 400);
  EXPECT_EQ(j["seed"], 3);
  ASSERT_EQ(j["points"].size(), 2u);
  EXPECT_DOUBLE_EQ(j["points"][1]["x"].get<double>(), 0.8);
  for (const auto& p : j["points"]) {
    expect_faces_one_to(p, 6);
    EXPECT_EQ(p["settled"].get<int>() + p["unresolved"].get<int>() + p["invalid"].get<int>(), 400);
  }
}

// An indexed key (an element of an array of tables) sweeps like a dotted one: moving die 1's steel
// slab's face down by 8 mm moves the COM, so the two points' counts differ.
TEST(CliSweep, IndexedKey) {
  const CliRun r = cli("sweep scenes/paper/die1.toml --param 'die.regions[0].cuts[0].offset' --values 0,0.008 -n 400 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["param"], "die.regions[0].cuts[0].offset");
  ASSERT_EQ(j["points"].size(), 2u);
  EXPECT_NE(j["points"][0]["faces"], j["points"][1]["faces"]);
  expect_bad_input(cli("sweep scenes/paper/die1.toml --param 'die.regions[2].cuts[0].offset' --values 0"),
                   {"(--set)", "die.regions[2].cuts[0].offset", "index 2 is out of range", "1 element"});
}

// Each point carries its corrections (issue 13: every guard counted and reported), the same as a
// toss of that point reports, and the table names the points where any is non-zero. The quarter on
// a table is the scene with the most (unconverged rim solves); where all are 0 the line is absent.
TEST(CliSweep, EveryPointReportsItsCorrectionsAsTossDoes) {
  const std::string args = "--fidelity impulse -n 60 --seed 5";
  const CliRun r = cli("sweep scenes/coins/quarter-table.toml --param floor.restitution --values 0.5 " + args + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["fidelity"], "impulse");
  const auto p = nlohmann::json::parse(r.out)["points"][0];
  const CliRun t = cli("toss scenes/coins/quarter-table.toml --set floor.restitution=0.5 " + args + " --json");
  ASSERT_EQ(t.code, 0) << t.err;
  const auto k = nlohmann::json::parse(t.out)["corrections"];
  bool any = false;
  for (const char* key : {"energy_clamps", "pgs_unconverged", "overlap_fixes", "fallbacks", "located_capped",
                          "support_search_capped", "rise_dropped", "contact_overlaps", "nudges"}) {
    ASSERT_TRUE(p["corrections"].contains(key)) << key;
    EXPECT_EQ(p["corrections"][key], k[key]) << key;
    any = any || k[key].get<long long>() > 0;
  }
  const CliRun table = cli("sweep scenes/coins/quarter-table.toml --param floor.restitution --values 0.5 " + args);
  ASSERT_EQ(table.code, 0) << table.err;
  EXPECT_EQ(table.out.find("point 0.5: corrections: ") != std::string::npos, any) << table.out;
  EXPECT_EQ(table.out.find("whole sweep: corrections: ") != std::string::npos, any) << table.out;
  expect_bad_input(cli("sweep scenes/coins/quarter-table.toml --param floor.restitution --values 0.5 --fidelity fast"),
                   {"--fidelity", "'fast' is not a fidelity"});  // refused before any scene is read
}

TEST(CliSweep, CsvColumnsAndVectorTemplate) {
  const CliRun r = cli("sweep scenes/paper/die1.toml --param throw.velocity.mean --template '[{}, 0, 0]' "
                           "--values 1:3:1 -n 300 --csv -");
  ASSERT_EQ(r.code, 0) << r.err;
  std::istringstream in(r.out);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("# provenance {\"", 0), 0u) << line;  // what made it, as one JSON line
  std::getline(in, line);
  EXPECT_EQ(line, "param,face,count,p,lo,hi");
  int rows = 0;
  double p_sum = 0;
  while (std::getline(in, line)) {
    ++rows;
    double x, p, lo, hi;
    int face, count;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%d,%d,%lf,%lf,%lf", &x, &face, &count, &p, &lo, &hi), 6) << line;
    EXPECT_LE(lo, p);
    EXPECT_GE(hi, p);
    if (x == 2) p_sum += p;
  }
  EXPECT_EQ(rows, 18);
  EXPECT_NEAR(p_sum, 1.0, 1e-5);
}

TEST(CliSweep, SweepFileWithPlotAndMarkdown) {
  const std::string png = tmp("orientation.png"), md = tmp("orientation.md");
  fs::remove(png);
  fs::remove(md);
  const CliRun r = cli("sweep scenes/paper/sweeps/initial-orientation.toml -n 300 --plot " + png + " --markdown " + md);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("6 (aluminium)"), std::string::npos) << r.out;
  ASSERT_TRUE(fs::exists(png));
  EXPECT_GT(fs::file_size(png), 5000u);
  EXPECT_LT(fs::file_size(png), 200000u);
  std::ifstream in(png, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  std::ifstream m(md);
  std::stringstream ss;
  ss << m.rdbuf();
  EXPECT_NE(ss.str().find("| face on top at release |"), std::string::npos) << ss.str();
  EXPECT_NE(ss.str().find("(0.1030)"), std::string::npos) << "the seed's Table 14 value beside ours";
}

TEST(CliSweep, SvgPlot) {
  const std::string svg = tmp("h.svg");
  fs::remove(svg);
  const CliRun r = cli("sweep scenes/paper/die1.toml --param throw.height.mean --values 0.5,1 -n 200 --plot " + svg);
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(svg);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_NE(ss.str().find("<svg"), std::string::npos);
}

TEST(CliSweep, BadInput) {
  expect_bad_input(cli("sweep scenes/paper/die1.toml --param floor.restitution --values 1:2:0"), {"--values", "1:2:0", "step"});
  expect_bad_input(cli("sweep scenes/paper/die1.toml --param floor.restitution --values 0.5,1.5"),
                   {"floor.restitution", "1.5", "[0, 1]"});
  expect_bad_input(cli("sweep scenes/paper/die1.toml --param floor.restitutoin --values 0.5"), {"restitutoin", "unknown key"});
  expect_bad_input(cli("sweep scenes/paper/die1.toml"), {"--param", "sweep file"});
  expect_bad_input(cli("sweep scenes/paper/die1.toml --param floor.restitution --values 0.5 --plot x.gif"), {"--plot", ".png"});
  expect_bad_input(cli("sweep scenes/paper/sweeps/height.toml --param floor.restitution --values 0.5"), {"height.toml", "sweep file"});
  expect_bad_input(cli("sweep no/such.toml --param a --values 1"), {"no/such.toml", "cannot open"});
  expect_bad_input(cli("sweep no/such.toml"), {"no/such.toml", "cannot open"});
  expect_bad_input(cli("sweep scenes/paper/die1.toml --param floor.restitution --values 0.5 --json --csv -"), {"--csv", "--json"});
  expect_bad_input(cli("sweep scenes/paper/die1.toml --param throw.velocity.mean --template '[1, 2]' --values 1"), {"--template", "{}"});
}

TEST(CliSweep, HelpTeachesWithExamples) {
  for (const char* cmd : {"sweep", "calibrate-restitution", "compare"}) {
    const CliRun r = cli(std::string(cmd) + " --help");
    EXPECT_EQ(r.code, 0) << cmd;
    EXPECT_NE(r.out.find("Examples:"), std::string::npos) << cmd;
  }
}

TEST(CliCalibrate, SeedTables4And5) {
  const std::string csv = "data/seed-tables/table04_05_restitution_trials.csv";
  for (const auto& [material, expected] : {std::pair{"steel", 0.487}, std::pair{"aluminium", 0.550}}) {
    const CliRun r = cli("calibrate-restitution --pairs " + csv + " --where material=" + material + " --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_NEAR(j["restitution"].get<double>(), expected, 0.0005) << material;
    EXPECT_EQ(j["n"], 6);
    EXPECT_LT(j["ci95"][0].get<double>(), expected);
    EXPECT_GT(j["ci95"][1].get<double>(), expected);
  }
  const CliRun table = cli("calibrate-restitution --pairs " + csv + " --where material=steel");
  EXPECT_EQ(table.code, 0);
  EXPECT_NE(table.out.find("restitution 0.4869"), std::string::npos) << table.out;
}

TEST(CliCalibrate, Track) {
  // A drop from 0.6 m, e = 0.5, sampled at 500 Hz until the third flight's apex.
  const std::string path = tmp("track.csv");
  {
    std::ofstream out(path);
    out << "# synthetic drop\nt_s,z_m\n";
    const double g = 9.81, e = 0.5, h = 0.6;
    const double t1 = std::sqrt(2 * h / g), v1 = e * g * t1, t2 = t1 + 2 * v1 / g, v2 = e * v1, t3 = t2 + 2 * v2 / g, v3 = e * v2;
    for (double t = 0.0; t < t3 + v3 / g; t += 0.002) {
      const double z = t < t1 ? h - 0.5 * g * t * t
                       : t < t2 ? v1 * (t - t1) - 0.5 * g * (t - t1) * (t - t1)
                       : t < t3 ? v2 * (t - t2) - 0.5 * g * (t - t2) * (t - t2)
                                : v3 * (t - t3) - 0.5 * g * (t - t3) * (t - t3);
      out << t << "," << z << "\n";
    }
  }
  const CliRun r = cli("calibrate-restitution --track " + path + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["restitution"].get<double>(), 0.5, 1e-3);
  EXPECT_EQ(j["n"], 3);
  EXPECT_EQ(j["impacts"].size(), 3u);
}

TEST(CliCalibrate, BadInput) {
  const std::string csv = "data/seed-tables/table04_05_restitution_trials.csv";
  expect_bad_input(cli("calibrate-restitution"), {"--pairs", "--track"});
  expect_bad_input(cli("calibrate-restitution --pairs " + csv + " --where material=gold"), {"need at least 2"});
  expect_bad_input(cli("calibrate-restitution --pairs " + csv + " --where colour=red"), {"colour", "not found"});
  expect_bad_input(cli("calibrate-restitution --track " + csv), {"column t", "not found", "v_in_m_s"});
  const std::string bad = tmp("bad_pairs.csv");
  std::ofstream(bad) << "v_in,v_out\n6.1,3.0\n6.2,fast\n";
  expect_bad_input(cli("calibrate-restitution --pairs " + bad), {"line 3", "v_out", "'fast'", "finite number"});
}

TEST(CliCompare, RunAgainstTheSeedsExperiment) {
  const std::string sim = tmp("die1_sim.json");
  const CliRun toss = cli("toss scenes/paper/die1.toml -n 2000 --json > " + sim);
  ASSERT_EQ(toss.code, 0) << toss.err;
  const CliRun r = cli("compare " + sim + " data/seed-experiments/die1_counts.csv --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["n_a"], 2000);
  EXPECT_EQ(j["n_b"], 501);
  EXPECT_EQ(j["chi2"]["dof"], 5);
  ASSERT_EQ(j["faces"].size(), 6u);
  EXPECT_EQ(j["faces"][5]["count_b"], 135);
  // Against itself: no difference at all.
  const CliRun self = cli("compare " + sim + " " + sim + " --json");
  ASSERT_EQ(self.code, 0);
  EXPECT_NEAR(nlohmann::json::parse(self.out)["chi2"]["statistic"].get<double>(), 0.0, 1e-9);
  const CliRun table = cli("compare " + sim + " data/seed-experiments/die1_counts.csv");
  EXPECT_NE(table.out.find("chi-square homogeneity"), std::string::npos) << table.out;
}

TEST(CliCompare, BadInput) {
  const std::string bad = tmp("bad_counts.csv");
  std::ofstream(bad) << "face,count\n1,10\n2,-3\n";
  expect_bad_input(cli("compare data/seed-experiments/die1_counts.csv " + bad), {"bad_counts.csv", "line 3", "count"});
  const std::string five = tmp("five_faces.csv");
  std::ofstream(five) << "1,10\n2,10\n3,10\n4,10\n5,10\n7,10\n";
  expect_bad_input(cli("compare data/seed-experiments/die1_counts.csv " + five),
                   {"different face labels", "missing in A: 7", "missing in B: 6"});
  expect_bad_input(cli("compare nope.json data/seed-experiments/die1_counts.csv"), {"nope.json", "cannot open"});
}

// Any die: a d20's run against observed counts with labels 0..999 (any integers), in label order
// with N - 1 degrees of freedom; and a sweep of a d20 reports its 20 outcomes at every point.
TEST(CliCompare, AnyLabelsInLabelOrderWithNMinusOneDof) {
  const std::string sim = tmp("d20.json");
  ASSERT_EQ(cli("toss scenes/dice/d20.toml -n 3000 --json > " + sim).code, 0);
  const std::string obs = tmp("d20_counts.csv");
  {
    std::ofstream out(obs);
    out << "face,count\n";
    for (int f = 20; f >= 1; --f) out << f << "," << 140 + f << "\n";  // any order in the file
  }
  const CliRun r = cli("compare " + sim + " " + obs + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["chi2"]["dof"], 19);
  ASSERT_EQ(j["faces"].size(), 20u);
  for (int f = 0; f < 20; ++f) {
    EXPECT_EQ(j["faces"][f]["face"], f + 1);
    EXPECT_EQ(j["faces"][f]["count_b"], 141 + f);
  }
  const CliRun table = cli("compare " + sim + " " + obs);
  EXPECT_NE(table.out.find("not corrected for 20 comparisons"), std::string::npos) << table.out;
  // Labels 0 and 999 are labels like any other; a d6's counts against a d20 name what is missing.
  const std::string wide = tmp("wide_labels.csv");
  std::ofstream(wide) << "0,10\n500,12\n999,9\n";
  const CliRun self = cli("compare " + wide + " " + wide + " --json");
  ASSERT_EQ(self.code, 0) << self.err;
  EXPECT_EQ(nlohmann::json::parse(self.out)["faces"][2]["face"], 999);
  expect_bad_input(cli("compare " + sim + " data/seed-experiments/die1_counts.csv"),
                   {"missing in B: 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20", "missing in A: none"});
  const std::string big = tmp("big_label.csv");
  std::ofstream(big) << "1,10\n1000,10\n";
  expect_bad_input(cli("compare " + wide + " " + big), {"big_label.csv", "line 2", "[0, 999]"});
}

TEST(CliSweep, AD20SweepReportsEveryOutcomeInLabelOrder) {
  const CliRun r = cli("sweep scenes/dice/d20.toml --param floor.restitution --values 0.3,0.8 -n 1000 --seed 2 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["points"].size(), 2u);
  for (const auto& p : j["points"]) {
    expect_faces_one_to(p, 20);
  }
  // The same points tossed one by one: identical counts (the sweep adds nothing of its own).
  const CliRun one = cli("toss scenes/dice/d20.toml --set floor.restitution=0.8 -n 1000 --seed 2 --json");
  ASSERT_EQ(one.code, 0) << one.err;
  const auto t = nlohmann::json::parse(one.out);
  for (int f = 0; f < 20; ++f) EXPECT_EQ(j["points"][1]["faces"][f]["count"], t["faces"][f]["count"]);
  EXPECT_EQ(t["chi2_uniform"]["dof"], 19);
  const std::string md = tmp("d20.md");
  const CliRun m = cli("sweep scenes/dice/d20.toml --param floor.restitution --values 0.3 -n 200 --markdown " + md);
  ASSERT_EQ(m.code, 0) << m.err;
  std::ifstream in(md);
  std::string header;
  std::getline(in, header);
  EXPECT_NE(header.find("P(1) |"), std::string::npos) << header;
  EXPECT_NE(header.find("P(20) |"), std::string::npos) << header;
  // Points whose dice differ in outcomes cannot share a table: bad input naming the point.
  expect_bad_input(cli("sweep scenes/dice/prism3.toml --param die.sides --values 3,4 -n 100"), {"die.sides", "same outcome labels"});
}

}  // namespace
