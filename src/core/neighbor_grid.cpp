#include "core/neighbor_grid.h"

#include "core/parallel.h"

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ff::core {
namespace {

// Hash of integer cell coordinates (Teschner et al. 2003 primes).
inline Index hash_cell(const Vec3i& c) {
  return static_cast<Index>(c.x()) * 73856093u ^ static_cast<Index>(c.y()) * 19349663u ^
         static_cast<Index>(c.z()) * 83492791u;
}

// Contiguous range of [0, n) handled by thread t of T: the same split in every pass.
inline void thread_range(std::size_t n, int t, int T, std::size_t& b, std::size_t& e) {
  const std::size_t chunk = (n + static_cast<std::size_t>(T) - 1) / static_cast<std::size_t>(T);
  b = std::min(n, chunk * static_cast<std::size_t>(t));
  e = std::min(n, b + chunk);
}

// The candidates of one cell's neighbourhood in SoA form, padded to a multiple of 8 with points at
// infinity so the SIMD filter needs no tail loop.
struct Candidates {
  std::vector<float> x, y, z;
  std::vector<Index> id;            // point index
  std::vector<std::uint16_t> code;  // compact (row, offset) code
  std::size_t n = 0;

  void clear() { n = 0; }
  void push(const Vec3f& p, Index j, std::uint16_t c) {
    if (n == x.size()) {
      const std::size_t m = std::max<std::size_t>(64, 2 * n);
      x.resize(m); y.resize(m); z.resize(m); id.resize(m); code.resize(m);
    }
    x[n] = p.x(); y[n] = p.y(); z[n] = p.z(); id[n] = j; code[n] = c;
    ++n;
  }
  void pad() {
    constexpr float inf = std::numeric_limits<float>::infinity();
    while (n % 8) push(Vec3f::Constant(inf), kInvalidIndex, 0);
  }
};

// pshufb controls that left-pack the selected lanes of a register: kPack16[m] for eight 16-bit
// lanes selected by the bits of m, kPack32[m] for four 32-bit lanes. Packing with a table instead of
// a loop over the mask bits keeps the filter free of data-dependent branches.
template <int kLaneBytes, int kLanes>
constexpr std::array<std::array<std::uint8_t, 16>, (1u << kLanes)> pack_table() {
  std::array<std::array<std::uint8_t, 16>, (1u << kLanes)> t{};
  for (unsigned m = 0; m < (1u << kLanes); ++m) {
    int o = 0;
    for (int l = 0; l < kLanes; ++l)
      if (m & (1u << l))
        for (int b = 0; b < kLaneBytes; ++b) t[m][static_cast<std::size_t>(o++)] = static_cast<std::uint8_t>(l * kLaneBytes + b);
    while (o < 16) t[m][static_cast<std::size_t>(o++)] = 0x80;
  }
  return t;
}
alignas(16) constexpr auto kPack16 = pack_table<2, 8>();
alignas(16) constexpr auto kPack32 = pack_table<4, 4>();

inline __m128i shuffle(__m128i v, const std::array<std::uint8_t, 16>& control) {
  return _mm_shuffle_epi8(v, _mm_load_si128(reinterpret_cast<const __m128i*>(control.data())));
}

// Bits of the lanes of 8 candidates at k within r² of q.
inline unsigned within(const Candidates& c, std::size_t k, __m128 qx, __m128 qy, __m128 qz, __m128 rr) {
  auto four = [&](std::size_t o) {
    const __m128 dx = _mm_sub_ps(_mm_loadu_ps(c.x.data() + o), qx);
    const __m128 dy = _mm_sub_ps(_mm_loadu_ps(c.y.data() + o), qy);
    const __m128 dz = _mm_sub_ps(_mm_loadu_ps(c.z.data() + o), qz);
    // Same operation order as Eigen's squaredNorm of the difference, so results equal the brute force.
    const __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    return static_cast<unsigned>(_mm_movemask_ps(_mm_cmplt_ps(d2, rr)));
  };
  return four(k) | four(k + 4) << 4;
}

// Bits of the lanes of 8 candidates at k whose point index is q (the query itself).
inline unsigned is_self(const Candidates& c, std::size_t k, __m128i q) {
  const __m128i* id = reinterpret_cast<const __m128i*>(c.id.data() + k);
  const auto lo = static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_loadu_si128(id), q))));
  const auto hi = static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(_mm_loadu_si128(id + 1), q))));
  return lo | hi << 4;
}

// Grows v (without zeroing) so that `used + extra` entries fit. The capacity is set explicitly, an eighth
// above the need, rather than letting the vector double: this is the solver's largest array.
template <class V>
void ensure_room(V& v, std::size_t used, std::size_t extra) {
  if (v.size() >= used + extra) return;
  const std::size_t want = used + extra + used / 8 + 64;
  v.reserve(want);
  v.resize(want);
}

}  // namespace

std::size_t NeighborList::total() const {
  std::size_t t = 0;
  for (const auto& s : index) t += s.size();
  for (const auto& s : code) t += s.size();
  return t;
}

std::size_t NeighborList::bytes() const {
  std::size_t b = 0;
  for (const auto& s : index) b += s.capacity() * sizeof(Index);
  for (const auto& s : code) b += s.capacity() * sizeof(std::uint16_t);
  for (const auto& s : offset) b += s.capacity() * sizeof(Index);
  return b;
}

std::size_t NeighborGrid::bytes() const {
  return (sorted_.capacity() + cell_start_.capacity() + key_.capacity()) * sizeof(Index);
}

Vec3i NeighborGrid::cell_of(const Vec3f& p) const {
  const Vec3f q = (p - origin_) / radius_;
  return {static_cast<int>(std::floor(q.x())), static_cast<int>(std::floor(q.y())), static_cast<int>(std::floor(q.z()))};
}

Index NeighborGrid::key_of(const Vec3i& c) const {
  if (hashed_) return hash_cell(c) & hash_mask_;
  return static_cast<Index>((c.z() * dims_.y() + c.y()) * dims_.x() + c.x());
}

int NeighborGrid::neighbor_keys(const Vec3i& c, Index* keys) const {
  int n = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const Vec3i d(c.x() + dx, c.y() + dy, c.z() + dz);
        if (!hashed_) {
          if (d.x() < 0 || d.y() < 0 || d.z() < 0 || d.x() >= dims_.x() || d.y() >= dims_.y() || d.z() >= dims_.z())
            continue;
          keys[n++] = key_of(d);
        } else {
          const Index k = key_of(d);
          // Two of the 27 cells may share a bucket: scan each bucket once.
          if (std::find(keys, keys + n, k) == keys + n) keys[n++] = k;
        }
      }
  return n;
}

void NeighborGrid::build(std::span<const Vec3f> points) {
  const std::size_t n = points.size();
  const int T = static_cast<std::int64_t>(n) < kMinParallel ? 1 : thread_count();
  const std::size_t cell_count = place_cells(points, T);
  key_.resize(n);
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) {
    const Vec3f& p = points[static_cast<std::size_t>(i)];
    Vec3i c = p.allFinite() ? cell_of(p) : Vec3i(0, 0, 0);
    if (!hashed_) c = c.cwiseMax(Vec3i::Zero()).cwiseMin(dims_ - Vec3i::Ones());
    key_[static_cast<std::size_t>(i)] = key_of(c);
  });
  sort_by_cell(cell_count, T);
}

std::size_t NeighborGrid::place_cells(std::span<const Vec3f> points, int T) {
  const std::size_t n = points.size();
  // Bounding box of the points (min/max are exact in any order, so per-thread boxes merge
  // deterministically); non-finite coordinates are the solver's to report, they land in cell 0.
  std::vector<Aabb> boxes(static_cast<std::size_t>(T));
#pragma omp parallel num_threads(T)
  {
    const int t = omp_get_thread_num();
    std::size_t b, e;
    thread_range(n, t, T, b, e);
    Aabb box;
    for (std::size_t i = b; i < e; ++i)
      if (points[i].allFinite()) box.extend(points[i]);
    boxes[static_cast<std::size_t>(t)] = box;
  }
  Aabb box;
  for (const auto& b : boxes)
    if (!b.empty()) { box.extend(b.min); box.extend(b.max); }
  if (box.empty()) box.extend(Vec3f::Zero());
  // Two cells of margin below: every finite point's cell then has x−1, y−1, z−1 neighbours even after
  // rounding, and one above (floor(ext) ≤ dims − 2), so compact rows never leave the key space.
  // The origin is snapped to the global lattice of cell edges (multiples of the radius), so two grids of one
  // radius have the same cells: a caller can sort its query points by that lattice (AdaptiveController does)
  // and consecutive queries then share their 27 candidate cells.
  origin_ = ((box.min / radius_).array().floor() - 2.0f).matrix() * radius_;
  const Vec3f ext = (box.max - origin_) / radius_;
  const double cells = (std::floor(double(ext.x())) + 2) * (std::floor(double(ext.y())) + 2) * (std::floor(double(ext.z())) + 2);
  // Dense keys while the box has at most a few cells per point (the constructor's limit): the cell table stays O(N).
  hashed_ = cells > dense_cells_per_point_ * double(n) + 4096.0;
  identity_order_ = false;
  std::size_t cell_count;
  if (!hashed_) {
    dims_ = Vec3i(int(ext.x()) + 2, int(ext.y()) + 2, int(ext.z()) + 2);
    cell_count = static_cast<std::size_t>(dims_.x()) * dims_.y() * dims_.z();
  } else {
    std::size_t table = 1024;
    while (table < n) table <<= 1;
    hash_mask_ = static_cast<Index>(table - 1);
    cell_count = table;
  }
  return cell_count;
}

void NeighborGrid::sort_by_cell(std::size_t cell_count, int T) {
  const std::size_t n = key_.size();
  // Stable counting sort with one cell table: thread t owns the cells [cb, ce) and scans all keys, counting
  // and then placing only its own cells' points. Points of a cell keep ascending order, so the result is
  // the serial stable sort for any thread count, and memory is one counter per cell (per-thread
  // histograms would cost T counters per cell). The solver's points arrive nearly sorted, so the
  // ownership test is a predictable branch.
  cell_start_.assign(cell_count + 1, 0);
  Index* count = cell_start_.data();
#pragma omp parallel num_threads(T)
  {
    std::size_t cb, ce;
    thread_range(cell_count, omp_get_thread_num(), T, cb, ce);
    for (std::size_t i = 0; i < n; ++i) {
      const Index k = key_[i];
      if (k >= cb && k < ce) ++count[k];
    }
  }
  // Exclusive scan; count[k] becomes the write cursor of cell k.
  Index run = 0, most = 0;
  for (std::size_t c = 0; c < cell_count; ++c) {
    const Index m = count[c];
    most = std::max(most, m);
    count[c] = run;
    run += m;
  }
  count[cell_count] = run;
  max_cell_points_ = most;
  sorted_.resize(n);
#pragma omp parallel num_threads(T)
  {
    std::size_t cb, ce;
    thread_range(cell_count, omp_get_thread_num(), T, cb, ce);
    for (std::size_t i = 0; i < n; ++i) {
      const Index k = key_[i];
      if (k >= cb && k < ce) sorted_[count[k]++] = static_cast<Index>(i);
    }
  }
  // Cursors now hold each cell's end, which is the next cell's start: shift them up by one.
  std::copy_backward(cell_start_.begin(), cell_start_.end() - 1, cell_start_.end());
  cell_start_[0] = 0;
}

void NeighborGrid::points_were_sorted() {
  // In cell order, point i's key is the cell whose run contains i, and the order is the identity.
  const auto cells = static_cast<std::int64_t>(cell_count());
  parallel_for(cells, [&](std::int64_t k) {
    const auto c = static_cast<std::size_t>(k);
    for (Index i = cell_start_[c]; i < cell_start_[c + 1]; ++i) {
      key_[i] = static_cast<Index>(c);
      sorted_[i] = i;
    }
  });
  identity_order_ = true;
}

template <bool kSelf, bool kCompact>
void NeighborGrid::gather(std::span<const Vec3f> binned, std::span<const Vec3f> queries, float r,
                          NeighborList& out) const {
  const std::size_t n = queries.size();
  const int T = static_cast<std::int64_t>(n) < kMinParallel ? 1 : thread_count();
  const std::size_t chunk = std::max<std::size_t>(1, (n + static_cast<std::size_t>(T) - 1) / static_cast<std::size_t>(T));
  const std::size_t segments = std::max<std::size_t>(1, (n + chunk - 1) / chunk);
  prepare_list<kCompact>(n, chunk, segments, out);
  const float r2 = r * r;
#pragma omp parallel for schedule(static, 1) num_threads(T)
  for (std::int64_t s = 0; s < static_cast<std::int64_t>(segments); ++s) {
    const auto seg = static_cast<std::size_t>(s);
    const std::size_t b = seg * chunk, e = std::min(n, b + chunk);
    auto& off = out.offset[seg];
    off.resize(e - b + 1);
    // Sizes are kept from the last build, so steady-state filling neither allocates nor zeroes.
    Buffer<Index>* wide = nullptr;
    Buffer<std::uint16_t>* codes = nullptr;
    if constexpr (kCompact)
      codes = &out.code[seg];
    else
      wide = &out.index[seg];
    std::size_t used = 0;  // entries written (the vector is kept larger while filling)
    Candidates cand;
    Vec3i run_cell(0, 0, 0);
    bool have_run = false;
    Index keys[27];
    const __m128 rr = _mm_set1_ps(r2);
    for (std::size_t q = b; q < e; ++q) {
      off[q - b] = static_cast<Index>(used);
      const Vec3f xq = queries[q];
      if (!xq.allFinite()) continue;
      const Vec3i c = cell_of(xq);
      // Points of one cell share their candidates: gather them once per run of the cell.
      if (!have_run || c != run_cell) {
        run_cell = c;
        have_run = true;
        cand.clear();
        if constexpr (kCompact) {
          const std::int64_t key = key_of(c);
          for (std::size_t row = 0; row < out.row_key.size(); ++row) {
            const auto k0 = static_cast<std::size_t>(key + out.row_key[row]);
            const Index rb = cell_start_[k0], re = cell_start_[k0 + 3];
            for (Index p = rb; p < re; ++p)
              cand.push(binned[p], p, static_cast<std::uint16_t>((row << NeighborRange::kRowBits) | (p - rb)));
          }
        } else {
          const int nk = neighbor_keys(c, keys);
          for (int k = 0; k < nk; ++k)
            for (Index p = cell_start_[keys[k]]; p < cell_start_[keys[k] + 1]; ++p) {
              const Index j = sorted_[p];
              cand.push(binned[j], j, 0);
            }
        }
        cand.pad();
      }
      // Filter 8 candidates at a time and left-pack the hits with a shuffle: unconditional 16-byte
      // stores, the output cursor advanced by the hit count (room for one overshoot is reserved).
      if constexpr (kCompact) ensure_room(*codes, used, cand.n + 8); else ensure_room(*wide, used, cand.n + 8);
      const __m128 qx = _mm_set1_ps(xq.x()), qy = _mm_set1_ps(xq.y()), qz = _mm_set1_ps(xq.z());
      const __m128i qi = _mm_set1_epi32(static_cast<int>(q));
      for (std::size_t k = 0; k < cand.n; k += 8) {
        unsigned m = within(cand, k, qx, qy, qz, rr);
        if constexpr (kSelf) m &= ~is_self(cand, k, qi);
        if constexpr (kCompact) {
          const __m128i cc = _mm_loadu_si128(reinterpret_cast<const __m128i*>(cand.code.data() + k));
          _mm_storeu_si128(reinterpret_cast<__m128i*>(codes->data() + used), shuffle(cc, kPack16[m]));
          used += static_cast<std::size_t>(__builtin_popcount(m));
        } else {
          const __m128i* ids = reinterpret_cast<const __m128i*>(cand.id.data() + k);
          _mm_storeu_si128(reinterpret_cast<__m128i*>(wide->data() + used), shuffle(_mm_loadu_si128(ids), kPack32[m & 15u]));
          used += static_cast<std::size_t>(__builtin_popcount(m & 15u));
          _mm_storeu_si128(reinterpret_cast<__m128i*>(wide->data() + used), shuffle(_mm_loadu_si128(ids + 1), kPack32[m >> 4]));
          used += static_cast<std::size_t>(__builtin_popcount(m >> 4));
        }
      }
    }
    off[e - b] = static_cast<Index>(used);
    if constexpr (kCompact) codes->resize(used); else wide->resize(used);  // keeps the capacity
  }
}

template <bool kCompact>
void NeighborGrid::prepare_list(std::size_t n, std::size_t chunk, std::size_t segments, NeighborList& out) const {
  out.count = n;
  out.chunk = chunk;
  out.chunk_inverse = ~std::uint64_t(0) / chunk + 1;
  out.compact = kCompact;
  out.offset.resize(segments);
  // Release the other representation so bytes() is what the list really holds.
  if constexpr (kCompact) {
    out.code.resize(segments);
    std::vector<Buffer<Index>>().swap(out.index);
    out.cell_key = key_.data();
    out.cell_start = cell_start_.data();
    const std::int64_t nx = dims_.x(), nxy = std::int64_t(dims_.x()) * dims_.y();
    int k = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy) out.row_key[static_cast<std::size_t>(k++)] = -1 + dy * nx + dz * nxy;
  } else {
    out.index.resize(segments);
    std::vector<Buffer<std::uint16_t>>().swap(out.code);
    out.cell_key = out.cell_start = nullptr;
  }
}

void NeighborGrid::neighbors(std::span<const Vec3f> points, NeighborList& out) const {
  // Compact codes need rows in point order (identity order) and rows short enough for 12-bit offsets.
  const bool compact = !hashed_ && identity_order_ && 3 * max_cell_points_ <= (std::size_t(1) << NeighborRange::kRowBits);
  if (compact)
    gather<true, true>(points, points, radius_, out);
  else
    gather<true, false>(points, points, radius_, out);
}

void NeighborGrid::query(std::span<const Vec3f> binned, std::span<const Vec3f> queries, float r,
                         NeighborList& out) const {
  gather<false, false>(binned, queries, std::min(r, radius_), out);
}

void NeighborGrid::any_within(std::span<const Vec3f> binned, std::span<const Vec3f> queries, float r,
                              std::vector<std::uint8_t>& hit) const {
  const float r2 = std::min(r, radius_) * std::min(r, radius_);
  hit.assign(queries.size(), 0);
  if (cell_count() == 0) return;
  parallel_for(static_cast<std::int64_t>(queries.size()), [&](std::int64_t qi) {
    const Vec3f xq = queries[static_cast<std::size_t>(qi)];
    if (!xq.allFinite()) return;
    auto in_cell = [&](Index key) {
      for (Index p = cell_start_[key]; p < cell_start_[key + 1]; ++p)
        if ((binned[sorted_[p]] - xq).squaredNorm() < r2) return true;
      return false;
    };
    const Vec3i c = cell_of(xq);
    // The query's own cell holds its nearest point most often; a cell outside a dense grid holds none.
    const bool inside = hashed_ || (c.x() >= 0 && c.y() >= 0 && c.z() >= 0 && c.x() < dims_.x() && c.y() < dims_.y() &&
                                    c.z() < dims_.z());
    const Index own = inside ? key_of(c) : 0;
    if (inside && in_cell(own)) {
      hit[static_cast<std::size_t>(qi)] = 1;
      return;
    }
    Index keys[27];
    const int nk = neighbor_keys(c, keys);
    for (int k = 0; k < nk; ++k)
      if (!(inside && keys[k] == own) && in_cell(keys[k])) {
        hit[static_cast<std::size_t>(qi)] = 1;
        return;
      }
  });
}

std::vector<Index> inverse_permutation(std::span<const Index> perm) {
  std::vector<Index> inv(perm.size());
  for (std::size_t i = 0; i < perm.size(); ++i) inv[perm[i]] = static_cast<Index>(i);
  return inv;
}

}  // namespace ff::core
