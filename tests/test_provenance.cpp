// Provenance (what made a result: version, resolved scene hash, overrides, fidelity and why, seed,
// tosses, threads) and no lost work (SIGINT keeps a reproducible prefix; output paths checked first).
#include <gtest/gtest.h>

#include "cli_runner.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "sim/scene/scene_hash.hpp"

namespace dicesim {
namespace {

using testing::CliRun;
using testing::expect_bad_input;
using testing::run_dicesim;
using testing::unique_temp;

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = unique_temp(name);
  std::ofstream(path) << text;
  return path;
}

const char* kBase =
    "# a plastic cube\n"
    "[materials.plastic]\n"
    "density = 1200.0\n"
    "restitution = 0.5\n"
    "\n"
    "[die]\n"
    "size = 0.03\n"
    "material = \"plastic\"\n";

TEST(Provenance, JsonCarriesTheOverrideTheHashAndTheVersion) {
  const CliRun r = run_dicesim("toss scenes/fair.toml -n 300 --seed 3 -j 2 --set materials.plastic.density=2000 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("provenance")) << r.out;
  const auto& p = j["provenance"];
  EXPECT_EQ(p["overrides"], nlohmann::json::array({"materials.plastic.density=2000"}));
  EXPECT_EQ(p["scene"], "scenes/fair.toml");
  const std::string hash = p["scene_sha256"];
  EXPECT_EQ(hash.size(), 64u);
  EXPECT_EQ(hash.find_first_not_of("0123456789abcdef"), std::string::npos) << hash;
  EXPECT_EQ(hash, scene_sha256(std::string(DICESIM_SOURCE_DIR) + "/scenes/fair.toml", {"materials.plastic.density=2000"}));
  EXPECT_NE(hash, scene_sha256(std::string(DICESIM_SOURCE_DIR) + "/scenes/fair.toml"));
  EXPECT_FALSE(std::string(p["version"]).empty());
  EXPECT_TRUE(p["dirty"].is_boolean() || p["dirty"].is_null());
  EXPECT_EQ(p["seed"], 3);
  EXPECT_EQ(p["tosses"], 300);
  EXPECT_EQ(p["threads"], 2);
  EXPECT_EQ(p["fidelity"], j["fidelity"]);
  EXPECT_FALSE(std::string(p["fidelity_reason"]).empty());
  EXPECT_EQ(j["partial"], false);

  // The table says the same in its header.
  const CliRun t = run_dicesim("toss scenes/fair.toml -n 300 --seed 3 --set materials.plastic.density=2000");
  ASSERT_EQ(t.code, 0) << t.err;
  EXPECT_NE(t.out.find("scene sha256 " + hash), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("overrides: materials.plastic.density=2000"), std::string::npos) << t.out;
}

// Canonical: the resolved tree with sorted keys, every number a double, no comments or layout.
TEST(Provenance, EqualResolvedScenesHashEqual) {
  const std::string base = write_file("base.toml", kBase);
  const std::string h = scene_sha256(base);
  ASSERT_EQ(h.size(), 64u);
  // Through extends (the base's name is dropped; ours is not hashed either).
  const std::string derived = write_file("derived.toml", "extends = \"" + base + "\"\nname = \"other\"\n");
  EXPECT_EQ(scene_sha256(derived), h);
  // Another key order, whitespace, comments, an inline table, and 1200 written as an integer and as 1.2e3.
  const std::string reordered = write_file("reordered.toml",
                                           "die = { material = \"plastic\",   size = 3e-2 }   # inline\n"
                                           "[materials.plastic]\n"
                                           "restitution=0.50\n"
                                           "density = 1.2e3\n");
  EXPECT_EQ(scene_sha256(reordered), h);
  const std::string integer = write_file("integer.toml", std::string(kBase).replace(std::string(kBase).find("1200.0"), 6, "1200"));
  EXPECT_EQ(scene_sha256(integer), h);
  // A value given by --set is the same scene as the value written in the file.
  const std::string other = write_file("other.toml", std::string(kBase).replace(std::string(kBase).find("1200.0"), 6, "2000"));
  EXPECT_EQ(scene_sha256(base, {"materials.plastic.density=2000"}), scene_sha256(other));
  // parse_scene (Python's scene_from_toml) hashes alike.
  EXPECT_EQ(scene_text_sha256(kBase, "text"), h);
}

TEST(Provenance, DifferentScenesHashDifferently) {
  const std::string base = write_file("base.toml", kBase);
  const std::string h = scene_sha256(base);
  EXPECT_NE(scene_sha256(base, {"materials.plastic.density=1200.5"}), h);
  EXPECT_NE(scene_sha256(base, {"die.size=0.031"}), h);
  EXPECT_NE(scene_sha256(base, {"sim.fidelity=\"impulse\""}), h);
  // A key stated at its default is not the key left out (documented: sim/scene/scene_hash.hpp).
  EXPECT_NE(scene_sha256(base, {"sim.gravity=9.81"}), h);
}

TEST(Provenance, VersionFlagAndBuild) {
  const CliRun v = run_dicesim("--version");
  ASSERT_EQ(v.code, 0) << v.err;
  EXPECT_EQ(v.out.rfind("dicesim ", 0), 0u) << v.out;
  EXPECT_GT(v.out.size(), std::string("dicesim \n").size());
  const CliRun b = run_dicesim("version --json");
  ASSERT_EQ(b.code, 0) << b.err;
  const auto j = nlohmann::json::parse(b.out);
  EXPECT_EQ("dicesim " + std::string(j["version"]) + "\n", v.out);
  EXPECT_FALSE(std::string(j["compiler"]).empty());
  EXPECT_NE(std::string(j["cxx_flags"]).find("-ffp-contract=off"), std::string::npos) << b.out;
  for (const char* lib : {"Eigen", "toml++", "CLI11", "spdlog", "nlohmann-json", "Boost", "LCM", "OpenSSL"})
    EXPECT_TRUE(j["libraries"].contains(lib)) << lib;
  // The version in a result is the build's.
  const CliRun t = run_dicesim("toss scenes/fair.toml -n 100 --json");
  ASSERT_EQ(t.code, 0) << t.err;
  EXPECT_EQ(nlohmann::json::parse(t.out)["provenance"]["version"], j["version"]);
}

// Output paths are checked before the first toss: a sweep of 10^5 tosses at each of 9 points (a
// minute or more) fails at once with exit 2 naming the option and the path.
TEST(Provenance, UnwritableOutputPathsFailBeforeWork) {
  const std::string sweep = "sweep scenes/paper/die1.toml --param floor.restitution --values 0.1:0.9:0.1 -n 100000 ";
  expect_bad_input(run_dicesim(sweep + "--plot /nonexistent-dir/p.png"), {"--plot", "/nonexistent-dir/p.png"});
  expect_bad_input(run_dicesim(sweep + "--csv /nonexistent-dir/p.csv"), {"--csv", "/nonexistent-dir/p.csv"});
  expect_bad_input(run_dicesim(sweep + "--markdown /tmp"), {"--markdown", "/tmp"});
  expect_bad_input(run_dicesim("fit scenes/paper/die1.toml --data data/seed-experiments/die1_counts.csv "
                               "--param floor.restitution=0.2:0.9 --fidelity static --plot /nonexistent-dir/f.svg"),
                   {"--plot", "/nonexistent-dir/f.svg"});
}

// True once `pid` catches SIGINT (its handler is installed: /proc/PID/status, SigCgt).
bool catches_sigint(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("SigCgt:", 0) == 0) return (std::stoull(line.substr(7), nullptr, 16) >> (SIGINT - 1)) & 1u;
  return false;
}

// Runs `dicesim ARGS` from the source tree, sends SIGINT `wait` after it started catching it (a
// loaded machine may take seconds to get there), and returns its exit code and stdout.
CliRun interrupt_after(const std::string& args, std::chrono::milliseconds wait) {
  int out[2];
  EXPECT_EQ(pipe(out), 0);
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], STDOUT_FILENO);
    close(out[0]);
    close(out[1]);
    if (chdir(DICESIM_SOURCE_DIR) != 0) _exit(127);
    const std::string cmd = std::string("exec ") + DICESIM_BINARY + " " + args + " 2>/dev/null";
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  close(out[1]);
  for (int i = 0; i < 1200 && !catches_sigint(pid); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_TRUE(catches_sigint(pid)) << "no SIGINT handler after 60 s";
  std::this_thread::sleep_for(wait);
  kill(pid, SIGINT);
  CliRun r;
  char buf[4096];
  for (ssize_t n; (n = read(out[0], buf, sizeof buf)) > 0;) r.out.append(buf, static_cast<std::size_t>(n));
  close(out[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// Ctrl-C on a long toss: the tosses done are printed as a complete prefix (exit 130), and their
// counts are exactly those of a fresh toss of that many tosses with the same seed.
TEST(Provenance, InterruptedTossKeepsAReproduciblePrefix) {
  const CliRun r = interrupt_after("toss scenes/fair.toml --fidelity paper -n 1000000000 --seed 11 -j 2 --json",
                                   std::chrono::seconds(2));
  ASSERT_EQ(r.code, 130) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["partial"], true);
  EXPECT_EQ(j["tosses_requested"], 1000000000);
  const std::uint64_t k = j["tosses"];
  ASSERT_GT(k, 0u) << "no toss finished in 2 s";
  ASSERT_LT(k, 1000000000u);
  EXPECT_EQ(static_cast<std::uint64_t>(j["settled"]) + static_cast<std::uint64_t>(j["unresolved"]) +
                static_cast<std::uint64_t>(j["invalid"]),
            k);
  const CliRun fresh = run_dicesim("toss scenes/fair.toml --fidelity paper -n " + std::to_string(k) + " --seed 11 -j 1 --json");
  ASSERT_EQ(fresh.code, 0) << fresh.err;
  const auto f = nlohmann::json::parse(fresh.out);
  EXPECT_EQ(j["faces"], f["faces"]);
  EXPECT_EQ(j["settled"], f["settled"]);
  EXPECT_EQ(j["bounces_per_toss"], f["bounces_per_toss"]);
  EXPECT_EQ(f["partial"], false);
}

TEST(Provenance, InterruptedTossSaysSoInTheTable) {
  const CliRun r = interrupt_after("toss scenes/fair.toml --fidelity paper -n 1000000000 --seed 11 -j 2", std::chrono::seconds(2));
  ASSERT_EQ(r.code, 130) << r.out;
  EXPECT_NE(r.out.find("interrupted after "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" of 1000000000 tosses"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("face       count"), std::string::npos) << r.out;
}

// A sweep interrupted in its first point prints that point's prefix (exit 130), marked partial.
TEST(Provenance, InterruptedSweepPrintsThePointsDone) {
  const CliRun r = interrupt_after(
      "sweep scenes/fair.toml --param floor.restitution --values 0.2,0.5 --fidelity paper -n 1000000000 -j 2 --json",
      std::chrono::seconds(2));
  ASSERT_EQ(r.code, 130) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["partial"], true);
  EXPECT_EQ(j["points_requested"], 2);
  ASSERT_EQ(j["points"].size(), 1u) << r.out;  // the first point's prefix
  EXPECT_EQ(j["points"][0]["partial"], true);
  EXPECT_TRUE(j.contains("provenance"));
}

}  // namespace
}  // namespace dicesim
