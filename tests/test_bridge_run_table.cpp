// The bridge's bookkeeping without a network: LCM -> DDS field mapping, run states over time,
// and which DDS configuration it picks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "bridge/dds_config.hpp"
#include "bridge/run_table.hpp"
#include "bridge/translate.hpp"

namespace b = dicesim::bridge;

namespace {

dicesim_lcm::run_start start(std::int64_t run) {
  dicesim_lcm::run_start m{};
  m.run_id = run;
  m.origin = "scenes/paper/die1.toml";
  m.scene_hash = "abc";
  m.fidelity = "paper";
  m.seed = 11;
  m.total_tosses = 1000;
  return m;
}

dicesim_lcm::probabilities answer(std::int64_t run, std::int64_t done, bool finished) {
  dicesim_lcm::probabilities m{};
  m.run_id = run;
  m.utime = 1000 + done;
  m.done = done;
  m.total = 1000;
  m.finished = finished ? 1 : 0;
  return m;
}

dicesim_lcm::worker_status heartbeat(std::int64_t worker, std::int64_t run, int state = 1) {
  dicesim_lcm::worker_status m{};
  m.worker_id = worker;
  m.run_id = run;
  m.state = static_cast<std::int8_t>(state);
  return m;
}

bool has(const std::vector<std::int64_t>& v, std::int64_t x) { return std::find(v.begin(), v.end(), x) != v.end(); }

}  // namespace

TEST(BridgeTranslate, EveryFieldCrosses) {
  dicesim_lcm::probabilities m{};
  m.utime = 17;
  m.run_id = 42;
  // A d20's answer: every outcome crosses, in order.
  m.n_outcomes = 20;
  for (int f = 0; f < 20; ++f) {
    m.labels.push_back(f + 1);
    m.counts.push_back(100 + f);
    m.p.push_back(0.1 + f * 0.01);
    m.ci_lo.push_back(0.05 + f * 0.01);
    m.ci_hi.push_back(0.15 + f * 0.01);
  }
  m.settled = 615, m.unresolved = 3, m.invalid = 2, m.done = 620, m.total = 1000;
  m.tosses_per_s = 123.5, m.finished = 1, m.workers = 3;
  m.duplicates = 4, m.rejected_foreign = 5, m.rejected_malformed = 6, m.rejected_range = 7, m.released = 8;
  m.rejected_unauthenticated = 9;
  const dicesim_dds_probabilities_v3 s = b::to_dds(m);
  EXPECT_EQ(s.run_id, 42);
  EXPECT_EQ(s.utime, 17);
  ASSERT_EQ(s.labels._length, 20u);
  ASSERT_EQ(s.counts._length, 20u);
  ASSERT_EQ(s.p._length, 20u);
  ASSERT_EQ(s.ci_lo._length, 20u);
  ASSERT_EQ(s.ci_hi._length, 20u);
  EXPECT_FALSE(s.labels._release);  // borrowed from m: Cyclone must not free it
  for (std::size_t f = 0; f < 20; ++f) {
    EXPECT_EQ(s.labels._buffer[f], static_cast<int>(f) + 1);
    EXPECT_EQ(s.counts._buffer[f], 100 + static_cast<int>(f));
    EXPECT_EQ(s.p._buffer[f], m.p[f]);
    EXPECT_EQ(s.ci_lo._buffer[f], m.ci_lo[f]);
    EXPECT_EQ(s.ci_hi._buffer[f], m.ci_hi[f]);
  }
  EXPECT_EQ(s.rejected_unauthenticated, 9);
  EXPECT_EQ(s.settled, 615);
  EXPECT_EQ(s.unresolved, 3);
  EXPECT_EQ(s.invalid, 2);
  EXPECT_EQ(s.done, 620);
  EXPECT_EQ(s.total, 1000);
  EXPECT_EQ(s.tosses_per_s, 123.5);
  EXPECT_TRUE(s.finished);
  EXPECT_EQ(s.workers, 3);
  EXPECT_EQ(s.duplicates, 4);
  EXPECT_EQ(s.rejected_foreign, 5);
  EXPECT_EQ(s.rejected_malformed, 6);
  EXPECT_EQ(s.rejected_range, 7);
  EXPECT_EQ(s.released, 8);
}

TEST(BridgeRunTable, AnnouncedRunningFinished) {
  b::RunTable t;
  t.on_run_start(start(7), 0.0);
  EXPECT_TRUE(has(t.tick(0.0), 7));
  EXPECT_EQ(t.find(7)->state, dicesim_dds_RUN_ANNOUNCED);
  EXPECT_TRUE(t.tick(0.1).empty());  // nothing new
  t.on_probabilities(answer(7, 100, false), 0.2);
  EXPECT_TRUE(has(t.tick(0.2), 7));
  EXPECT_EQ(t.find(7)->state, dicesim_dds_RUN_RUNNING);
  t.on_probabilities(answer(7, 200, false), 0.4);
  EXPECT_TRUE(t.tick(0.4).empty());  // progress alone: at the refresh period
  EXPECT_TRUE(has(t.tick(1.3), 7));
  EXPECT_EQ(t.find(7)->done, 200);
  t.on_probabilities(answer(7, 1000, true), 1.5);
  EXPECT_TRUE(has(t.tick(1.5), 7));
  EXPECT_EQ(t.find(7)->state, dicesim_dds_RUN_FINISHED);
  EXPECT_TRUE(t.tick(10.0).empty());  // finished runs are neither refreshed nor silenced
  EXPECT_EQ(t.find(7)->state, dicesim_dds_RUN_FINISHED);
  const dicesim_dds_run_status s = b::to_dds(*t.find(7), 99);
  EXPECT_EQ(s.run_id, 7);
  EXPECT_EQ(s.utime, 99);
  EXPECT_STREQ(s.origin, "scenes/paper/die1.toml");
  EXPECT_STREQ(s.fidelity, "paper");
  EXPECT_EQ(s.seed, 11);
  EXPECT_EQ(s.done, 1000);
}

TEST(BridgeRunTable, ARunJoinedMidwayWaitsForItsDescription) {
  b::RunTable t;
  t.on_probabilities(answer(7, 100, false), 0.0);
  EXPECT_TRUE(t.tick(0.0).empty());  // scene unknown yet: run_start comes within a second
  t.on_run_start(start(7), 0.8);
  EXPECT_TRUE(has(t.tick(0.8), 7));
  EXPECT_EQ(t.find(7)->origin, "scenes/paper/die1.toml");
  t.on_probabilities(answer(8, 100, false), 1.0);  // no run_start ever (e.g. a partial log)
  EXPECT_FALSE(has(t.tick(3.9), 8));
  EXPECT_TRUE(has(t.tick(4.1), 8));
}

TEST(BridgeRunTable, QuietAggregatorMakesARunSilentUntilItSpeaksAgain) {
  b::RunTable t;
  t.on_run_start(start(7), 0.0);
  t.on_probabilities(answer(7, 100, false), 0.5);
  t.tick(0.5);
  t.tick(3.4);
  EXPECT_EQ(t.find(7)->state, dicesim_dds_RUN_RUNNING);  // 2.9 s quiet: not yet
  EXPECT_TRUE(has(t.tick(3.6), 7));
  EXPECT_EQ(t.find(7)->state, dicesim_dds_RUN_SILENT);
  t.on_run_start(start(7), 4.0);
  EXPECT_TRUE(has(t.tick(4.0), 7));
  EXPECT_EQ(t.find(7)->state, dicesim_dds_RUN_RUNNING);
}

TEST(BridgeRunTable, WorkersCountWhileTheyHeartbeat) {
  b::RunTable t;
  t.on_worker_status(heartbeat(1, 7), 0.0);  // before run_start: not a run we know
  EXPECT_EQ(t.size(), 0u);
  t.on_run_start(start(7), 0.0);
  t.on_worker_status(heartbeat(1, 7), 0.1);
  t.on_worker_status(heartbeat(2, 7), 0.1);
  t.on_worker_status(heartbeat(3, 7, 2), 0.1);  // refused the run
  t.on_worker_status(heartbeat(4, 8), 0.1);     // another run's worker
  t.tick(0.1);
  EXPECT_EQ(t.find(7)->workers.size(), 2u);
  EXPECT_EQ(t.find(7)->refused.size(), 1u);
  t.on_run_start(start(7), 1.5);
  t.on_worker_status(heartbeat(1, 7), 1.5);
  EXPECT_TRUE(has(t.tick(2.2), 7));  // worker 2 went quiet: a change
  EXPECT_EQ(t.find(7)->workers.size(), 1u);
}

TEST(BridgeRunTable, ANewRunIsANewInstanceAndOldOnesAreForgotten) {
  b::RunTableDef def = b::default_run_table_def();
  def.max_runs = 3;
  b::RunTable t(def);
  for (int r = 1; r <= 5; ++r) t.on_run_start(start(r), r);
  const auto due = t.tick(5.0);
  EXPECT_EQ(t.size(), 3u);
  EXPECT_EQ(t.take_forgotten(), (std::vector<std::int64_t>{1, 2}));
  EXPECT_TRUE(t.take_forgotten().empty());
  EXPECT_FALSE(has(due, 1));
  EXPECT_TRUE(has(due, 5));
  EXPECT_EQ(t.find(1), nullptr);
  EXPECT_NE(t.find(5), nullptr);
}

TEST(BridgeDdsConfig, FlagThenEnvironmentThenRepositoryFile) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "dicesim_bridge_cfg_test";
  fs::create_directories(dir);
  const fs::path file = dir / "my.xml";
  std::ofstream(file) << "<CycloneDDS/>";
  EXPECT_EQ(b::resolve_dds_config(file.string(), "file:///elsewhere.xml", "").uri, "file://" + file.string());
  EXPECT_EQ(b::resolve_dds_config(file.string(), nullptr, "").source, "--dds-config");
  EXPECT_THROW(b::resolve_dds_config((dir / "missing.xml").string(), nullptr, ""), std::runtime_error);
  EXPECT_EQ(b::resolve_dds_config("", "file:///elsewhere.xml", "").uri, "file:///elsewhere.xml");
  // Neither: the repository's loopback file, e.g. <build>/bridge/ next to <build>/apps/dicesim.
  const b::DdsConfigChoice c = b::resolve_dds_config("", "", "/nonexistent/apps");
  EXPECT_EQ(c.source, "default");
  EXPECT_EQ(c.uri, "file://" DICESIM_SOURCE_DIR "/bridge/cyclonedds-loopback.xml");
  const auto cands = b::default_config_candidates("/opt/x/bin");
  ASSERT_GE(cands.size(), 2u);
  EXPECT_EQ(cands[0], "/opt/x/share/dicesim/cyclonedds-loopback.xml");
  EXPECT_EQ(cands[1], "/opt/x/bridge/cyclonedds-loopback.xml");
  fs::remove_all(dir);
}
