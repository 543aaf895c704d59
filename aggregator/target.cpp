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

}  // namespace dicesim::agg
