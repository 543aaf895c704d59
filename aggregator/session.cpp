#include "aggregator/session.hpp"

#include <algorithm>
#include <chrono>
#include <memory>

#include <lcm/lcm-cpp.hpp>

#include "messages/lcm_wait.hpp"

namespace dicesim::agg {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Forwards every subscribed channel's raw bytes to the Aggregator.
struct Inbox {
  Aggregator* agg;
  std::chrono::steady_clock::time_point t0;
  void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    agg->on_message(channel, rbuf->data, rbuf->data_size, seconds_since(t0));
  }
};

}  // namespace

std::string health_line(const Health& h) {
  return "batches " + std::to_string(h.batches) + ", duplicates " + std::to_string(h.duplicates) +
         ", rejected: foreign " + std::to_string(h.foreign) + ", malformed " + std::to_string(h.malformed) +
         ", out of range " + std::to_string(h.range) + "; re-leased " + std::to_string(h.released) +
         " tosses; messages in " + std::to_string(h.messages_in) + ", out " + std::to_string(h.messages_out) +
         ", unauthenticated " + std::to_string(h.unauthenticated) + "; tail splits " + std::to_string(h.splits) + " (" +
         std::to_string(h.split_tosses) + " tosses)";
}

SessionResult run_session(const SessionOptions& opt, const AggregatorConfig& cfg) {
  SessionResult res;
  lcm::LCM bus(opt.url);
  if (!bus.good()) {
    res.error = "cannot open LCM at '" + opt.url + "' (is there a multicast route? see README, Scale-out)";
    return res;
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto send = [&bus](const char* channel, const std::vector<std::uint8_t>& bytes) {
    bus.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  };
  Aggregator agg = opt.resume ? Aggregator(cfg, send, *opt.resume, 0.0) : Aggregator(cfg, send);
  const double elapsed_before = opt.resume ? opt.resume->elapsed_s : 0.0;
  std::unique_ptr<CheckpointWriter> writer;
  if (!opt.checkpoint_path.empty()) writer = std::make_unique<CheckpointWriter>(opt.checkpoint_path);
  double last_checkpoint = -1e9;
  auto take_checkpoint = [&](double now) {
    const auto s0 = std::chrono::steady_clock::now();
    std::string text = to_json(agg.checkpoint(elapsed_before + now));
    const double s = seconds_since(s0);
    ++res.snapshots;
    res.snapshot_s += s;
    res.max_snapshot_s = std::max(res.max_snapshot_s, s);
    writer->submit(std::move(text));
    last_checkpoint = now;
  };
  if (opt.on_start) opt.on_start(agg);
  Inbox inbox{&agg, t0};
  for (const char* ch : {wire::kTossBatch, wire::kWorkerStatus, wire::kRunStart, wire::kWorkLease,
                         wire::kProbabilities, wire::kBounceState}) {
    // Bounce states are for other subscribers; listening keeps their malformed copies counted,
    // but a small queue is enough (excess is dropped by LCM, never by us silently elsewhere).
    lcm::Subscription* sub = bus.subscribe(ch, &Inbox::handle, &inbox);
    sub->setQueueCapacity(ch == wire::kBounceState ? 64 : opt.queue_capacity);
  }

  // The first tick at once: run_start goes out now, not after the first wait for a message (up to
  // 10 ms), in case the workers spoke before this subscribed.
  double last_tick = seconds_since(t0);
  agg.tick(last_tick);
  for (;;) {
    if (opt.cancel && opt.cancel->load()) {
      res.end = SessionEnd::Cancelled;
      break;
    }
    wire::handle_timeout(bus, 10);
    const double now = seconds_since(t0);
    if (now - last_tick >= 0.02) {
      last_tick = now;
      agg.tick(now);
      if (writer && now - last_checkpoint >= opt.checkpoint_period_s) take_checkpoint(now);
      if (opt.on_tick) {
        if (std::string why = opt.on_tick(agg); !why.empty()) {
          res.error = why;
          break;
        }
      }
    }
    if (agg.finished()) {
      res.end = SessionEnd::Finished;
      break;
    }
  }
  res.elapsed_s = seconds_since(t0);
  res.run_elapsed_s = elapsed_before + res.elapsed_s;
  if (res.end == SessionEnd::Finished && opt.url.rfind("tcpq://", 0) == 0) {
    // Over a TCP hub the final answers are bytes on our socket: closing it with workers' batches
    // still unread makes the kernel reset the connection, and the hub may never relay them (a
    // listener then never hears the run finish). Keep reading a moment first, so they go out.
    const double until = seconds_since(t0) + 0.3;
    while (seconds_since(t0) < until) wire::handle_timeout(bus, 10);
  }
  if (writer) {
    // The last state (finished, interrupted or failed), so that --resume continues from here.
    take_checkpoint(res.elapsed_s);
    writer->flush();
    res.writer = writer->stats();
  }
  res.counts = agg.result();
  res.tosses = agg.stop();
  res.health = agg.health();
  res.refusals = agg.refusals();
  return res;
}

}  // namespace dicesim::agg
