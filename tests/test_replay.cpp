// Replay from LCM event logs (logger/replay.hpp), without any network: the logs are written here
// with the same messages workers and the aggregator publish (tosses from sim::toss, the final
// result from agg::Aggregator itself), then damaged in the ways real files get damaged.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sim/body/outcome.hpp"
#include "aggregator/aggregator.hpp"
#include "cli_runner.hpp"
#include "logger/event_log.hpp"
#include "logger/replay.hpp"
#include "messages/run_spec.hpp"
#include "messages/wire.hpp"
#include "sim/body/die_model.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene.hpp"
#include "sim/models/toss.hpp"

namespace el = dicesim::eventlog;
namespace w = dicesim::wire;
using dicesim::testing::run_dicesim;
using dicesim::testing::unique_temp;

namespace {

const std::string kScene = "scenes/paper/die1.toml";  // relative: the CLI tests run from the source root

struct LogPlan {
  std::uint64_t tosses = 20000;
  std::uint64_t seed = 5;
  int trace_every = 0;
  int batch = 1024;
  bool shuffle_and_repeat = false;   // batches in reverse order, some twice
  bool skip_one_batch = false;       // a hole: the log does not hold the whole run
  bool with_final = true;            // the live aggregator's final result
  double target_halfwidth = 0.0;     // the live run stopped at a block boundary
  std::uint64_t announced = 0;       // run_start's total (0: tosses)
};

struct Written {
  std::string path;
  dicesim::RunCounts counts;  // over [0, stop)
  std::uint64_t stop = 0;
  std::int64_t run_id = 0;
};

// A log as a recorded run looks: run_start, statuses, batches (+ bounce states), probabilities.
Written write_log(const std::string& path, const LogPlan& plan) {
  const std::string scene = std::string(DICESIM_SOURCE_DIR) + "/" + kScene;
  const dicesim::DieModel model = dicesim::compile(dicesim::load_scene(scene), scene);
  const std::uint64_t announced = plan.announced ? plan.announced : plan.tosses;
  w::RunSpec spec = w::make_run_spec(4242, scene, {}, model, plan.seed, announced, plan.trace_every);
  spec.origin = kScene;  // as a user types it, so that the report names the scene as `toss` does

  el::EventLogWriter out(path);
  std::int64_t utime = 1'700'000'000'000'000;
  auto put = [&](const char* channel, const std::vector<std::uint8_t>& bytes) {
    EXPECT_TRUE(out.write(utime, channel, bytes.data(), bytes.size()));
    utime += 100;
  };
  dicesim::agg::AggregatorConfig cfg;
  cfg.spec = spec;
  cfg.target_halfwidth = plan.target_halfwidth;
  std::vector<std::vector<std::uint8_t>> finals;
  dicesim::agg::Aggregator live(cfg, [&](const char* ch, const std::vector<std::uint8_t>& bytes) {
    if (std::string(ch) == w::kProbabilities) finals.push_back(bytes);
  });
  put(w::kRunStart, w::encode(w::to_message(spec)));
  dicesim_lcm::worker_status st{};  // every count zero: no held leases
  st.worker_id = 9;
  st.run_id = spec.run_id;
  st.state = 1;
  st.host = "test";
  put(w::kWorkerStatus, w::encode(st));

  std::vector<std::vector<std::uint8_t>> batches;
  for (std::uint64_t first = 0; first < plan.tosses; first += static_cast<std::uint64_t>(plan.batch)) {
    const std::uint64_t n = std::min<std::uint64_t>(static_cast<std::uint64_t>(plan.batch), plan.tosses - first);
    dicesim_lcm::toss_batch b{};
    b.run_id = spec.run_id;
    b.worker_id = 9;
    b.lease_id = 1;
    b.first_index = static_cast<std::int64_t>(first);
    b.count = static_cast<std::int32_t>(n);
    for (std::uint64_t i = first; i < first + n; ++i) {
      std::vector<dicesim::BounceRecord> recs;
      dicesim::TossProbe probe;
      probe.trace = &recs;
      const bool traced = plan.trace_every > 0 && i % static_cast<std::uint64_t>(plan.trace_every) == 0;
      const dicesim::TossResult r = dicesim::toss(model, plan.seed, i, traced ? &probe : nullptr);
      b.outcomes.push_back(static_cast<std::int8_t>(r.status == dicesim::TossStatus::Settled ? r.outcome : -1));
      b.statuses.push_back(static_cast<std::int8_t>(r.status));
      b.bounces.push_back(r.bounces);
      for (const dicesim::BounceRecord& rec : recs) {  // as sim/worker publishes them
        dicesim_lcm::bounce_state s{};
        s.run_id = spec.run_id;
        s.worker_id = 9;
        s.toss_index = static_cast<std::int64_t>(i);
        s.bounce = rec.bounce;
        s.t = rec.t;
        const Eigen::Quaterniond q(rec.before.R);
        s.quaternion[0] = q.w(), s.quaternion[1] = q.x(), s.quaternion[2] = q.y(), s.quaternion[3] = q.z();
        for (int k = 0; k < 3; ++k) {
          s.position[k] = rec.before.position[k];
          s.velocity[k] = rec.before.velocity[k];
          s.angular_velocity[k] = rec.before.omega[k];
          s.velocity_after[k] = rec.after.velocity[k];
          s.angular_velocity_after[k] = rec.after.omega[k];
        }
        s.contact_vertex = rec.vertex;
        s.impulse = rec.impulse;
        put(w::kBounceState, w::encode(s));
      }
    }
    batches.push_back(w::encode(b));
  }
  if (plan.shuffle_and_repeat) {  // reversed, and every third batch again right after itself
    std::reverse(batches.begin(), batches.end());
    std::vector<std::vector<std::uint8_t>> twice;
    for (std::size_t k = 0; k < batches.size(); ++k) {
      twice.push_back(batches[k]);
      if (k % 3 == 0) twice.push_back(batches[k]);
    }
    batches = twice;
  }
  if (plan.skip_one_batch) batches.erase(batches.begin() + static_cast<long>(batches.size() / 2));
  for (const auto& b : batches) {
    put(w::kTossBatch, b);
    live.on_message(w::kTossBatch, b.data(), b.size(), 1.0);
  }
  if (plan.with_final)
    for (const auto& f : finals) put(w::kProbabilities, f);
  EXPECT_TRUE(out.flush());
  Written wr{path, {}, 0, spec.run_id};
  if (live.finished()) wr.counts = live.result(), wr.stop = live.stop();
  return wr;
}

dicesim::RunCounts direct_counts(std::uint64_t n, std::uint64_t seed) {
  const std::string scene = std::string(DICESIM_SOURCE_DIR) + "/" + kScene;
  const dicesim::DieModel model = dicesim::compile(dicesim::load_scene(scene), scene);
  dicesim::RunCounts c;
  for (std::uint64_t i = 0; i < n; ++i) c.add(dicesim::toss(model, seed, i));
  return c;
}

el::ReplayResult replay(const std::string& path) {
  el::ReplayOptions o = el::default_replay_options();
  o.path = path;
  return el::replay(o);
}

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
void write_all(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

std::string error_of(const std::string& path) {
  try {
    replay(path);
  } catch (const el::LogError& e) {
    return e.what();
  }
  return "";
}

// The JSON without the keys that legitimately differ between runs (as tests/integration does).
nlohmann::json stable(nlohmann::json j) {
  for (const char* k : {"elapsed_s", "tosses_per_s", "threads"}) j.erase(k);
  if (j.contains("provenance")) j["provenance"].erase("threads");
  return j;
}

}  // namespace

TEST(Replay, RecomputesTheRunFromTheLogAlone) {
  const Written log = write_log(unique_temp("run.lcmlog"), {});
  const el::ReplayResult r = replay(log.path);
  EXPECT_EQ(r.spec.run_id, log.run_id);
  EXPECT_EQ(r.tosses, 20000u);
  EXPECT_EQ(r.counts, direct_counts(20000, 5));
  EXPECT_TRUE(r.model_matches);
  EXPECT_EQ(r.workers, 1);
  ASSERT_TRUE(r.recorded_final);
  EXPECT_TRUE(el::same_as_recorded(r));
  std::remove(log.path.c_str());
}

TEST(Replay, OutOfOrderAndRepeatedBatchesCountOnce) {
  LogPlan p;
  p.shuffle_and_repeat = true;
  const Written log = write_log(unique_temp("shuffled.lcmlog"), p);
  const el::ReplayResult r = replay(log.path);
  EXPECT_EQ(r.counts, direct_counts(20000, 5));
  EXPECT_GT(r.health.duplicates, 0u);
  EXPECT_TRUE(el::same_as_recorded(r));
  std::remove(log.path.c_str());
}

TEST(Replay, RunStoppedAtATargetHalfWidthReplaysToTheSameStop) {
  LogPlan p;
  p.tosses = 30000;
  p.announced = 1000000;  // as with --target-halfwidth and no --tosses
  p.target_halfwidth = 0.008;
  const Written log = write_log(unique_temp("target.lcmlog"), p);
  ASSERT_GT(log.stop, 0u) << "the writer's aggregator should have stopped at the target";
  ASSERT_LT(log.stop, 30000u);
  const el::ReplayResult r = replay(log.path);
  EXPECT_TRUE(r.stopped_at_target);
  EXPECT_EQ(r.tosses, log.stop);
  EXPECT_EQ(r.counts, log.counts);
  EXPECT_EQ(r.counts, direct_counts(log.stop, 5));
  std::remove(log.path.c_str());
}

TEST(Replay, TruncatedCorruptOrIncompleteLogsAreClearErrors) {
  const Written log = write_log(unique_temp("good.lcmlog"), {});
  const std::string bytes = read_all(log.path);
  const std::string bad = unique_temp("bad.lcmlog");

  // Cut inside the last event's data, inside a header, one byte short.
  for (std::size_t cut : {bytes.size() - 1, bytes.size() - 100, bytes.size() / 2 + 7}) {
    write_all(bad, bytes.substr(0, cut));
    const std::string e = error_of(bad);
    EXPECT_NE(e.find("truncated"), std::string::npos) << "cut at " << cut << ": " << e;
    EXPECT_NE(e.find("at byte"), std::string::npos) << e;
  }
  // A sync word overwritten in the middle: liblcm would silently skip to the next event.
  {
    std::string b = bytes;
    const std::size_t at = b.find("\xED\xA1\xDA\x01", b.size() / 2);
    ASSERT_NE(at, std::string::npos);
    b[at + 1] = 'X';
    write_all(bad, b);
    const std::string e = error_of(bad);
    EXPECT_NE(e.find("corrupt"), std::string::npos) << e;
  }
  // Garbage after the last event.
  write_all(bad, bytes + "garbage");
  EXPECT_NE(error_of(bad).find("corrupt"), std::string::npos) << error_of(bad);
  // Not a log at all, an empty file, no file.
  write_all(bad, "scene = 'not a log'\n");
  EXPECT_NE(error_of(bad).find("not an LCM log"), std::string::npos) << error_of(bad);
  write_all(bad, "");
  EXPECT_NE(error_of(bad).find("no DICESIM_RUN_START"), std::string::npos) << error_of(bad);
  EXPECT_NE(error_of(bad + ".missing").find("cannot read"), std::string::npos);
  // Whole events, but a batch missing: the run is not all there.
  LogPlan p;
  p.skip_one_batch = true;
  write_log(bad, p);
  EXPECT_NE(error_of(bad).find("does not hold the whole run"), std::string::npos) << error_of(bad);
  std::remove(bad.c_str());
  std::remove(log.path.c_str());
}

TEST(Replay, TracedTossAgreesWithItsResimulation) {
  LogPlan p;
  p.tosses = 3000;
  p.trace_every = 1000;
  const Written log = write_log(unique_temp("trace.lcmlog"), p);
  const el::TossCheck c = el::check_toss(log.path, 0, 1000);
  ASSERT_FALSE(c.logged.empty());
  EXPECT_EQ(c.logged.size(), c.simulated.size());
  EXPECT_TRUE(c.batch_found);
  EXPECT_TRUE(c.agree);
  EXPECT_TRUE(c.bit_identical);
  EXPECT_EQ(c.max_abs_diff, 0.0);

  // No trace for toss 1001: the message says which tosses were traced.
  try {
    el::check_toss(log.path, 0, 1001);
    FAIL() << "toss 1001 was not traced";
  } catch (const el::LogError& e) {
    EXPECT_NE(std::string(e.what()).find("no bounce states for toss 1001"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0, 1000, 2000"), std::string::npos) << e.what();
  }
  std::remove(log.path.c_str());
}

TEST(Replay, TamperedBounceStateDisagrees) {
  LogPlan p;
  p.tosses = 2000;
  p.trace_every = 1000;
  const Written log = write_log(unique_temp("tamper.lcmlog"), p);
  // Re-write the log with one impulse of toss 1000 changed by one part in a million.
  const std::string tampered = unique_temp("tampered.lcmlog");
  {
    el::EventLogReader in(log.path);
    el::EventLogWriter out(tampered);
    bool done = false;
    while (const lcm::LogEvent* e = in.next()) {
      std::vector<std::uint8_t> bytes(static_cast<const std::uint8_t*>(e->data),
                                      static_cast<const std::uint8_t*>(e->data) + e->datalen);
      if (!done && e->channel == w::kBounceState) {
        auto m = w::decode<dicesim_lcm::bounce_state>(bytes.data(), bytes.size());
        if (m && m->toss_index == 1000) {
          m->impulse *= 1.000001;
          bytes = w::encode(*m);
          done = true;
        }
      }
      ASSERT_TRUE(out.write(e->timestamp, e->channel, bytes.data(), bytes.size()));
    }
    ASSERT_TRUE(done);
  }
  const el::TossCheck c = el::check_toss(tampered, 0, 1000);
  EXPECT_FALSE(c.agree);
  EXPECT_FALSE(c.bit_identical);
  EXPECT_GT(c.max_abs_diff, 0.0);
  const auto cli = run_dicesim("replay " + tampered + " --toss 1000");
  EXPECT_EQ(cli.code, 1) << cli.err;
  EXPECT_NE(cli.out.find("DISAGREE"), std::string::npos) << cli.out;
  std::remove(tampered.c_str());
  std::remove(log.path.c_str());
}

TEST(ReplayCli, SameJsonAsTossAndExitCodes) {
  LogPlan p;
  p.tosses = 5000;
  p.trace_every = 2500;
  const Written log = write_log(unique_temp("cli.lcmlog"), p);
  const auto rep = run_dicesim("replay " + log.path + " --json");
  ASSERT_EQ(rep.code, 0) << rep.err;
  const auto ref = run_dicesim("toss " + kScene + " --tosses 5000 --seed 5 --threads 1 --json");
  ASSERT_EQ(ref.code, 0) << ref.err;
  EXPECT_EQ(stable(nlohmann::json::parse(rep.out)), stable(nlohmann::json::parse(ref.out)));
  EXPECT_NE(rep.err.find("identical to the live aggregator's final result"), std::string::npos) << rep.err;

  const auto toss = run_dicesim("replay " + log.path + " --toss 2500");
  EXPECT_EQ(toss.code, 0) << toss.err;
  EXPECT_NE(toss.out.find("agree (bit-identical)"), std::string::npos) << toss.out;
  const auto toss_json = run_dicesim("replay " + log.path + " --toss 2500 --json");
  ASSERT_EQ(toss_json.code, 0) << toss_json.err;
  EXPECT_EQ(nlohmann::json::parse(toss_json.out)["agree"], true);

  const auto untraced = run_dicesim("replay " + log.path + " --toss 7");
  dicesim::testing::expect_bad_input(untraced, {"no bounce states for toss 7", "0, 2500"});

  const std::string cut = unique_temp("cut.lcmlog");
  const std::string bytes = read_all(log.path);
  write_all(cut, bytes.substr(0, bytes.size() - 10));
  dicesim::testing::expect_bad_input(run_dicesim("replay " + cut + " --json"), {"truncated", cut.c_str()});
  dicesim::testing::expect_bad_input(run_dicesim("replay " + cut + ".none"), {"cannot read"});
  std::remove(cut.c_str());
  std::remove(log.path.c_str());
}

// A log of the six-outcome wire (recorded before the wire carried any number of outcomes): its
// run_start has the old LCM type hash. Refused by name, exit 2, nothing on stdout.
TEST(ReplayCli, ALogOfTheSixOutcomeWireIsRefusedByName) {
  const std::string path = unique_temp("old.lcmlog");
  {
    el::EventLogWriter out(path);
    // The old run_start's hash, then a body: never decoded, only recognised.
    std::vector<std::uint8_t> old = {0x16, 0x85, 0x4f, 0xcd, 0x47, 0xc1, 0x6d, 0x6e};
    old.resize(200, 0);
    ASSERT_TRUE(out.write(1'700'000'000'000'000, w::kRunStart, old.data(), old.size()));
  }
  dicesim::testing::expect_bad_input(run_dicesim("replay " + path + " --json"),
                                     {"recorded before runs carried any number of outcomes", "six-outcome wire", path.c_str()});
  std::remove(path.c_str());
}

// A recorded d20 run replays to the live counts, 20 outcomes in label order (the log alone).
TEST(ReplayCli, AD20LogReplaysToTossCounts) {
  const std::string scene = std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/d20.toml";
  const std::string path = unique_temp("d20.lcmlog");
  const dicesim::DieModel model = dicesim::compile(dicesim::load_scene(scene), scene);
  const w::RunSpec spec = w::make_run_spec(77, scene, {}, model, 3, 3000);
  {
    el::EventLogWriter out(path);
    std::int64_t utime = 1'700'000'000'000'000;
    auto put = [&](const char* ch, const std::vector<std::uint8_t>& b) { ASSERT_TRUE(out.write(utime += 100, ch, b.data(), b.size())); };
    put(w::kRunStart, w::encode(w::to_message(spec)));
    for (std::uint64_t first = 0; first < 3000; first += 1000) {
      dicesim_lcm::toss_batch b{};
      b.run_id = 77, b.worker_id = 1, b.lease_id = 1, b.first_index = static_cast<std::int64_t>(first), b.count = 1000;
      for (std::uint64_t i = first; i < first + 1000; ++i) {
        const dicesim::TossResult r = dicesim::toss(model, 3, i);
        b.outcomes.push_back(static_cast<std::int8_t>(r.status == dicesim::TossStatus::Settled ? r.outcome : -1));
        b.statuses.push_back(static_cast<std::int8_t>(r.status));
        b.bounces.push_back(r.bounces);
      }
      put(w::kTossBatch, w::encode(b));
    }
  }
  const auto rep = run_dicesim("replay " + path + " --json");
  ASSERT_EQ(rep.code, 0) << rep.err;
  const auto ref = run_dicesim("toss " + scene + " --tosses 3000 --seed 3 --threads 1 --json");
  ASSERT_EQ(ref.code, 0) << ref.err;
  const auto a = nlohmann::json::parse(rep.out), b = nlohmann::json::parse(ref.out);
  ASSERT_EQ(a["faces"].size(), 20u);
  EXPECT_EQ(a["faces"], b["faces"]);
  EXPECT_EQ(a["chi2_uniform"], b["chi2_uniform"]);
  std::remove(path.c_str());
}
