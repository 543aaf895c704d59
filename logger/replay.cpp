#include "logger/replay.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <set>
#include <thread>

#include <Eigen/Geometry>
#include <spdlog/spdlog.h>

#include "aggregator/target.hpp"
#include "logger/event_log.hpp"
#include "logger/log.hpp"
#include "messages/auth.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim::eventlog {
namespace {

bool is_dicesim(const std::string& channel) { return channel.rfind("DICESIM_", 0) == 0; }

std::string list_ids(const std::vector<std::int64_t>& ids) {
  std::string s;
  for (std::size_t i = 0; i < ids.size() && i < 10; ++i) s += (i ? ", " : "") + std::to_string(ids[i]);
  if (ids.size() > 10) s += ", ...";
  return s.empty() ? "none" : s;
}

// The announcement of the run to replay: the first in the log, or the one asked for. It comes
// within the first second of a run (and every second after), so this reads little of the file.
// Without a key, a log with sealed announcements is refused outright: it is an authenticated
// run's, and any unsealed run_start in it may be a forgery heard on the bus.
dicesim_lcm::run_start find_run(const std::string& path, std::int64_t want, const std::vector<std::uint8_t>& key) {
  EventLogReader in(path);
  wire::Sealer sealer(key);
  std::vector<std::int64_t> seen;
  std::uint64_t sealed = 0, failed = 0;
  const char* legacy = nullptr;  // a run_start of the six-outcome wire
  std::optional<dicesim_lcm::run_start> found;
  while (const lcm::LogEvent* e = in.next()) {
    if (e->channel != wire::kRunStart) continue;
    const auto raw = static_cast<std::size_t>(e->datalen);
    if (wire::looks_sealed(e->data, raw)) {
      ++sealed;
      if (!sealer.enabled()) break;
    }
    if (found) continue;  // without a key: read on, looking for seals
    const auto len = sealer.open(e->channel, e->data, raw);
    if (!len) {
      ++failed;
      continue;
    }
    auto m = wire::decode<dicesim_lcm::run_start>(e->data, *len);
    if (!m && !legacy) legacy = wire::legacy_format(e->data, *len);
    if (!m || m->run_id == 0) continue;
    if (want == 0 || m->run_id == want) {
      found = *m;
      if (sealer.enabled()) break;
      continue;
    }
    if (std::find(seen.begin(), seen.end(), m->run_id) == seen.end()) seen.push_back(m->run_id);
  }
  if (sealed > 0 && !sealer.enabled())
    throw LogError("'" + path + "' is the log of an authenticated run (its messages carry HMAC seals): replay it with "
                   "--key-file FILE, the run's key");
  if (found) return *found;
  if (seen.empty() && legacy)
    throw LogError("'" + path + "' was recorded before runs carried any number of outcomes (its run_start is a " +
                   legacy + "): this dicesim cannot replay it; replay it with the dicesim that recorded it");
  if (seen.empty() && failed > 0 && sealer.enabled())
    throw LogError("'" + path + "': none of its " + std::to_string(failed) +
                   " run_start messages opens with this key (another run's key, or a log without seals)");
  if (want != 0)
    throw LogError("'" + path + "' has no run " + std::to_string(want) + " (runs in it: " + list_ids(seen) + ")");
  throw LogError("'" + path + "' holds no DICESIM_RUN_START message, so it does not describe a run (" +
                 std::to_string(in.events()) + " events; record the DICESIM_.* channels from before the run ends)");
}

struct Rebuilt {
  wire::RunSpec spec;
  DieModel model;
  bool matches = true;
};

Rebuilt rebuild(const dicesim_lcm::run_start& m) {
  Rebuilt r{wire::from_message(m), {}, true};
  try {
    r.model = wire::compile_spec(r.spec);
  } catch (const SceneError& e) {
    throw std::runtime_error("the scene recorded in run_start does not build here: " + std::string(e.what()));
  }
  r.matches = wire::model_fingerprint(r.model) == r.spec.fingerprint;
  return r;
}

struct PassOut {
  bool finished = false, cancelled = false;
  RunCounts counts;
  std::uint64_t tosses = 0, received = 0;  // tosses: complete prefix [0, tosses)
  agg::Health health;
};

// One pass over the file: every DICESIM_ message to a fresh Aggregator (until it has the answer),
// and with `publish` every event to the bus at the recorded pace.
PassOut feed(const ReplayOptions& opt, const agg::AggregatorConfig& cfg, lcm::LCM* bus, ReplayResult& res) {
  PassOut out;
  agg::Aggregator agg(cfg, [](const char*, const std::vector<std::uint8_t>&) {});  // its replies go nowhere
  wire::Sealer sealer(cfg.key);  // for what is read here besides the aggregator (which checks for itself)
  res.results_in_log = 0;
  EventLogReader in(opt.path);
  const std::int64_t run = cfg.spec.run_id;
  std::set<std::int64_t> workers;
  std::int64_t ts0 = 0, last_ts = 0;
  bool first = true;
  const auto wall0 = std::chrono::steady_clock::now();
  while (const lcm::LogEvent* e = in.next()) {
    if (first) ts0 = e->timestamp, first = false;
    const std::int64_t ts = e->timestamp;
    if (bus) {
      const double due = static_cast<double>(ts - ts0) * 1e-6 / opt.speed;
      const auto when = wall0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>(due));
      // In slices, so that Ctrl-C is heard during a long quiet stretch of the recording.
      while (std::chrono::steady_clock::now() < when && !(opt.cancel && opt.cancel->load()))
        std::this_thread::sleep_until(std::min(when, std::chrono::steady_clock::now() + std::chrono::milliseconds(100)));
      bus->publish(e->channel, e->data, static_cast<unsigned>(e->datalen));
    }
    if (bus || (in.events() & 255) == 0) {
      if (opt.cancel && opt.cancel->load()) {
        out.cancelled = true;
        break;
      }
      if (opt.on_progress) opt.on_progress(in.offset(), in.size());
    }
    if (!is_dicesim(e->channel)) continue;
    const auto* data = e->data;
    const auto raw = static_cast<std::size_t>(e->datalen);
    // The aggregator judges the raw bytes itself (and counts what fails); here only authentic ones.
    if (!agg.finished()) {
      agg.on_message(e->channel, data, raw, static_cast<double>(ts - ts0) * 1e-6);
      last_ts = ts;
    }
    const auto opened = sealer.open(e->channel, data, raw);
    if (!opened) continue;
    const std::size_t len = *opened;
    if (e->channel == wire::kTossBatch) {
      if (auto b = wire::decode<dicesim_lcm::toss_batch>(data, len))
        if (b->run_id == run && b->count > 0) res.results_in_log += static_cast<std::uint64_t>(b->count);
    } else if (e->channel == wire::kWorkerStatus) {
      if (auto m = wire::decode<dicesim_lcm::worker_status>(data, len))
        if (m->run_id == run && m->state == 1) workers.insert(m->worker_id);
    } else if (e->channel == wire::kProbabilities) {
      if (auto m = wire::decode<dicesim_lcm::probabilities>(data, len))
        if (m->run_id == run && m->finished == 1 && !res.recorded_final) res.recorded_final = *m;
    } else if (e->channel == wire::kRunStart) {
      if (auto m = wire::decode<dicesim_lcm::run_start>(data, len))
        if (m->run_id != run && m->run_id != 0 &&
            std::find(res.other_runs.begin(), res.other_runs.end(), m->run_id) == res.other_runs.end())
          res.other_runs.push_back(m->run_id);
    }
    // Once the answer is in, the rest is only read through (above): a log truncated or corrupt
    // anywhere is an error, not a result.
  }
  res.events = in.events();
  res.bytes = in.offset();
  res.workers = static_cast<int>(workers.size());
  res.run_span_s = static_cast<double>(last_ts - ts0) * 1e-6;
  if (opt.on_progress) opt.on_progress(in.offset(), in.size());
  out.finished = agg.finished();
  out.counts = agg.result();
  out.tosses = agg.stop();
  out.received = agg.received();
  out.health = agg.health();
  return out;
}

// The counts of the live aggregator's final message, in the order of `labels`.
RunCounts recorded_counts(const dicesim_lcm::probabilities& m, const std::vector<int>& labels) {
  RunCounts c(static_cast<int>(labels.size()));
  for (std::size_t k = 0; k < m.labels.size() && k < m.counts.size(); ++k) {
    const auto it = std::find(labels.begin(), labels.end(), m.labels[k]);
    if (it != labels.end() && m.counts[k] >= 0)
      c.faces[static_cast<std::size_t>(it - labels.begin())] = static_cast<std::uint64_t>(m.counts[k]);
  }
  c.settled = static_cast<std::uint64_t>(std::max<std::int64_t>(0, m.settled));
  return c;
}

}  // namespace

ReplayOptions default_replay_options() { return ReplayOptions{}; }

ReplayResult replay(const ReplayOptions& opt) {
  ReplayResult res;
  const dicesim_lcm::run_start start = find_run(opt.path, opt.run_id, opt.key);
  const Rebuilt rb = rebuild(start);
  res.spec = rb.spec;
  res.labels = rb.spec.labels;
  res.model_matches = rb.matches;
  res.model = rb.model;
  logging::set_run_id(rb.spec.run_id);
  spdlog::info("replaying run {}: {} ({}), seed {}, {} tosses", rb.spec.run_id, rb.spec.origin, rb.spec.fidelity,
               rb.spec.seed, rb.spec.total);

  agg::AggregatorConfig cfg;
  cfg.spec = rb.spec;
  cfg.key = opt.key;
  std::unique_ptr<lcm::LCM> bus;
  if (opt.live) {
    bus = std::make_unique<lcm::LCM>(opt.url);
    if (!bus->good()) throw std::runtime_error("cannot open LCM at '" + opt.url + "'");
  }
  PassOut p = feed(opt, cfg, bus.get(), res);
  if (!p.finished && !p.cancelled && res.recorded_final && res.recorded_final->total > 0 &&
      static_cast<std::uint64_t>(res.recorded_final->total) < cfg.spec.total) {
    // The live run stopped at a block boundary (--target-halfwidth H, which run_start does not
    // carry): its last message says where, S. The widest half-width at S, H* <= H, stops the
    // aggregator's own rule at exactly S: every earlier boundary was wider than H >= H*.
    res.stopped_at_target = true;
    cfg.target_halfwidth = agg::max_halfwidth(recorded_counts(*res.recorded_final, res.labels));
    spdlog::info("the live run stopped early at {} tosses (a target half-width); replaying to the same stop",
                 res.recorded_final->total);
    p = feed(opt, cfg, nullptr, res);
  }
  res.cancelled = p.cancelled;
  res.health = p.health;
  if (p.cancelled) return res;
  if (!p.finished)
    throw LogError("'" + opt.path + "' does not hold the whole run " + std::to_string(rb.spec.run_id) + ": " +
                   std::to_string(p.received) + " of " + std::to_string(cfg.spec.total) +
                   " toss results, complete up to index " + std::to_string(p.tosses) +
                   " (recording started late or stopped early? dicesim record --until-done waits for the end)");
  res.counts = p.counts;
  res.tosses = p.tosses;
  return res;
}

bool same_as_recorded(const ReplayResult& r) {
  if (!r.recorded_final) return false;
  const dicesim_lcm::probabilities& m = *r.recorded_final;
  if (m.settled != static_cast<std::int64_t>(r.counts.settled) ||
      m.unresolved != static_cast<std::int64_t>(r.counts.unresolved) ||
      m.invalid != static_cast<std::int64_t>(r.counts.invalid) || m.done != static_cast<std::int64_t>(r.tosses))
    return false;
  // The same outcomes in the same (label) order, and the same count for each.
  if (m.labels != std::vector<std::int32_t>(r.labels.begin(), r.labels.end()) || m.counts.size() != r.counts.faces.size())
    return false;
  for (std::size_t k = 0; k < m.counts.size(); ++k)
    if (m.counts[k] != static_cast<std::int64_t>(r.counts.faces[k])) return false;
  return true;
}

namespace {

// Largest |a - b| over the pairs, and whether every pair is bit-for-bit the same.
struct Diff {
  double max_abs = 0.0, max_rel = 0.0;
  bool identical = true;
  void add(double a, double b) {
    if (std::memcmp(&a, &b, sizeof a) != 0) identical = false;
    const double d = std::abs(a - b);
    if (!(d <= max_abs)) max_abs = d;  // NaN propagates
    const double rel = d / std::max({1.0, std::abs(a), std::abs(b)});
    if (!(rel <= max_rel)) max_rel = rel;
  }
  void add3(const double (&logged)[3], const Vec3& sim) {
    for (int i = 0; i < 3; ++i) add(logged[i], sim[i]);
  }
};

}  // namespace

TossCheck check_toss(const std::string& path, std::int64_t run_id, std::uint64_t index,
                     const std::vector<std::uint8_t>& key) {
  const dicesim_lcm::run_start start = find_run(path, run_id, key);
  wire::Sealer sealer(key);
  const Rebuilt rb = rebuild(start);
  TossCheck c;
  c.spec = rb.spec;
  c.index = index;
  c.model_matches = rb.matches;
  if (index >= rb.spec.total)
    throw LogError("toss " + std::to_string(index) + " is outside run " + std::to_string(rb.spec.run_id) + " (indices 0.." +
                   std::to_string(rb.spec.total - 1) + ")");

  std::map<int, dicesim_lcm::bounce_state> by_bounce;
  std::set<std::int64_t> traced;
  EventLogReader in(path);
  const auto want = static_cast<std::int64_t>(index);
  while (const lcm::LogEvent* e = in.next()) {
    const auto opened = sealer.open(e->channel, e->data, static_cast<std::size_t>(e->datalen));
    if (!opened) continue;  // unauthenticated: not evidence
    const std::size_t len = *opened;
    if (e->channel == wire::kBounceState) {
      auto m = wire::decode<dicesim_lcm::bounce_state>(e->data, len);
      if (!m || m->run_id != rb.spec.run_id) continue;
      if (traced.size() < 100000) traced.insert(m->toss_index);
      if (m->toss_index == want && m->bounce >= 1) by_bounce.emplace(m->bounce, *m);  // a repeat is the same impact
    } else if (e->channel == wire::kTossBatch && !c.batch_found) {
      auto b = wire::decode<dicesim_lcm::toss_batch>(e->data, len);
      if (!b || b->run_id != rb.spec.run_id || b->first_index > want || want - b->first_index >= b->count) continue;
      const auto k = static_cast<std::size_t>(want - b->first_index);
      if (k >= b->outcomes.size() || k >= b->statuses.size() || k >= b->bounces.size()) continue;
      c.batch_found = true;
      // The result is an outcome index: its label (-1: an index the run does not have).
      const int o = b->outcomes[k];
      c.log_face = b->statuses[k] != 0                                          ? 0
                   : o >= 0 && static_cast<std::size_t>(o) < rb.spec.labels.size() ? rb.spec.labels[static_cast<std::size_t>(o)]
                                                                                  : -1;
      c.log_status = b->statuses[k];
      c.log_bounces = b->bounces[k];
    }
  }
  if (by_bounce.empty()) {
    std::vector<std::int64_t> some(traced.begin(), traced.end());
    std::string why = rb.spec.trace_every == 0
                          ? "the run was not traced (dicesim aggregate/run --trace-every K publishes the bounces of every "
                            "K-th toss)"
                          : "the run traced every " + std::to_string(rb.spec.trace_every) +
                                "-th toss; traced tosses in this log: " + list_ids(some);
    throw LogError("'" + path + "' has no bounce states for toss " + std::to_string(index) + " of run " +
                   std::to_string(rb.spec.run_id) + ": " + why);
  }
  for (auto& [b, m] : by_bounce) c.logged.push_back(m);

  TossProbe probe;
  probe.trace = &c.simulated;
  c.sim = toss(rb.model, rb.spec.seed, index, &probe);

  Diff d;
  bool same_events = true;
  for (const dicesim_lcm::bounce_state& m : c.logged) {
    if (m.bounce > static_cast<int>(c.simulated.size())) {
      same_events = false;
      continue;
    }
    const BounceRecord& r = c.simulated[static_cast<std::size_t>(m.bounce - 1)];
    if (r.vertex != m.contact_vertex) same_events = false;
    const Eigen::Quaterniond q(r.before.R);  // as the worker writes it
    d.add(m.t, r.t);
    d.add3(m.position, r.before.position);
    d.add(m.quaternion[0], q.w()), d.add(m.quaternion[1], q.x()), d.add(m.quaternion[2], q.y()), d.add(m.quaternion[3], q.z());
    d.add3(m.velocity, r.before.velocity);
    d.add3(m.angular_velocity, r.before.omega);
    d.add3(m.velocity_after, r.after.velocity);
    d.add3(m.angular_velocity_after, r.after.omega);
    d.add(m.impulse, r.impulse);
  }
  if (c.batch_found &&
      (c.log_bounces != c.sim.bounces || c.log_status != static_cast<int>(c.sim.status) ||
       c.log_face != (c.sim.status == TossStatus::Settled ? c.sim.face : 0)))
    same_events = false;
  c.max_abs_diff = d.max_abs;
  c.bit_identical = same_events && d.identical;
  // Same build, same inputs: bit-identical is expected. A relative 1e-9 leaves room for another
  // CPU's libm, never for a different toss.
  c.agree = same_events && d.max_rel <= 1e-9;
  return c;
}

}  // namespace dicesim::eventlog
