// Bridge latency: from an aggregator's publish of `probabilities` on LCM to a DDS subscriber's
// receipt of the bridged sample on `dicesim_probabilities`. Plays the aggregator itself (same
// channel, same type, same encoding) so that it can send many answers and time each one on one
// steady clock: publish answer i, wait for sample i on DDS, record the time between. Needs a
// running `dicesim bridge` on the same LCM URL; bench/bridge_latency.sh sets all of it up in a
// private network namespace.
//   dicesim_bridge_latency [--samples N] [--rate HZ] [--lcm URL]      (DDS: $CYCLONEDDS_URI)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "bridge/dds_entity.hpp"
#include "bridge/dds_writers.hpp"
#include "dicesim_dds/probabilities.h"
#include "messages/wire.hpp"

namespace b = dicesim::bridge;
namespace w = dicesim::wire;
using Clock = std::chrono::steady_clock;

namespace {

// Waits up to `timeout` for the sample of run `run` whose `done` is `seq`; older ones are skipped.
bool wait_for(dds_entity_t reader, dds_entity_t waitset, std::int64_t run, std::int64_t seq, Clock::duration timeout) {
  const auto until = Clock::now() + timeout;
  while (Clock::now() < until) {
    void* samples[8] = {nullptr};
    dds_sample_info_t infos[8];
    const int n = dds_take(reader, samples, infos, 8, 8);
    bool got = false;
    for (int k = 0; k < n; ++k) {
      const auto* s = static_cast<const dicesim_dds_probabilities_v3*>(samples[k]);
      if (infos[k].valid_data && s->run_id == run && s->done == seq) got = true;
    }
    if (n > 0) dds_return_loan(reader, samples, n);
    if (got) return true;
    dds_waitset_wait(waitset, nullptr, 0, DDS_MSECS(100));
  }
  return false;
}

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  return v[i];
}

}  // namespace

int main(int argc, char** argv) {
  int samples = 2000;
  double rate = 200.0;
  std::string url;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--samples")) samples = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--rate")) rate = std::atof(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--lcm")) url = argv[i + 1];
    else return std::fprintf(stderr, "usage: %s [--samples N] [--rate HZ] [--lcm URL]\n", argv[0]), 2;
  }
  lcm::LCM bus(w::resolve_url(url));
  if (!bus.good()) return std::fprintf(stderr, "cannot open LCM\n"), 1;

  b::DdsEntity participant(dds_create_participant(DDS_DOMAIN_DEFAULT, nullptr, nullptr), "participant");
  const b::Qos qos = b::latest_per_run_qos();
  b::DdsEntity topic(dds_create_topic(participant.get(), &dicesim_dds_probabilities_v3_desc, b::kProbabilitiesTopic,
                                      qos.get(), nullptr),
                     "topic");
  b::DdsEntity reader(dds_create_reader(participant.get(), topic.get(), qos.get(), nullptr), "reader");
  b::DdsEntity waitset(dds_create_waitset(participant.get()), "waitset");
  b::DdsEntity readcond(dds_create_readcondition(reader.get(), DDS_ANY_STATE), "read condition");
  dds_waitset_attach(waitset.get(), readcond.get(), 0);

  dicesim_lcm::probabilities m{};
  m.run_id = 0x5eed0000 + (std::chrono::system_clock::now().time_since_epoch().count() & 0xffff);
  m.total = samples;
  m.n_outcomes = 6;
  for (int f = 0; f < 6; ++f) m.labels.push_back(f + 1);
  m.counts.assign(6, 0);
  m.p.assign(6, 0.0);
  m.ci_lo.assign(6, 0.0);
  m.ci_hi.assign(6, 0.0);
  auto publish = [&](std::int64_t seq) {
    m.done = seq;
    m.utime = w::now_utime();
    const auto bytes = w::encode(m);
    bus.publish(w::kProbabilities, bytes.data(), static_cast<unsigned>(bytes.size()));
  };

  // Warm-up: until the bridge forwards at all (discovery, LCM subscription), then 50 more.
  bool up = false;
  for (int i = 0; i < 100 && !up; ++i) {
    publish(-1 - i);
    up = wait_for(reader.get(), waitset.get(), m.run_id, -1 - i, std::chrono::milliseconds(200));
  }
  if (!up) return std::fprintf(stderr, "no answer came back over DDS in 20 s: is `dicesim bridge` running?\n"), 1;
  for (int i = 0; i < 50; ++i) {
    publish(-1000 - i);
    wait_for(reader.get(), waitset.get(), m.run_id, -1000 - i, std::chrono::milliseconds(200));
  }

  std::vector<double> ms;
  int lost = 0;
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate));
  auto next = Clock::now();
  for (int i = 0; i < samples; ++i) {
    std::this_thread::sleep_until(next);
    next += period;
    const auto t0 = Clock::now();
    publish(i);
    if (wait_for(reader.get(), waitset.get(), m.run_id, i, std::chrono::seconds(1)))
      ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    else
      ++lost;
  }
  if (ms.empty()) return std::fprintf(stderr, "nothing received\n"), 1;
  std::printf("bridge latency, LCM publish -> DDS receipt (%zu samples at %.0f Hz, %d lost): median %.3f ms, p95 %.3f ms, "
              "p99 %.3f ms, max %.3f ms\n",
              ms.size(), rate, lost, percentile(ms, 0.5), percentile(ms, 0.95), percentile(ms, 0.99),
              *std::max_element(ms.begin(), ms.end()));
  return 0;
}
