// "Stop when every face's 95% half-width is <= H", made deterministic: tosses are judged in
// fixed blocks in index order, and a run stops at the first block boundary where the criterion
// holds. The stopping point depends only on (scene, seed, H), never on threads or workers, so
// `toss --target-halfwidth` and `run --target-halfwidth` agree to the toss.
#pragma once

#include <cstdint>

#include "sim/study/monte_carlo.hpp"

namespace dicesim::agg {

inline constexpr std::uint64_t kTargetBlock = 10000;

// Widest 95% Wilson half-width over the die's outcomes (over settled tosses; 0.5 when none settled).
double max_halfwidth(const RunCounts& c);
inline bool halfwidth_reached(const RunCounts& c, double h) { return c.settled > 0 && max_halfwidth(c) <= h; }

// In this process (`toss --target-halfwidth`, the Python module): blocks of kTargetBlock in index
// order from cfg.first = 0, stopping at the first block boundary where halfwidth_reached(h), after
// `cap` tosses, or when cfg.cancel is set. `done` receives the tosses taken; cfg.progress (if any)
// sees (done, cap) over the whole run.
RunCounts run_to_target(const DieModel& model, RunConfig cfg, std::uint64_t cap, double h, std::uint64_t& done);

}  // namespace dicesim::agg
