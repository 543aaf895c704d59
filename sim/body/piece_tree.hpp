// A static broad phase over a world's obstacle pieces: an axis-aligned bounding box tree of the
// pieces' boxes (World::piece_lo, piece_hi), built once with the scene, so that a toss visits only
// the pieces near a die instead of all of them (a craps backboard is ~320 pyramids) every step.
// Half-space pieces have no box; the caller visits them itself.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "sim/math.hpp"

namespace dicesim {

class PieceTree {
 public:
  PieceTree() = default;
  // Over the pieces `include` (indices into lo and hi, each once).
  PieceTree(std::span<const Vec3> lo, std::span<const Vec3> hi, std::span<const int> include);

  // A lower bound on the gap between a sphere and anything inside the box [lo, hi]: the distance
  // from the centre to the box (0 inside it) minus the radius.
  static double box_gap(const Vec3& lo, const Vec3& hi, const Vec3& centre, double radius) {
    const Vec3 d = (lo - centre).cwiseMax(centre - hi).cwiseMax(0.0);
    return std::sqrt(d.x() * d.x() + d.y() * d.y() + d.z() * d.z()) - radius;
  }

  // Calls f(piece, gap) for every piece whose box_gap(...) `gap` is <= reach, where f returns the
  // reach from then on (it may shrink it as it learns of nearer pieces) or returns nothing (reach
  // fixed). The nearer child first, so that a shrinking reach prunes early; the order depends only
  // on the boxes and the sphere. A node's box is its pieces' min and max (exact), so its gap is
  // never above theirs: it visits exactly what a loop over every piece would.
  template <class F>
  void visit_near(const Vec3& centre, double radius, double reach, F&& f) const;

  // The pieces it holds, in leaf order.
  std::span<const int> pieces() const { return piece_; }
  int size() const { return static_cast<int>(piece_.size()); }

 private:
  struct Node {
    Vec3 lo, hi;     // bounds every piece below it
    int begin = 0;   // a leaf: its pieces are slots [begin, end); an inner node: end == begin
    int end = 0;
    int child = 0;   // an inner node: its children are nodes child and child + 1
  };
  static constexpr int kLeafSize = 4;
  // A median split halves the count at each level, so depth <= log2(pieces) + 1; the traversal's
  // stack holds at most one pending sibling per level.
  static constexpr int kMaxDepth = 48;

  // Makes `node` over slots [begin, end), reordering them: a leaf, or the parent of two halves.
  void build(std::size_t node, int begin, int end, int depth, const std::vector<Vec3>& centroid);

  std::vector<Node> node_;      // node 0 is the root
  std::vector<int> piece_;      // per slot: the piece's index
  std::vector<Vec3> lo_, hi_;   // per slot: the piece's box (beside each other for a leaf's scan)
};

template <class F>
void PieceTree::visit_near(const Vec3& centre, double radius, double reach, F&& f) const {
  if (node_.empty()) return;
  struct Pending {
    int node;
    double gap;
  };
  std::array<Pending, kMaxDepth + 2> stack;
  int top = 0;
  stack[top++] = {0, box_gap(node_[0].lo, node_[0].hi, centre, radius)};
  while (top > 0) {
    const Pending at = stack[--top];
    if (!(at.gap <= reach)) continue;  // reach may have shrunk since it was pushed
    const Node& n = node_[static_cast<std::size_t>(at.node)];
    if (n.end > n.begin) {
      for (int s = n.begin; s < n.end; ++s) {
        const auto k = static_cast<std::size_t>(s);
        const double gap = box_gap(lo_[k], hi_[k], centre, radius);
        if (!(gap <= reach)) continue;
        if constexpr (std::is_void_v<std::invoke_result_t<F&, int, double>>) {
          f(piece_[k], gap);
        } else {
          reach = f(piece_[k], gap);
        }
      }
      continue;
    }
    const Node& a = node_[static_cast<std::size_t>(n.child)];
    const Node& b = node_[static_cast<std::size_t>(n.child) + 1];
    Pending near{n.child, box_gap(a.lo, a.hi, centre, radius)};
    Pending far{n.child + 1, box_gap(b.lo, b.hi, centre, radius)};
    if (far.gap < near.gap) std::swap(near, far);  // a tie: the first child first
    if (far.gap <= reach) stack[top++] = far;
    if (near.gap <= reach) stack[top++] = near;
  }
}

}  // namespace dicesim
