#include "bridge/run_table.hpp"

#include <algorithm>

namespace dicesim::bridge {

RunTableDef default_run_table_def() { return RunTableDef{}; }

dicesim_dds_run_status to_dds(const RunRecord& r, std::int64_t utime) {
  dicesim_dds_run_status s{};
  s.run_id = r.run_id;
  s.utime = utime;
  s.state = r.state;
  // The sample only borrows the strings: dds_write serializes them before it returns.
  s.origin = const_cast<char*>(r.origin.c_str());
  s.scene_hash = const_cast<char*>(r.scene_hash.c_str());
  s.fidelity = const_cast<char*>(r.fidelity.c_str());
  s.seed = r.seed;
  s.total_tosses = r.total;
  s.done = r.done;
  s.tosses_per_s = r.tosses_per_s;
  s.workers = static_cast<std::int32_t>(r.workers.size());
  s.workers_refused = static_cast<std::int32_t>(r.refused.size());
  s.last_answer_utime = r.last_answer_utime;
  return s;
}

RunRecord& RunTable::record(std::int64_t run_id, double now) {
  auto [it, inserted] = runs_.try_emplace(run_id);
  if (inserted) {
    it->second.run_id = run_id;
    it->second.first_heard = it->second.last_heard = now;
  }
  return it->second;
}

namespace {
void set_state(RunRecord& r, dicesim_dds_run_state s) {
  if (r.state != s) r.state = s, r.changed = true;
}
}  // namespace

void RunTable::on_run_start(const dicesim_lcm::run_start& m, double now) {
  if (m.run_id == 0) return;
  RunRecord& r = record(m.run_id, now);
  if (r.origin != m.origin || r.scene_hash != m.scene_hash) r.changed = true;  // first time, normally
  r.origin = m.origin;
  r.scene_hash = m.scene_hash;
  r.fidelity = m.fidelity;
  r.seed = m.seed;
  if (r.state != dicesim_dds_RUN_FINISHED) r.total = m.total_tosses;
  r.last_heard = now;
  if (r.state == dicesim_dds_RUN_SILENT) set_state(r, r.last_answer_utime ? dicesim_dds_RUN_RUNNING : dicesim_dds_RUN_ANNOUNCED);
}

void RunTable::on_probabilities(const dicesim_lcm::probabilities& m, double now) {
  if (m.run_id == 0) return;
  RunRecord& r = record(m.run_id, now);
  r.done = m.done;
  r.total = m.total;
  r.tosses_per_s = m.tosses_per_s;
  r.last_answer_utime = m.utime;
  r.last_heard = now;
  if (m.finished) set_state(r, dicesim_dds_RUN_FINISHED);
  else if (r.state != dicesim_dds_RUN_FINISHED) set_state(r, dicesim_dds_RUN_RUNNING);
}

void RunTable::on_worker_status(const dicesim_lcm::worker_status& m, double now) {
  // Only runs an aggregator announced: a worker still naming a forgotten run must not revive it.
  auto it = runs_.find(m.run_id);
  if (m.run_id == 0 || it == runs_.end()) return;
  RunRecord& r = it->second;
  if (m.state == 2) {
    if (r.refused.insert(m.worker_id).second) r.changed = true;
    return;
  }
  if (r.workers.find(m.worker_id) == r.workers.end()) r.changed = true;
  r.workers[m.worker_id] = now;
}

std::vector<std::int64_t> RunTable::tick(double now) {
  std::vector<std::int64_t> due;
  for (auto& [id, r] : runs_) {
    for (auto w = r.workers.begin(); w != r.workers.end();) {
      if (now - w->second > def_.worker_timeout_s) {
        w = r.workers.erase(w);
        r.changed = true;
      } else {
        ++w;
      }
    }
    const bool live = r.state == dicesim_dds_RUN_ANNOUNCED || r.state == dicesim_dds_RUN_RUNNING;
    if (live && now - r.last_heard > def_.silent_after_s) set_state(r, dicesim_dds_RUN_SILENT);
    const bool refresh = r.state == dicesim_dds_RUN_RUNNING && now - r.last_published >= def_.status_period_s;
    const bool described = !r.origin.empty() || now - r.first_heard > def_.silent_after_s;
    if (described && (r.changed || refresh)) {
      r.changed = false;
      r.last_published = now;
      due.push_back(id);
    }
  }
  while (runs_.size() > def_.max_runs) {
    auto oldest = std::min_element(runs_.begin(), runs_.end(),
                                   [](const auto& a, const auto& b) { return a.second.last_heard < b.second.last_heard; });
    forgotten_.push_back(oldest->first);
    due.erase(std::remove(due.begin(), due.end(), oldest->first), due.end());
    runs_.erase(oldest);
  }
  return due;
}

std::vector<std::int64_t> RunTable::take_forgotten() {
  std::vector<std::int64_t> out;
  out.swap(forgotten_);
  return out;
}

const RunRecord* RunTable::find(std::int64_t run_id) const {
  auto it = runs_.find(run_id);
  return it == runs_.end() ? nullptr : &it->second;
}

}  // namespace dicesim::bridge
