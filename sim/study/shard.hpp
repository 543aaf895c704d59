// A run's index range cut into N shards for batch schedulers (Slurm job arrays, Kubernetes
// Indexed Jobs): shard I of N tosses one contiguous block, so N shards of a run toss exactly the
// indices of the whole run, and their counts add up to the whole run's counts.
#pragma once

#include <cstdint>
#include <string>

namespace dicesim {

struct Shard {
  std::uint64_t index = 0;  // 0 .. count-1 (a Slurm array task id, a Kubernetes completion index)
  std::uint64_t count = 1;
};

struct IndexRange {
  std::uint64_t first = 0;   // first toss index
  std::uint64_t tosses = 0;  // count
};

// Shard I of N over tosses 0 .. total-1: [floor(total*I/N), floor(total*(I+1)/N)). Block sizes differ
// by at most one; a shard may be empty when N > total.
IndexRange shard_range(std::uint64_t total, Shard s);

// "I/N" with 0 <= I < N <= 1e6. Throws std::invalid_argument saying what is wrong.
Shard parse_shard(const std::string& text);

}  // namespace dicesim
