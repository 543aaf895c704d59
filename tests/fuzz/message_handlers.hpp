// One fuzz input -> the message handlers of an aggregator and a worker, exactly as bytes from
// the network reach them. Shared by the libFuzzer target (fuzz_message_handlers.cpp) and the
// deterministic smoke test in the normal suite (tests/test_lcm_fuzz_smoke.cpp).
// Input: byte 0 picks the channel, byte 1 the receiver(s) and whether time advances; the rest
// is the payload.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "aggregator/aggregator.hpp"
#include "sim/worker/worker.hpp"

namespace dicesim::fuzz {

struct Handlers {
  std::unique_ptr<agg::Aggregator> agg;
  std::unique_ptr<worker::WorkerCore> worker;
  double now = 0.0;

  Handlers() {
    agg::AggregatorConfig cfg;
    cfg.spec.run_id = 77;
    cfg.spec.total = 100000;
    cfg.spec.seed = 1;
    cfg.spec.files = {{"die.toml", "name = 'x'"}};
    cfg.spec.labels = {1, 2, 3, 4, 5, 6};
    auto sink = [](const char*, const std::vector<std::uint8_t>&) {};
    agg = std::make_unique<agg::Aggregator>(cfg, sink);
    worker::WorkerConfig wc;
    wc.worker_id = 5;
    worker = std::make_unique<worker::WorkerCore>(wc, sink);
  }

  void one(const std::uint8_t* data, std::size_t size) {
    static const char* const kChannels[] = {wire::kRunStart,    wire::kWorkLease,     wire::kTossBatch,
                                            wire::kBounceState, wire::kWorkerStatus, wire::kProbabilities};
    if (size < 2) return;
    const char* channel = kChannels[data[0] % 6];
    const std::uint8_t how = data[1];
    data += 2, size -= 2;
    if (how & 1) agg->on_message(channel, data, size, now);
    // The worker compiles scenes from run_start payloads; only a fraction of inputs go there.
    if ((how & 6) == 6) worker->on_message(channel, data, size, now);
    if (how & 8) {
      now += 0.05 * (how >> 4);
      agg->tick(now);
      worker->tick(now);
      worker->step(now);
    }
  }
};

}  // namespace dicesim::fuzz
