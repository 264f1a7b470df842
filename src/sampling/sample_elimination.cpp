#include "sampling/sample_elimination.h"

#include "core/neighbor_grid.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace ff::sampling {
namespace {

// A binary max-heap over sample weights that can lower one entry in place (the elimination lowers
// the weights of the removed sample's neighbours). Ties go to the lower index, so the order is total.
class WeightHeap {
 public:
  explicit WeightHeap(std::vector<float> weight) : w_(std::move(weight)), heap_(w_.size()), pos_(w_.size()) {
    std::iota(heap_.begin(), heap_.end(), Index(0));
    for (std::size_t i = 0; i < heap_.size(); ++i) pos_[heap_[i]] = static_cast<Index>(i);
    for (std::size_t i = heap_.size() / 2; i-- > 0;) down(i);
  }
  std::size_t size() const { return heap_.size(); }
  Index pop() {
    const Index top = heap_[0];
    move(heap_.size() - 1, 0);
    heap_.pop_back();
    pos_[top] = kInvalidIndex;
    if (!heap_.empty()) down(0);
    return top;
  }
  bool contains(Index i) const { return pos_[i] != kInvalidIndex; }
  void lower(Index i, float by) {
    w_[i] -= by;
    down(pos_[i]);
  }

 private:
  bool above(Index a, Index b) const { return w_[a] > w_[b] || (w_[a] == w_[b] && a < b); }
  void move(std::size_t from, std::size_t to) {
    heap_[to] = heap_[from];
    pos_[heap_[to]] = static_cast<Index>(to);
  }
  void down(std::size_t k) {
    const Index item = heap_[k];
    const std::size_t n = heap_.size();
    for (;;) {
      std::size_t c = 2 * k + 1;
      if (c >= n) break;
      if (c + 1 < n && above(heap_[c + 1], heap_[c])) ++c;
      if (!above(heap_[c], item)) break;
      move(c, k);
      k = c;
    }
    heap_[k] = item;
    pos_[item] = static_cast<Index>(k);
  }
  std::vector<float> w_;
  std::vector<Index> heap_, pos_;
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
