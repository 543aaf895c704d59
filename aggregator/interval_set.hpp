// A set of toss indices stored as disjoint half-open ranges [lo, hi). Toss results arrive in
// batches of contiguous indices, out of order and sometimes twice; the set makes "have I got
// index i?" and "what is still missing in [a, b)?" logarithmic, and its size stays the number
// of holes (a few), not the number of tosses.
#pragma once

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace dicesim::agg {

class IntervalSet {
 public:
  using Range = std::pair<std::uint64_t, std::uint64_t>;  // [first, second)

  // Adds [lo, hi). Calls fresh(a, b) for every sub-range that was not present before, in
  // increasing order, before the set changes; returns how many indices were new.
  template <class F>
  std::uint64_t add(std::uint64_t lo, std::uint64_t hi, F&& fresh) {
    if (lo >= hi) return 0;
    std::uint64_t added = 0;
    for (const Range& g : gaps(lo, hi)) {
      fresh(g.first, g.second);
      added += g.second - g.first;
    }
    insert(lo, hi);
    size_ += added;
    return added;
  }
  std::uint64_t add(std::uint64_t lo, std::uint64_t hi) {
    return add(lo, hi, [](std::uint64_t, std::uint64_t) {});
  }

  // Removes [lo, hi) (the indices that were present there).
  void remove(std::uint64_t lo, std::uint64_t hi);

  bool contains(std::uint64_t i) const;
  bool covers(std::uint64_t lo, std::uint64_t hi) const;  // all of [lo, hi) present (true if empty)
  std::vector<Range> gaps(std::uint64_t lo, std::uint64_t hi) const;  // missing parts of [lo, hi)
  // End of the contiguous run that starts at `from` (== from if `from` is absent).
  std::uint64_t run_end(std::uint64_t from) const;

  std::uint64_t size() const { return size_; }  // number of indices
  bool empty() const { return ranges_.empty(); }
  std::size_t ranges() const { return ranges_.size(); }
  Range first() const { return *ranges_.begin(); }  // precondition: !empty()
  const std::map<std::uint64_t, std::uint64_t>& ranges_list() const { return ranges_; }  // lo -> hi, in order

 private:
  void insert(std::uint64_t lo, std::uint64_t hi);
  std::map<std::uint64_t, std::uint64_t> ranges_;  // lo -> hi, disjoint and not touching
  std::uint64_t size_ = 0;
};

}  // namespace dicesim::agg
