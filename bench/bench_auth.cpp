// HMAC cost (authenticated runs, messages/auth.hpp): sealing a worker's toss_batch and opening it
// at the aggregator, against the work the batch stands for. Target: <= 3% of `run` throughput.
// A 1024-toss batch (6 KB + 36 bytes of seal) is about 2 ms of `paper` tossing on one core, so
// seal + open must stay under ~60 us; BM_AuthenticatedIngest is the aggregator's whole path.
#include <benchmark/benchmark.h>

#include <random>

#include "aggregator/aggregator.hpp"
#include "messages/auth.hpp"
#include "messages/run_spec.hpp"
#include "sim/worker/worker.hpp"

namespace {

using namespace dicesim;

std::vector<std::uint8_t> batch_bytes(std::uint64_t first, int n) {
  std::mt19937 rng(5);
  dicesim_lcm::toss_batch b{};
  b.run_id = 1, b.worker_id = 2, b.lease_id = 0, b.first_index = static_cast<std::int64_t>(first), b.count = n;
  for (int i = 0; i < n; ++i) {
    b.outcomes.push_back(static_cast<std::int8_t>(rng() % 6));
    b.statuses.push_back(0);
    b.bounces.push_back(static_cast<std::int32_t>(1 + rng() % 4));
  }
  return wire::encode(b);
}

const std::vector<std::uint8_t> kKey(32, 0x5a);

void BM_SealTossBatch(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  wire::Sealer s(kKey);
  const std::vector<std::uint8_t> plain = batch_bytes(0, n);
  std::vector<std::uint8_t> msg;
  for (auto _ : state) {
    msg = plain;
    s.seal(wire::kTossBatch, msg);
    benchmark::DoNotOptimize(msg.data());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * plain.size()));
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * n);
}
BENCHMARK(BM_SealTossBatch)->Arg(1024)->Arg(2048);

void BM_OpenTossBatch(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  wire::Sealer s(kKey);
  std::vector<std::uint8_t> msg = batch_bytes(0, n);
  s.seal(wire::kTossBatch, msg);
  for (auto _ : state) benchmark::DoNotOptimize(s.open(wire::kTossBatch, msg.data(), msg.size()));
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * n);
}
BENCHMARK(BM_OpenTossBatch)->Arg(1024)->Arg(2048);

// Aggregator ingest of 1024-toss batches with and without a key (compare with BM_IngestFresh).
void BM_AuthenticatedIngest(benchmark::State& state) {
  const bool keyed = state.range(0) != 0;
  constexpr int n = 1024;
  agg::AggregatorConfig cfg;
  cfg.spec.run_id = 1;
  cfg.spec.total = 1ULL << 40;
  cfg.spec.labels = {1, 2, 3, 4, 5, 6};
  if (keyed) cfg.key = kKey;
  agg::Aggregator agg(cfg, [](const char*, const std::vector<std::uint8_t>&) {});
  wire::Sealer s(keyed ? kKey : std::vector<std::uint8_t>{});
  std::vector<std::uint8_t> plain = batch_bytes(0, n), msg;
  std::uint64_t first = 0;
  for (auto _ : state) {
    state.PauseTiming();  // the worker's seal, not the aggregator's cost
    for (int k = 0; k < 8; ++k) plain[40 + k] = static_cast<std::uint8_t>(first >> (56 - 8 * k));
    msg = plain;
    s.seal(wire::kTossBatch, msg);
    state.ResumeTiming();
    agg.on_message(wire::kTossBatch, msg.data(), msg.size(), 0.0);
    first += n;
  }
  if (agg.received() != first) state.SkipWithError("batches were not all accepted");
  state.SetItemsProcessed(static_cast<std::int64_t>(first));
}
BENCHMARK(BM_AuthenticatedIngest)->Arg(0)->Arg(1);

}  // namespace

namespace {

// A worker's whole cost per batch of 1024 `paper` tosses of Die 1, with and without sealing:
// the ratio is the HMAC's share of a worker's throughput (what `run` throughput is made of).
void BM_WorkerBatch(benchmark::State& state) {
  const bool keyed = state.range(0) != 0;
  const std::vector<std::uint8_t> key = keyed ? kKey : std::vector<std::uint8_t>{};
  wire::RunSpec spec;
  spec.run_id = 9;
  spec.origin = DICESIM_SOURCE_DIR "/scenes/paper/die1.toml";
  spec.files = wire::read_scene_files(spec.origin);
  spec.seed = 1;
  spec.total = 1ULL << 40;
  const DieModel model = wire::compile_spec(spec);
  spec.fingerprint = wire::model_fingerprint(model);
  spec.labels = model.outcome_labels;
  std::uint64_t sent_bytes = 0;
  worker::WorkerConfig cfg;
  cfg.worker_id = 5;
  cfg.batch = 1024;
  cfg.key = key;
  worker::WorkerCore core(cfg, [&](const char*, const std::vector<std::uint8_t>& b) { sent_bytes += b.size(); });
  wire::Sealer aggregator_side(key);
  auto deliver = [&](const char* ch, std::vector<std::uint8_t> bytes) {
    aggregator_side.seal(ch, bytes);
    core.on_message(ch, bytes.data(), bytes.size(), 0.0);
  };
  deliver(wire::kRunStart, wire::encode(wire::to_message(spec)));
  std::int64_t lease = 1;
  std::uint64_t first = 0, tosses = 0;
  for (auto _ : state) {
    if (!core.step(0.0)) {  // out of work: the next lease (16 batches)
      state.PauseTiming();
      dicesim_lcm::work_lease l{};
      l.run_id = 9, l.worker_id = 5, l.lease_id = lease++, l.first_index = static_cast<std::int64_t>(first), l.count = 16 * 1024;
      first += 16 * 1024;
      deliver(wire::kWorkLease, wire::encode(l));
      state.ResumeTiming();
      core.step(0.0);
    }
    tosses += 1024;
  }
  if (core.tosses_done() != tosses) state.SkipWithError("the worker did not toss every batch");
  state.SetItemsProcessed(static_cast<std::int64_t>(tosses));
}
BENCHMARK(BM_WorkerBatch)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
