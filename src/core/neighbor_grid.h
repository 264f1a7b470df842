#pragma once
// Uniform-grid neighbour search with compact (CSR) neighbour lists: the cell-sorted fixed-radius search of
// Green ("Particle Simulation using CUDA", NVIDIA 2010) and Hoetzlein ("Fast Fixed-Radius Nearest Neighbors",
// GTC 2014), with Ihmsen et al.'s hashed fallback for sparse domains ("A Parallel SPH Implementation on Multi-Core
// CPUs", CGF 2011) and compressed lists in the spirit of Band et al. ("Compressed Neighbour Lists for SPH", CGF 2020).
//
// Points are binned into cubic cells of edge `radius` by a stable parallel counting sort, so each
// cell's points are one contiguous run of `sorted()`. Queries are answered one cell at a time: the
// candidates of the 27 surrounding cells are gathered once into a small SoA buffer and every point of
// the cell filters them four at a time (SSE), so the per-cell work is shared by ~8 points.
// Dense bounding-box cell keys are used while the box has few cells; a domain that is large relative to
// the particle count falls back to a hashed key space of ~N buckets (collisions are harmless:
// candidates are filtered by distance, and duplicate buckets among the 27 are skipped).
//
// Compact lists. Once the caller has re-ordered its points by cell (`points_were_sorted()`), the
// neighbours of a point lie in 9 runs of the point order: the x-rows (x−1 .. x+1) of the 9 (y, z)
// neighbour rows. A neighbour is then stored in 16 bits, as (row, offset within the row), and decoded
// against the row starts (`cell_start`). That halves the largest array of the solver (≈30 neighbours
// per particle). Lists fall back to plain 32-bit indices when the points are not in cell order, the
// keys are hashed, or a row holds more than 4096 points (a pathological clump).
//
// Determinism: lists depend only on the input, never on the thread count: the sort is stable, and each
// point's list is filled in a fixed (row, offset) order (the brute-force oracle is in
// tests/core/neighbor_grid_test.cpp).
#include "core/types.h"

#include <array>
#include <memory>
#include <utility>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::core {

/// std::allocator that default-initialises: growing a buffer that is about to be overwritten skips the
/// zero fill (the neighbour search resizes its output ahead of SIMD stores).
template <class T>
struct NoInitAllocator : std::allocator<T> {
  using std::allocator<T>::allocator;
  template <class U>
  struct rebind { using other = NoInitAllocator<U>; };
  template <class U>
  void construct(U* p) noexcept { ::new (static_cast<void*>(p)) U; }
  template <class U, class... A>
  void construct(U* p, A&&... a) { ::new (static_cast<void*>(p)) U(std::forward<A>(a)...); }
};
template <class T>
using Buffer = std::vector<T, NoInitAllocator<T>>;

/// The neighbours of one point: random access and range-for, decoding compact entries on the fly.
class NeighborRange {
 public:
  static constexpr int kRowBits = 12;                       ///< offset bits of a compact entry
  static constexpr std::uint32_t kRowMask = (1u << kRowBits) - 1;
  static constexpr int kRows = 9;

  std::size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  /// The plain 32-bit entries of a wide list (nullptr for a compact one): pair loops read them in place.
  const Index* wide() const { return wide_; }
  Index operator[](std::size_t k) const {
    if (wide_) return wide_[k];
    const std::uint32_t c = code_[k];
    return base_[c >> kRowBits] + (c & kRowMask);
  }

  /// Writes neighbours [from, from + count) to out (decoded): the SIMD pair loops work on batches.
  void decode(std::size_t from, std::size_t count, Index* out) const {
    if (wide_) {
      for (std::size_t k = 0; k < count; ++k) out[k] = wide_[from + k];
      return;
    }
    for (std::size_t k = 0; k < count; ++k) {
      const std::uint32_t c = code_[from + k];
      out[k] = base_[c >> kRowBits] + (c & kRowMask);
    }
  }

  class iterator {
   public:
    using value_type = Index;
    using difference_type = std::ptrdiff_t;
    iterator() = default;
    iterator(const NeighborRange* r, std::size_t k) : r_(r), k_(k) {}
    Index operator*() const { return (*r_)[k_]; }
    iterator& operator++() { ++k_; return *this; }
    iterator operator++(int) { iterator t = *this; ++k_; return t; }
    bool operator==(const iterator& o) const { return k_ == o.k_; }
   private:
    const NeighborRange* r_ = nullptr;
    std::size_t k_ = 0;
  };
  iterator begin() const { return {this, 0}; }
  iterator end() const { return {this, n_}; }

 private:
  friend struct NeighborList;
  const Index* wide_ = nullptr;
  const std::uint16_t* code_ = nullptr;
  std::size_t n_ = 0;
  Index base_[kRows] = {};
};

/// Neighbour lists in CSR form, stored as one segment per thread chunk so a single pass can fill them
/// without an extra count pass or a copy. Neighbours of i: `of(i)` (self excluded, order deterministic).
/// A compact list borrows the grid's cell table: it is valid until that grid is built again.
struct NeighborList {
  std::size_t count = 0;                       ///< number of query points
  std::size_t chunk = 1;                       ///< query points per segment (the last may be shorter)
  std::uint64_t chunk_inverse = 0;             ///< ⌊(2⁶⁴ − 1) / chunk⌋ + 1, for the division in of()
  bool compact = false;                        ///< entries are 16-bit (row, offset) codes
  std::vector<Buffer<Index>> index;            ///< wide: per segment, concatenated neighbour indices
  std::vector<Buffer<std::uint16_t>> code;     ///< compact: per segment, concatenated codes
  std::vector<std::vector<Index>> offset;      ///< per segment: local offsets, size = points in segment + 1
  // Decoding context of compact lists (borrowed from the grid).
  const Index* cell_key = nullptr;             ///< per point: its cell key
  const Index* cell_start = nullptr;           ///< per cell: first point
  std::array<std::int64_t, NeighborRange::kRows> row_key{};  ///< key of each row's first cell − point's key

  NeighborRange of(std::size_t i) const {
    NeighborRange r;
    // i / chunk by Lemire's multiply (exact for 32-bit i): every pair loop calls this once per particle.
    // (chunk = 1 has no 64-bit inverse: there the segment is i itself.)
    const std::size_t s =
        chunk == 1 ? i : static_cast<std::size_t>((static_cast<__uint128_t>(chunk_inverse) * i) >> 64);
    const std::size_t l = i - std::size_t(s) * chunk;
    const auto& off = offset[s];
    r.n_ = off[l + 1] - off[l];
    if (!compact) {
      r.wide_ = index[s].data() + off[l];
    } else {
      r.code_ = code[s].data() + off[l];
      if (r.n_) {  // a point without neighbours may sit in a border cell whose rows are out of range
        const std::int64_t key = cell_key[i];
        for (int k = 0; k < NeighborRange::kRows; ++k) r.base_[k] = cell_start[key + row_key[static_cast<std::size_t>(k)]];
      }
    }
    return r;
  }
  std::size_t size() const { return count; }
  /// Total number of (point, neighbour) entries.
  std::size_t total() const;
  /// Bytes held (capacity), for the solver's memory estimate.
  std::size_t bytes() const;
};

class NeighborGrid {
 public:
  /// `radius` (metres, > 0) is both the cell edge and the largest query radius. Cell keys are dense (a table of
  /// every cell of the points' box, and compact lists) while the box has at most `dense_cells_per_point` cells per
  /// point, else hashed. 2 suits cells about the size of the spacing; a grid of cells smaller than the spacing (the
  /// sampler's spacing repair, 0.85 d) has ~6 per point in a bunny's box, where hashing made it 4–6× slower.
  explicit NeighborGrid(float radius, double dense_cells_per_point = 2.0)
      : radius_(radius), dense_cells_per_point_(dense_cells_per_point) {}

  float radius() const { return radius_; }

  /// Bins `points`. Afterwards `sorted()` lists point indices grouped by cell (stable: ascending within a cell).
  void build(std::span<const Vec3f> points);

  /// Point indices in cell order: the permutation that a caller may apply to its arrays for locality
  /// (new[i] = old[sorted()[i]]); then call `points_were_sorted()` so the grid refers to the new order.
  const std::vector<Index>& sorted() const { return sorted_; }
  void points_were_sorted();

  /// For every binned point i: all other binned points j with |x_i − x_j| < radius. `points` must be the
  /// array given to build() (or its sorted copy after points_were_sorted()). Compact when it can be.
  void neighbors(std::span<const Vec3f> points, NeighborList& out) const;

  /// For every query point q: all binned points j with |q − x_j| < r (r ≤ radius()). Always wide.
  void query(std::span<const Vec3f> binned, std::span<const Vec3f> queries, float r, NeighborList& out) const;

  /// For every query point q: hit[q] = 1 when some binned point j has |q − x_j| < r (r ≤ radius()), else 0. Stops
  /// at the first such point, starting with q's own cell: far cheaper than query() when only "is there one?" matters.
  void any_within(std::span<const Vec3f> binned, std::span<const Vec3f> queries, float r,
                  std::vector<std::uint8_t>& hit) const;

  bool hashed() const { return hashed_; }
  std::size_t cell_count() const { return cell_start_.empty() ? 0 : cell_start_.size() - 1; }
  /// Most points in one cell at the last build.
  std::size_t max_cell_points() const { return max_cell_points_; }
  std::size_t bytes() const;

 private:
  Vec3i cell_of(const Vec3f& p) const;
  // Fills keys[0..] with the distinct keys of the cells around `c`; returns how many.
  int neighbor_keys(const Vec3i& c, Index* keys) const;
  Index key_of(const Vec3i& c) const;

  // build(), step 1: the points' box gives the origin and the key space (dense or hashed); returns the cell count.
  std::size_t place_cells(std::span<const Vec3f> points, int T);
  // build(), step 3: the stable parallel counting sort of the points' keys into sorted_ and cell_start_.
  void sort_by_cell(std::size_t cell_count, int T);

  template <bool kSelf, bool kCompact>
  void gather(std::span<const Vec3f> binned, std::span<const Vec3f> queries, float r, NeighborList& out) const;
  // gather(), step 1: sizes `out` for n queries in `segments` segments of `chunk` (one thread's share) and points it
  // at this grid's cell table when compact.
  template <bool kCompact>
  void prepare_list(std::size_t n, std::size_t chunk, std::size_t segments, NeighborList& out) const;

  float radius_;
  double dense_cells_per_point_;
  Vec3f origin_{Vec3f::Zero()};
  Vec3i dims_{Vec3i::Zero()};
  bool hashed_ = false;
  bool identity_order_ = false;    // sorted_ is the identity (points_were_sorted() since the last build)
  Index hash_mask_ = 0;
  std::size_t max_cell_points_ = 0;
  std::vector<Index> sorted_;      // point indices, grouped by cell
  std::vector<Index> cell_start_;  // size cells + 1: run of cell k is sorted_[cell_start_[k] .. cell_start_[k+1])
  std::vector<Index> key_;         // per point: its cell key
};

/// new[i] = old[perm[i]] for one array; `scratch` is reused between calls.
template <class T>
void apply_permutation(std::vector<T>& a, std::span<const Index> perm, std::vector<T>& scratch) {
  scratch.resize(a.size());
  const auto n = static_cast<std::int64_t>(a.size());
#pragma omp parallel for schedule(static) if (n >= 2048)
  for (std::int64_t i = 0; i < n; ++i) scratch[static_cast<std::size_t>(i)] = a[perm[static_cast<std::size_t>(i)]];
  a.swap(scratch);
}

/// inv[perm[i]] = i.
std::vector<Index> inverse_permutation(std::span<const Index> perm);

}  // namespace ff::core
