#include "core/neighbor_grid.h"

#include "core/parallel.h"

#include <algorithm>
#include <cmath>

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

}  // namespace

std::size_t NeighborList::total() const {
  std::size_t t = 0;
  for (const auto& s : index) t += s.size();
  return t;
}

std::size_t NeighborList::bytes() const {
  std::size_t b = 0;
  for (const auto& s : index) b += s.capacity() * sizeof(Index);
  for (const auto& s : offset) b += s.capacity() * sizeof(Index);
  return b;
}

std::size_t NeighborGrid::bytes() const {
  return (sorted_.capacity() + cell_start_.capacity() + key_.capacity() + key_scratch_.capacity() +
          histogram_.capacity()) *
         sizeof(Index);
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
  // Bounding box of the points; non-finite coordinates are the solver's to report, they land in cell 0.
  Aabb box;
  for (const auto& p : points)
    if (p.allFinite()) box.extend(p);
  if (box.empty()) box.extend(Vec3f::Zero());
  origin_ = box.min - Vec3f::Constant(radius_);
  const Vec3f ext = (box.max - origin_) / radius_;
  const double cells = (std::floor(double(ext.x())) + 2) * (std::floor(double(ext.y())) + 2) * (std::floor(double(ext.z())) + 2);
  // Dense keys while the box has at most ~2 cells per point: the per-thread histograms stay O(N).
  hashed_ = cells > 2.0 * double(n) + 4096.0;
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

  key_.resize(n);
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) {
    const Vec3f& p = points[static_cast<std::size_t>(i)];
    Vec3i c = p.allFinite() ? cell_of(p) : Vec3i(0, 0, 0);
    if (!hashed_) c = c.cwiseMax(Vec3i::Zero()).cwiseMin(dims_ - Vec3i::Ones());
    key_[static_cast<std::size_t>(i)] = key_of(c);
  });

  // Stable counting sort, parallel over contiguous point ranges: per-thread histograms, then
  // offsets in (cell, thread) order, so the result is the serial stable sort for any thread count.
  const int T = thread_count();
  histogram_.assign(cell_count * static_cast<std::size_t>(T), 0);
#pragma omp parallel num_threads(T)
  {
    const int t = omp_get_thread_num();
    std::size_t b, e;
    thread_range(n, t, T, b, e);
    Index* h = histogram_.data() + static_cast<std::size_t>(t) * cell_count;
    for (std::size_t i = b; i < e; ++i) ++h[key_[i]];
  }
  cell_start_.resize(cell_count + 1);
  Index run = 0;
  for (std::size_t c = 0; c < cell_count; ++c) {
    cell_start_[c] = run;
    for (int t = 0; t < T; ++t) {
      Index& h = histogram_[static_cast<std::size_t>(t) * cell_count + c];
      const Index cnt = h;
      h = run;  // becomes this thread's write cursor for cell c
      run += cnt;
    }
  }
  cell_start_[cell_count] = run;
  sorted_.resize(n);
#pragma omp parallel num_threads(T)
  {
    const int t = omp_get_thread_num();
    std::size_t b, e;
    thread_range(n, t, T, b, e);
    Index* h = histogram_.data() + static_cast<std::size_t>(t) * cell_count;
    for (std::size_t i = b; i < e; ++i) sorted_[h[key_[i]]++] = static_cast<Index>(i);
  }
}

void NeighborGrid::points_were_sorted() {
  const auto n = static_cast<std::int64_t>(sorted_.size());
  key_scratch_.resize(key_.size());
  parallel_for(n, [&](std::int64_t i) {
    key_scratch_[static_cast<std::size_t>(i)] = key_[sorted_[static_cast<std::size_t>(i)]];
    sorted_[static_cast<std::size_t>(i)] = static_cast<Index>(i);
  });
  key_.swap(key_scratch_);
}

template <bool kSelf>
void NeighborGrid::gather(std::span<const Vec3f> binned, std::span<const Vec3f> queries, float r,
                          NeighborList& out) const {
  const std::size_t n = queries.size();
  const int T = thread_count();
  const std::size_t chunk = std::max<std::size_t>(1, (n + static_cast<std::size_t>(T) - 1) / static_cast<std::size_t>(T));
  const std::size_t segments = std::max<std::size_t>(1, (n + chunk - 1) / chunk);
  out.count = n;
  out.chunk = chunk;
  out.index.resize(segments);
  out.offset.resize(segments);
  const float r2 = r * r;
#pragma omp parallel for schedule(static, 1) num_threads(T)
  for (std::int64_t s = 0; s < static_cast<std::int64_t>(segments); ++s) {
    const std::size_t b = static_cast<std::size_t>(s) * chunk, e = std::min(n, b + chunk);
    auto& idx = out.index[static_cast<std::size_t>(s)];
    auto& off = out.offset[static_cast<std::size_t>(s)];
    idx.clear();
    off.resize(e - b + 1);
    Index keys[27];
    for (std::size_t q = b; q < e; ++q) {
      off[q - b] = static_cast<Index>(idx.size());
      const Vec3f xq = queries[q];
      if (!xq.allFinite()) continue;
      const int nk = neighbor_keys(cell_of(xq), keys);
      for (int k = 0; k < nk; ++k) {
        const Index cb = cell_start_[keys[k]], ce = cell_start_[keys[k] + 1];
        for (Index c = cb; c < ce; ++c) {
          const Index j = sorted_[c];
          if (kSelf && j == q) continue;
          if ((binned[j] - xq).squaredNorm() < r2) idx.push_back(j);
        }
      }
    }
    off[e - b] = static_cast<Index>(idx.size());
  }
}

void NeighborGrid::neighbors(std::span<const Vec3f> points, NeighborList& out) const {
  gather<true>(points, points, radius_, out);
}

void NeighborGrid::query(std::span<const Vec3f> binned, std::span<const Vec3f> queries, float r,
                         NeighborList& out) const {
  gather<false>(binned, queries, std::min(r, radius_), out);
}

std::vector<Index> inverse_permutation(std::span<const Index> perm) {
  std::vector<Index> inv(perm.size());
  for (std::size_t i = 0; i < perm.size(); ++i) inv[perm[i]] = static_cast<Index>(i);
  return inv;
}

}  // namespace ff::core
