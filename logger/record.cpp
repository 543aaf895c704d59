#include "logger/record.hpp"

#include <algorithm>
#include <chrono>

#include <spdlog/spdlog.h>

#include "logger/event_log.hpp"
#include "logger/log.hpp"
#include "messages/auth.hpp"
#include "messages/wire.hpp"
#include "messages/lcm_wait.hpp"

namespace dicesim::eventlog {
namespace {

struct Recorder {
  EventLogWriter* out;
  const RecordOptions* opt;
  RecordResult* res;
  bool write_failed = false;
  double done_at = -1.0;  // seconds since start, when the awaited run's final result came
  std::chrono::steady_clock::time_point t0;
  wire::Sealer sealer;
  bool told_sealed = false;

  void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (!out->write(rbuf->recv_utime, channel, rbuf->data, rbuf->data_size)) write_failed = true;
    if (channel != wire::kRunStart && channel != wire::kProbabilities) return;
    // Only two kinds are looked at: who runs, and whether the awaited run has finished.
    const auto len = sealer.open(channel, rbuf->data, rbuf->data_size);
    if (!len) {
      ++res->unauthenticated;
      return;
    }
    if (!sealer.enabled() && !told_sealed && wire::looks_sealed(rbuf->data, rbuf->data_size)) {
      told_sealed = true;
      spdlog::warn("the run's messages carry HMAC seals: they are recorded, but without --key-file this recorder "
                   "cannot read them (nor tell when the run ends)");
    }
    if (channel == wire::kRunStart) {
      if (auto m = wire::decode<dicesim_lcm::run_start>(rbuf->data, *len))
        if (m->run_id != 0 && std::find(res->runs.begin(), res->runs.end(), m->run_id) == res->runs.end()) {
          res->runs.push_back(m->run_id);
          if (logging::run_id() == 0 && (opt->run_id == 0 || opt->run_id == m->run_id)) logging::set_run_id(m->run_id);
          spdlog::info("recording run {}: {}, {} tosses, seed {}", m->run_id, m->origin, m->total_tosses, m->seed);
        }
    } else if (opt->until_done && done_at < 0 && channel == wire::kProbabilities) {
      if (auto m = wire::decode<dicesim_lcm::probabilities>(rbuf->data, *len)) {
        const std::int64_t awaited = opt->run_id != 0 ? opt->run_id : (res->runs.empty() ? 0 : res->runs.front());
        if (m->finished == 1 && awaited != 0 && m->run_id == awaited) {
          res->done_run = awaited;
          done_at = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          spdlog::info("run {} finished ({} tosses); stopping in {} s", awaited, m->done, opt->linger_s);
        }
      }
    }
  }
};

// A recorder cannot ask for a lost datagram again (the aggregator can, and does): a UDP multicast
// URL gets a 4 MB kernel receive buffer (a few hundred toss_batch messages) unless it names its
// own. The kernel caps it at net.core.rmem_max.
std::string with_receive_buffer(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0 || url.find("recv_buf_size=") != std::string::npos) return url;
  return url + (url.find('?') == std::string::npos ? "?" : "&") + "recv_buf_size=4194304";
}

}  // namespace

RecordOptions default_record_options() { return RecordOptions{}; }

RecordResult record(const RecordOptions& opt) {
  RecordResult res;
  EventLogWriter out(opt.path);
  lcm::LCM bus(with_receive_buffer(opt.url));
  if (!bus.good()) {
    res.error = "cannot open LCM at '" + opt.url + "' (is there a multicast route? see README, Scale-out)";
    return res;
  }
  const auto t0 = std::chrono::steady_clock::now();
  Recorder rec{&out, &opt, &res, false, -1.0, t0, wire::Sealer(opt.key)};
  lcm::Subscription* sub = bus.subscribe(opt.channels, &Recorder::handle, &rec);
  // A recorder must not be where messages get lost: liblcm 1.3.1 keeps only 30 per subscription.
  sub->setQueueCapacity(1 << 16);
  if (opt.on_ready) opt.on_ready();
  for (;;) {
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (opt.cancel && opt.cancel->load()) {
      res.end = RecordEnd::Stopped;
      break;
    }
    if (rec.write_failed) {
      res.error = "cannot write '" + opt.path + "' (disk full?)";
      break;
    }
    if (rec.done_at >= 0 && now - rec.done_at >= opt.linger_s) {
      res.end = RecordEnd::Done;
      break;
    }
    if (opt.timeout_s > 0 && now >= opt.timeout_s) {
      res.end = RecordEnd::TimedOut;
      break;
    }
    wire::listen_timeout(bus, 20);
  }
  // Whatever is already queued was received before the stop: keep it.
  while (!rec.write_failed && wire::listen_timeout(bus, 0) > 0) {
  }
  if (!out.flush() && res.error.empty()) {
    res.error = "cannot write '" + opt.path + "' (disk full?)";
    res.end = RecordEnd::Failed;
  }
  res.events = out.events();
  res.bytes = out.bytes();
  res.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace dicesim::eventlog
