#include "sim/study/monte_carlo.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

namespace dicesim {

void RunCounts::add(const TossResult& r) {
  switch (r.status) {
    case TossStatus::Settled:
      ++settled;
      if (static_cast<std::size_t>(r.outcome) >= faces.size()) faces.resize(static_cast<std::size_t>(r.outcome) + 1, 0);
      ++faces[static_cast<std::size_t>(r.outcome)];
      break;
    case TossStatus::Unresolved: ++unresolved; break;
    case TossStatus::Invalid: ++invalid; break;
  }
  bounces += static_cast<std::uint64_t>(r.bounces);
  corrections.add(r.corrections);
}

void RunCounts::merge(const RunCounts& o) {
  // An empty count (no tosses yet) takes the other's number of outcomes.
  if (total() == 0 && bounces == 0 && o.faces.size() != faces.size() &&
      std::all_of(faces.begin(), faces.end(), [](std::uint64_t c) { return c == 0; }))
    faces.assign(o.faces.size(), 0);
  if (o.faces.size() > faces.size()) faces.resize(o.faces.size(), 0);
  for (std::size_t i = 0; i < o.faces.size(); ++i) faces[i] += o.faces[i];
  settled += o.settled;
  unresolved += o.unresolved;
  invalid += o.invalid;
  bounces += o.bounces;
  corrections.add(o.corrections);
}

RunCounts run_tosses(const DieModel& m, const RunConfig& cfg) {
  // Chunks are claimed in order from one counter; a chunk is small enough to balance two
  // threads on short runs and large enough that the counter is never contended.
  const std::uint64_t chunk = std::clamp<std::uint64_t>(cfg.tosses / 64, 64, 16384);
  const std::uint64_t n_chunks = (cfg.tosses + chunk - 1) / chunk;
  const int threads = static_cast<int>(std::max<std::uint64_t>(1, std::min<std::uint64_t>(cfg.threads, n_chunks)));

  std::atomic<std::uint64_t> next{0}, done{0};
  // Finished chunks join `total` in index order; one finished ahead of a gap waits in `ahead` (at
  // most about one per thread). A cancelled run thus returns exactly the tosses 0..k-1 of its
  // longest complete prefix: the same counts as a run of k tosses (what an interrupted toss reports).
  RunCounts total(m.outcomes());
  if (cfg.outcomes) cfg.outcomes->assign(cfg.tosses, std::int16_t{-1});  // each thread writes its own indices
  std::mutex total_mu;
  std::uint64_t merged_chunks = 0;
  std::map<std::uint64_t, RunCounts> ahead;
  const auto cancelled = [&cfg] { return cfg.cancel && cfg.cancel->load(std::memory_order_relaxed); };
  auto work = [&] {
    for (;;) {
      if (cancelled()) return;
      const std::uint64_t c = next.fetch_add(1, std::memory_order_relaxed);
      if (c >= n_chunks) return;
      const std::uint64_t lo = c * chunk, hi = std::min(cfg.tosses, lo + chunk);
      RunCounts local(m.outcomes());
      for (std::uint64_t i = lo; i < hi; ++i) {
        if (cancelled()) return;  // this chunk is dropped: the prefix ends before it
        const TossResult r = toss(m, cfg.seed, cfg.first + i);
        if (cfg.outcomes && r.status == TossStatus::Settled) (*cfg.outcomes)[i] = static_cast<std::int16_t>(r.outcome);
        local.add(r);
      }
      {
        std::lock_guard lock(total_mu);
        ahead.emplace(c, std::move(local));
        for (auto it = ahead.begin(); it != ahead.end() && it->first == merged_chunks; it = ahead.erase(it), ++merged_chunks)
          total.merge(it->second);
      }
      done.fetch_add(hi - lo, std::memory_order_relaxed);
    }
  };

  {
    std::vector<std::jthread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(work);
    if (!cfg.progress) {
      work();
    } else {
      // The calling thread works too, so progress comes from a mostly sleeping reporter thread,
      // woken at once when the work ends (a plain 100 ms sleep added up to 0.1 s to every run).
      std::mutex mu;
      std::condition_variable cv;
      bool finished = false;
      std::jthread reporter([&] {
        std::unique_lock lock(mu);
        while (!cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return finished; }))
          cfg.progress(done.load(), cfg.tosses);
      });
      work();
      for (auto& th : pool) th.join();
      {
        std::lock_guard lock(mu);
        finished = true;
      }
      cv.notify_one();
    }
  }
  if (cfg.progress) cfg.progress(done.load(), cfg.tosses);
  return total;
}

}  // namespace dicesim
