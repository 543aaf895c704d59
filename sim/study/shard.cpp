#include "sim/study/shard.hpp"

#include <charconv>
#include <stdexcept>

namespace dicesim {

IndexRange shard_range(std::uint64_t total, Shard s) {
  // 128-bit products: total (up to 2^40) times N (up to 1e6) does not fit 64 bits.
  const auto at = [&](std::uint64_t i) {
    return static_cast<std::uint64_t>(static_cast<unsigned __int128>(total) * i / s.count);
  };
  const std::uint64_t lo = at(s.index), hi = at(s.index + 1);
  return {lo, hi - lo};
}

Shard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  const auto number = [&](std::size_t from, std::size_t to, std::uint64_t& v) {
    const char* b = text.data() + from;
    const char* e = text.data() + to;
    const auto [p, ec] = std::from_chars(b, e, v);
    return b != e && ec == std::errc() && p == e;
  };
  Shard s;
  if (slash == std::string::npos || !number(0, slash, s.index) || !number(slash + 1, text.size(), s.count))
    throw std::invalid_argument("'" + text + "' is not I/N (shard I of N, e.g. 0/16)");
  if (s.count < 1 || s.count > 1000000)
    throw std::invalid_argument("'" + text + "': N must be in 1..1000000");
  if (s.index >= s.count)
    throw std::invalid_argument("'" + text + "': I must be in 0..N-1 (shards count from 0, as Slurm array task ids do)");
  return s;
}

}  // namespace dicesim
