#include "sim/body/outcome.hpp"
#include "apps/sweep_workers.hpp"

#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "aggregator/session.hpp"
#include "messages/run_spec.hpp"
#include "sim/body/die_model.hpp"

namespace dicesim {

SweepOverLcm::SweepOverLcm(std::string scene_path, std::string url, int local_workers, const std::atomic<bool>* cancel)
    : scene_(std::move(scene_path)), url_(std::move(url)), local_workers_(local_workers), cancel_(cancel) {
  for (int k = 0; k < local_workers_; ++k)
    if (!workers_.spawn(url_, 0)) throw std::runtime_error("cannot start worker process " + std::to_string(k + 1));
}

SweepRunOptions::PointRunner SweepOverLcm::runner() {
  return [this](const DieModel& model, const std::vector<std::string>& overrides, const RunConfig& cfg,
                const std::function<void(std::uint64_t)>& progress) { return run_point(model, overrides, cfg, progress); };
}

RunCounts SweepOverLcm::run_point(const DieModel& model, const std::vector<std::string>& overrides, const RunConfig& cfg,
                                  const std::function<void(std::uint64_t)>& progress) {
  agg::AggregatorConfig ac;
  ac.spec = wire::make_run_spec(wire::new_run_id(), scene_, overrides, model, cfg.seed, cfg.tosses);
  agg::SessionOptions opt;
  opt.url = url_;
  opt.cancel = cancel_;
  const auto t0 = std::chrono::steady_clock::now();
  double last_hint = 0.0;
  opt.on_tick = [&](const agg::Aggregator& agg) -> std::string {
    if (progress) progress(agg.received());
    if (!agg.refusals().empty()) return "a worker refused the run: " + agg.refusals().front();
    if (local_workers_ > 0 && workers_.poll() == 0) return "every worker process exited before the sweep finished";
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (agg.live_workers() == 0 && now - last_hint > 10.0) {
      last_hint = now;
      std::fprintf(stderr, "\ndicesim: no worker has answered on %s for %.0f s (start some: dicesim worker --lcm '%s')\n",
                   url_.c_str(), now, url_.c_str());
    }
    return "";
  };
  const agg::SessionResult res = agg::run_session(opt, ac);
  if (res.end == agg::SessionEnd::Failed) throw std::runtime_error("run " + std::to_string(ac.spec.run_id) + ": " + res.error);
  return res.counts;  // Cancelled: run_sweep sees the cancel flag and drops the point
}

}  // namespace dicesim
