#include "bridge/translate.hpp"

namespace dicesim::bridge {

dicesim_dds_probabilities to_dds(const dicesim_lcm::probabilities& m) {
  dicesim_dds_probabilities s{};
  s.run_id = m.run_id;
  s.utime = m.utime;
  for (int f = 0; f < 6; ++f) {
    s.face_labels[f] = m.face_labels[f];
    s.counts[f] = m.counts[f];
    s.p[f] = m.p[f];
    s.ci_lo[f] = m.ci_lo[f];
    s.ci_hi[f] = m.ci_hi[f];
  }
  s.settled = m.settled;
  s.unresolved = m.unresolved;
  s.invalid = m.invalid;
  s.done = m.done;
  s.total = m.total;
  s.tosses_per_s = m.tosses_per_s;
  s.finished = m.finished != 0;
  s.workers = m.workers;
  s.duplicates = m.duplicates;
  s.rejected_foreign = m.rejected_foreign;
  s.rejected_malformed = m.rejected_malformed;
  s.rejected_range = m.rejected_range;
  s.released = m.released;
  return s;
}

}  // namespace dicesim::bridge
