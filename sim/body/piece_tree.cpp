// PieceTree's build: a median split on the longest axis of the pieces' box centres.
#include "sim/body/piece_tree.hpp"

#include <algorithm>
#include <stdexcept>

namespace dicesim {

PieceTree::PieceTree(std::span<const Vec3> lo, std::span<const Vec3> hi, std::span<const int> include) {
  if (lo.size() != hi.size()) throw std::invalid_argument("PieceTree: lo and hi differ in size");
  std::vector<Vec3> centroid(lo.size(), Vec3::Zero());  // per piece (not per slot: slots move)
  std::vector<bool> seen(lo.size(), false);
  for (const int p : include) {
    if (p < 0 || static_cast<std::size_t>(p) >= lo.size())
      throw std::out_of_range("PieceTree: piece index out of range");
    const auto k = static_cast<std::size_t>(p);
    if (seen[k]) throw std::invalid_argument("PieceTree: a piece included twice");
    // The split's order must be a strict weak one: no NaN.
    if (!lo[k].allFinite() || !hi[k].allFinite()) throw std::invalid_argument("PieceTree: a piece's box is not finite");
    seen[k] = true;
    centroid[k] = 0.5 * (lo[k] + hi[k]);
  }
  piece_.assign(include.begin(), include.end());
  if (piece_.empty()) return;
  node_.reserve(2 * piece_.size());
  node_.emplace_back();
  build(0, 0, size(), 0, centroid);
  for (const int p : piece_) {
    lo_.push_back(lo[static_cast<std::size_t>(p)]);
    hi_.push_back(hi[static_cast<std::size_t>(p)]);
  }
  // Each node's box from its pieces' (a leaf) or its children's, which come after it.
  for (auto n = node_.size(); n-- > 0;) {
    Node& x = node_[n];
    if (x.end > x.begin) {
      x.lo = lo_[static_cast<std::size_t>(x.begin)];
      x.hi = hi_[static_cast<std::size_t>(x.begin)];
      for (int s = x.begin + 1; s < x.end; ++s) {
        x.lo = x.lo.cwiseMin(lo_[static_cast<std::size_t>(s)]);
        x.hi = x.hi.cwiseMax(hi_[static_cast<std::size_t>(s)]);
      }
    } else {
      const Node& a = node_[static_cast<std::size_t>(x.child)];
      const Node& b = node_[static_cast<std::size_t>(x.child) + 1];
      x.lo = a.lo.cwiseMin(b.lo);
      x.hi = a.hi.cwiseMax(b.hi);
    }
  }
}

void PieceTree::build(std::size_t node, int begin, int end, int depth, const std::vector<Vec3>& centroid) {
  if (depth > kMaxDepth) throw std::length_error("PieceTree: too deep");  // > 2^47 pieces
  const auto first = piece_.begin() + begin, last = piece_.begin() + end;
  if (end - begin <= kLeafSize) {
    std::sort(first, last);  // a leaf's pieces in index order, whatever the split's order left
    node_[node].begin = begin;
    node_[node].end = end;
    return;
  }
  Vec3 clo = centroid[static_cast<std::size_t>(*first)], chi = clo;
  for (auto it = first; it != last; ++it) {
    clo = clo.cwiseMin(centroid[static_cast<std::size_t>(*it)]);
    chi = chi.cwiseMax(centroid[static_cast<std::size_t>(*it)]);
  }
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  // Ties broken by index: the halves are the same sets whatever the standard library's nth_element.
  const auto before = [&](int a, int b) {
    const double ca = centroid[static_cast<std::size_t>(a)][axis], cb = centroid[static_cast<std::size_t>(b)][axis];
    return ca < cb || (ca == cb && a < b);
  };
  const int mid = begin + (end - begin) / 2;
  std::nth_element(first, piece_.begin() + mid, last, before);
  const std::size_t child = node_.size();
  node_.emplace_back();
  node_.emplace_back();
  node_[node].begin = node_[node].end = begin;
  node_[node].child = static_cast<int>(child);
  build(child, begin, mid, depth + 1, centroid);
  build(child + 1, mid, end, depth + 1, centroid);
}

}  // namespace dicesim
