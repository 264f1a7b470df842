#include "sampling/sdf_grid.h"

#include "core/parallel.h"
#include "core/params.h"
#include "core/timer.h"

#include <fmt/format.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace ff::sampling {
namespace {

constexpr int kTopStride = 8;         // coarsest sign cells: 8³ nodes decided by one set of 8 winding numbers
constexpr float kSignMargin = 0.25f;  // corners must agree with |w − 0.5| > this to fill a cell
constexpr int kProjectionSteps = 4;
constexpr int kSweepRounds = 2;  // far-field sweeps (±x, ±y, ±z each round)

Error cancelled() { return {Error::Kind::Cancelled, "signed distance grid: cancelled"}; }

// Position of the node with linear index n.
Vec3f position(const SdfGrid& g, std::size_t n) {
  const auto nx = static_cast<std::size_t>(g.dims.x()), ny = static_cast<std::size_t>(g.dims.y());
  return g.node(static_cast<int>(n % nx), static_cast<int>((n / nx) % ny), static_cast<int>(n / (nx * ny)));
}

// Grid geometry: nodes per axis covering bounds ± margin, centred on the box.
Result<SdfGrid> empty_grid(const Aabb& bounds, float spacing, float margin) {
  FF_CHECK(core::check_range("sdf_grid", "spacing", spacing, 0.0, std::numeric_limits<double>::max(), core::Bound::Open,
                             core::Bound::Closed));
  FF_CHECK(core::check_range("sdf_grid", "margin", margin, 0.0, std::numeric_limits<double>::max()));
  SdfGrid g;
  g.spacing = spacing;
  double nodes = 1.0;
  Vec3d extent;
  for (int a = 0; a < 3; ++a) {
    extent[a] = double(bounds.max[a]) - double(bounds.min[a]) + 2.0 * double(margin);
    const double n = std::max(2.0, std::ceil(extent[a] / spacing) + 1.0);
    nodes *= n;
    if (!(nodes <= double(SdfGrid::kMaxNodes)))
      return param_error(fmt::format("sdf_grid.spacing = {:.7g} m gives more than {} nodes over a {:.7g} m box",
                                     spacing, SdfGrid::kMaxNodes, extent.maxCoeff()));
    g.dims[a] = static_cast<int>(n);
  }
  for (int a = 0; a < 3; ++a) {
    const double covered = double(g.dims[a] - 1) * spacing;
    g.origin[a] = static_cast<float>(double(bounds.min[a]) - double(margin) - 0.5 * (covered - extent[a]));
  }
  g.value.assign(static_cast<std::size_t>(nodes), 0.0f);
  return g;
}

// ---- unsigned distance ---------------------------------------------------------------------------------
//
// Band: every triangle is rasterised into the nodes within `band` of it (its box grown by `band`, and along the
// normal's dominant axis only the slab |n·(x − a)| ≤ band), each node keeping the nearest triangle by an
// atomic minimum of the packed key (distance bits, triangle): non-negative floats order like their bits, and
// the minimum of a totally ordered key does not depend on the order of the updates, so the band is exact and
// the same for any thread count. A node within `band` of the surface has its closest triangle among those
// rasterised into it, so its distance is exact.
//
// Far field: every other node takes the nearest of its neighbours' triangles, in sweeps along ±x, ±y, ±z
// (each line or slab in order, the lines in parallel), twice. The value is the distance to an actual triangle,
// so an upper bound; it is exact wherever the closest triangle reaches the node through the sweeps, which is
// almost everywhere (bunny at diagonal/256: 2.6 % of the far nodes are over, by at most 0.77 spacing; the tests
// print the figure for their shapes). Two rounds: one leaves 24 % over, by up to 3.5 spacings.

struct DistancePass {
  const MeshField& field;
  SdfGrid& g;
  float band;
  std::vector<Index> tri;  // per node: the triangle (field order) its value is the distance to

  static std::uint64_t pack(float d, Index t) { return (std::uint64_t{std::bit_cast<std::uint32_t>(d)} << 32) | t; }

  float distance(const Vec3f& p, Index t) const {
    const MeshField::Triangle& tr = field.triangles()[t];
    return (closest_point_on_triangle(p, tr.a, tr.b, tr.c) - p).norm();
  }

  void rasterise(Index t, std::vector<std::uint64_t>& key) const {
    const MeshField::Triangle& tr = field.triangles()[t];
    const Vec3f lo = tr.a.cwiseMin(tr.b).cwiseMin(tr.c) - Vec3f::Constant(band);
    const Vec3f hi = tr.a.cwiseMax(tr.b).cwiseMax(tr.c) + Vec3f::Constant(band);
    Vec3i first, last;
    for (int a = 0; a < 3; ++a) {
      first[a] = std::max(0, static_cast<int>(std::ceil((lo[a] - g.origin[a]) / g.spacing)));
      last[a] = std::min(g.dims[a] - 1, static_cast<int>(std::floor((hi[a] - g.origin[a]) / g.spacing)));
    }
    const Vec3f n = (tr.b - tr.a).cross(tr.c - tr.a).normalized();
    int w = 0;
    n.cwiseAbs().maxCoeff(&w);
    const int u = (w + 1) % 3, v = (w + 2) % 3;
    const float offset = n.dot(tr.a);
    Vec3i at;
    for (at[u] = first[u]; at[u] <= last[u]; ++at[u])
      for (at[v] = first[v]; at[v] <= last[v]; ++at[v]) {
        int w0 = first[w], w1 = last[w];
        if (n[w] != 0.0f) {  // the slab of the plane: n_w x_w ∈ offset − n_u x_u − n_v x_v ± band
          const float xu = g.origin[u] + g.spacing * float(at[u]), xv = g.origin[v] + g.spacing * float(at[v]);
          const float s = offset - n[u] * xu - n[v] * xv;
          float a0 = (s - band) / n[w], a1 = (s + band) / n[w];
          if (a0 > a1) std::swap(a0, a1);
          // One node of slack on each side: the slab test is in float, the distance test below is the real one.
          w0 = std::max(w0, static_cast<int>(std::ceil((a0 - g.origin[w]) / g.spacing)) - 1);
          w1 = std::min(w1, static_cast<int>(std::floor((a1 - g.origin[w]) / g.spacing)) + 1);
        }
        for (at[w] = w0; at[w] <= w1; ++at[w]) {
          const Vec3f p = g.node(at.x(), at.y(), at.z());
          const float d = distance(p, t);
          if (!(d <= band)) continue;
          std::atomic_ref<std::uint64_t> slot(key[g.index(at.x(), at.y(), at.z())]);
          const std::uint64_t mine = pack(d, t);
          std::uint64_t cur = slot.load(std::memory_order_relaxed);
          while (mine < cur && !slot.compare_exchange_weak(cur, mine, std::memory_order_relaxed)) {
          }
        }
      }
  }

  Status run_band(core::Progress& progress) {
    const std::size_t n = g.value.size();
    std::vector<std::uint64_t> key(n, ~std::uint64_t{0});
    const auto count = static_cast<Index>(field.triangle_count());
    const Index per_tick = std::max<Index>(1, count / 16);
    for (Index t0 = 0; t0 < count; t0 += per_tick) {
      const Index t1 = std::min(count, t0 + per_tick);
      core::parallel_for(std::int64_t(t1 - t0), [&](std::int64_t i) { rasterise(t0 + static_cast<Index>(i), key); });
      if (!progress.tick(16 * std::size_t(t1) / count)) return cancelled();
    }
    tri.resize(n);
    core::parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) {
      const auto k = static_cast<std::size_t>(i);
      const bool hit = key[k] != ~std::uint64_t{0};
      g.value[k] =
          hit ? std::bit_cast<float>(static_cast<std::uint32_t>(key[k] >> 32)) : std::numeric_limits<float>::infinity();
      tri[k] = hit ? static_cast<Index>(key[k] & 0xffffffffu) : kInvalidIndex;
    });
    return {};
  }

  // Offers node n (at p) the triangle of a neighbour. Band nodes (value ≤ band) are exact already.
  void offer(std::size_t n, std::size_t from, const Vec3f& p) {
    const Index cand = tri[from];
    if (cand == kInvalidIndex || cand == tri[n] || g.value[n] <= band) return;
    const float d = distance(p, cand);
    if (d < g.value[n] || (d == g.value[n] && cand < tri[n])) g.value[n] = d, tri[n] = cand;
  }

  // Row i of a y or z sweep: each node first takes the triangle of the row before (`back`), then its x
  // neighbours' within the row, both ways, so a triangle can travel diagonally within one pass.
  void sweep_row(int j, int k, std::ptrdiff_t back) {
    const int nx = g.dims.x();
    for (int i = 0; i < nx; ++i) {
      const std::size_t n = g.index(i, j, k);
      const Vec3f p = g.node(i, j, k);
      offer(n, static_cast<std::size_t>(static_cast<std::ptrdiff_t>(n) + back), p);
      if (i > 0) offer(n, n - 1, p);
    }
    for (int i = nx - 2; i >= 0; --i) offer(g.index(i, j, k), g.index(i, j, k) + 1, g.node(i, j, k));
  }

  void sweep() {
    const int nx = g.dims.x(), ny = g.dims.y(), nz = g.dims.z();
    const auto sy = static_cast<std::ptrdiff_t>(nx), sz = sy * ny;
    core::parallel_for(std::int64_t(ny) * nz, [&](std::int64_t r) {  // ±x, one row per task
      const int j = static_cast<int>(r % ny), k = static_cast<int>(r / ny);
      for (int i = 1; i < nx; ++i) offer(g.index(i, j, k), g.index(i - 1, j, k), g.node(i, j, k));
      for (int i = nx - 2; i >= 0; --i) offer(g.index(i, j, k), g.index(i + 1, j, k), g.node(i, j, k));
    });
    core::parallel_for(nz, [&](std::int64_t kk) {  // ±y, one xy slab per task
      const int k = static_cast<int>(kk);
      for (int j = 1; j < ny; ++j) sweep_row(j, k, -sy);
      for (int j = ny - 2; j >= 0; --j) sweep_row(j, k, sy);
    });
    core::parallel_for(ny, [&](std::int64_t jj) {  // ±z, one xz slab per task
      const int j = static_cast<int>(jj);
      for (int k = 1; k < nz; ++k) sweep_row(j, k, -sz);
      for (int k = nz - 2; k >= 0; --k) sweep_row(j, k, sz);
    });
  }

  Status run(core::Progress& progress) {
    FF_CHECK(run_band(progress));
    for (int round = 0; round < kSweepRounds; ++round) sweep();
    // Unreachable when the band is not empty (some node is always within √3/2 spacing of the surface), but
    // cheap to guarantee: anything still unset gets an exact query.
    core::parallel_for(static_cast<std::int64_t>(g.value.size()), [&](std::int64_t i) {
      const auto k = static_cast<std::size_t>(i);
      if (tri[k] == kInvalidIndex) g.value[k] = field.unsigned_distance(position(g, k));
    });
    return {};
  }
};

// A cell of the sign pass: nodes [lo, hi] per axis, hi = min(lo + stride, dims − 1). It owns the nodes
// [lo, hi) per axis, plus hi where hi is the last node, so the cells of a level partition the grid and can
// write their nodes in parallel.
struct SignPass {
  const MeshField& field;
  SdfGrid& g;
  float band;            // values up to this are exact (DistancePass)
  std::vector<float> w;  // winding number per node, NaN until evaluated
  std::size_t evaluations = 0;

  Vec3i hi_of(const Vec3i& lo, int stride) const {
    return (lo + Vec3i::Constant(stride)).cwiseMin(g.dims - Vec3i::Ones());
  }
  Vec3i owned_end(const Vec3i& hi) const {
    Vec3i e = hi;
    for (int a = 0; a < 3; ++a)
      if (hi[a] == g.dims[a] - 1) e[a] = g.dims[a];
    return e;
  }
  std::size_t corner(const Vec3i& lo, const Vec3i& hi, int c) const {
    return g.index((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
  }

  // Winding numbers at every corner of `cells` not evaluated yet (sorted, so the work list is deterministic).
  void evaluate_corners(const std::vector<Vec3i>& cells, int stride) {
    std::vector<std::size_t> todo;
    for (const Vec3i& lo : cells) {
      const Vec3i hi = hi_of(lo, stride);
      for (int c = 0; c < 8; ++c)
        if (const std::size_t n = corner(lo, hi, c); std::isnan(w[n])) todo.push_back(n);
    }
    std::sort(todo.begin(), todo.end());
    todo.erase(std::unique(todo.begin(), todo.end()), todo.end());
    core::parallel_for(static_cast<std::int64_t>(todo.size()), [&](std::int64_t t) {
      const std::size_t n = todo[static_cast<std::size_t>(t)];
      w[n] = field.winding_number(position(g, n));
    });
    evaluations += todo.size();
  }

  enum class Verdict : std::uint8_t { Split, Inside, Outside, PerNode };

  // Read-only: whether the cell is surface-free with agreeing corners (one sign for all its nodes), must be
  // split, or (finest level) is signed node by node. Values are read as |d|: a neighbour's node may already
  // carry its sign from an earlier level.
  Verdict verdict(const Vec3i& lo, int stride) const {
    const Vec3i hi = hi_of(lo, stride);
    const float diagonal = g.spacing * (hi - lo).cast<float>().norm();
    float farthest = 0.0f;
    std::size_t far_corner = 0;
    int in = 0, out = 0;
    for (int c = 0; c < 8; ++c) {
      const std::size_t n = corner(lo, hi, c);
      if (std::abs(g.value[n]) > farthest) farthest = std::abs(g.value[n]), far_corner = n;
      in += w[n] > 0.5f + kSignMargin;
      out += w[n] < 0.5f - kSignMargin;
    }
    if ((in == 8 || out == 8) && surface_free(far_corner, farthest, diagonal))
      return in == 8 ? Verdict::Inside : Verdict::Outside;
    return stride > 1 ? Verdict::Split : Verdict::PerNode;
  }

  // True when no surface lies within `radius` of node n, so the ball of that radius around it (which holds the
  // cell) is surface-free. Band values are exact; far values are upper bounds, so those are confirmed by a
  // bounded query (cheap: it only opens the BVH nodes within `radius`).
  bool surface_free(std::size_t n, float value, float radius) const {
    if (!(value > radius)) return false;
    if (value <= band) return true;
    return field.closest(position(g, n), radius).triangle == kInvalidIndex;
  }

  // Writes the signs of the cell's own nodes (cells partition the nodes, so this runs in parallel).
  void apply(const Vec3i& lo, int stride, Verdict v) {
    const Vec3i end = owned_end(hi_of(lo, stride));
    if (v == Verdict::Inside) for_each_owned(lo, end, [&](std::size_t n) { g.value[n] = -g.value[n]; });
    // At the finest level every owned node is a corner, so its own winding number is known.
    if (v == Verdict::PerNode)
      for_each_owned(lo, end, [&](std::size_t n) {
        if (w[n] > 0.5f) g.value[n] = -g.value[n];
      });
  }

  template <class F>
  void for_each_owned(const Vec3i& lo, const Vec3i& end, F&& f) const {
    for (int k = lo.z(); k < end.z(); ++k)
      for (int j = lo.y(); j < end.y(); ++j)
        for (int i = lo.x(); i < end.x(); ++i) f(g.index(i, j, k));
  }

  // The sub-cells (stride / 2) of the undecided cells, in order.
  std::vector<Vec3i> children(const std::vector<Vec3i>& cells, const std::vector<Verdict>& verdicts, int stride) const {
    std::vector<Vec3i> next;
    const int half = stride / 2;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      if (verdicts[c] != Verdict::Split) continue;
      const Vec3i lo = cells[c], hi = hi_of(lo, stride);
      for (int dz = 0; dz <= half; dz += half)
        for (int dy = 0; dy <= half; dy += half)
          for (int dx = 0; dx <= half; dx += half) {
            const Vec3i child = lo + Vec3i(dx, dy, dz);
            if ((child.array() < hi.array()).all()) next.push_back(child);
          }
    }
    return next;
  }

  Status run(core::Progress& progress, std::size_t ticks) {
    std::vector<Vec3i> cells;
    for (int k = 0; k < g.dims.z() - 1; k += kTopStride)
      for (int j = 0; j < g.dims.y() - 1; j += kTopStride)
        for (int i = 0; i < g.dims.x() - 1; i += kTopStride) cells.emplace_back(i, j, k);
    for (int stride = kTopStride; stride >= 1; stride /= 2) {
      evaluate_corners(cells, stride);
      std::vector<Verdict> verdicts(cells.size());
      const auto count = static_cast<std::int64_t>(cells.size());
      core::parallel_for(count, [&](std::int64_t c) {
        verdicts[static_cast<std::size_t>(c)] = verdict(cells[static_cast<std::size_t>(c)], stride);
      });
      core::parallel_for(count, [&](std::int64_t c) {
        apply(cells[static_cast<std::size_t>(c)], stride, verdicts[static_cast<std::size_t>(c)]);
      });
      if (!progress.tick(++ticks)) return cancelled();
      if (stride > 1) cells = children(cells, verdicts, stride);
    }
    return {};
  }
};

}  // namespace

Result<SdfGrid> SdfGrid::build(const MeshField& field, float spacing, float margin, core::Progress& progress,
                               SdfGridStats* stats) {
  FF_TRY(SdfGrid g, empty_grid(field.bounds(), spacing, margin));
  progress.begin("signed distance grid", 16 + 4);
  core::Stopwatch watch;
  const float band = SdfGrid::kBandCells * spacing;
  Status s;
  {
    DistancePass distance{field, g, band, {}};
    s = distance.run(progress);
  }
  const double seconds_distance = watch.seconds();
  watch.restart();
  SignPass pass{field, g, band, {}, 0};
  if (s.ok()) {
    pass.w.assign(g.value.size(), std::numeric_limits<float>::quiet_NaN());
    s = pass.run(progress, 16);
  }
  progress.end();
  if (!s.ok()) return s.error();
  if (stats) {
    const double exact = core::deterministic_sum(static_cast<std::int64_t>(g.value.size()), [&](std::int64_t i) {
      return std::abs(g.value[static_cast<std::size_t>(i)]) <= band ? 1.0 : 0.0;
    });
    *stats = {g.value.size(), static_cast<std::size_t>(exact), pass.evaluations, seconds_distance, watch.seconds()};
  }
  return g;
}

// Trilinear interpolation and its exact derivative; outside the box, value(clamp(p)) + |p − clamp(p)|, whose
// gradient along a clamped axis is the unit offset from the box.
SdfGrid::Sample SdfGrid::sample(const Vec3f& p) const {
  // A NaN would reach the float-to-int casts below (undefined behaviour): answer NaN instead.
  if (!p.allFinite()) return {std::numeric_limits<float>::quiet_NaN(), Vec3f::Zero()};
  const Vec3f g = (p - origin) / spacing;
  const Vec3f top = (dims - Vec3i::Ones()).cast<float>();
  const Vec3f gc = g.cwiseMax(Vec3f::Zero()).cwiseMin(top);
  int c[3];
  float f[3];
  for (int a = 0; a < 3; ++a) {
    c[a] = std::min(static_cast<int>(gc[a]), dims[a] - 2);
    f[a] = gc[a] - float(c[a]);
  }
  const std::size_t sx = 1, sy = static_cast<std::size_t>(dims.x()), sz = sy * static_cast<std::size_t>(dims.y());
  const float* v = value.data() + index(c[0], c[1], c[2]);
  const float v000 = v[0], v100 = v[sx], v010 = v[sy], v110 = v[sx + sy];
  const float v001 = v[sz], v101 = v[sx + sz], v011 = v[sy + sz], v111 = v[sx + sy + sz];
  // Interpolate along x on the four x-edges, then along y, then z.
  const float x00 = v000 + f[0] * (v100 - v000), x10 = v010 + f[0] * (v110 - v010);
  const float x01 = v001 + f[0] * (v101 - v001), x11 = v011 + f[0] * (v111 - v011);
  const float y0 = x00 + f[1] * (x10 - x00), y1 = x01 + f[1] * (x11 - x01);
  Sample s{y0 + f[2] * (y1 - y0), Vec3f::Zero()};
  const float dx0 = (v100 - v000) + f[1] * ((v110 - v010) - (v100 - v000));
  const float dx1 = (v101 - v001) + f[1] * ((v111 - v011) - (v101 - v001));
  s.gradient = Vec3f(dx0 + f[2] * (dx1 - dx0), (x10 - x00) + f[2] * ((x11 - x01) - (x10 - x00)), y1 - y0) / spacing;
  const Vec3f outside = (g - gc) * spacing;
  if (const float len = outside.norm(); len > 0.0f) {
    s.distance += len;
    for (int a = 0; a < 3; ++a)
      if (outside[a] != 0.0f) s.gradient[a] = outside[a] / len;
  }
  return s;
}

Vec3f SdfGrid::gradient(const Vec3f& p) const {
  const Vec3f g = sample(p).gradient;
  const float n = g.norm();
  return n > 0.0f ? Vec3f(g / n) : Vec3f::Zero();
}

Vec3f SdfGrid::project_to_surface(const Vec3f& p) const {
  // Newton steps on the interpolant: the first one alone is off by O(d·angle error) where the gradient bends
  // (concave creases, thin walls); a few more settle on the zero level set for little extra cost.
  Vec3f x = p;
  for (int step = 0; step < kProjectionSteps; ++step) {
    const Sample s = sample(x);
    const float n = s.gradient.norm();
    if (!(n > 0.0f)) break;
    x -= (s.distance / n) * (s.gradient / n);
    if (std::abs(s.distance) <= 1e-3f * spacing) break;
  }
  return x;
}

float auto_sdf_spacing(const Aabb& box, float margin, float d, double max_nodes) {
  float s = 0.5f * d;
  while (sdf_node_count(box, s, margin) > max_nodes) s *= 1.25f;
  return s;
}

double sdf_node_count(const Aabb& box, float spacing, float margin) {
  const Vec3f size = box.size() + Vec3f::Constant(2.0f * margin);
  return double(size.x() / spacing) * double(size.y() / spacing) * double(size.z() / spacing);
}

}  // namespace ff::sampling
