#include "bridge/translate.hpp"

#include <cstdint>
#include <iterator>
#include <vector>

namespace dicesim::bridge {

namespace {
// A bounded DDS sequence viewing a vector (Cyclone does not free a buffer with _release false).
template <class Seq, class T>
Seq view(const std::vector<T>& v) {
  Seq s{};
  s._maximum = s._length = static_cast<std::uint32_t>(v.size());
  s._buffer = const_cast<T*>(v.data());
  s._release = false;
  return s;
}
}  // namespace

dicesim_dds_probabilities_v3 to_dds(const dicesim_lcm::probabilities& m) {
  dicesim_dds_probabilities_v3 s{};
  s.run_id = m.run_id;
  s.utime = m.utime;
  // decode() admits 1..120 outcomes, the sequences' bound.
  s.labels = view<dds_sequence_long>(m.labels);
  s.counts = view<dds_sequence_long_long>(m.counts);
  s.p = view<dds_sequence_double>(m.p);
  s.ci_lo = view<dds_sequence_double>(m.ci_lo);
  s.ci_hi = view<dds_sequence_double>(m.ci_hi);
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
  s.rejected_unauthenticated = m.rejected_unauthenticated;
  static_assert(std::size(decltype(s.corrections){}) == std::size(decltype(m.corrections){}));
  for (std::size_t k = 0; k < std::size(s.corrections); ++k) s.corrections[k] = m.corrections[k];
  // A view, as the sequences (the sample is written before m goes away).
  s.provenance = const_cast<char*>(m.provenance.c_str());
  return s;
}

}  // namespace dicesim::bridge
