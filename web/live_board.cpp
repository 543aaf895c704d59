// The serve page's state from the bus (live_board.hpp).
#include "web/live_board.hpp"

#include <cmath>

#include "messages/wire.hpp"

namespace dicesim::web {

LiveBoard::LiveBoard(const std::vector<std::uint8_t>& key) : sealer_(key) {}

void LiveBoard::handle(const std::string& channel, const void* data, std::size_t len) {
  const bool answer = channel == wire::kProbabilities, status = channel == wire::kWorkerStatus;
  if (!answer && !status) return;
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
  if (answer) {
    const auto m = wire::decode<dicesim_lcm::probabilities>(data, *n);
    if (!m) {
      ++malformed_;
    } else {
      // A run that has finished stays on the page until another run's answer arrives.
      const double rate = m->tosses_per_s;
      const double left = static_cast<double>(m->total - m->done);
      run_ = {{"run_id", m->run_id}, {"labels", m->labels}, {"counts", m->counts}, {"p", m->p}, {"ci_lo", m->ci_lo},
              {"ci_hi", m->ci_hi}, {"settled", m->settled}, {"unresolved", m->unresolved}, {"invalid", m->invalid},
              {"done", m->done}, {"total", m->total}, {"tosses_per_s", rate},
              {"eta_s", m->finished || rate <= 0.0 ? 0.0 : left / rate}, {"finished", m->finished != 0},
              {"workers", m->workers}, {"duplicates", m->duplicates}, {"rejected_foreign", m->rejected_foreign},
              {"rejected_malformed", m->rejected_malformed}, {"rejected_range", m->rejected_range},
              {"rejected_unauthenticated", m->rejected_unauthenticated}, {"released", m->released}};
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
  return nlohmann::json{{"version", version_},
                        {"run", run_.is_null() ? nlohmann::json() : run_},
                        {"workers", w},
                        {"heard", {{"unauthenticated", unauthenticated_}, {"sealed", sealed_}, {"malformed", malformed_}}},
                        {"key", sealer_.enabled()}}
      .dump();
}

std::uint64_t LiveBoard::wait(std::uint64_t seen, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mu_);
  changed_.wait_for(lock, timeout, [&] { return version_ != seen; });
  return version_;
}

}  // namespace dicesim::web
