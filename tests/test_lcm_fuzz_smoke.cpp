// The fuzz target's handler code under the normal build: valid messages of every type, mutated
// and truncated deterministically, on every channel. Never a crash; foreign and malformed
// messages are counted.
#include <gtest/gtest.h>

#include <random>

#include "tests/fuzz/message_handlers.hpp"

TEST(LcmFuzzSmoke, MutatedMessagesOnEveryChannel) {
  using namespace dicesim;
  fuzz::Handlers h;
  dicesim_lcm::toss_batch b{};
  b.run_id = 77, b.first_index = 10, b.count = 4;
  b.outcomes = {0, 1, -1, 5};
  b.statuses = {0, 0, 1, 0};
  b.bounces = {1, 2, 3, 4};
  dicesim_lcm::worker_status s{};
  s.run_id = 77, s.worker_id = 9, s.state = 1, s.n_held = 1, s.held_leases = {1};
  dicesim_lcm::work_lease l{};
  l.run_id = 77, l.worker_id = 5, l.lease_id = 1, l.first_index = 0, l.count = 10;
  dicesim_lcm::probabilities p{};
  p.run_id = 77;
  p.n_outcomes = 6;
  p.labels = {1, 2, 3, 4, 5, 6};
  p.counts.assign(6, 0);
  p.p = p.ci_lo = p.ci_hi = std::vector<double>(6, 0.0);
  const std::vector<std::vector<std::uint8_t>> seeds = {wire::encode(b), wire::encode(s), wire::encode(l), wire::encode(p),
                                                         wire::encode(dicesim_lcm::bounce_state{})};
  std::mt19937 rng(2024);
  for (int i = 0; i < 20000; ++i) {
    std::vector<std::uint8_t> in{static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng() | 1)};
    auto msg = seeds[rng() % seeds.size()];
    const int flips = static_cast<int>(rng() % 4);
    for (int k = 0; k < flips; ++k) msg[rng() % msg.size()] = static_cast<std::uint8_t>(rng());
    if (rng() % 3 == 0) msg.resize(rng() % msg.size());
    in.insert(in.end(), msg.begin(), msg.end());
    h.one(in.data(), in.size());
  }
  const auto& health = h.agg->health();
  EXPECT_GT(health.malformed, 0u);
  EXPECT_GT(health.foreign + health.range, 0u);
  EXPECT_LE(h.agg->received(), h.agg->total());
}
