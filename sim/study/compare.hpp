// Are two sets of face counts (two runs, or a run and a real experiment) statistically
// different? Pearson chi-square test of homogeneity on the 2 x k table, and each face's
// difference of proportions with a 95% interval (Newcombe's hybrid score interval, built from
// the two Wilson intervals: it stays inside [-1, 1] and behaves for small counts).
// Pure computation: nothing here prints.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/study/statistics.hpp"

namespace dicesim {

// Counts by face label; labels are unique.
struct FaceCounts {
  std::vector<int> labels;
  std::vector<std::uint64_t> counts;
  std::uint64_t total() const;
};

struct FaceDifference {
  int label = 0;
  std::uint64_t count_a = 0, count_b = 0;
  double p_a = 0.0, p_b = 0.0;
  double diff = 0.0;   // p_a - p_b
  Interval ci95;       // of p_a - p_b
};

struct Comparison {
  std::uint64_t n_a = 0, n_b = 0;
  ChiSquare chi2;                 // homogeneity, dof = (faces used) - 1
  double min_expected = 0.0;      // smallest expected cell count (< 5: the chi-square p is rough)
  std::vector<FaceDifference> faces;  // by label, ascending
};

// Pearson chi-square of homogeneity for two count vectors over the same categories; categories
// empty in both are left out.
ChiSquare chi2_homogeneity(const std::vector<std::uint64_t>& a, const std::vector<std::uint64_t>& b,
                           double* min_expected = nullptr);

// Newcombe's hybrid score interval (method 10) for p_a - p_b.
Interval difference_interval(std::uint64_t x_a, std::uint64_t n_a, std::uint64_t x_b, std::uint64_t n_b,
                             double z = kZ95);

// Observed (or simulated) counts from a file: the output of `dicesim toss --json` (faces[].face,
// faces[].count), or a CSV face,count with an optional header and '#' comments. Throws SceneError
// naming the file, the line and what is allowed; at least 2 faces, not all 0.
FaceCounts read_face_counts(const std::string& path);

// Per-toss outcomes (`dicesim toss --outcomes FILE`): '#' comment lines, then one line per toss in
// index order, its outcome label, or -1 for a toss that did not settle. Throws SceneError naming
// the file and line.
std::vector<int> read_toss_outcomes(const std::string& path);

// Compares two results. The label sets must be equal (throws std::invalid_argument otherwise).
Comparison compare_counts(const FaceCounts& a, const FaceCounts& b);

}  // namespace dicesim
