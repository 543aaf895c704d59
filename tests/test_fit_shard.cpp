// A fit sharded by point (`dicesim fit --points I/N --parts DIR`, `--merge DIR`): the shards'
// passes, merged, print exactly the unsharded fit, and merge refuses parts that are not one fit's
// whole set (apps/fit_parts.hpp, sim/study/fit.hpp FitPointCounts).
#include <gtest/gtest.h>

#include "cli_runner.hpp"

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;
using dicesim::testing::CliRun;
using dicesim::testing::expect_bad_input;
using dicesim::testing::run_dicesim;
using dicesim::testing::unique_temp;

// Counts that put the estimate inside the range (~4100), so rounds 2 and 3 narrow the box around
// round 1's estimate: a stage's points depend on the stages before it.
const std::string& counts() {
  static const std::string file = [] {
    const std::string f = unique_temp("counts.csv");
    std::ofstream(f) << "face,count\n1,150\n2,170\n3,168\n4,166\n5,170\n6,176\n";
    return f;
  }();
  return file;
}

// A joint fit of two data sets (the stage's points are data set by data set), static: cheap.
std::string fit_args(int seed) {
  return "fit scenes/paper/die1.toml --data " + counts() + " --data " + counts() +
         " --scene scenes/paper/die2.toml --param materials.steel.density=3000:20000 --fidelity static -n 4000 -j 2 --seed " +
         std::to_string(seed);
}

// Every shard's pass, again and again until each says the fit is counted; returns the passes run.
int run_passes(const std::string& args, const std::string& dir, int n) {
  for (int pass = 1; pass <= 10; ++pass) {
    bool complete = true;
    for (int i = 0; i < n; ++i) {
      const CliRun r = run_dicesim(args + " --json --points " + std::to_string(i) + "/" + std::to_string(n) + " --parts " + dir);
      EXPECT_EQ(r.code, 0) << r.err;
      if (r.code != 0) return -1;
      complete = complete && nlohmann::json::parse(r.out)["fit_pass"]["complete"].get<bool>();
    }
    if (complete) return pass;
  }
  return -1;
}

// The parts of seed 3's fit in 3 shards, made once per test process.
const std::string& parts_dir() {
  static const std::string dir = [] {
    const std::string d = unique_temp("fit-parts");
    EXPECT_GT(run_passes(fit_args(3), d, 3), 1);  // at least the rounds' stages and the fitted point
    return d;
  }();
  return dir;
}

// A copy of the parts to spoil.
std::string copy_of_parts(const std::string& name) {
  const std::string d = unique_temp(name);
  fs::copy(parts_dir(), d);
  return d;
}

std::string without_elapsed(std::string text) {
  return std::regex_replace(text, std::regex(R"(simulated in [0-9.]+ s)"), "simulated in _ s");
}

}  // namespace

TEST(CliFitShard, MergedPartsAreTheUnshardedFitExactly) {
  const CliRun whole = run_dicesim(fit_args(3) + " --json");
  ASSERT_EQ(whole.code, 0) << whole.err;
  const CliRun merged = run_dicesim(fit_args(3) + " --json --merge " + parts_dir());
  ASSERT_EQ(merged.code, 0) << merged.err;
  nlohmann::json w = nlohmann::json::parse(whole.out), m = nlohmann::json::parse(merged.out);
  ASSERT_TRUE(w["estimated"].get<bool>());
  ASSERT_LT(w["rounds"][1]["box_hi"][0].get<double>(), 20000.0);  // round 2 placed by round 1's estimate
  w.erase("elapsed_s");  // wall time: the only field that may differ
  m.erase("elapsed_s");
  EXPECT_EQ(m.dump(), w.dump());  // estimate, intervals, rounds, fitted p, gof, simulated_tosses
  // Each part holds one shard's block of one stage; three shards, at least four stages.
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(parts_dir())) files += e.path().filename().string().rfind("fit-part-s", 0) == 0;
  EXPECT_GE(files, 3u * 3u);
  // The table too, but for the timing.
  const CliRun t_whole = run_dicesim(fit_args(3));
  const CliRun t_merged = run_dicesim(fit_args(3) + " --merge " + parts_dir());
  ASSERT_EQ(t_merged.code, 0) << t_merged.err;
  EXPECT_EQ(without_elapsed(t_merged.out), without_elapsed(t_whole.out));
  // A pass after the last has nothing to toss and says the fit is counted.
  const CliRun again = run_dicesim(fit_args(3) + " --json --points 1/3 --parts " + parts_dir());
  ASSERT_EQ(again.code, 0) << again.err;
  const auto status = nlohmann::json::parse(again.out)["fit_pass"];
  EXPECT_TRUE(status["complete"].get<bool>());
  EXPECT_TRUE(status["written"].empty());
}

TEST(CliFitShard, MergeRefusesMissingOverlappingAndOtherFitsPartsNamingTheFile) {
  // Missing: one shard's part of the second stage.
  const std::string missing = copy_of_parts("fit-missing");
  const std::string gone = (fs::path(missing) / "fit-part-s1-1of3.json").string();
  ASSERT_TRUE(fs::remove(gone));
  expect_bad_input(run_dicesim(fit_args(3) + " --merge " + missing), {gone.c_str(), "missing"});
  // Overlapping: a part twice, under another name.
  const std::string twice = copy_of_parts("fit-twice");
  const std::string copy = (fs::path(twice) / "fit-part-zz-copy.json").string();
  fs::copy_file(fs::path(twice) / "fit-part-s0-2of3.json", copy);
  expect_bad_input(run_dicesim(fit_args(3) + " --merge " + twice), {copy.c_str(), "fit-part-s0-2of3.json", "overlapping"});
  // Another fit's part (seed 4): named, with the field that differs.
  const std::string other = unique_temp("fit-other");
  const CliRun pass = run_dicesim(fit_args(4) + " --points 0/3 --parts " + other);
  ASSERT_EQ(pass.code, 0) << pass.err;
  const std::string mixed = copy_of_parts("fit-mixed");
  const std::string stranger = (fs::path(mixed) / "fit-part-s0-0of3-seed4.json").string();
  fs::copy_file(fs::path(other) / "fit-part-s0-0of3.json", stranger);
  expect_bad_input(run_dicesim(fit_args(3) + " --merge " + mixed), {stranger.c_str(), "seed"});
  // A pass of another N into the same directory.
  expect_bad_input(run_dicesim(fit_args(3) + " --points 0/2 --parts " + parts_dir()), {"shard count N", "fit-part-s0-0of3.json"});
  // `dicesim merge` (of toss shards) given a fit part says how to merge it.
  const std::string part = (fs::path(parts_dir()) / "fit-part-s0-0of3.json").string();
  expect_bad_input(run_dicesim("merge " + part), {part.c_str(), "fit ARGS --merge"});
  // Nothing to merge; half a pass's options; a bad shard.
  const std::string empty = unique_temp("fit-empty");
  fs::create_directories(empty);
  expect_bad_input(run_dicesim(fit_args(3) + " --merge " + empty), {empty.c_str(), "no fit parts"});
  expect_bad_input(run_dicesim(fit_args(3) + " --points 0/3"), {"--parts"});
  expect_bad_input(run_dicesim(fit_args(3) + " --points 3/3 --parts " + empty), {"--points", "3/3"});
  expect_bad_input(run_dicesim(fit_args(3) + " --merge " + parts_dir() + " --points 0/3 --parts " + empty), {"--merge"});
}
