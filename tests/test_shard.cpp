// Shards for batch schedulers: `toss --shard I/N --out FILE` and `merge` give the counts of one
// toss of the whole range, and merge refuses shards that are not one run's (sim/study/shard.hpp,
// apps/shard_file.hpp).
#include <gtest/gtest.h>

#include "cli_runner.hpp"

#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "sim/study/shard.hpp"

namespace {

using dicesim::testing::CliRun;
using dicesim::testing::expect_bad_input;
using dicesim::testing::run_dicesim;
using dicesim::testing::unique_temp;

// Four shards of 4001 paper tosses of die1 (seed 5), written once per test process.
struct Parts {
  std::string file[4];
  Parts() {
    for (int i = 0; i < 4; ++i) {
      file[i] = unique_temp("part-" + std::to_string(i) + ".json");
      const CliRun r = run_dicesim("toss scenes/paper/die1.toml -n 4001 --seed 5 --threads 2 --shard " + std::to_string(i) +
                                   "/4 --out " + file[i]);
      EXPECT_EQ(r.code, 0) << r.err;
    }
  }
  std::string all() const { return file[0] + " " + file[1] + " " + file[2] + " " + file[3]; }
};
const Parts& parts() {
  static const Parts p;
  return p;
}

// Everything in a report that counts decide (not threads, elapsed_s, tosses_per_s).
std::string counted(const nlohmann::json& j) {
  nlohmann::json c;
  for (const char* k : {"scene", "fidelity", "seed", "tosses", "settled", "unresolved", "invalid", "faces", "chi2_uniform",
                        "chi2_heads_tails", "bounces_per_toss", "corrections"})
    c[k] = j.at(k);
  return c.dump();
}

std::string read(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// A copy of `from` with shard.<key> (or the top-level key) set to `value`.
std::string edited(const std::string& from, const std::string& key, const nlohmann::json& value, bool in_shard) {
  nlohmann::json j = nlohmann::json::parse(read(from));
  (in_shard ? j["shard"][key] : j[key]) = value;
  const std::string path = unique_temp("edited-" + key + ".json");
  std::ofstream(path) << j.dump();
  return path;
}

}  // namespace

TEST(Shard, BlocksAreContiguousAndCoverTheRange) {
  for (const std::uint64_t total : {0ULL, 1ULL, 7ULL, 4001ULL, 10000000ULL, 1ULL << 40})
    for (const std::uint64_t n : {1ULL, 3ULL, 4ULL, 16ULL, 1000ULL}) {
      std::uint64_t next = 0, lo = ~0ULL, hi = 0;
      for (std::uint64_t i = 0; i < n; ++i) {
        const dicesim::IndexRange b = dicesim::shard_range(total, {i, n});
        ASSERT_EQ(b.first, next) << total << " " << i << "/" << n;
        next += b.tosses;
        lo = std::min(lo, b.tosses);
        hi = std::max(hi, b.tosses);
      }
      EXPECT_EQ(next, total);
      EXPECT_LE(hi - lo, 1u) << total << " over " << n;
    }
}

TEST(Shard, ParsesIOfNAndNamesWhatIsWrong) {
  EXPECT_EQ(dicesim::parse_shard("3/16").index, 3u);
  EXPECT_EQ(dicesim::parse_shard("3/16").count, 16u);
  for (const char* bad : {"16/16", "3", "a/4", "1/0", "-1/4", "1/4x", "/4"})
    EXPECT_THROW(dicesim::parse_shard(bad), std::invalid_argument) << bad;
}

TEST(CliShard, FourShardsMergeToOneTossOfTheWholeRange) {
  const CliRun whole = run_dicesim("toss scenes/paper/die1.toml -n 4001 --seed 5 --threads 2 --json");
  ASSERT_EQ(whole.code, 0) << whole.err;
  const CliRun merged = run_dicesim("merge --json " + parts().all());
  ASSERT_EQ(merged.code, 0) << merged.err;
  EXPECT_EQ(counted(nlohmann::json::parse(merged.out)), counted(nlohmann::json::parse(whole.out)));
  // Any order; a shard's own report is its block.
  const CliRun reordered = run_dicesim("merge --json " + parts().file[3] + " " + parts().file[1] + " " + parts().file[0] +
                                       " " + parts().file[2]);
  EXPECT_EQ(counted(nlohmann::json::parse(reordered.out)), counted(nlohmann::json::parse(whole.out)));
  const auto s2 = nlohmann::json::parse(read(parts().file[2]));
  EXPECT_EQ(s2["tosses"], 1000);  // floor(4001*3/4) - floor(4001*2/4)
  EXPECT_EQ(s2["shard"]["first"], 2000);
  // The table too: the same lines but the header's thread count and the timing line.
  const CliRun table = run_dicesim("merge " + parts().all());
  ASSERT_EQ(table.code, 0) << table.err;
  EXPECT_NE(table.out.find("4001 tosses"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("face       count"), std::string::npos);
}

TEST(CliShard, MergedCorrectionsAreEveryKindTossCounts) {
  // A d20 in impulse fires the sustained phase's guards (located_capped ~1 in 100 tosses): merge
  // must add every kind, not only the first four.
  const std::string base = "toss scenes/dice/d20.toml --fidelity impulse -n 2000 --seed 3 --json";
  const CliRun whole = run_dicesim(base);
  ASSERT_EQ(whole.code, 0) << whole.err;
  const std::string a = unique_temp("d20-0.json"), b = unique_temp("d20-1.json");
  ASSERT_EQ(run_dicesim(base + " --shard 0/2 --out " + a).code, 0);
  ASSERT_EQ(run_dicesim(base + " --shard 1/2 --out " + b).code, 0);
  const CliRun merged = run_dicesim("merge --json " + a + " " + b);
  ASSERT_EQ(merged.code, 0) << merged.err;
  const auto w = nlohmann::json::parse(whole.out), m = nlohmann::json::parse(merged.out);
  ASSERT_GT(w["corrections"]["located_capped"].get<long long>(), 0) << w["corrections"];
  EXPECT_EQ(m["corrections"], w["corrections"]);
}

TEST(CliShard, MergeRefusesShardsOfOtherRunsNamingTheFile) {
  const Parts& p = parts();
  // A missing shard.
  expect_bad_input(run_dicesim("merge " + p.file[0] + " " + p.file[1] + " " + p.file[3]), {"shard 2/4 is missing"});
  // An overlap: one shard twice.
  expect_bad_input(run_dicesim("merge " + p.all() + " " + p.file[1]), {p.file[1].c_str(), "overlapping"});
  // Another seed, scene, fidelity, build.
  const CliRun seed7 = run_dicesim("toss scenes/paper/die1.toml -n 4001 --seed 7 --shard 1/4 --out " + unique_temp("seed7.json"));
  ASSERT_EQ(seed7.code, 0) << seed7.err;
  expect_bad_input(run_dicesim("merge " + p.file[0] + " " + unique_temp("seed7.json") + " " + p.file[2] + " " + p.file[3]),
                   {unique_temp("seed7.json").c_str(), "seed"});
  const CliRun die2 = run_dicesim("toss scenes/paper/die2.toml -n 4001 --seed 5 --shard 1/4 --out " + unique_temp("die2.json"));
  ASSERT_EQ(die2.code, 0) << die2.err;
  expect_bad_input(run_dicesim("merge " + p.file[0] + " " + unique_temp("die2.json") + " " + p.file[2] + " " + p.file[3]),
                   {unique_temp("die2.json").c_str(), "scene hash"});
  const CliRun stat = run_dicesim("toss scenes/paper/die1.toml -n 4001 --seed 5 --fidelity static --shard 1/4 --out " +
                                  unique_temp("static.json"));
  ASSERT_EQ(stat.code, 0) << stat.err;
  expect_bad_input(run_dicesim("merge " + p.file[0] + " " + unique_temp("static.json") + " " + p.file[2] + " " + p.file[3]),
                   {unique_temp("static.json").c_str()});
  const std::string old_build = edited(p.file[1], "version", "0.0.1", true);
  expect_bad_input(run_dicesim("merge " + p.file[0] + " " + old_build + " " + p.file[2] + " " + p.file[3]),
                   {old_build.c_str(), "version"});
  const std::string other_n = edited(p.file[1], "total", 4000, true);
  expect_bad_input(run_dicesim("merge " + p.file[0] + " " + other_n + " " + p.file[2] + " " + p.file[3]), {other_n.c_str()});
  // Not a shard file at all: a plain toss --json.
  const std::string plain = unique_temp("plain.json");
  std::ofstream(plain) << run_dicesim("toss scenes/paper/die1.toml -n 100 --json").out;
  expect_bad_input(run_dicesim("merge " + plain), {plain.c_str(), "not a shard file"});
  expect_bad_input(run_dicesim("merge " + unique_temp("absent.json")), {"absent.json"});
}

TEST(CliShard, ShardOptionsRefuseBadValues) {
  expect_bad_input(run_dicesim("toss scenes/paper/die1.toml -n 100 --shard 4/4"), {"--shard", "4/4"});
  expect_bad_input(run_dicesim("toss scenes/paper/die1.toml -n 100 --shard 1/4 --target-halfwidth 0.01"), {"--target-halfwidth"});
}

// A sweep shards by point: each point's counts are the whole sweep's (common random numbers).
TEST(CliShard, SweepPointsShardGivesTheWholeSweepsPoints) {
  const std::string base = "sweep scenes/paper/die1.toml --param floor.restitution --values 0.2,0.4,0.6,0.8,0.9 -n 1500 --seed 3 -j 2 --json";
  const CliRun whole = run_dicesim(base);
  ASSERT_EQ(whole.code, 0) << whole.err;
  nlohmann::json joined = nlohmann::json::array();
  for (const char* shard : {"0/2", "1/2"}) {
    const CliRun part = run_dicesim(base + " --points " + shard);
    ASSERT_EQ(part.code, 0) << part.err;
    const nlohmann::json j = nlohmann::json::parse(part.out);
    for (const auto& p : j["points"]) joined.push_back(p);
  }
  EXPECT_EQ(joined.size(), 5u);
  EXPECT_EQ(joined.dump(), nlohmann::json::parse(whole.out)["points"].dump());
  expect_bad_input(run_dicesim(base + " --points 2/2"), {"--points"});
  expect_bad_input(run_dicesim(base + " --points 0/10"), {"--points", "no points"});  // [0, floor(5/10)) is empty
}
