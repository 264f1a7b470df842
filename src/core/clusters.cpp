#include "core/clusters.h"

#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace ff::core {
namespace {

constexpr std::size_t W = kClusterWidth;

// Box of the real lanes of every cluster.
void cluster_boxes(ClusterSet& s) {
  s.lo.resize(s.clusters);
  s.hi.resize(s.clusters);
  parallel_for(static_cast<std::int64_t>(s.clusters), [&](std::int64_t cc) {
    const auto c = static_cast<std::size_t>(cc);
    Vec3f lo = Vec3f::Constant(INFINITY), hi = Vec3f::Constant(-INFINITY);
    for (std::size_t l = c * W; l < (c + 1) * W; ++l) {
      if (s.point[l] == kInvalidIndex) continue;
      const Vec3f q(s.x[l], s.y[l], s.z[l]);
      lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
    }
    s.lo[c] = lo, s.hi[c] = hi;
  });
}

// Squared distance between two boxes (0 when they overlap).
inline float box_dist2(const Vec3f& alo, const Vec3f& ahi, const Vec3f& blo, const Vec3f& bhi) {
  const Vec3f gap = (alo - bhi).cwiseMax(blo - ahi).cwiseMax(0.0f);
  return gap.squaredNorm();
}

}  // namespace

std::size_t ClusterSet::bytes() const {
  return point.capacity() * sizeof(Index) + (x.capacity() + y.capacity() + z.capacity()) * sizeof(float) +
         (lo.capacity() + hi.capacity()) * sizeof(Vec3f);
}

void ClusterSet::assign(std::span<const Vec3f> p, float spacing) {
  points = p.size();
  if (p.empty()) {
    clusters = 0;
    point.clear(), x.clear(), y.clear(), z.clear(), lo.clear(), hi.clear();
    return;
  }
  // Columns of 2d × 2d: eight points of a lattice of spacing d fill one 2d cube, so a cluster cut from a column
  // sorted by z is about cubic where the fluid is dense.
  Vec3f bmin = p[0], bmax = p[0];
  for (const Vec3f& q : p) bmin = bmin.cwiseMin(q), bmax = bmax.cwiseMax(q);
  float s = 2.0f * spacing;
  auto dims = [&](float edge, int axis) {
    return static_cast<std::int64_t>(std::floor((bmax[axis] - bmin[axis]) / edge)) + 1;
  };
  // A few far-flung points on a huge domain: widen the columns until there are not many more than points.
  while (dims(s, 0) * dims(s, 1) > 4 * static_cast<std::int64_t>(p.size()) + 64) s *= 2.0f;
  const std::int64_t nx = dims(s, 0), ny = dims(s, 1), ncol = nx * ny;
  std::vector<Index> col(p.size()), start(static_cast<std::size_t>(ncol) + 1, 0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const auto cx = std::min<std::int64_t>(nx - 1, static_cast<std::int64_t>((p[i].x() - bmin.x()) / s));
    const auto cy = std::min<std::int64_t>(ny - 1, static_cast<std::int64_t>((p[i].y() - bmin.y()) / s));
    col[i] = static_cast<Index>(cx + nx * cy);
    ++start[col[i] + 1];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<Index> order(p.size()), cursor(start.begin(), start.end() - 1);
  for (std::size_t i = 0; i < p.size(); ++i) order[cursor[col[i]]++] = static_cast<Index>(i);
  // z order within each column (ties by index), then whole clusters per column.
  std::vector<Index> first(static_cast<std::size_t>(ncol) + 1, 0);
  for (std::int64_t c = 0; c < ncol; ++c)
    first[static_cast<std::size_t>(c) + 1] = first[static_cast<std::size_t>(c)] + static_cast<Index>(cluster_count(start[c + 1] - start[c]));
  clusters = first[static_cast<std::size_t>(ncol)];
  point.assign(padded(), kInvalidIndex);
  parallel_for(ncol, [&](std::int64_t c) {
    Index* b = order.data() + start[c];
    Index* e = order.data() + start[c + 1];
    std::sort(b, e, [&](Index u, Index v) { return p[u].z() < p[v].z() || (p[u].z() == p[v].z() && u < v); });
    std::copy(b, e, point.data() + std::size_t(first[static_cast<std::size_t>(c)]) * W);
  });
  update(p);
  cluster_boxes(*this);
}

void ClusterSet::update(std::span<const Vec3f> p) {
  x.resize(padded()), y.resize(padded()), z.resize(padded());
  parallel_for(static_cast<std::int64_t>(padded()), [&](std::int64_t kk) {
    const auto k = static_cast<std::size_t>(kk);
    const Index i = point[k];
    if (i == kInvalidIndex) {
      x[k] = y[k] = z[k] = kFar;
    } else {
      x[k] = p[i].x(), y[k] = p[i].y(), z[k] = p[i].z();
    }
  });
}

void build_cluster_pairs(const ClusterSet& a, const ClusterSet& b, float r, ClusterPairs& out,
                         ClusterPairScratch& scratch) {
  out.offset.assign(a.clusters + 1, 0);
  out.j.clear();
  if (a.clusters == 0 || b.clusters == 0) return;
  // A grid of cell edge ≥ r over B's boxes; each B cluster is listed in every cell its box touches (a cluster
  // stretched along a sparse column then costs only its own cells).
  Vec3f gmin = b.lo[0], gmax = b.hi[0];
  for (std::size_t c = 0; c < b.clusters; ++c) gmin = gmin.cwiseMin(b.lo[c]), gmax = gmax.cwiseMax(b.hi[c]);
  float s = r;
  auto dim = [&](int axis) { return static_cast<std::int64_t>(std::floor((gmax[axis] - gmin[axis]) / s)) + 1; };
  while (dim(0) * dim(1) * dim(2) > 8 * static_cast<std::int64_t>(b.clusters) + 512) s *= 1.5f;
  const std::int64_t nx = dim(0), ny = dim(1), nz = dim(2);
  auto cell = [&](const Vec3f& q, int axis, std::int64_t n) {
    const auto v = static_cast<std::int64_t>(std::floor((q[axis] - gmin[axis]) / s));
    return std::clamp<std::int64_t>(v, 0, n - 1);
  };
  auto for_cells = [&](const Vec3f& lo, const Vec3f& hi, auto&& f) {
    const std::int64_t x0 = cell(lo, 0, nx), x1 = cell(hi, 0, nx), y0 = cell(lo, 1, ny), y1 = cell(hi, 1, ny),
                       z0 = cell(lo, 2, nz), z1 = cell(hi, 2, nz);
    for (std::int64_t z = z0; z <= z1; ++z)
      for (std::int64_t y = y0; y <= y1; ++y)
        for (std::int64_t x = x0; x <= x1; ++x) f(static_cast<std::size_t>(x + nx * (y + ny * z)));
  };
  auto& start = scratch.cell_start;
  auto& list = scratch.order;
  start.assign(static_cast<std::size_t>(nx * ny * nz) + 1, 0);
  for (std::size_t c = 0; c < b.clusters; ++c) for_cells(b.lo[c], b.hi[c], [&](std::size_t k) { ++start[k + 1]; });
  std::partial_sum(start.begin(), start.end(), start.begin());
  list.resize(start.back());
  {
    auto& cur = scratch.cursor;
    cur.assign(start.begin(), start.end() - 1);
    for (std::size_t c = 0; c < b.clusters; ++c)
      for_cells(b.lo[c], b.hi[c], [&](std::size_t k) { list[cur[k]++] = static_cast<Index>(c); });
  }
  // Per A cluster: the B clusters of the cells its box (grown by r) touches, tested box to box, ascending and
  // without repeats. Counted first, then written: two passes, no per-thread lists to merge.
  const float r2 = r * r;
  auto candidates = [&](std::size_t c, std::vector<Index>& tmp) {
    tmp.clear();
    const Vec3f lo = a.lo[c] - Vec3f::Constant(r), hi = a.hi[c] + Vec3f::Constant(r);
    for_cells(lo, hi, [&](std::size_t k) {
      for (Index q = start[k]; q < start[k + 1]; ++q)
        if (box_dist2(a.lo[c], a.hi[c], b.lo[list[q]], b.hi[list[q]]) <= r2) tmp.push_back(list[q]);
    });
    std::sort(tmp.begin(), tmp.end());
    tmp.erase(std::unique(tmp.begin(), tmp.end()), tmp.end());
  };
  const auto na = static_cast<std::int64_t>(a.clusters);
#pragma omp parallel if (na >= 64)
  {
    std::vector<Index> tmp;
#pragma omp for schedule(static)
    for (std::int64_t c = 0; c < na; ++c) {
      candidates(static_cast<std::size_t>(c), tmp);
      out.offset[static_cast<std::size_t>(c) + 1] = static_cast<Index>(tmp.size());
    }
#pragma omp single
    {
      std::partial_sum(out.offset.begin(), out.offset.end(), out.offset.begin());
      out.j.resize(out.offset.back());
    }
#pragma omp for schedule(static)
    for (std::int64_t c = 0; c < na; ++c) {
      candidates(static_cast<std::size_t>(c), tmp);
      std::copy(tmp.begin(), tmp.end(), out.j.begin() + out.offset[static_cast<std::size_t>(c)]);
    }
  }
}

}  // namespace ff::core
