#include "aggregator/interval_set.hpp"

#include <algorithm>
#include <iterator>

namespace dicesim::agg {

void IntervalSet::insert(std::uint64_t lo, std::uint64_t hi) {
  // Merge with every range that overlaps or touches [lo, hi).
  auto it = ranges_.upper_bound(lo);
  if (it != ranges_.begin()) {
    auto prev = std::prev(it);
    if (prev->second >= lo) {
      lo = prev->first;
      hi = std::max(hi, prev->second);
      it = ranges_.erase(prev);
    }
  }
  while (it != ranges_.end() && it->first <= hi) {
    hi = std::max(hi, it->second);
    it = ranges_.erase(it);
  }
  ranges_.emplace_hint(it, lo, hi);
}

void IntervalSet::remove(std::uint64_t lo, std::uint64_t hi) {
  if (lo >= hi) return;
  auto it = ranges_.upper_bound(lo);
  if (it != ranges_.begin()) --it;
  while (it != ranges_.end() && it->first < hi) {
    const std::uint64_t a = it->first, b = it->second;
    if (b <= lo) {
      ++it;
      continue;
    }
    it = ranges_.erase(it);
    size_ -= std::min(b, hi) - std::max(a, lo);
    if (a < lo) ranges_.emplace(a, lo);
    if (b > hi) {
      ranges_.emplace(hi, b);
      break;
    }
  }
}

bool IntervalSet::contains(std::uint64_t i) const {
  auto it = ranges_.upper_bound(i);
  return it != ranges_.begin() && std::prev(it)->second > i;
}

bool IntervalSet::covers(std::uint64_t lo, std::uint64_t hi) const {
  if (lo >= hi) return true;
  auto it = ranges_.upper_bound(lo);
  return it != ranges_.begin() && std::prev(it)->second >= hi;
}

std::vector<IntervalSet::Range> IntervalSet::gaps(std::uint64_t lo, std::uint64_t hi) const {
  std::vector<Range> out;
  if (lo >= hi) return out;
  auto it = ranges_.upper_bound(lo);
  if (it != ranges_.begin() && std::prev(it)->second > lo) lo = std::prev(it)->second;
  for (; lo < hi; ++it) {
    if (it == ranges_.end() || it->first >= hi) {
      out.emplace_back(lo, hi);
      break;
    }
    if (it->first > lo) out.emplace_back(lo, it->first);
    lo = it->second;
  }
  return out;
}

std::uint64_t IntervalSet::run_end(std::uint64_t from) const {
  auto it = ranges_.upper_bound(from);
  if (it == ranges_.begin()) return from;
  --it;
  return it->second > from ? it->second : from;
}

}  // namespace dicesim::agg
