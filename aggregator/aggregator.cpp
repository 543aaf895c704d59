#include "aggregator/aggregator.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <unordered_set>

#include "aggregator/target.hpp"
#include "sim/study/statistics.hpp"

namespace dicesim::agg {

Aggregator::Aggregator(AggregatorConfig cfg, Send send)
    : cfg_(std::move(cfg)),
      send_(std::move(send)),
      limit_(cfg_.spec.total),
      outcomes_(cfg_.spec.labels.size()),
      prefix_(static_cast<int>(outcomes_)),
      all_(static_cast<int>(outcomes_)),
      sealer_(cfg_.key) {
  if (!wire::valid_outcome_labels(std::vector<std::int32_t>(cfg_.spec.labels.begin(), cfg_.spec.labels.end())))
    throw std::invalid_argument("the run's " + std::to_string(cfg_.spec.labels.size()) + " outcome labels (" +
                                (cfg_.spec.labels.empty() ? std::string("none")
                                                          : std::to_string(cfg_.spec.labels.front()) + " to " +
                                                                std::to_string(cfg_.spec.labels.back())) +
                                ") are not 1 to " + std::to_string(wire::kMaxOutcomes) + " ascending labels in [0, " +
                                std::to_string(wire::kMaxLabel) + "], what the wire carries (several dice: read their sum)");
}

namespace {
// Lease ids of a resumed run start this far above the checkpoint's: the dead aggregator may have
// granted more after its last checkpoint (a few hundred a second at most), and a worker ignores
// a lease id it has already finished or holds.
constexpr std::int64_t kResumeLeaseGap = 1'000'000;
}  // namespace

Aggregator::Aggregator(AggregatorConfig cfg, Send send, const Checkpoint& from, double now)
    : Aggregator(std::move(cfg), std::move(send)) {
  limit_ = std::min<std::uint64_t>(from.limit, cfg_.spec.total);
  for (const auto& [lo, hi] : from.received) received_.add(lo, hi);
  frontier_ = from.frontier;
  next_lease_ = from.next_lease + kResumeLeaseGap;
  prefix_ = from.prefix;
  prefix_end_ = from.prefix_end;
  all_ = from.all;
  blocks_ = from.blocks;
  const HealthCounts& h = from.health;
  health_.batches = h.batches, health_.duplicates = h.duplicates, health_.foreign = h.foreign;
  health_.malformed = h.malformed, health_.range = h.range, health_.released = h.released, health_.leases = h.leases;
  health_.messages_out = h.messages_out, health_.messages_in = h.messages_in, health_.unauthenticated = h.unauthenticated;
  resumes_ = from.resumes + 1;
  // Leases out at the checkpoint: their workers probably still work on them. Kept as if just
  // granted; a worker that does not report within worker_timeout_s loses them (tick).
  IntervalSet covered;
  for (const Checkpoint::Lease& cl : from.leases) {
    if (cl.count == 0 || cl.first >= limit_) continue;
    Lease l;
    l.id = cl.id, l.worker = cl.worker, l.first = cl.first, l.count = cl.count;
    l.granted = now;
    l.deadline = now + 3.0 * static_cast<double>(2 * cfg_.max_lease) / 500.0 + 2.0 * cfg_.worker_timeout_s;
    leases_[l.id] = l;
    covered.add(l.first, std::min(limit_, l.first + l.count));
    Worker& w = workers_[l.worker];
    w.last_seen = now;  // not ready until it reports: no new lease before that
  }
  // Below the frontier, what is neither held nor under a restored lease was lost with the old
  // aggregator (results after its last checkpoint, leases granted after it): lease it again.
  for (const IntervalSet::Range& g : received_.gaps(0, std::min(frontier_, limit_)))
    for (const IntervalSet::Range& r : covered.gaps(g.first, g.second)) {
      const std::uint64_t n = requeue_.add(r.first, r.second);
      health_.released += n;
      resume_.requeued += n;
    }
  resume_.resumed = true;
  resume_.held = received_.size();
  resume_.leases = leases_.size();
  resume_.resumes = resumes_;
  resume_.age_s = std::max(0.0, static_cast<double>(wire::now_utime() - from.written_utime) * 1e-6);
  rate_n_ = received_.size();
  advance_prefix();  // a checkpoint of a finished run is finished at once
}

Checkpoint Aggregator::checkpoint(double elapsed_s) const {
  Checkpoint c;
  c.start = wire::to_message(cfg_.spec);
  c.labels = cfg_.spec.labels;
  c.target_halfwidth = cfg_.target_halfwidth;
  c.limit = limit_;
  for (const auto& [lo, hi] : received_.ranges_list()) c.received.emplace_back(lo, hi);
  c.frontier = frontier_;
  c.next_lease = next_lease_;
  c.prefix_end = prefix_end_;
  c.prefix = prefix_;
  c.all = all_;
  c.blocks = blocks_;
  for (const auto& [id, l] : leases_)
    if (l.done_at < 0) c.leases.push_back({l.id, l.worker, l.first, l.count});
  const Health& h = health_;
  c.health = {h.batches, h.duplicates, h.foreign, h.malformed, h.range, h.released, h.leases, h.messages_out, h.messages_in,
              h.unauthenticated};
  c.elapsed_s = elapsed_s;
  c.written_utime = wire::now_utime();
  c.finished = finished_;
  c.resumes = resumes_;
  return c;
}

template <class T>
void Aggregator::publish(const char* channel, const T& msg) {
  ++health_.messages_out;
  std::vector<std::uint8_t> bytes = wire::encode(msg);
  sealer_.seal(channel, bytes);
  send_(channel, bytes);
}

void Aggregator::on_message(std::string_view channel, const void* data, std::size_t len, double now) {
  ++health_.messages_in;
  // Authentication first, on the raw bytes: nothing unauthenticated is even decoded.
  if (const auto payload = sealer_.open(channel, data, len)) {
    len = *payload;
  } else {
    ++health_.unauthenticated;
    return;
  }
  if (channel == wire::kTossBatch) {
    if (auto b = wire::decode<dicesim_lcm::toss_batch>(data, len)) return on_batch(*b, now);
    ++health_.malformed;
  } else if (channel == wire::kWorkerStatus) {
    if (auto s = wire::decode<dicesim_lcm::worker_status>(data, len)) return on_status(*s, now);
    ++health_.malformed;
  } else if (channel == wire::kRunStart) {
    // Another aggregator's run on the same URL is foreign; our own echo is not counted.
    auto r = wire::decode<dicesim_lcm::run_start>(data, len);
    if (!r) ++health_.malformed;
    else if (r->run_id != cfg_.spec.run_id) ++health_.foreign;
  } else if (channel == wire::kWorkLease || channel == wire::kProbabilities || channel == wire::kBounceState) {
    // Our own messages come back (multicast loops back); only check that they decode.
    bool ok = false;
    std::int64_t run = 0;
    if (channel == wire::kWorkLease) {
      if (auto m = wire::decode<dicesim_lcm::work_lease>(data, len)) ok = true, run = m->run_id;
    } else if (channel == wire::kProbabilities) {
      if (auto m = wire::decode<dicesim_lcm::probabilities>(data, len)) ok = true, run = m->run_id;
    } else if (auto m = wire::decode<dicesim_lcm::bounce_state>(data, len)) {
      ok = true, run = m->run_id;
    }
    if (!ok) ++health_.malformed;
    else if (run != cfg_.spec.run_id) ++health_.foreign;
  }
}

bool Aggregator::valid_batch(const dicesim_lcm::toss_batch& b) const {
  const std::size_t n = static_cast<std::size_t>(b.count);
  if (b.count < 1 || b.outcomes.size() != n || b.statuses.size() != n || b.bounces.size() != n) return false;
  const std::size_t nc = static_cast<std::size_t>(b.n_corrected);
  const std::vector<std::int32_t>* kinds[] = {&b.energy_clamps, &b.pgs_unconverged, &b.overlap_fixes, &b.fallbacks,
                                              &b.located_capped, &b.support_search_capped, &b.rise_dropped, &b.contact_overlaps,
                                              &b.nudges};
  static_assert(std::size(kinds) == RunCorrections::kKinds);
  if (b.n_corrected < 0 || b.corrected_offset.size() != nc) return false;
  for (const auto* k : kinds)
    if (k->size() != nc) return false;
  for (std::size_t j = 0; j < nc; ++j) {
    if (b.corrected_offset[j] < 0 || b.corrected_offset[j] >= b.count) return false;
    for (const auto* k : kinds)
      if ((*k)[j] < 0) return false;
  }
  for (std::size_t k = 0; k < n; ++k) {
    const int outcome = b.outcomes[k], status = b.statuses[k];
    if (b.bounces[k] < 0) return false;
    if (status == 0) {
      if (outcome < 0 || static_cast<std::size_t>(outcome) >= outcomes_) return false;
    } else if ((status != 1 && status != 2) || outcome != -1) {
      return false;
    }
  }
  return true;
}

void Aggregator::on_batch(const dicesim_lcm::toss_batch& b, double now) {
  if (b.run_id != cfg_.spec.run_id) {
    ++health_.foreign;
    return;
  }
  if (b.first_index < 0 || b.count < 1 || static_cast<std::uint64_t>(b.first_index) >= cfg_.spec.total ||
      static_cast<std::uint64_t>(b.count) > cfg_.spec.total - static_cast<std::uint64_t>(b.first_index)) {
    ++health_.range;
    return;
  }
  if (!valid_batch(b)) {
    ++health_.malformed;
    return;
  }
  ++health_.batches;
  if (auto w = workers_.find(b.worker_id); w != workers_.end()) w->second.last_seen = now, w->second.batch = static_cast<std::uint64_t>(b.count);
  const std::uint64_t first = static_cast<std::uint64_t>(b.first_index), n = static_cast<std::uint64_t>(b.count);
  const std::uint64_t fresh = received_.add(first, first + n, [&](std::uint64_t lo, std::uint64_t hi) {
    ingest(first, lo, hi, b);
  });
  health_.duplicates += n - fresh;
  if (finished_) return;
  advance_prefix();
  if (finished_) return finish(now);
  // A completed lease frees its worker's slot at once: the next lease is on its way before the
  // worker runs out of queued work.
  if (auto it = leases_.find(b.lease_id); it != leases_.end() && it->second.worker == b.worker_id &&
                                           received_.covers(it->second.first, it->second.first + it->second.count)) {
    leases_.erase(it);
    grant(b.worker_id, now);
  }
}

void Aggregator::ingest(std::uint64_t first, std::uint64_t lo, std::uint64_t hi, const dicesim_lcm::toss_batch& b) {
  // Split at block boundaries; each piece is summed locally, then added to its block.
  while (lo < hi) {
    const std::uint64_t block = lo / kTargetBlock;
    const std::uint64_t end = std::min(hi, (block + 1) * kTargetBlock);
    RunCounts c(static_cast<int>(outcomes_));
    for (std::uint64_t i = lo; i < end; ++i) {
      const std::size_t k = static_cast<std::size_t>(i - first);
      switch (b.statuses[k]) {
        case 0:
          ++c.settled;
          ++c.faces[static_cast<std::size_t>(b.outcomes[k])];
          break;
        case 1: ++c.unresolved; break;
        default: ++c.invalid; break;
      }
      c.bounces += static_cast<std::uint64_t>(b.bounces[k]);
    }
    // Corrections of the tosses in [lo, end) (only fresh indices reach here: no double counting).
    for (std::size_t j = 0; j < b.corrected_offset.size(); ++j) {
      const std::uint64_t i = first + static_cast<std::uint64_t>(b.corrected_offset[j]);
      if (i < lo || i >= end) continue;
      c.corrections.energy_clamps += static_cast<std::uint64_t>(b.energy_clamps[j]);
      c.corrections.pgs_unconverged += static_cast<std::uint64_t>(b.pgs_unconverged[j]);
      c.corrections.overlap_fixes += static_cast<std::uint64_t>(b.overlap_fixes[j]);
      c.corrections.fallbacks += static_cast<std::uint64_t>(b.fallbacks[j]);
      c.corrections.located_capped += static_cast<std::uint64_t>(b.located_capped[j]);
      c.corrections.support_search_capped += static_cast<std::uint64_t>(b.support_search_capped[j]);
      c.corrections.rise_dropped += static_cast<std::uint64_t>(b.rise_dropped[j]);
      c.corrections.contact_overlaps += static_cast<std::uint64_t>(b.contact_overlaps[j]);
      c.corrections.nudges += static_cast<std::uint64_t>(b.nudges[j]);
    }
    blocks_.try_emplace(block, static_cast<int>(outcomes_)).first->second.merge(c);
    all_.merge(c);
    lo = end;
  }
}

void Aggregator::advance_prefix() {
  while (prefix_end_ < limit_) {
    const std::uint64_t block = prefix_end_ / kTargetBlock;
    const std::uint64_t end = std::min(limit_, (block + 1) * kTargetBlock);
    if (!received_.covers(prefix_end_, end)) return;
    if (auto it = blocks_.find(block); it != blocks_.end()) {
      prefix_.merge(it->second);
      blocks_.erase(it);
    }
    prefix_end_ = end;
    if (cfg_.target_halfwidth > 0.0 && halfwidth_reached(prefix_, cfg_.target_halfwidth)) limit_ = prefix_end_;
  }
  finished_ = true;
}

void Aggregator::finish(double now) {
  finished_ = true;
  leases_.clear();
  // Three copies: a worker that misses all of them still stops when run_start stops.
  for (int i = 0; i < 3; ++i) publish_probabilities(now);
}

void Aggregator::on_status(const dicesim_lcm::worker_status& s, double now) {
  if (s.run_id != 0 && s.run_id != cfg_.spec.run_id) {
    ++health_.foreign;
    return;
  }
  if (s.state < 0 || s.state > 2 || s.n_held > 64 || s.last_done_lease < 0) {
    ++health_.malformed;
    return;
  }
  if (finished_) return;
  Worker& w = workers_[s.worker_id];
  w.last_seen = now;
  w.rate = std::isfinite(s.tosses_per_s) && s.tosses_per_s > 0 ? s.tosses_per_s : 0.0;
  if (s.run_id == 0 || s.state == 0) {  // has not got (or not yet compiled) our run: tell it again
    w.ready = false;
    // At most one announcement per 20 ms (a storm of new workers), but never a lost one: a worker
    // that asked just after an announcement it missed gets the next, from tick, not the periodic one.
    run_start_wanted_ = true;
    if (now - last_run_start_ > 0.02) publish_run_start(), last_run_start_ = now, run_start_wanted_ = false;
    return;
  }
  if (s.state == 2) {
    w.ready = false;
    if (!refused_[s.worker_id]) {
      refused_[s.worker_id] = true;
      refusals_.push_back("worker " + std::to_string(s.worker_id) + " (" + s.host + ", pid " + std::to_string(s.pid) +
                          ") refused the run: " + s.error);
    }
    return;
  }
  w.ready = true;
  const std::unordered_set<std::int64_t> held(s.held_leases.begin(), s.held_leases.end());
  for (auto it = leases_.begin(); it != leases_.end();) {
    Lease& l = it->second;
    if (l.worker != s.worker_id || held.count(l.id)) {
      ++it;
    } else if (l.id <= s.last_done_lease) {
      if (l.done_at < 0) l.done_at = now;  // finished; its last batch may still be on the way
      ++it;
    } else if (now - l.granted > cfg_.lost_lease_s) {
      release(l);  // the worker never received it
      it = leases_.erase(it);
    } else {
      ++it;
    }
  }
  grant(s.worker_id, now);
}

void Aggregator::release(const Lease& l) {
  const std::uint64_t hi = std::min(limit_, l.first + l.count);
  for (const IntervalSet::Range& g : received_.gaps(l.first, hi)) health_.released += requeue_.add(g.first, g.second);
}

void Aggregator::grant(std::int64_t worker, double now) {
  if (finished_) return;
  auto wit = workers_.find(worker);
  if (wit == workers_.end() || !wit->second.ready) return;
  int held = 0;
  std::uint64_t queued = 0;
  for (const auto& [id, l] : leases_)
    if (l.worker == worker && l.done_at < 0) ++held, queued += l.count;
  while (held < cfg_.leases_per_worker) {
    std::uint64_t a = 0, b = 0;
    // Holes first (lowest indices: they hold back the result), then fresh indices.
    while (!requeue_.empty() && b == 0) {
      auto [lo, hi] = requeue_.first();
      if (lo >= limit_) {
        requeue_.remove(lo, ~0ULL);
        break;
      }
      hi = std::min({hi, limit_, lo + cfg_.max_lease});
      requeue_.remove(lo, hi);
      const auto g = received_.gaps(lo, hi);
      if (g.empty()) continue;
      a = g[0].first, b = g[0].second;
      for (std::size_t i = 1; i < g.size(); ++i) requeue_.add(g[i].first, g[i].second);
    }
    if (b == 0 && frontier_ < limit_) {
      // Leases shrink towards the end so that every worker finishes at about the same time.
      const std::uint64_t remaining = limit_ - frontier_;
      const std::uint64_t live = static_cast<std::uint64_t>(std::max(1, live_workers()));
      const std::uint64_t size =
          std::min(remaining, std::clamp<std::uint64_t>(remaining / (2 * live), cfg_.min_lease, cfg_.max_lease));
      a = frontier_, b = frontier_ + size;
      frontier_ = b;
    }
    if (b == 0 && held == 0 && !steal(worker, now, a, b)) return;
    if (b == 0) return;
    Lease l;
    l.id = next_lease_++;
    l.worker = worker;
    l.first = a;
    l.count = b - a;
    l.granted = now;
    queued += l.count;
    const double rate = std::max(wit->second.rate, 500.0);
    l.deadline = now + 3.0 * static_cast<double>(queued) / rate + 2.0 * cfg_.worker_timeout_s;
    leases_[l.id] = l;
    ++held;
    ++health_.leases;
    dicesim_lcm::work_lease m;
    m.utime = wire::now_utime();
    m.run_id = cfg_.spec.run_id;
    m.worker_id = worker;
    m.lease_id = l.id;
    m.first_index = static_cast<std::int64_t>(l.first);
    m.count = static_cast<std::int64_t>(l.count);
    m.deadline_utime = m.utime + static_cast<std::int64_t>((l.deadline - now) * 1e6);
    publish(wire::kWorkLease, m);
  }
}

bool Aggregator::steal(std::int64_t worker, double now, std::uint64_t& a, std::uint64_t& b) {
  // Without this the run ends when its slowest worker has finished both leases it holds (up to
  // 2 x max_lease tosses, tens of ms of `paper` on a quiet machine and far more when another
  // process takes that worker's core) while the others idle.
  Lease* victim = nullptr;
  std::uint64_t lo = 0, hi = 0;
  std::set<std::int64_t> started;  // workers whose lease in progress (their lowest id) was seen
  for (auto& [id, l] : leases_) {  // in id order
    if (l.done_at >= 0) continue;
    const bool in_progress = started.insert(l.worker).second;
    if (l.worker == worker) continue;
    const std::uint64_t end = std::min(limit_, l.first + l.count);
    const auto g = received_.gaps(l.first, end);
    if (g.empty()) continue;
    // A worker tosses its leases in id order and each in index order: it is at about the first
    // missing index of the lease in progress plus the batch it is tossing (as large as its last).
    std::uint64_t at = g.front().first;
    if (in_progress) {
      const auto w = workers_.find(l.worker);
      at += w != workers_.end() ? w->second.batch : 0;
    }
    if (at < end && end - at > hi - lo) victim = &l, lo = at, hi = end;
  }
  // Halves of at least min_lease, so that a split is worth its two messages.
  if (!victim || hi - lo < 2 * cfg_.min_lease) return false;
  const std::uint64_t cut = lo + (hi - lo) / 2;
  victim->count = cut - victim->first;
  ++health_.splits;
  health_.split_tosses += hi - cut;
  // The holder hears its lease again with the same id and a smaller count, and stops at `cut`.
  // Should it not hear it (a lost message, a worker of an older build), it tosses the moved half
  // too: duplicates, which are ignored, never a gap.
  dicesim_lcm::work_lease m;
  m.utime = wire::now_utime();
  m.run_id = cfg_.spec.run_id;
  m.worker_id = victim->worker;
  m.lease_id = victim->id;
  m.first_index = static_cast<std::int64_t>(victim->first);
  m.count = static_cast<std::int64_t>(victim->count);
  m.deadline_utime = m.utime + static_cast<std::int64_t>((victim->deadline - now) * 1e6);
  publish(wire::kWorkLease, m);
  a = cut, b = hi;
  return true;
}

int Aggregator::live_workers() const {
  int n = 0;
  for (const auto& [id, w] : workers_) n += w.ready ? 1 : 0;
  return n;
}

void Aggregator::tick(double now) {
  if (started_ < 0) started_ = rate_t_ = now;
  if (!finished_) {
    if (now - last_run_start_ >= cfg_.run_start_period_s || (run_start_wanted_ && now - last_run_start_ > 0.02))
      publish_run_start(), last_run_start_ = now, run_start_wanted_ = false;
    for (auto it = workers_.begin(); it != workers_.end();) {
      if (now - it->second.last_seen <= cfg_.worker_timeout_s) {
        ++it;
        continue;
      }
      for (auto l = leases_.begin(); l != leases_.end();) {
        if (l->second.worker == it->first) release(l->second), l = leases_.erase(l);
        else ++l;
      }
      it = workers_.erase(it);
    }
    for (auto it = leases_.begin(); it != leases_.end();) {
      const Lease& l = it->second;
      if (received_.covers(l.first, std::min(limit_, l.first + l.count))) {
        it = leases_.erase(it);
      } else if ((l.done_at >= 0 && now - l.done_at > cfg_.done_grace_s) || now > l.deadline) {
        release(l);
        it = leases_.erase(it);
      } else {
        ++it;
      }
    }
    for (const auto& [id, w] : workers_)
      if (w.ready) grant(id, now);
  }
  if (now - last_probabilities_ >= cfg_.probabilities_period_s) publish_probabilities(now);
}

void Aggregator::publish_run_start() { publish(wire::kRunStart, wire::to_message(cfg_.spec)); }

dicesim_lcm::probabilities Aggregator::snapshot() const {
  const RunCounts& c = finished_ ? prefix_ : all_;
  dicesim_lcm::probabilities m;
  m.utime = wire::now_utime();
  m.run_id = cfg_.spec.run_id;
  // Outcomes in label order (the spec's labels are ascending), as the printed table.
  m.n_outcomes = static_cast<std::int32_t>(outcomes_);
  for (std::size_t i = 0; i < outcomes_; ++i) {
    const std::uint64_t n = i < c.faces.size() ? c.faces[i] : 0;
    m.labels.push_back(cfg_.spec.labels[i]);
    m.counts.push_back(static_cast<std::int64_t>(n));
    m.p.push_back(c.settled ? static_cast<double>(n) / static_cast<double>(c.settled) : 0.0);
    const Interval ci = wilson_interval(n, c.settled);
    m.ci_lo.push_back(ci.lo);
    m.ci_hi.push_back(ci.hi);
  }
  m.settled = static_cast<std::int64_t>(c.settled);
  m.unresolved = static_cast<std::int64_t>(c.unresolved);
  m.invalid = static_cast<std::int64_t>(c.invalid);
  m.done = static_cast<std::int64_t>(finished_ ? prefix_end_ : received_.size());
  m.total = static_cast<std::int64_t>(finished_ ? prefix_end_ : cfg_.spec.total);
  m.tosses_per_s = rate_;
  m.finished = finished_ ? 1 : 0;
  m.workers = live_workers();
  m.duplicates = static_cast<std::int64_t>(health_.duplicates);
  m.rejected_foreign = static_cast<std::int64_t>(health_.foreign);
  m.rejected_malformed = static_cast<std::int64_t>(health_.malformed);
  m.rejected_range = static_cast<std::int64_t>(health_.range);
  m.released = static_cast<std::int64_t>(health_.released);
  static_assert(std::size(decltype(m.corrections){}) == RunCorrections::kKinds);
  int kind = 0;
  c.corrections.for_each([&](const char*, std::uint64_t n) { m.corrections[kind++] = static_cast<std::int64_t>(n); });
  m.rejected_unauthenticated = static_cast<std::int64_t>(health_.unauthenticated);
  m.provenance = cfg_.provenance;
  return m;
}

void Aggregator::publish_probabilities(double now) {
  if (now > rate_t_ + 0.5) {  // throughput over the last half second or more
    const double r = static_cast<double>(received_.size() - rate_n_) / (now - rate_t_);
    rate_ = rate_ == 0.0 ? r : 0.5 * rate_ + 0.5 * r;
    rate_t_ = now;
    rate_n_ = received_.size();
  }
  last_probabilities_ = now;
  publish(wire::kProbabilities, snapshot());
}

}  // namespace dicesim::agg
