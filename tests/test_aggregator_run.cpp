// The aggregator and workers end to end over an in-memory bus (no sockets): lost, duplicated and
// hostile messages, dead workers — and always the counts of run_tosses on one thread.
#include <gtest/gtest.h>

#include <atomic>
#include <deque>
#include <memory>
#include <random>

#include "sim/body/outcome.hpp"
#include "aggregator/aggregator.hpp"
#include "aggregator/target.hpp"
#include "messages/run_spec.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/scene/scene.hpp"
#include "sim/worker/worker.hpp"

namespace {

using namespace dicesim;

struct Message {
  std::string channel;
  std::vector<std::uint8_t> bytes;
};

// Everyone hears every message (multicast), unless the bus drops or repeats it.
struct Net {
  std::deque<Message> queue;
  std::mt19937_64 rng{99};
  double drop = 0.0;       // probability a delivery to one listener is lost
  double duplicate = 0.0;  // probability a toss_batch is delivered twice
  std::unique_ptr<agg::Aggregator> agg;
  std::vector<std::unique_ptr<worker::WorkerCore>> workers;
  std::vector<bool> alive;
  std::vector<int> period;  // worker w computes a batch every period[w] steps (a slower core)
  int steps = 0;
  double now = 0.0;
  std::vector<Message> all_batches;  // for replays
  std::vector<std::uint8_t> last_answer;  // the last probabilities message published

  auto sender() {
    return [this](const char* ch, const std::vector<std::uint8_t>& b) { queue.push_back({ch, b}); };
  }
  bool lost() { return drop > 0 && std::uniform_real_distribution<>(0, 1)(rng) < drop; }
  void deliver(const Message& m) {
    if (!lost()) agg->on_message(m.channel, m.bytes.data(), m.bytes.size(), now);
    for (std::size_t w = 0; w < workers.size(); ++w)
      if (alive[w] && !lost()) workers[w]->on_message(m.channel, m.bytes.data(), m.bytes.size(), now);
  }
  void add_worker() {
    worker::WorkerConfig c;
    c.batch = 100;
    workers.push_back(std::make_unique<worker::WorkerCore>(c, sender()));
    alive.push_back(true);
    period.push_back(1);
  }
  // Advances 10 ms of simulated time: every live worker may compute one batch.
  void step() {
    now += 0.01;
    ++steps;
    agg->tick(now);
    for (std::size_t w = 0; w < workers.size(); ++w)
      if (alive[w]) {
        workers[w]->tick(now);
        if (steps % period[w] == 0) workers[w]->step(now);
      }
    while (!queue.empty()) {
      Message m = std::move(queue.front());
      queue.pop_front();
      if (m.channel == wire::kProbabilities) last_answer = m.bytes;
      if (m.channel == wire::kTossBatch) {
        all_batches.push_back(m);
        if (duplicate > 0 && std::uniform_real_distribution<>(0, 1)(rng) < duplicate) deliver(m);
      }
      deliver(m);
    }
  }
  bool run(int max_steps = 200000) {
    for (int i = 0; i < max_steps && !agg->finished(); ++i) step();
    return agg->finished();
  }
};

struct Fixture {
  wire::RunSpec spec;
  DieModel model;
  agg::AggregatorConfig cfg;
  explicit Fixture(std::uint64_t total, std::uint64_t seed = 3, double target = 0.0, std::string fidelity = {}) {
    spec.run_id = 1234;
    spec.origin = DICESIM_SOURCE_DIR "/scenes/paper/die1.toml";
    spec.files = wire::read_scene_files(spec.origin);
    if (!fidelity.empty()) spec.overrides = {"sim.fidelity=" + fidelity};
    spec.seed = seed;
    spec.total = total;
    model = wire::compile_spec(spec);
    spec.fingerprint = wire::model_fingerprint(model);
    cfg.spec = spec;
    cfg.spec.labels = spec.labels = model.outcome_labels;
    cfg.max_lease = 700;
    cfg.min_lease = 150;
    cfg.target_halfwidth = target;
  }
  RunCounts reference(std::uint64_t n) const {
    RunConfig rc;
    rc.seed = spec.seed;
    rc.tosses = n;
    return run_tosses(model, rc);
  }
};

Net make_net(const Fixture& f, int workers) {
  Net net;
  net.agg = std::make_unique<agg::Aggregator>(f.cfg, net.sender());
  for (int i = 0; i < workers; ++i) net.add_worker();
  return net;
}

TEST(AggregatorRun, ThreeWorkersGiveTheCountsOfOneThread) {
  Fixture f(4000);
  Net net = make_net(f, 3);
  ASSERT_TRUE(net.run());
  EXPECT_EQ(net.agg->stop(), 4000u);
  EXPECT_EQ(net.agg->result(), f.reference(4000));
  EXPECT_EQ(net.agg->health().duplicates, 0u);
  EXPECT_EQ(net.agg->health().malformed, 0u);
  for (auto& w : net.workers) EXPECT_GT(w->tosses_done(), 0u) << "every worker takes part";
}

// The sustained phase's guards (issue 39) travel in toss_batch like the other corrections: an
// `impulse` Die 1 run has located steps out of trials (located_capped), and the aggregator's
// totals of every kind are one thread's.
TEST(AggregatorRun, SustainedPhaseGuardsArriveAsCounted) {
  Fixture f(1500, 3, 0.0, "impulse");
  const RunCounts ref = f.reference(1500);
  ASSERT_GT(ref.corrections.located_capped, 0u) << "the run must exercise a guard of the sustained phase";
  Net net = make_net(f, 2);
  ASSERT_TRUE(net.run());
  EXPECT_EQ(net.agg->result().corrections, ref.corrections);
  EXPECT_EQ(net.agg->result(), ref);
}

// The final answer on the wire says what made it (issue 35): the provenance the aggregator was
// given travels in every probabilities message, the finished one included.
TEST(AggregatorRun, FinalAnswerCarriesTheProvenance) {
  Fixture f(800);
  f.cfg.provenance = R"({"scene_sha256":"5ca1ab1e","seed":3,"tosses":800})";
  Net net = make_net(f, 2);
  ASSERT_TRUE(net.run());
  for (int i = 0; i < 3; ++i) net.step();
  const auto m = wire::decode<dicesim_lcm::probabilities>(net.last_answer.data(), net.last_answer.size());
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->finished, 1);
  EXPECT_EQ(m->provenance, f.cfg.provenance);
}

TEST(AggregatorRun, LossyBusStillGivesIdenticalCounts) {
  Fixture f(3000);
  Net net = make_net(f, 2);
  net.drop = 0.1;
  ASSERT_TRUE(net.run());
  EXPECT_EQ(net.agg->result(), f.reference(3000));
  EXPECT_GT(net.agg->health().released, 0u) << "10% loss must have forced re-leases";
}

TEST(AggregatorRun, DuplicatesAndReplaysAreNotCountedTwice) {
  Fixture f(3000);
  Net net = make_net(f, 2);
  net.duplicate = 0.3;
  for (int i = 0; i < 5; ++i) net.step();
  ASSERT_FALSE(net.agg->finished());
  // Replay everything published so far, as a restarted worker re-sending old batches would.
  for (const Message& m : std::vector<Message>(net.all_batches)) net.deliver(m);
  ASSERT_TRUE(net.run());
  EXPECT_EQ(net.agg->result(), f.reference(3000));
  EXPECT_GT(net.agg->health().duplicates, 0u);
}

TEST(AggregatorRun, DeadWorkersLeasesGoToTheOthers) {
  Fixture f(12000);
  Net net = make_net(f, 3);
  for (int i = 0; i < 10; ++i) net.step();
  ASSERT_GT(net.workers[0]->tosses_done(), 0u);
  ASSERT_FALSE(net.agg->finished());
  net.alive[0] = false;  // kill -9: no more batches, no heartbeats
  ASSERT_TRUE(net.run());
  EXPECT_EQ(net.agg->result(), f.reference(12000));
  EXPECT_GT(net.agg->health().released, 0u);
}

// One worker ten times slower than the other (another process on its core): at the end the fast
// one takes the back half of the slow one's unfinished leases, which the slow one then skips,
// instead of idling until the slow one has tossed both leases it holds.
TEST(AggregatorRun, AnIdleWorkerTakesHalfOfASlowWorkersLeaseAtTheEnd) {
  Fixture f(20000);
  f.cfg.min_lease = 50;  // halves down to 50 tosses: half a second of the slow worker at most
  Net net = make_net(f, 2);
  net.period[1] = 10;
  ASSERT_TRUE(net.run());
  EXPECT_EQ(net.agg->result(), f.reference(20000));
  EXPECT_GT(net.agg->health().splits, 0u);
  // 100 tosses per 10 ms plus 100 per 100 ms: 20000 take 1.82 s at best; 2.0 s with splitting.
  // Without it the slow worker still holds up to 2 x 700 tosses when the fast one runs out: 2.8 s.
  EXPECT_LT(net.now, 2.3) << net.agg->health().splits << " splits";
  // The slow worker heard its leases shortened and skipped their moved halves: few duplicates.
  EXPECT_LT(net.agg->health().duplicates, 2 * 100 * net.agg->health().splits);
  EXPECT_EQ(net.workers[0]->tosses_done() + net.workers[1]->tosses_done(), 20000u + net.agg->health().duplicates);
}

TEST(AggregatorRun, LateWorkerTakesPart) {
  Fixture f(8000);
  Net net = make_net(f, 1);
  for (int i = 0; i < 20; ++i) net.step();
  ASSERT_FALSE(net.agg->finished());
  net.add_worker();
  ASSERT_TRUE(net.run());
  EXPECT_EQ(net.agg->result(), f.reference(8000));
  EXPECT_GT(net.workers[1]->tosses_done(), 0u);
}

TEST(AggregatorRun, TargetStopsAtTheSameBlockAsInOrderTossing) {
  const double h = 0.02;
  Fixture f(200000, 5, h);
  Net net = make_net(f, 2);
  ASSERT_TRUE(net.run());
  // In order, block by block, as `dicesim toss --target-halfwidth` does.
  RunCounts c;
  std::uint64_t done = 0;
  while (!agg::halfwidth_reached(c, h)) {
    RunConfig rc;
    rc.seed = 5;
    rc.first = done;
    rc.tosses = agg::kTargetBlock;
    c.merge(run_tosses(f.model, rc));
    done += agg::kTargetBlock;
  }
  EXPECT_EQ(net.agg->stop(), done);
  EXPECT_EQ(net.agg->result(), c);
  EXPECT_LT(done, 200000u);
}

// Hostile input straight into the handlers: counted, never counted as tosses, never a crash.
TEST(AggregatorRun, ForeignAndMalformedBatchesAreCountedAndIgnored) {
  Fixture f(2000);
  Net net = make_net(f, 1);
  auto batch = [](std::int64_t run, std::int64_t first, int n, int outcome, int status) {
    dicesim_lcm::toss_batch b{};
    b.run_id = run, b.worker_id = 1, b.lease_id = 1, b.first_index = first, b.count = n;
    b.outcomes.assign(static_cast<std::size_t>(n), static_cast<std::int8_t>(outcome));
    b.statuses.assign(static_cast<std::size_t>(n), static_cast<std::int8_t>(status));
    b.bounces.assign(static_cast<std::size_t>(n), 2);
    return wire::encode(b);
  };
  auto feed = [&](const std::vector<std::uint8_t>& b) { net.agg->on_message(wire::kTossBatch, b.data(), b.size(), 0.0); };
  feed(batch(999, 0, 10, 1, 0));    // foreign
  feed(batch(1234, 1995, 10, 1, 0));  // past the end
  feed(batch(1234, -1, 10, 1, 0));  // negative
  feed(batch(1234, 0, 10, 6, 0));   // outcome index 6 of a die with 6 outcomes (0..5)
  feed(batch(1234, 0, 10, -1, 0));  // settled on no outcome
  feed(batch(1234, 0, 10, 3, 2));   // invalid toss with an outcome
  feed(batch(1234, 0, 10, -1, 5));  // status 5
  feed(batch(1234, 0, 10, 19, 0));  // a d20's outcome in a d6 run
  // Messages claiming more outcomes than the wire carries (120): not decoded, counted.
  dicesim_lcm::probabilities many{};
  many.run_id = 1234;
  many.n_outcomes = 121;
  for (int i = 0; i < 121; ++i) many.labels.push_back(i);
  many.counts.assign(121, 0);
  many.p = many.ci_lo = many.ci_hi = std::vector<double>(121, 0.0);
  const auto mb = wire::encode(many);
  net.agg->on_message(wire::kProbabilities, mb.data(), mb.size(), 0.0);
  dicesim_lcm::run_start rs = wire::to_message(f.cfg.spec);
  rs.n_outcomes = 121;
  rs.outcome_labels = many.labels;
  const auto rb = wire::encode(rs);
  net.agg->on_message(wire::kRunStart, rb.data(), rb.size(), 0.0);
  auto good = batch(1234, 0, 10, 1, 0);
  feed(std::vector<std::uint8_t>(good.begin(), good.end() - 1));  // truncated
  good.push_back(0);
  feed(good);  // trailing byte
  good.pop_back();
  good[51] = 0x7f;  // count far beyond the payload
  feed(good);
  const auto& h = net.agg->health();
  EXPECT_EQ(h.foreign, 1u);
  EXPECT_EQ(h.range, 2u);
  EXPECT_EQ(h.malformed, 10u);
  EXPECT_EQ(net.agg->received(), 0u);
  ASSERT_TRUE(net.run());
  EXPECT_EQ(net.agg->result(), f.reference(2000));
}

// A run_start that nobody leases from (another run's, forged, or an aggregator that died at once)
// does not count as a served run: `dicesim worker --once` must not exit after it. CI once saw both
// workers of the hostile scenario hear the injector's foreign run_start first, wait out its
// silence and exit, leaving the real run without workers.
TEST(AggregatorRun, ARunThatNeverLeasedTheWorkerIsNotAServedRun) {
  Fixture f(1000);
  Net net = make_net(f, 1);
  wire::RunSpec foreign = f.cfg.spec;
  foreign.run_id = f.cfg.spec.run_id + 1;
  foreign.total = 5;
  const auto m = wire::encode(wire::to_message(foreign));
  net.workers[0]->on_message(wire::kRunStart, m.data(), m.size(), 0.0);
  ASSERT_EQ(net.workers[0]->run_id(), foreign.run_id);
  while (net.workers[0]->run_id() != f.cfg.spec.run_id && net.steps < 2000) net.step();
  ASSERT_EQ(net.workers[0]->run_id(), f.cfg.spec.run_id) << "the silent run ends and the real one is taken up";
  EXPECT_EQ(net.workers[0]->runs_served(), 0) << "the foreign run leased nothing: not served";
  ASSERT_TRUE(net.run());
  for (int i = 0; i < 10; ++i) net.step();  // the final probabilities reach the worker
  EXPECT_EQ(net.workers[0]->runs_served(), 1);
  EXPECT_EQ(net.agg->result().faces, f.reference(1000).faces);
}

TEST(AggregatorRun, WorkerRefusesAModelItCannotRebuild) {
  Fixture f(1000);
  f.cfg.spec.fingerprint ^= 1;  // as if the aggregator ran another build
  Net net = make_net(f, 1);
  for (int i = 0; i < 50; ++i) net.step();
  ASSERT_EQ(net.agg->refusals().size(), 1u);
  EXPECT_NE(net.agg->refusals()[0].find("fingerprint"), std::string::npos) << net.agg->refusals()[0];
  EXPECT_EQ(net.agg->received(), 0u);
}

}  // namespace

namespace {

// A worker that asks for the run (status state 0) just after an announcement it missed gets the
// next announcement about 20 ms later, not the periodic one (1 s): `run` waited for the
// worker's 200 ms heartbeat before this.
TEST(AggregatorRun, AWorkerAskingJustAfterAnAnnouncementGetsTheNextWithin20ms) {
  Fixture f(1000);
  std::vector<double> announced;
  double now = 0.0;
  agg::Aggregator a(f.cfg, [&](const char* ch, const std::vector<std::uint8_t>&) {
    if (std::string(ch) == wire::kRunStart) announced.push_back(now);
  });
  a.tick(now);
  ASSERT_EQ(announced.size(), 1u);
  dicesim_lcm::worker_status s{};
  s.worker_id = 7;
  s.state = 0;
  now = 0.005;
  const auto sb = wire::encode(s);
  a.on_message(wire::kWorkerStatus, sb.data(), sb.size(), now);
  EXPECT_EQ(announced.size(), 1u) << "within 20 ms of the last: not at once";
  for (int i = 1; i <= 5; ++i) now = 0.005 + 0.01 * i, a.tick(now);
  ASSERT_EQ(announced.size(), 2u) << "the asked-for announcement must come from tick";
  EXPECT_LE(announced[1], 0.04);
}

}  // namespace

namespace {

// A worker that `dicesim run` forked after compiling the run adopts it: its first status (ready)
// brings leases before any run_start was heard, and it never compiles the scene (the spec below
// carries no files: compiling it would fail and the worker would refuse the run).
TEST(AggregatorRun, AnAdoptedWorkerIsLeasedAtOnceWithoutCompiling) {
  Fixture f(3000);
  wire::RunSpec no_files = f.cfg.spec;
  no_files.files.clear();
  Net net = make_net(f, 0);
  net.add_worker();
  net.workers[0]->adopt(no_files, f.model, 0.0);
  ASSERT_EQ(net.queue.size(), 1u) << "adopt says at once that it is ready";
  const Message status = net.queue.front();
  net.queue.clear();
  std::vector<std::string> out;
  agg::Aggregator& a = *net.agg;
  agg::Aggregator probe(f.cfg, [&](const char* ch, const std::vector<std::uint8_t>&) { out.emplace_back(ch); });
  probe.on_message(status.channel, status.bytes.data(), status.bytes.size(), 0.0);
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.front(), wire::kWorkLease) << "the first answer is a lease, not an announcement";
  a.on_message(status.channel, status.bytes.data(), status.bytes.size(), 0.0);
  ASSERT_TRUE(net.run());
  EXPECT_TRUE(net.agg->refusals().empty()) << net.agg->refusals()[0];
  EXPECT_EQ(net.agg->result().faces, f.reference(3000).faces);
}

// A model that is not the spec's is not used: the worker compiles the spec as any other would.
TEST(AggregatorRun, AnAdoptedModelThatIsNotTheSpecsIsCompiledAfresh) {
  Fixture f(2000);
  wire::RunSpec other;
  other.origin = DICESIM_SOURCE_DIR "/scenes/paper/die3.toml";
  other.files = wire::read_scene_files(other.origin);
  const DieModel wrong = wire::compile_spec(other);
  Net net = make_net(f, 0);
  net.add_worker();
  net.workers[0]->adopt(f.cfg.spec, wrong, 0.0);
  ASSERT_TRUE(net.run());
  EXPECT_EQ(net.agg->result().faces, f.reference(2000).faces);
}

// An adopted worker can speak before the aggregator listens. If its "ready" was lost, it says it
// again on hearing run_start, not at its next heartbeat 200 ms later.
TEST(AggregatorRun, AnAdoptedWorkerWhoseReadyWasLostRepeatsItOnRunStart) {
  Fixture f(1000);
  Net net = make_net(f, 0);
  net.add_worker();
  net.workers[0]->adopt(f.cfg.spec, f.model, 0.0);
  net.queue.clear();  // nobody heard it
  net.step();         // t = 10 ms: the aggregator announces, the worker answers, a lease follows
  net.step();
  EXPECT_GT(net.agg->health().leases, 0u) << "leased within 20 ms";
  EXPECT_GT(net.workers[0]->tosses_done(), 0u);
  ASSERT_TRUE(net.run());
  EXPECT_EQ(net.agg->result().faces, f.reference(1000).faces);
}

}  // namespace


namespace {

// A worker's batches hold about WorkerConfig::batch_s of work: growing at most fourfold a batch up
// to `batch` when tosses are cheap (fewer messages), down to 256 tosses when they are slow (a
// heartbeat, a lease hand-over or the run's end is never a long batch away).
TEST(AggregatorRun, BatchesHoldAboutBatchSOfWork) {
  Fixture f(100000);
  std::vector<int> counts;
  worker::WorkerConfig c;
  c.batch = 8192;
  c.batch_s = 0.02;
  worker::WorkerCore w(c, [&](const char* ch, const std::vector<std::uint8_t>& b) {
    if (std::string(ch) == wire::kTossBatch) counts.push_back(wire::decode<dicesim_lcm::toss_batch>(b.data(), b.size())->count);
  });
  w.adopt(f.spec, f.model, 0.0);
  dicesim_lcm::work_lease m{};
  m.run_id = f.spec.run_id, m.worker_id = w.id(), m.lease_id = 1, m.first_index = 0, m.count = 100000;
  const auto lease = wire::encode(m);
  w.on_message(wire::kWorkLease, lease.data(), lease.size(), 0.0);
  double now = 0.0;
  for (int i = 0; i < 5; ++i, now += 0.001) ASSERT_TRUE(w.step(now));  // 1 ms a batch, whatever its size
  EXPECT_EQ(counts, (std::vector<int>{512, 2048, 8192, 8192, 8192}));
  counts.clear();
  for (int i = 0; i < 2; ++i) {
    now += 2.0;  // 2 s a batch
    ASSERT_TRUE(w.step(now));
  }
  EXPECT_EQ(counts, (std::vector<int>{256, 256}));
}

// Stopping (SIGTERM from `dicesim run` once the run is over): a batch in progress ends within
// 64 tosses and is not published.
TEST(AggregatorRun, ACancelledWorkerStopsInsideABatch) {
  Fixture f(10000);
  std::atomic<bool> stop{true};
  int batches = 0;
  worker::WorkerConfig c;
  c.cancel = &stop;
  worker::WorkerCore w(c, [&](const char* ch, const std::vector<std::uint8_t>&) { batches += std::string(ch) == wire::kTossBatch; });
  w.adopt(f.spec, f.model, 0.0);
  dicesim_lcm::work_lease m{};
  m.run_id = f.spec.run_id, m.worker_id = w.id(), m.lease_id = 1, m.first_index = 0, m.count = 10000;
  const auto lease = wire::encode(m);
  w.on_message(wire::kWorkLease, lease.data(), lease.size(), 0.0);
  EXPECT_FALSE(w.step(0.0));
  EXPECT_EQ(batches, 0);
  EXPECT_EQ(w.tosses_done(), 0u);
  stop = false;
  EXPECT_TRUE(w.step(0.1));
  EXPECT_EQ(batches, 1);
}

}  // namespace
