#include "bridge/bridge.hpp"

#include <cerrno>
#include <chrono>
#include <cstring>
#include <set>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "bridge/dds_writers.hpp"
#include "bridge/translate.hpp"
#include "messages/auth.hpp"
#include "messages/wire.hpp"
#include "messages/lcm_wait.hpp"

namespace dicesim::bridge {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

const char* state_name(dicesim_dds_run_state s) {
  switch (s) {
    case dicesim_dds_RUN_ANNOUNCED: return "announced";
    case dicesim_dds_RUN_RUNNING: return "running";
    case dicesim_dds_RUN_FINISHED: return "finished";
    case dicesim_dds_RUN_SILENT: return "silent";
  }
  return "?";
}

// LCM callbacks: decode (never trusting the bytes), forward answers at once, note the rest.
struct Inbox {
  DdsWriters* dds;
  RunTable* runs;
  BridgeStats* stats;
  std::set<std::int64_t>* seen;
  std::chrono::steady_clock::time_point t0;
  wire::Sealer sealer;

  void handle(const lcm::ReceiveBuffer* rb, const std::string& channel) {
    const double now = seconds_since(t0);
    // With a key, only authentic messages go on (to DDS, or into the run table): the payload.
    const auto opened = sealer.open(channel, rb->data, rb->data_size);
    if (!opened) return void(++stats->unauthenticated);
    const void* data = rb->data;
    const std::size_t len = *opened;
    if (channel == wire::kProbabilities) {
      const auto m = wire::decode<dicesim_lcm::probabilities>(data, len);
      if (!m) return void(++stats->malformed);
      dds->write(to_dds(*m));  // first: this is the latency that matters
      ++stats->answers;
      note_run(m->run_id);
      runs->on_probabilities(*m, now);
    } else if (channel == wire::kRunStart) {
      const auto m = wire::decode<dicesim_lcm::run_start>(data, len);
      if (!m) return void(++stats->malformed);
      note_run(m->run_id);
      runs->on_run_start(*m, now);
    } else if (channel == wire::kWorkerStatus) {
      const auto m = wire::decode<dicesim_lcm::worker_status>(data, len);
      if (!m) return void(++stats->malformed);
      runs->on_worker_status(*m, now);
    }
  }
  void note_run(std::int64_t id) {
    if (id != 0 && seen->insert(id).second) {
      ++stats->runs;
      spdlog::info("bridge: new run {}", id);
    }
  }
};

}  // namespace

BridgeDef default_bridge_def() {
  BridgeDef d;
  d.lcm_url = wire::kDefaultUrl;
  return d;
}

BridgeStats run_bridge(const BridgeDef& def) {
  BridgeStats stats;
  lcm::LCM bus(def.lcm_url);
  if (!bus.good()) throw std::runtime_error("cannot open LCM at '" + def.lcm_url + "' (is there a multicast route?)");
  DdsWriters dds(def.dds_config, def.dds_domain);
  RunTable runs(def.runs);
  std::set<std::int64_t> seen;
  const auto t0 = std::chrono::steady_clock::now();
  Inbox inbox{&dds, &runs, &stats, &seen, t0, wire::Sealer(def.key)};
  for (const char* ch : {wire::kProbabilities, wire::kRunStart, wire::kWorkerStatus}) {
    lcm::Subscription* sub = bus.subscribe(ch, &Inbox::handle, &inbox);
    sub->setQueueCapacity(256);  // answers come at 4 Hz, heartbeats at 5 Hz per worker
  }
  spdlog::info("bridge: LCM {} -> DDS domain {} (topics {}, {})", def.lcm_url, def.dds_domain, kProbabilitiesTopic,
               kRunStatusTopic);

  double last_tick = -1.0;
  while (!(def.stop && def.stop->load())) {
    if (wire::listen_timeout(bus, 50) < 0) {
      // A signal interrupts the wait: that is how we are asked to stop, not a failure.
      if (errno == EINTR) continue;
      throw std::runtime_error("LCM receive failed on '" + def.lcm_url + "': " + std::strerror(errno));
    }
    const double now = seconds_since(t0);
    if (now - last_tick < 0.05) continue;
    last_tick = now;
    for (std::int64_t id : runs.tick(now)) {
      const RunRecord* r = runs.find(id);
      dds.write(to_dds(*r, wire::now_utime()));
      ++stats.statuses;
      // Once per change for the end states; every refresh of a live run only at debug level.
      const bool ended = r->state == dicesim_dds_RUN_FINISHED || r->state == dicesim_dds_RUN_SILENT;
      spdlog::log(ended ? spdlog::level::info : spdlog::level::debug, "bridge: run {} {} ({} of {} tosses, {} workers)",
                  id, state_name(r->state), r->done, r->total, r->workers.size());
    }
    for (std::int64_t id : runs.take_forgotten()) {
      dds.dispose(id);
      spdlog::info("bridge: forgot run {} (more than {} runs)", id, def.runs.max_runs);
    }
  }
  stats.write_errors = dds.write_errors();
  return stats;
}

}  // namespace dicesim::bridge
