#include "sim/worker/worker.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <random>

#include <Eigen/Geometry>
#include <lcm/lcm-cpp.hpp>

#include "messages/lcm_wait.hpp"

#include "sim/scene/scene_error.hpp"
#include "sim/models/toss.hpp"

namespace dicesim::worker {
namespace {

std::int64_t random_id() {
  std::random_device rd;
  std::uint64_t v = 0;
  while (v == 0) v = ((std::uint64_t{rd()} << 32) ^ rd() ^ static_cast<std::uint64_t>(getpid())) & INT64_MAX;
  return static_cast<std::int64_t>(v);
}

std::string hostname() {
  char buf[256] = {};
  gethostname(buf, sizeof buf - 1);
  return buf;
}

void put3(double (&out)[3], const Vec3& v) {
  for (int i = 0; i < 3; ++i) out[i] = v[i];
}

}  // namespace

WorkerCore::WorkerCore(WorkerConfig cfg, Send send)
    : cfg_(std::move(cfg)), send_(std::move(send)), sealer_(cfg_.key), host_(hostname()) {
  if (cfg_.worker_id == 0) cfg_.worker_id = random_id();
  cfg_.batch = std::clamp(cfg_.batch, 1, wire::kMaxBatch);
}

void WorkerCore::send(const char* channel, std::vector<std::uint8_t> bytes) {
  sealer_.seal(channel, bytes);
  send_(channel, bytes);
}

void WorkerCore::on_message(std::string_view channel, const void* data, std::size_t len, double now) {
  if (channel != wire::kRunStart && channel != wire::kWorkLease && channel != wire::kProbabilities) return;
  if (const auto payload = sealer_.open(channel, data, len)) {
    len = *payload;
  } else {
    ++unauthenticated_;
    if (!told_key_ && channel == wire::kRunStart && cfg_.log) {
      told_key_ = true;
      cfg_.log("ignoring a run_start that fails the HMAC check (no seal, or another key): unauthenticated messages "
               "are dropped and counted");
    }
    return;
  }
  if (!sealer_.enabled() && channel == wire::kRunStart && wire::looks_sealed(data, len) && !told_key_ && cfg_.log) {
    told_key_ = true;
    cfg_.log("heard a run whose messages carry an HMAC seal: this worker has no key (dicesim worker --key-file FILE)");
  }
  if (channel == wire::kRunStart) {
    if (auto m = wire::decode<dicesim_lcm::run_start>(data, len)) return on_run_start(*m, now);
  } else if (channel == wire::kWorkLease) {
    if (auto m = wire::decode<dicesim_lcm::work_lease>(data, len)) return on_lease(*m, now);
  } else if (channel == wire::kProbabilities) {
    if (auto m = wire::decode<dicesim_lcm::probabilities>(data, len)) {
      if (run_ && m->run_id == run_->spec.run_id && m->finished == 1) end_run(RunEnd::Finished);
      return;
    }
  }
  ++ignored_;
}

void WorkerCore::on_run_start(const dicesim_lcm::run_start& m, double now) {
  if (m.run_id == 0 || (cfg_.only_run != 0 && m.run_id != cfg_.only_run) || ended_runs_.count(m.run_id)) return;
  if (run_ && run_->spec.run_id == m.run_id) {
    run_->last_heard = now;
    // Ready but never leased anything: the aggregator may not have heard the status that said so
    // (an adopted run's worker can speak before the aggregator listens). Say it again now, not at
    // the next heartbeat (up to 200 ms later).
    if (run_->model && last_lease_seen_ == 0 && leases_.empty()) send_status(now);
    return;
  }
  if (run_ && now - run_->last_heard < cfg_.run_silence_s) return;  // busy with another live run
  if (run_) end_run(RunEnd::Replaced);
  start_run(wire::from_message(m), nullptr, now);
}

void WorkerCore::adopt(const wire::RunSpec& spec, const DieModel& model, double now) {
  if (spec.run_id == 0 || (cfg_.only_run != 0 && spec.run_id != cfg_.only_run) || ended_runs_.count(spec.run_id)) return;
  if (run_) end_run(RunEnd::Replaced);
  start_run(spec, &model, now);
}

void WorkerCore::start_run(wire::RunSpec spec, const DieModel* known, double now) {
  const std::int64_t run_id = spec.run_id;
  run_ = std::make_unique<Run>();
  run_->spec = std::move(spec);
  if (cfg_.on_run) cfg_.on_run(run_id);
  run_->last_heard = now;
  leases_.clear();
  last_lease_seen_ = last_done_ = 0;
  tosses_done_ = rate_n_ = 0;
  batch_now_ = 0, last_n_ = 0;  // another run may be another fidelity
  rate_t_ = now;
  const wire::RunSpec& s = run_->spec;
  try {
    if (s.total == 0 || s.total > static_cast<std::uint64_t>(INT64_MAX) || s.seed > static_cast<std::uint64_t>(INT64_MAX))
      throw std::runtime_error("total_tosses and seed must be positive");
    // A model handed over in memory is used only if it is exactly the one the spec describes.
    const bool use_known = known && wire::model_fingerprint(*known) == s.fingerprint && known->outcome_labels == s.labels;
    DieModel model = use_known ? *known : wire::compile_spec(s);
    if (!use_known && wire::model_fingerprint(model) != s.fingerprint)
      throw std::runtime_error("the model compiled here differs from the aggregator's (fingerprint mismatch: "
                               "a different dicesim build?)");
    // Results go out as indices into run_start's outcome list: it must be this model's.
    if (model.outcome_labels != s.labels)
      throw std::runtime_error("the die compiled here has other outcome labels than run_start announces");
    run_->model = std::move(model);
  } catch (const std::exception& e) {  // SceneError or anything else: refuse, say why
    run_->error = e.what();
  }
  if (cfg_.log)
    cfg_.log(run_->model ? "run " + std::to_string(run_id) + ": " + s.origin + ", " + std::to_string(s.total) +
                               " tosses, seed " + std::to_string(s.seed)
                         : "refusing run " + std::to_string(run_id) + ": " + run_->error);
  send_status(now);
}

void WorkerCore::on_lease(const dicesim_lcm::work_lease& m, double now) {
  if (!run_ || !run_->model || m.run_id != run_->spec.run_id || m.worker_id != cfg_.worker_id) return;
  const std::uint64_t total = run_->spec.total;
  if (m.lease_id <= last_done_ || m.count <= 0 || m.first_index < 0 || static_cast<std::uint64_t>(m.first_index) >= total ||
      static_cast<std::uint64_t>(m.count) > total - static_cast<std::uint64_t>(m.first_index)) {
    ++ignored_;
    return;
  }
  const std::uint64_t first = static_cast<std::uint64_t>(m.first_index);
  const std::uint64_t end = first + static_cast<std::uint64_t>(m.count);
  for (auto it = leases_.begin(); it != leases_.end(); ++it) {
    if (it->id != m.lease_id) continue;
    // The same lease, shorter: the aggregator gave its back part to an idle worker (the run's
    // tail). Anything else under a known id (a repeat, a longer count) changes nothing.
    if (first == it->first && end < it->end) {
      it->end = std::max(end, it->next);
      if (it->next == it->end) finish_lease(it, now);  // it had already tossed up to the new end
    }
    return;
  }
  if (leases_.size() >= 16) {
    ++ignored_;
    return;
  }
  Lease l{m.lease_id, first, first, end};
  leases_.insert(std::upper_bound(leases_.begin(), leases_.end(), l, [](const Lease& a, const Lease& b) { return a.id < b.id; }),
                 l);
  last_lease_seen_ = std::max(last_lease_seen_, m.lease_id);
}

void WorkerCore::end_run(RunEnd how) {
  if (!run_) return;
  const char* why = how == RunEnd::Finished   ? "finished"
                    : how == RunEnd::Replaced ? "replaced by a newer run"
                                              : "no run_start heard for a while";
  if (cfg_.log)
    cfg_.log("run " + std::to_string(run_->spec.run_id) + " ended: " + why + " (" + std::to_string(tosses_done_) +
             " tosses by this worker)");
  if (how != RunEnd::Silent) ended_runs_.insert(run_->spec.run_id);
  // Finished with its aggregator, or leased work: served. Otherwise only heard of.
  if (how == RunEnd::Finished || last_lease_seen_ > 0) ++runs_served_;
  run_.reset();
  if (cfg_.on_run) cfg_.on_run(0);
  leases_.clear();
}

void WorkerCore::send_status(double now) {
  last_status_ = now;
  dicesim_lcm::worker_status s;
  s.utime = wire::now_utime();
  s.worker_id = cfg_.worker_id;
  s.run_id = run_ ? run_->spec.run_id : 0;
  s.pid = static_cast<std::int32_t>(getpid());
  s.host = host_;
  s.state = !run_ ? 0 : run_->model ? 1 : 2;
  s.error = run_ ? run_->error : "";
  for (const Lease& l : leases_) s.held_leases.push_back(l.id);
  s.n_held = static_cast<std::int32_t>(s.held_leases.size());
  s.last_done_lease = last_done_;
  s.tosses_done = static_cast<std::int64_t>(tosses_done_);
  s.tosses_per_s = rate_;
  s.traces_skipped = static_cast<std::int64_t>(traces_skipped_);
  send(wire::kWorkerStatus, wire::encode(s));
}

void WorkerCore::tick(double now) {
  if (run_ && now - run_->last_heard > cfg_.run_silence_s) end_run(RunEnd::Silent);
  if (now - rate_t_ >= 1.0) {
    rate_ = static_cast<double>(tosses_done_ - rate_n_) / (now - rate_t_);
    rate_t_ = now;
    rate_n_ = tosses_done_;
  }
  if (now - last_status_ >= cfg_.heartbeat_s) send_status(now);
}

bool WorkerCore::step(double now) {
  if (!run_ || !run_->model || leases_.empty()) {
    last_n_ = 0;  // idle: the next step's wait is not a batch's cost
    return false;
  }
  const DieModel& model = *run_->model;
  const wire::RunSpec& spec = run_->spec;
  Lease& l = leases_.front();
  // Steps follow each other while there is work: the time since the last one is its batch's
  // cost. Sized to batch_s of work, growing at most fourfold a step; never below 256 tosses.
  if (batch_now_ == 0) batch_now_ = std::min(cfg_.batch, 512);
  if (last_n_ > 0 && now > last_step_) {
    const double fit = cfg_.batch_s * static_cast<double>(last_n_) / (now - last_step_);
    batch_now_ = std::min(cfg_.batch, static_cast<int>(std::max(256.0, std::min(fit, 4.0 * batch_now_))));
  }
  const std::uint64_t n = std::min<std::uint64_t>(static_cast<std::uint64_t>(batch_now_), l.end - l.next);
  last_step_ = now;
  last_n_ = n;

  // Bounce-state budget for this batch: a token bucket refilled at max_trace_per_s.
  trace_tokens_ = std::min(cfg_.max_trace_per_s, trace_tokens_ + (now - trace_t_) * cfg_.max_trace_per_s);
  trace_t_ = now;

  dicesim_lcm::toss_batch b;
  b.utime = wire::now_utime();
  b.run_id = spec.run_id;
  b.worker_id = cfg_.worker_id;
  b.lease_id = l.id;
  b.first_index = static_cast<std::int64_t>(l.next);
  b.count = static_cast<std::int32_t>(n);
  b.outcomes.resize(n);
  b.statuses.resize(n);
  b.bounces.resize(n);
  b.n_corrected = 0;
  std::vector<BounceRecord> records;
  for (std::uint64_t k = 0; k < n; ++k) {
    if (k % 64 == 63 && cfg_.cancel && cfg_.cancel->load(std::memory_order_relaxed)) return false;
    const std::uint64_t i = l.next + k;
    const bool traced = spec.trace_every > 0 && i % static_cast<std::uint64_t>(spec.trace_every) == 0;
    records.clear();
    // The probe only records: the result is the same toss as without it. (Built only when
    // traced: the untraced toss, nearly all of them, passes no probe.)
    TossResult r;
    if (traced) {
      TossProbe probe;
      probe.trace = &records;
      r = toss(model, spec.seed, i, &probe);
    } else {
      r = toss(model, spec.seed, i);
    }
    b.outcomes[k] = static_cast<std::int8_t>(r.status == TossStatus::Settled ? r.outcome : -1);
    b.statuses[k] = static_cast<std::int8_t>(r.status);
    b.bounces[k] = r.bounces;
    if (r.corrections.any()) {
      ++b.n_corrected;
      b.corrected_offset.push_back(static_cast<std::int32_t>(k));
      b.energy_clamps.push_back(static_cast<std::int32_t>(r.corrections.energy_clamps));
      b.pgs_unconverged.push_back(static_cast<std::int32_t>(r.corrections.pgs_unconverged));
      b.overlap_fixes.push_back(static_cast<std::int32_t>(r.corrections.overlap_fixes));
      b.fallbacks.push_back(static_cast<std::int32_t>(r.corrections.fallbacks));
      b.located_capped.push_back(static_cast<std::int32_t>(r.corrections.located_capped));
      b.support_search_capped.push_back(static_cast<std::int32_t>(r.corrections.support_search_capped));
      b.rise_dropped.push_back(static_cast<std::int32_t>(r.corrections.rise_dropped));
      b.contact_overlaps.push_back(static_cast<std::int32_t>(r.corrections.contact_overlaps));
      b.nudges.push_back(static_cast<std::int32_t>(r.corrections.nudges));
    }
    for (const BounceRecord& rec : records) {
      if (trace_tokens_ < 1.0) {
        ++traces_skipped_;
        continue;
      }
      trace_tokens_ -= 1.0;
      dicesim_lcm::bounce_state s;
      s.utime = b.utime;
      s.run_id = spec.run_id;
      s.worker_id = cfg_.worker_id;
      s.toss_index = static_cast<std::int64_t>(i);
      s.bounce = rec.bounce;
      s.t = rec.t;
      put3(s.position, rec.before.position);
      const Eigen::Quaterniond q(rec.before.R);
      s.quaternion[0] = q.w(), s.quaternion[1] = q.x(), s.quaternion[2] = q.y(), s.quaternion[3] = q.z();
      put3(s.velocity, rec.before.velocity);
      put3(s.angular_velocity, rec.before.omega);
      put3(s.velocity_after, rec.after.velocity);
      put3(s.angular_velocity_after, rec.after.omega);
      s.contact_vertex = rec.vertex;
      s.impulse = rec.impulse;
      send(wire::kBounceState, wire::encode(s));
    }
  }
  send(wire::kTossBatch, wire::encode(b));
  l.next += n;
  tosses_done_ += n;
  if (l.next == l.end) finish_lease(leases_.begin(), now);
  return true;
}

void WorkerCore::finish_lease(std::deque<Lease>::iterator it, double now) {
  last_done_ = it->id;
  leases_.erase(it);
  send_status(now);  // "done with that one": the aggregator may re-lease what it did not get
}

namespace {
struct Inbox {
  WorkerCore* core;
  std::chrono::steady_clock::time_point t0;
  void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    core->on_message(channel, rbuf->data, rbuf->data_size,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
};
}  // namespace

int run_worker(const WorkerOptions& opt) {
  lcm::LCM bus(opt.url);
  if (!bus.good()) {
    if (opt.core.log) opt.core.log("cannot open LCM at '" + opt.url + "'");
    return 1;
  }
  const auto t0 = std::chrono::steady_clock::now();
  WorkerCore core(opt.core, [&bus](const char* channel, const std::vector<std::uint8_t>& bytes) {
    bus.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  });
  Inbox inbox{&core, t0};
  for (const char* ch : {wire::kRunStart, wire::kWorkLease, wire::kProbabilities})
    bus.subscribe(ch, &Inbox::handle, &inbox)->setQueueCapacity(4096);
  // After subscribing: adopt's status brings leases at once, which must not go unheard.
  if (opt.known_spec && opt.known_model) core.adopt(*opt.known_spec, *opt.known_model, 0.0);
  if (opt.core.log) opt.core.log("worker " + std::to_string(core.id()) + " listening on " + opt.url);
  for (;;) {
    if (opt.cancel && opt.cancel->load()) break;
    while (wire::handle_timeout(bus, 0) > 0) {
    }
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    core.tick(now);
    if (opt.once && core.runs_served() > 0) break;
    if (!core.step(now)) wire::handle_timeout(bus, 50);
  }
  if (opt.core.log && core.unauthenticated() > 0)
    opt.core.log("dropped " + std::to_string(core.unauthenticated()) +
                 " messages that failed the HMAC check (unsealed, forged, tampered or another key)");
  return 0;
}

}  // namespace dicesim::worker
