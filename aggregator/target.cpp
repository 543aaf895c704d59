#include "aggregator/target.hpp"

#include <algorithm>

#include "sim/study/statistics.hpp"

namespace dicesim::agg {

double max_halfwidth(const RunCounts& c) {
  if (c.settled == 0) return 0.5;
  double w = 0.0;
  for (std::uint64_t k : c.faces) w = std::max(w, wilson_interval(k, c.settled).half_width());
  return w;
}

RunCounts run_to_target(const DieModel& model, RunConfig cfg, std::uint64_t cap, double h, std::uint64_t& done) {
  RunCounts total;
  const auto progress = cfg.progress;
  const auto cancelled = [&cfg] { return cfg.cancel && cfg.cancel->load(); };
  for (done = 0; done < cap && !halfwidth_reached(total, h) && !cancelled();) {
    cfg.first = done;
    cfg.tosses = std::min(kTargetBlock, cap - done);
    const std::uint64_t base = done;
    if (progress) cfg.progress = [&](std::uint64_t d, std::uint64_t) { progress(base + d, cap); };
    const RunCounts block = run_tosses(model, cfg);  // all of it, or a prefix when cancelled
    total.merge(block);
    done += block.total();
  }
  return total;
}

}  // namespace dicesim::agg
