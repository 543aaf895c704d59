// The serve page's state from the bus (live_board.hpp).
#include "web/live_board.hpp"

#include <cmath>

#include "messages/wire.hpp"

namespace dicesim::web {

LiveBoard::LiveBoard(const std::vector<std::uint8_t>& key, std::uint64_t trace_every) : sealer_(key), trace_every_(trace_every) {}

void LiveBoard::handle(const std::string& channel, const void* data, std::size_t len) {
  const bool answer = channel == wire::kProbabilities, status = channel == wire::kWorkerStatus;
  const bool start = trace_every_ > 0 && channel == wire::kRunStart;
  if (!answer && !status && !start) return;
  std::lock_guard lock(mu_);
  const auto n = sealer_.open(channel, data, len);
  // Without a key a sealed message would open whole: it is counted, not shown (this server cannot
  // tell a genuine run from a forgery without the key).
  const bool sealed_unread = !sealer_.enabled() && wire::looks_sealed(data, len);
  if (!n || sealed_unread) {
    ++(sealed_unread ? sealed_ : unauthenticated_);
    ++version_;
    changed_.notify_all();
    return;
  }
  if (start) {
    // Repeated every second: kept (and the page told) only when it describes another run.
    const auto m = wire::decode<dicesim_lcm::run_start>(data, *n);
    if (!m) {
      ++malformed_;
    } else if (!spec_ || spec_->run_id != m->run_id) {
      spec_ = wire::from_message(*m);
      ++version_;
      changed_.notify_all();
    }
    return;
  }
  if (answer) {
    const auto m = wire::decode<dicesim_lcm::probabilities>(data, *n);
    if (!m) {
      ++malformed_;
    } else {
      // A run that has finished stays on the page until another run's answer arrives.
      const double rate = m->tosses_per_s;
      const double left = static_cast<double>(m->total - m->done);
      run_ = {{"run_id", m->run_id}, {"run_id_text", std::to_string(m->run_id)}, {"labels", m->labels}, {"counts", m->counts}, {"p", m->p}, {"ci_lo", m->ci_lo},
              {"ci_hi", m->ci_hi}, {"settled", m->settled}, {"unresolved", m->unresolved}, {"invalid", m->invalid},
              {"done", m->done}, {"total", m->total}, {"tosses_per_s", rate},
              {"eta_s", m->finished || rate <= 0.0 ? 0.0 : left / rate}, {"finished", m->finished != 0},
              {"workers", m->workers}, {"duplicates", m->duplicates}, {"rejected_foreign", m->rejected_foreign},
              {"rejected_malformed", m->rejected_malformed}, {"rejected_range", m->rejected_range},
              {"rejected_unauthenticated", m->rejected_unauthenticated}, {"released", m->released}};
      run_id_ = m->run_id;
      provenance_ = nlohmann::json::parse(m->provenance, nullptr, /*allow_exceptions=*/false);
      if (provenance_.is_discarded()) provenance_ = nullptr;
    }
  } else {
    const auto m = wire::decode<dicesim_lcm::worker_status>(data, *n);
    if (!m) {
      ++malformed_;
    } else {
      static const char* const states[] = {"idle", "ready", "refused"};
      workers_[m->worker_id] = {{{"id", m->worker_id}, {"host", m->host}, {"pid", m->pid}, {"run_id", m->run_id},
                                 {"state", m->state >= 0 && m->state <= 2 ? states[m->state] : "?"}, {"error", m->error},
                                 {"tosses_done", m->tosses_done}, {"tosses_per_s", m->tosses_per_s}},
                                std::chrono::steady_clock::now()};
    }
  }
  ++version_;
  changed_.notify_all();
}

std::string LiveBoard::json(std::uint64_t* version) const {
  std::lock_guard lock(mu_);
  const auto now = std::chrono::steady_clock::now();
  nlohmann::json w = nlohmann::json::array();
  for (const auto& [id, worker] : workers_) {
    nlohmann::json j = worker.last;
    const double age = std::chrono::duration<double>(now - worker.heard).count();
    j["age_s"] = std::round(age * 10.0) / 10.0;
    // Heartbeats come every 200 ms: a second without one is late, five silent.
    j["health"] = age < 1.0 ? "ok" : age < 5.0 ? "late" : "silent";
    w.push_back(std::move(j));
  }
  if (version) *version = version_;
  nlohmann::json trace;
  if (trace_every_ > 0 && !run_.is_null()) {
    const auto done = run_["done"].get<std::int64_t>();
    trace = {{"every", trace_every_}, {"run", std::to_string(run_id_)},
             {"index", done > 0 ? nlohmann::json(trace_every_ * ((static_cast<std::uint64_t>(done) - 1) / trace_every_)) : nlohmann::json()},
             {"run_start", spec_ && spec_->run_id == run_id_}};
  }
  return nlohmann::json{{"trace", trace},{"version", version_},
                        {"run", run_.is_null() ? nlohmann::json() : run_},
                        {"workers", w},
                        {"heard", {{"unauthenticated", unauthenticated_}, {"sealed", sealed_}, {"malformed", malformed_}}},
                        {"key", sealer_.enabled()}}
      .dump();
}

std::optional<wire::RunSpec> LiveBoard::run_spec(std::int64_t run_id) const {
  std::lock_guard lock(mu_);
  if (spec_ && spec_->run_id == run_id) return spec_;
  return std::nullopt;
}

nlohmann::json LiveBoard::provenance(std::int64_t run_id) const {
  std::lock_guard lock(mu_);
  return run_id == run_id_ ? provenance_ : nlohmann::json();
}

std::uint64_t LiveBoard::wait(std::uint64_t seen, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mu_);
  changed_.wait_for(lock, timeout, [&] { return version_ != seen; });
  return version_;
}

}  // namespace dicesim::web
