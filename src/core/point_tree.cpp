#include "core/point_tree.h"

#include <algorithm>
#include <cassert>
#include <numeric>

namespace ff::core {
namespace {

// Squared distance from q to the box [lo, hi] (0 inside).
inline float box_distance2(const Vec3f& q, const Vec3f& lo, const Vec3f& hi) {
  const Vec3f d = (lo - q).cwiseMax(q - hi).cwiseMax(Vec3f::Zero());
  return d.squaredNorm();
}

}  // namespace

PointTree::PointTree(std::span<const Vec3f> points) {
  assert(points.size() < std::size_t(kInvalidIndex));
  const auto n = static_cast<Index>(points.size());
  if (n == 0) return;
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), Index{0});
  nodes_.reserve(2 * (std::size_t(n) / kLeafSize + 1));
  nodes_.emplace_back();
  build_node(0, 0, n, points);
  points_.resize(n);
  for (Index k = 0; k < n; ++k) points_[k] = points[order_[k]];
}

void PointTree::build_node(Index self, Index begin, Index end, std::span<const Vec3f> input) {
  Aabb box;
  for (Index k = begin; k < end; ++k) box.extend(input[order_[k]]);
  nodes_[self].lo = box.min;
  nodes_[self].hi = box.max;
  const Vec3f size = box.max - box.min;
  // A leaf when small, or when every point is the same (no split would separate them).
  if (end - begin <= kLeafSize || size.maxCoeff() <= 0.0f) {
    nodes_[self].first = begin;
    nodes_[self].count = end - begin;
    return;
  }
  int axis = 0;
  size.maxCoeff(&axis);
  const Index mid = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](Index a, Index b) { return input[a][axis] < input[b][axis]; });
  const auto left = static_cast<Index>(nodes_.size());
  nodes_.emplace_back();
  nodes_.emplace_back();
  nodes_[self].first = left;
  nodes_[self].count = 0;
  build_node(left, begin, mid, input);
  build_node(left + 1, mid, end, input);
}

PointTree::Nearest PointTree::nearest(const Vec3f& q, Index hint) const {
  Nearest best;
  if (nodes_.empty()) return best;
  if (hint < points_.size()) best = {(points_[hint] - q).squaredNorm(), hint};
  // Depth-first, nearer child first; a subtree whose box is no nearer than the best so far is skipped.
  // The tree is balanced (median splits), so its depth is below 2·log2(n) and 128 entries always suffice.
  struct Entry {
    Index node;
    float distance2;
  };
  Entry stack[128];
  int top = 0;
  stack[top++] = {0, box_distance2(q, nodes_[0].lo, nodes_[0].hi)};
  while (top > 0) {
    const Entry e = stack[--top];
    if (!(e.distance2 < best.distance2)) continue;
    const Node& node = nodes_[e.node];
    if (node.count > 0) {
      for (Index k = node.first; k < node.first + node.count; ++k) {
        const float d2 = (points_[k] - q).squaredNorm();
        if (d2 < best.distance2) best = {d2, k};
      }
      continue;
    }
    const Node& a = nodes_[node.first];
    const Node& b = nodes_[node.first + 1];
    const float da = box_distance2(q, a.lo, a.hi), db = box_distance2(q, b.lo, b.hi);
    // Push the farther first so that the nearer is searched first.
    if (da <= db) {
      if (db < best.distance2) stack[top++] = {node.first + 1, db};
      if (da < best.distance2) stack[top++] = {node.first, da};
    } else {
      if (da < best.distance2) stack[top++] = {node.first, da};
      if (db < best.distance2) stack[top++] = {node.first + 1, db};
    }
  }
  return best;
}

Aabb PointTree::bounds() const {
  Aabb box;
  if (!nodes_.empty()) {
    box.min = nodes_[0].lo;
    box.max = nodes_[0].hi;
  }
  return box;
}

std::size_t PointTree::bytes() const {
  return sizeof(*this) + nodes_.capacity() * sizeof(Node) + points_.capacity() * sizeof(Vec3f) +
         order_.capacity() * sizeof(Index);
}

}  // namespace ff::core
