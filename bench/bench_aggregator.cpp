// Aggregator ingest: synthetic toss_batch messages (encoded bytes, as they come off the wire)
// through Aggregator::on_message — decode, validation, interval-set de-duplication, counting.
// Target: >= 1e7 toss results per second, so one aggregator never limits 100 workers.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>

#include "aggregator/aggregator.hpp"

namespace {

using namespace dicesim;

agg::AggregatorConfig bench_config() {
  agg::AggregatorConfig cfg;
  cfg.spec.run_id = 1;
  cfg.spec.total = 1ULL << 40;
  cfg.spec.labels = {1, 2, 3, 4, 5, 6};
  return cfg;
}

std::vector<std::uint8_t> make_batch(std::uint64_t first, int n, std::mt19937& rng) {
  dicesim_lcm::toss_batch b{};
  b.run_id = 1, b.worker_id = 2, b.lease_id = 0, b.first_index = static_cast<std::int64_t>(first), b.count = n;
  for (int i = 0; i < n; ++i) {
    const bool settled = rng() % 100 != 0;
    b.outcomes.push_back(static_cast<std::int8_t>(settled ? rng() % 6 : -1));
    b.statuses.push_back(static_cast<std::int8_t>(settled ? 0 : 1));
    b.bounces.push_back(static_cast<std::int32_t>(1 + rng() % 4));
  }
  return wire::encode(b);
}

// Fresh batches in index order (the common case), `n` tosses each.
void BM_IngestFresh(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::mt19937 rng(1);
  // Re-encoding each batch would dominate; patch first_index (bytes 40..47) in a template.
  std::vector<std::uint8_t> msg = make_batch(0, n, rng);
  agg::Aggregator agg(bench_config(), [](const char*, const std::vector<std::uint8_t>&) {});
  std::uint64_t first = 0;
  for (auto _ : state) {
    for (int k = 0; k < 8; ++k) msg[40 + k] = static_cast<std::uint8_t>(first >> (56 - 8 * k));
    agg.on_message(wire::kTossBatch, msg.data(), msg.size(), 0.0);
    first += static_cast<std::uint64_t>(n);
  }
  if (agg.received() != first) state.SkipWithError("batches were not all accepted");
  state.SetItemsProcessed(static_cast<std::int64_t>(first));
}
BENCHMARK(BM_IngestFresh)->Arg(256)->Arg(1024)->Arg(2048);

// Out of order, with 10% duplicates: batches of 2048 from 16 interleaved "workers".
void BM_IngestShuffledWithDuplicates(benchmark::State& state) {
  constexpr int n = 2048, kBatches = 4096;
  std::mt19937 rng(2);
  std::vector<std::vector<std::uint8_t>> msgs;
  std::vector<std::uint64_t> order;
  for (int i = 0; i < kBatches; ++i) order.push_back(static_cast<std::uint64_t>(i));
  std::shuffle(order.begin(), order.end(), rng);
  for (std::uint64_t i : order) {
    msgs.push_back(make_batch(i * n, n, rng));
    if (rng() % 10 == 0) msgs.push_back(msgs.back());
  }
  std::int64_t items = 0;
  for (auto _ : state) {
    state.PauseTiming();
    agg::Aggregator agg(bench_config(), [](const char*, const std::vector<std::uint8_t>&) {});
    state.ResumeTiming();
    for (const auto& m : msgs) agg.on_message(wire::kTossBatch, m.data(), m.size(), 0.0);
    benchmark::DoNotOptimize(agg.received());
    items += static_cast<std::int64_t>(msgs.size()) * n;
  }
  state.SetItemsProcessed(items);
}
BENCHMARK(BM_IngestShuffledWithDuplicates)->Unit(benchmark::kMillisecond);

}  // namespace
