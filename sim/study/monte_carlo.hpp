// Many tosses on a thread pool. Toss i depends only on (model, seed, i), and counts are sums,
// so the result is identical for any number of threads.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "sim/body/die_model.hpp"
#include "sim/models/toss.hpp"

namespace dicesim {

struct RunCounts {
  RunCounts() = default;
  explicit RunCounts(int outcomes) : faces(static_cast<std::size_t>(outcomes), 0) {}
  // Settled tosses per outcome, in label order (the model's outcome_labels; several faces may
  // share one). Six zeros by default (a d6); run_tosses and the aggregator size it to the model.
  std::vector<std::uint64_t> faces = std::vector<std::uint64_t>(6, 0);
  std::uint64_t settled = 0, unresolved = 0, invalid = 0;
  std::uint64_t bounces = 0;  // impacts over all tosses
  RunCorrections corrections;  // guards and fallbacks over all tosses (sim/dynamics/corrections.hpp)

  std::uint64_t total() const { return settled + unresolved + invalid; }
  void add(const TossResult& r);
  void merge(const RunCounts& o);
  bool operator==(const RunCounts&) const = default;
};

struct RunConfig {
  std::uint64_t seed = 1;
  std::uint64_t first = 0;   // first toss index
  std::uint64_t tosses = 0;  // count
  int threads = 1;
  // Called from a reporter thread about every 100 ms, and once at the end, with (done, total).
  std::function<void(std::uint64_t, std::uint64_t)> progress;
  // Set to true from anywhere to stop early: no new chunk starts; counts cover whole chunks only.
  const std::atomic<bool>* cancel = nullptr;
  // If set: resized to `tosses`, entry i the outcome index (label order) of toss first + i, -1 if
  // it did not settle (a cancelled run's entries past its prefix: unspecified). For paired
  // comparisons of two runs over the same indices (sim/study/equivalence.hpp).
  std::vector<std::int16_t>* outcomes = nullptr;
};

RunCounts run_tosses(const DieModel& m, const RunConfig& cfg);

}  // namespace dicesim
