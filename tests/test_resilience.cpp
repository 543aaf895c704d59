// Authenticated runs (messages/auth.hpp) and aggregator checkpoints (aggregator/checkpoint.hpp),
// over the same in-memory bus as test_aggregator_run.cpp: forgeries are dropped and counted, a
// run resumed from a checkpoint gives the counts of one thread.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <memory>

#include "aggregator/aggregator.hpp"
#include "aggregator/checkpoint.hpp"
#include "messages/auth.hpp"
#include "messages/run_spec.hpp"
#include "sim/body/outcome.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/worker/worker.hpp"

namespace {

using namespace dicesim;
namespace fs = std::filesystem;

std::vector<std::uint8_t> key_of(std::uint8_t seed) {
  std::vector<std::uint8_t> k(32);
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = static_cast<std::uint8_t>(seed + 7 * i);
  return k;
}

TEST(Auth, SealedMessagesOpenAndEveryAlteredByteFails) {
  wire::Sealer a(key_of(1)), b(key_of(1)), other(key_of(2));
  std::vector<std::uint8_t> msg = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  const std::size_t n = msg.size();
  a.seal("DICESIM_TOSS_BATCH", msg);
  ASSERT_EQ(msg.size(), n + wire::kSealSize);
  EXPECT_TRUE(wire::looks_sealed(msg.data(), msg.size()));
  EXPECT_EQ(b.open("DICESIM_TOSS_BATCH", msg.data(), msg.size()), std::optional<std::size_t>(n));
  EXPECT_FALSE(other.open("DICESIM_TOSS_BATCH", msg.data(), msg.size())) << "another key";
  EXPECT_FALSE(b.open("DICESIM_WORK_LEASE", msg.data(), msg.size())) << "the channel is covered";
  for (std::size_t i = 0; i < msg.size(); ++i) {
    auto t = msg;
    t[i] ^= 0x40;
    EXPECT_FALSE(b.open("DICESIM_TOSS_BATCH", t.data(), t.size())) << "byte " << i;
  }
  EXPECT_FALSE(b.open("DICESIM_TOSS_BATCH", msg.data(), n)) << "seal stripped";
  EXPECT_FALSE(b.open("DICESIM_TOSS_BATCH", msg.data(), msg.size() - 1)) << "truncated";
  wire::Sealer none;
  EXPECT_EQ(none.open("X", msg.data(), 3), std::optional<std::size_t>(3)) << "no key: everything passes whole";
}

TEST(Auth, KeyFileRules) {
  EXPECT_EQ(wire::parse_key_text(std::string(64, 'a') + "\n", "k").size(), 32u);
  EXPECT_EQ(wire::parse_key_text("00112233 44556677 8899aabb ccddeeff\n00112233445566778899AABBCCDDEEFF", "k").size(), 32u);
  EXPECT_THROW(wire::parse_key_text(std::string(62, 'a'), "k"), wire::KeyError) << "31 bytes: too short";
  EXPECT_THROW(wire::parse_key_text(std::string(65, 'a'), "k"), wire::KeyError) << "odd number of digits";
  EXPECT_THROW(wire::parse_key_text(std::string(63, 'a') + "g", "k"), wire::KeyError) << "not hex";

  const fs::path dir = fs::temp_directory_path() / ("dicesim-key-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "run.key").string();
  std::ofstream(path) << std::string(64, 'b') << "\n";
  ::chmod(path.c_str(), 0644);
  try {
    wire::load_key_file(path);
    ADD_FAILURE() << "a world-readable key file was accepted";
  } catch (const wire::KeyError& e) {
    EXPECT_NE(std::string(e.what()).find("0644"), std::string::npos) << e.what();
  }
  ::chmod(path.c_str(), 0600);
  EXPECT_EQ(wire::load_key_file(path), std::vector<std::uint8_t>(32, 0xbb));
  EXPECT_THROW(wire::load_key_file((dir / "missing.key").string()), wire::KeyError);
  EXPECT_THROW(wire::load_key_file(dir.string()), wire::KeyError) << "a directory";
  fs::remove_all(dir);
}

// A bus where everyone hears everything, plus a forger who injects messages.
struct Bus {
  std::deque<std::pair<std::string, std::vector<std::uint8_t>>> queue;
  std::unique_ptr<agg::Aggregator> agg;
  std::vector<std::unique_ptr<worker::WorkerCore>> workers;
  double now = 0.0;
  auto sender() {
    return [this](const char* ch, const std::vector<std::uint8_t>& b) { queue.emplace_back(ch, b); };
  }
  void deliver(const std::string& ch, const std::vector<std::uint8_t>& b) {
    agg->on_message(ch, b.data(), b.size(), now);
    for (auto& w : workers) w->on_message(ch, b.data(), b.size(), now);
  }
  void add_worker(const std::vector<std::uint8_t>& key) {
    worker::WorkerConfig c;
    c.batch = 100;
    c.key = key;
    workers.push_back(std::make_unique<worker::WorkerCore>(c, sender()));
  }
  void step() {
    now += 0.01;
    agg->tick(now);
    for (auto& w : workers) w->tick(now), w->step(now);
    while (!queue.empty()) {
      auto m = std::move(queue.front());
      queue.pop_front();
      deliver(m.first, m.second);
    }
  }
  bool run(int max_steps = 100000) {
    for (int i = 0; i < max_steps && !agg->finished(); ++i) step();
    return agg->finished();
  }
};

struct TestRun {
  agg::AggregatorConfig cfg;
  DieModel model;
  explicit TestRun(std::uint64_t total) {
    wire::RunSpec& spec = cfg.spec;
    spec.run_id = 77;
    spec.origin = DICESIM_SOURCE_DIR "/scenes/paper/die1.toml";
    spec.files = wire::read_scene_files(spec.origin);
    spec.seed = 5;
    spec.total = total;
    model = wire::compile_spec(spec);
    spec.fingerprint = wire::model_fingerprint(model);
    spec.labels = model.outcome_labels;
    cfg.max_lease = 700;
    cfg.min_lease = 150;
  }
  RunCounts reference() const {
    RunConfig rc;
    rc.seed = cfg.spec.seed;
    rc.tosses = cfg.spec.total;
    return run_tosses(model, rc);
  }
};

dicesim_lcm::toss_batch forged_batch(std::int64_t run, std::int64_t first, int n) {
  dicesim_lcm::toss_batch b{};
  b.run_id = run;
  b.worker_id = 666;
  b.lease_id = 1;
  b.first_index = first;
  b.count = n;
  b.outcomes.assign(static_cast<std::size_t>(n), 5);  // label 6 of die1, settled
  b.statuses.assign(static_cast<std::size_t>(n), 0);
  b.bounces.assign(static_cast<std::size_t>(n), 1);
  return b;
}

TEST(Auth, ForgedBatchesAreDroppedAndCountedAndTheCountsStayExact) {
  TestRun r(3000);
  r.cfg.key = key_of(9);
  Bus bus;
  bus.agg = std::make_unique<agg::Aggregator>(r.cfg, bus.sender());
  // Before any worker: every index claimed by a forger, unsealed and sealed with another key.
  wire::Sealer wrong(key_of(10));
  int forged = 0;
  for (std::int64_t first = 0; first < 3000; first += 500) {
    auto bytes = wire::encode(forged_batch(77, first, 500));
    bus.deliver(wire::kTossBatch, bytes), ++forged;
    wrong.seal(wire::kTossBatch, bytes);
    bus.deliver(wire::kTossBatch, bytes), ++forged;
  }
  EXPECT_EQ(bus.agg->received(), 0u);
  EXPECT_EQ(bus.agg->health().unauthenticated, static_cast<std::uint64_t>(forged));
  bus.add_worker(r.cfg.key);
  bus.add_worker(r.cfg.key);
  // A forged "finished" must not stop the workers.
  dicesim_lcm::probabilities fin{};
  fin.run_id = 77;
  fin.finished = 1;
  bus.step();
  bus.deliver(wire::kProbabilities, wire::encode(fin));
  ASSERT_TRUE(bus.run());
  EXPECT_EQ(bus.agg->result(), r.reference());
  EXPECT_EQ(bus.agg->health().unauthenticated, static_cast<std::uint64_t>(forged) + 1);
  for (auto& w : bus.workers) {
    EXPECT_GT(w->tosses_done(), 0u);
    EXPECT_GE(w->unauthenticated(), 1u) << "the forged finished message";
  }
}

TEST(Auth, AWorkerWithoutTheKeyDoesNotServeTheRun) {
  TestRun r(500);
  r.cfg.key = key_of(3);
  Bus bus;
  bus.agg = std::make_unique<agg::Aggregator>(r.cfg, bus.sender());
  bus.add_worker({});  // no key: its unsealed statuses are dropped, it cannot read the run
  for (int i = 0; i < 300; ++i) bus.step();
  EXPECT_FALSE(bus.agg->finished());
  EXPECT_EQ(bus.workers[0]->run_id(), 0);
  EXPECT_GT(bus.agg->health().unauthenticated, 0u);
}

TEST(Checkpoint, JsonRoundTripKeepsEveryField) {
  TestRun r(5000);
  Bus bus;
  bus.agg = std::make_unique<agg::Aggregator>(r.cfg, bus.sender());
  bus.add_worker({});
  for (int i = 0; i < 12; ++i) bus.step();
  ASSERT_FALSE(bus.agg->finished());
  const agg::Checkpoint c = bus.agg->checkpoint(1.5);
  ASSERT_GT(c.all.total(), 0u);
  const agg::Checkpoint d = agg::checkpoint_from_json(agg::to_json(c), "mem");
  EXPECT_EQ(agg::to_json(d), agg::to_json(c));
  EXPECT_EQ(d.start.run_id, 77);
  EXPECT_EQ(d.all, c.all);
  EXPECT_EQ(d.received, c.received);
  EXPECT_EQ(d.leases.size(), c.leases.size());
  // Inconsistent or foreign files are refused with the file named.
  std::string bad = agg::to_json(c);
  bad.replace(bad.find("\"limit\":"), 8, "\"limit\":9");
  EXPECT_THROW(agg::checkpoint_from_json(bad, "bad.ckpt"), agg::CheckpointError);
  EXPECT_THROW(agg::checkpoint_from_json("{\"format\":\"x\"}", "x.ckpt"), agg::CheckpointError);
  EXPECT_THROW(agg::checkpoint_from_json("not json", "y.ckpt"), agg::CheckpointError);
  // Counts whose outcome count is not the run_start's die's: refused.
  nlohmann::json j = nlohmann::json::parse(agg::to_json(c));
  j["labels"].push_back(7);
  EXPECT_THROW(agg::checkpoint_from_json(j.dump(), "labels.ckpt"), agg::CheckpointError);
  // A checkpoint of the six-outcome wire (its run_start has the old type hash): refused by name.
  j = nlohmann::json::parse(agg::to_json(c));
  std::string hex = j["run_start"].get<std::string>();
  hex.replace(0, 16, "16854fcd47c16d6e");
  j["run_start"] = hex;
  try {
    agg::checkpoint_from_json(j.dump(), "old.ckpt");
    FAIL() << "an old checkpoint was accepted";
  } catch (const agg::CheckpointError& e) {
    EXPECT_NE(std::string(e.what()).find("before runs carried any number of outcomes"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("old.ckpt"), std::string::npos) << e.what();
  }
}

// Every kind of correction survives a checkpoint (issue 39: the sustained phase's guards too), and
// a checkpoint written when the counts held four kinds still reads (the rest 0).
TEST(Checkpoint, EveryCorrectionKindRoundTrips) {
  TestRun r(5000);
  Bus bus;
  bus.agg = std::make_unique<agg::Aggregator>(r.cfg, bus.sender());
  bus.add_worker({});
  for (int i = 0; i < 12; ++i) bus.step();
  agg::Checkpoint c = bus.agg->checkpoint(1.5);
  std::uint64_t v = 1;
  c.all.corrections.for_each([&](const char*, std::uint64_t& n) { n = v++; });
  c.prefix.corrections = c.all.corrections;
  const agg::Checkpoint d = agg::checkpoint_from_json(agg::to_json(c), "mem");
  EXPECT_EQ(d.all.corrections, c.all.corrections);
  EXPECT_EQ(d.all.corrections.nudges, 9u);
  EXPECT_EQ(d.prefix.corrections.located_capped, 5u);
  nlohmann::json j = nlohmann::json::parse(agg::to_json(c));
  ASSERT_EQ(j["all"]["corrections"].size(), 9u);
  for (const char* part : {"all", "prefix"}) j[part]["corrections"] = {1, 2, 3, 4};
  const agg::Checkpoint old = agg::checkpoint_from_json(j.dump(), "old.ckpt");
  EXPECT_EQ(old.all.corrections.fallbacks, 4u);
  EXPECT_EQ(old.all.corrections.located_capped, 0u);
  EXPECT_EQ(old.all.corrections.nudges, 0u);
  j["all"]["corrections"] = {1, 2, 3};
  EXPECT_THROW(agg::checkpoint_from_json(j.dump(), "three.ckpt"), agg::CheckpointError);
}

TEST(Checkpoint, ResumedAggregatorGivesTheCountsOfOneThread) {
  TestRun r(6000);
  r.cfg.key = key_of(4);  // a resumed authenticated run: the key is given again, never stored
  Bus bus;
  bus.agg = std::make_unique<agg::Aggregator>(r.cfg, bus.sender());
  bus.add_worker(r.cfg.key);
  bus.add_worker(r.cfg.key);
  for (int i = 0; i < 15; ++i) bus.step();
  const std::string saved = agg::to_json(bus.agg->checkpoint(bus.now));
  // The aggregator goes on a little (results after the checkpoint are lost with it), then dies.
  for (int i = 0; i < 5; ++i) bus.step();
  const std::uint64_t held_at_death = bus.agg->received();
  const agg::Checkpoint ck = agg::checkpoint_from_json(saved, "mem");
  ASSERT_LT(ck.all.total(), held_at_death);
  ASSERT_GT(ck.all.total(), 0u);
  // Messages in flight to nobody; the same workers go on; a new aggregator resumes.
  bus.queue.clear();
  bus.agg = std::make_unique<agg::Aggregator>(r.cfg, bus.sender(), ck, bus.now);
  EXPECT_TRUE(bus.agg->resume_info().resumed);
  EXPECT_EQ(bus.agg->resume_info().held, ck.all.total());
  ASSERT_TRUE(bus.run());
  EXPECT_EQ(bus.agg->result(), r.reference());
  EXPECT_EQ(bus.agg->checkpoint(bus.now).resumes, 1);
  std::uint64_t computed = 0;
  for (auto& w : bus.workers) computed += w->tosses_done();
  EXPECT_GE(computed, 6000u);
  EXPECT_LE(computed - 6000u, held_at_death - ck.all.total() + 4 * 700u) << "recomputed about what the checkpoint missed";
}

TEST(Checkpoint, AtomicWriteReplacesTheFileAndLeavesNoTemporary) {
  const fs::path dir = fs::temp_directory_path() / ("dicesim-ckpt-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "run.ckpt").string();
  agg::write_atomic(path, "first\n");
  {
    agg::CheckpointWriter w(path);
    w.submit("second\n");
    w.submit("third\n");
    w.flush();
    EXPECT_GE(w.stats().writes, 1u);
    EXPECT_TRUE(w.stats().error.empty());
  }
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "third") << "the newest state wins";
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 077, 0u) << "checkpoints hold the run: private to the user";
  EXPECT_THROW(agg::write_atomic((dir / "no" / "such" / "dir.ckpt").string(), "x"), std::runtime_error);
  fs::remove_all(dir);
}

}  // namespace
