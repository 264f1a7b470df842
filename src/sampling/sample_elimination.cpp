#include "sampling/sample_elimination.h"

#include "core/neighbor_grid.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace ff::sampling {
namespace {

// A max-heap over sample weights that can lower one entry in place (the elimination lowers the weights of the
// removed sample's neighbours). Ties go to the lower index, so the order is total and the samples popped are the same
// for any heap layout. Four children per node, each entry holding its weight: a node's children are 32 contiguous
// bytes (one or two cache lines), and 1M samples take 11 levels instead of 21 with a weight looked up per child (the
// elimination is serial, and at 1M samples it waited on those lookups).
class WeightHeap {
 public:
  // Takes the weights by value: the caller moves them in, and they are gone once the entries hold them.
  explicit WeightHeap(std::vector<float> weight) : heap_(weight.size()), pos_(weight.size()) {
    for (std::size_t i = 0; i < heap_.size(); ++i) {
      heap_[i] = {weight[i], static_cast<Index>(i)};
      pos_[i] = static_cast<Index>(i);
    }
    for (std::size_t k = heap_.size() / kArity + 1; k-- > 0;)
      if (k < heap_.size()) down(k, heap_[k]);
  }
  std::size_t size() const { return heap_.size(); }
  Index pop() {
    const Index top = heap_[0].index;
    const Entry last = heap_.back();
    heap_.pop_back();
    pos_[top] = kInvalidIndex;
    if (!heap_.empty()) down(0, last);
    return top;
  }
  bool contains(Index i) const { return pos_[i] != kInvalidIndex; }
  void lower(Index i, float by) {
    const std::size_t k = pos_[i];
    Entry e = heap_[k];
    e.weight -= by;
    down(k, e);
  }

 private:
  static constexpr std::size_t kArity = 4;
  struct Entry {
    float weight;
    Index index;
  };
  static bool above(const Entry& a, const Entry& b) {
    return a.weight > b.weight || (a.weight == b.weight && a.index < b.index);
  }
  // Puts `item` at k or below, moving larger children up.
  void down(std::size_t k, const Entry item) {
    const std::size_t n = heap_.size();
    for (;;) {
      const std::size_t first = kArity * k + 1;
      if (first >= n) break;
      std::size_t c = first;
      for (std::size_t o = first + 1; o < std::min(n, first + kArity); ++o)
        if (above(heap_[o], heap_[c])) c = o;
      if (!above(heap_[c], item)) break;
      heap_[k] = heap_[c];
      pos_[heap_[k].index] = static_cast<Index>(k);
      k = c;
    }
    heap_[k] = item;
    pos_[item.index] = static_cast<Index>(k);
  }
  std::vector<Entry> heap_;
  std::vector<Index> pos_;
};

}  // namespace

double volume_r_max(double volume, std::size_t n) { return std::cbrt(volume / (4.0 * std::sqrt(2.0) * double(n))); }
double surface_r_max(double area, std::size_t n) { return std::sqrt(area / (2.0 * std::sqrt(3.0) * double(n))); }

std::vector<Index> eliminate_samples(std::span<const Vec3f> candidates, std::size_t keep, const EliminationParams& params,
                                     core::Progress& progress) {
  const std::size_t m = candidates.size();
  if (keep >= m) {
    std::vector<Index> all(m);
    std::iota(all.begin(), all.end(), Index(0));
    return all;
  }
  // Candidates in cell order, so the neighbour lists are compact (16-bit) and the pair loops local.
  core::NeighborGrid grid(params.d_max);
  grid.build(candidates);
  std::vector<Vec3f> x(candidates.begin(), candidates.end()), scratch;
  const std::vector<Index> order = grid.sorted();  // x[k] = candidates[order[k]]
  core::apply_permutation(x, std::span<const Index>(order), scratch);
  grid.points_were_sorted();
  core::NeighborList nb;
  grid.neighbors(x, nb);

  const float d_max = params.d_max;
  const float d_min = d_max * params.beta * (1.0f - std::pow(float(keep) / float(m), params.gamma));
  auto weight = [&](Index i, Index j) {
    const float d = std::max((x[i] - x[j]).norm(), d_min);
    return d < d_max ? std::pow(1.0f - d / d_max, params.alpha) : 0.0f;
  };
  std::vector<float> w(m);
  core::parallel_for(static_cast<std::int64_t>(m), [&](std::int64_t ii) {
    const auto i = static_cast<Index>(ii);
    float s = 0.0f;
    for (Index j : nb.of(i)) s += weight(i, j);
    w[i] = s;
  });

  // The elimination itself is sequential: each removal changes the weights the next one compares.
  WeightHeap heap(std::move(w));
  const std::size_t remove = m - keep;
  progress.begin("sample elimination", remove);
  for (std::size_t r = 0; r < remove; ++r) {
    const Index i = heap.pop();
    for (Index j : nb.of(i))
      if (heap.contains(j)) heap.lower(j, weight(i, j));
    if ((r & 0xFFFF) == 0) progress.tick(r);
  }
  progress.end();
  std::vector<Index> kept;
  kept.reserve(keep);
  for (Index k = 0; k < m; ++k)
    if (heap.contains(k)) kept.push_back(order[k]);
  std::sort(kept.begin(), kept.end());
  return kept;
}

}  // namespace ff::sampling
