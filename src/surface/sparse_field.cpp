#include "surface/sparse_field.h"

#include "core/memory.h"

#include "core/parallel.h"
#include "surface/block_loop.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace ff::surface {

std::int64_t SparseField::find(std::uint64_t key) const {
  const auto it = std::lower_bound(keys.begin(), keys.end(), key);
  return it != keys.end() && *it == key ? std::int64_t(it - keys.begin()) : -1;
}

std::vector<std::array<std::int64_t, 8>> SparseField::upper_neighbors() const {
  std::vector<std::array<std::int64_t, 8>> up(keys.size());
  for_each_block(std::int64_t(keys.size()), [&](std::int64_t b) {
    const auto c = block_coords(keys[std::size_t(b)]);
    for (int s = 0; s < 8; ++s) {
      const std::int64_t x = c[0] + (s & 1), y = c[1] + ((s >> 1) & 1), z = c[2] + ((s >> 2) & 1);
      const bool inside = x < block_dims[0] && y < block_dims[1] && z < block_dims[2];
      up[std::size_t(b)][s] = inside ? find(block_key(x, y, z)) : -1;
    }
  });
  return up;
}

std::size_t SparseField::bytes() const {
  std::size_t b = keys.capacity() * sizeof(std::uint64_t) + values.capacity() * sizeof(std::vector<float>);
  for (const auto& v : values) b += v.capacity() * sizeof(float);
  return b;
}

bool SparseField::sample(const Vec3f& p, float* value, Vec3f* gradient) const {
  if (keys.empty()) return false;
  double g[3];
  std::int64_t b[3];
  int l[3];
  double t[3];
  for (int a = 0; a < 3; ++a) {
    g[a] = (double(p[a]) - origin[a]) / cell;
    const double fl = std::floor(g[a]);
    if (!(fl >= 0.0) || !(fl < double(block_dims[a] * kBlockCells))) return false;
    const auto n = std::int64_t(fl);
    b[a] = n / kBlockCells;
    l[a] = int(n - b[a] * kBlockCells);
    t[a] = g[a] - fl;
  }
  const std::int64_t idx = find(block_key(b[0], b[1], b[2]));
  if (idx < 0) return false;
  const float* v = values[std::size_t(idx)].data();
  float c[8];
  for (int k = 0; k < 8; ++k) c[k] = v[local(l[0] + (k & 1), l[1] + ((k >> 1) & 1), l[2] + ((k >> 2) & 1))];
  const float x = float(t[0]), y = float(t[1]), z = float(t[2]);
  // Trilinear: interpolate along x, then y, then z; the gradient from the same partial sums.
  const float c00 = c[0] + x * (c[1] - c[0]), c10 = c[2] + x * (c[3] - c[2]);
  const float c01 = c[4] + x * (c[5] - c[4]), c11 = c[6] + x * (c[7] - c[6]);
  const float c0 = c00 + y * (c10 - c00), c1 = c01 + y * (c11 - c01);
  *value = c0 + z * (c1 - c0);
  const float dx0 = (1 - y) * (c[1] - c[0]) + y * (c[3] - c[2]), dx1 = (1 - y) * (c[5] - c[4]) + y * (c[7] - c[6]);
  const float inv = float(1.0 / cell);
  *gradient = Vec3f((1 - z) * dx0 + z * dx1, (1 - z) * (c10 - c00) + z * (c11 - c01), c1 - c0) * inv;
  return true;
}

Vec3f SparseField::project(const Vec3f& p) const {
  Vec3f x = p;
  float v = 0.0f;
  Vec3f grad;
  if (!sample(x, &v, &grad)) return p;
  const float max_step = float(0.5 * cell);
  for (int it = 0; it < 3; ++it) {
    const float g2 = grad.squaredNorm();
    if (!(g2 > 0.0f)) break;
    Vec3f step = -((v - iso) / g2) * grad;
    if (step.norm() > max_step) step *= max_step / step.norm();
    float v2 = 0.0f;
    Vec3f grad2;
    if (!sample(x + step, &v2, &grad2) || !(std::abs(v2 - iso) < std::abs(v - iso))) break;
    x += step;
    v = v2;
    grad = grad2;
  }
  return x;
}

namespace {

constexpr int kB = SparseField::kBlockCells;
constexpr int kN = SparseField::kBlockNodes;
// Widening of the node ranges, in cells: far above the rounding of the range bounds (~1e-5 cells at |o| < 32).
constexpr float kSlack = 1e-3f;

// Particles sorted by home block: the blocks' keys (bins) with their particle ranges, and each particle's
// position inside its home block in cells (SoA: the evaluation loop reads these three arrays only).
struct Binned {
  std::vector<std::uint64_t> bin_key;
  std::vector<std::uint32_t> bin_start;  // bin b holds particles [bin_start[b], bin_start[b + 1])
  std::vector<float> ox, oy, oz;         // in [0, 8) cells
};


/// The grid's frame: cell, iso, origin and block counts of a grid that holds every node within h of a particle.
Status frame_grid(std::span<const Vec3f> particles, float spacing, const SurfaceParams& params, SparseField& field) {
  const double d = spacing;
  field.cell = params.cell_size * d;
  field.iso = params.iso;
  const double h = params.kernel_radius * d;
  const double block_edge = kB * field.cell;

  Aabb box;
  for (const Vec3f& p : particles) box.extend(p);
  const double margin = h + field.cell;  // every node within h of a particle has a non-negative index
  field.origin = box.min.cast<double>() - Vec3d::Constant(margin);
  long double node_count = 1.0L;
  for (int a = 0; a < 3; ++a) {
    // +2: the block holding the farthest node, and one more so that every home block has a +1 neighbour.
    const double extent = double(box.max[a]) + margin - field.origin[a];
    const double blocks = std::floor(extent / block_edge) + 2.0;
    if (!(blocks < double(1 << 20)))
      return param_error(
          fmt::format("surface: the particles span {:.4g} m along axis {}, {:.4g} blocks of {:.4g} m "
                      "(at most 2^20): spacing or cell_size is too small for this cloud",
                      extent, a, blocks, block_edge));
    field.block_dims[a] = std::int64_t(blocks);
    node_count *= (long double)(field.block_dims[a] * kB + 1);
  }
  if (!(node_count < 9.0e18L))
    return param_error("surface: the particle cloud needs more grid nodes than a 64-bit id can number");
  return {};
}

/// The particles binned by home block: sorted by key, then index (one global order for every block).
Binned bin_particles(std::span<const Vec3f> particles, const SparseField& field) {
  const double block_edge = kB * field.cell;
  const auto n = std::int64_t(particles.size());
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order(static_cast<std::size_t>(n));
  core::parallel_for(n, [&](std::int64_t i) {
    const Vec3f& p = particles[std::size_t(i)];
    std::int64_t b[3];
    for (int a = 0; a < 3; ++a)
      b[a] = std::clamp(std::int64_t(std::floor((double(p[a]) - field.origin[a]) / block_edge)), std::int64_t(0),
                        field.block_dims[a] - 1);
    order[std::size_t(i)] = {field.block_key(b[0], b[1], b[2]), std::uint32_t(i)};
  });
  std::sort(order.begin(), order.end());

  Binned bins;
  bins.ox.resize(std::size_t(n));
  bins.oy.resize(std::size_t(n));
  bins.oz.resize(std::size_t(n));
  for (std::int64_t i = 0; i < n; ++i)
    if (i == 0 || order[std::size_t(i)].first != order[std::size_t(i - 1)].first) {
      bins.bin_key.push_back(order[std::size_t(i)].first);
      bins.bin_start.push_back(std::uint32_t(i));
    }
  bins.bin_start.push_back(std::uint32_t(n));
  core::parallel_for(n, [&](std::int64_t i) {
    const auto [key, idx] = order[std::size_t(i)];
    const auto b = field.block_coords(key);
    const Vec3f& p = particles[idx];
    // The offset inside the home block, rounded once: every block that sees this particle uses these floats.
    bins.ox[std::size_t(i)] = float((double(p.x()) - field.origin.x()) / field.cell - double(kB * b[0]));
    bins.oy[std::size_t(i)] = float((double(p.y()) - field.origin.y()) / field.cell - double(kB * b[1]));
    bins.oz[std::size_t(i)] = float((double(p.z()) - field.origin.z()) / field.cell - double(kB * b[2]));
  });
  return bins;
}

/// Every block within one block of a home block (h ≤ 8 cells), ascending and unique.
std::vector<std::uint64_t> candidate_blocks(const Binned& bins, const SparseField& field) {
  std::vector<std::uint64_t> candidates;
  candidates.reserve(bins.bin_key.size() * 8);
  for (const std::uint64_t key : bins.bin_key) {
    field.for_each_block_around(field.block_coords(key), [&](std::uint64_t k, int, int, int) { candidates.push_back(k); });
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  return candidates;
}

/// The support of the poly6 kernel in cell units; splat_particle adds the unscaled (h² − r²)³ and the caller applies
/// the kernel's constant once per node.
struct Splat {
  float hc;      // support in cells
  float h2;      // hc²
  float reach;   // hc + kSlack: how far outside a block a particle can still touch a node
};

/// Adds one particle's unscaled kernel to the nodes of block `v`. (px, py, pz) is its offset inside its home
/// block and (sx, sy, sz) = 8 · (home − this block) in cells.
void splat_particle(const Splat& k, float px, float py, float pz, int sx, int sy, int sz,
                    std::array<float, SparseField::kNodesPerBlock>& v) {
  const float hc = k.hc, h2 = k.h2, reach = k.reach;
  const float ox = px + float(sx), oy = py + float(sy), oz = pz + float(sz);
  // Most particles of the 26 neighbouring bins cannot reach this block: reject them with compares.
  if (ox < -reach || ox > float(kB) + reach || oy < -reach || oy > float(kB) + reach || oz < -reach ||
      oz > float(kB) + reach)
    return;
  // Node ranges of the support (a ball, sliced into z planes and y rows). They are widened by kSlack
  // against rounding, so that every node with a positive contribution is visited by every block that
  // has it; a node visited outside the support adds exactly +0, so the ranges need not agree.
  const int x0 = std::max(0, int(std::ceil(ox - hc - kSlack)));
  const int x1 = std::min(kB, int(std::floor(ox + hc + kSlack)));
  const int y0 = std::max(0, int(std::ceil(oy - hc - kSlack)));
  const int y1 = std::min(kB, int(std::floor(oy + hc + kSlack)));
  const int z0 = std::max(0, int(std::ceil(oz - hc - kSlack)));
  const int z1 = std::min(kB, int(std::floor(oz + hc + kSlack)));
  if (x0 > x1 || y0 > y1 || z0 > z1) return;  // the support misses this block
  // Offsets from the particle as float(l − 8d) − o: the same floats in every block (see above).
  // Squared x offsets of the whole row: nodes out of reach get a large value and so add +0 below.
  float fx2[kN];
  for (int lx = 0; lx < kN; ++lx) {
    const float fx = float(lx - sx) - px;
    fx2[lx] = fx * fx;
  }
  for (int lz = z0; lz <= z1; ++lz) {
    const float fz = float(lz - sz) - pz;
    const float fz2 = fz * fz;
    if (fz2 >= h2) continue;
    const float ry = std::sqrt(h2 - fz2) + kSlack;
    const int ya = std::max(y0, int(std::ceil(oy - ry))), yb = std::min(y1, int(std::floor(oy + ry)));
    for (int ly = ya; ly <= yb; ++ly) {
      const float fy = float(ly - sy) - py;
      const float rem = h2 - (fz2 + fy * fy);  // h² − (dy² + dz²)
      if (rem <= 0.0f) continue;
      float* row = &v[std::size_t(SparseField::local(0, ly, lz))];
      // (h² − r²)³ where positive over the whole 9-node row: branch-free and vectorised, which beats
      // clipping the row to the ball; the weight is applied once per node by the caller.
      for (int lx = 0; lx < kN; ++lx) {
        const float q = rem - fx2[lx];
        const float qp = q > 0.0f ? q : 0.0f;
        row[lx] += qp * qp * qp;
      }
    }
  }
}

}  // namespace

Result<SparseField> sparse_field(std::span<const Vec3f> particles, float spacing, const SurfaceParams& params,
                                 double max_memory_mib) {
  SparseField field;
  FF_CHECK(frame_grid(particles, spacing, params, field));
  const Binned bins = bin_particles(particles, field);
  const std::vector<std::uint64_t> candidates = candidate_blocks(bins, field);
  field.candidate_blocks = candidates.size();
  if (candidates.size() > params.max_blocks)
    return param_error(
        fmt::format("surface: {} grid blocks needed, more than max_blocks = {}", candidates.size(), params.max_blocks));
  // The worst case: every candidate block kept (its 9³ values, its key, its slot), before any is evaluated.
  const double block_bytes = sizeof(float) * SparseField::kNodesPerBlock + sizeof(std::vector<float>) + 2 * sizeof(std::uint64_t) + sizeof(float);
  const double need_mib = double(candidates.size()) * block_bytes / (1024.0 * 1024.0);
  double limit_mib = max_memory_mib;
  if (!(limit_mib > 0.0)) {
    const double machine = core::machine_memory_mib();
    limit_mib = machine > 0.0 ? 0.8 * machine : 16384.0;
  }
  if (need_mib > limit_mib)
    return param_error(fmt::format(
        "surface: the grid could need {:.0f} MiB ({} blocks of {}³ cells of {:.4g} m), more than the limit of {:.0f} MiB; "
        "raise surface.cell_size, or limits.max_memory_mb / --max-memory",
        need_mib, candidates.size(), kB, field.cell, limit_mib));

  // Evaluate each candidate block; keep it when the surface passes through it.
  const double d = spacing;
  const double h = params.kernel_radius * d;
  Splat splat;
  splat.hc = float(h / field.cell);
  splat.h2 = splat.hc * splat.hc;
  splat.reach = splat.hc + kSlack;
  // φ in cell units: V_p W(r) = pv (d/cell)³ · 315/(64π hc⁹) (hc² − r²)³ with r in cells (Müller et al. 2003's poly6).
  const float kw = float(params.particle_volume * std::pow(d / field.cell, 3.0) * 315.0 /
                         (64.0 * std::numbers::pi * std::pow(double(splat.hc), 9.0)));
  const float iso = params.iso;
  const auto nc = std::int64_t(candidates.size());
  std::vector<std::vector<float>> kept(candidates.size());
  std::vector<float> block_max(candidates.size(), 0.0f);
  for_each_block(nc, [&](std::int64_t c) {
    std::array<float, SparseField::kNodesPerBlock> v{};
    const auto b = field.block_coords(candidates[std::size_t(c)]);
    // Neighbours in increasing key order (z, then y, then x): the one global particle order.
    field.for_each_block_around(b, [&](std::uint64_t key, int dx, int dy, int dz) {
      const auto it = std::lower_bound(bins.bin_key.begin(), bins.bin_key.end(), key);
      if (it == bins.bin_key.end() || *it != key) return;
      const auto bin = std::size_t(it - bins.bin_key.begin());
      // Node l of this block is node (l − 8·d) of the home block.
      for (std::uint32_t i = bins.bin_start[bin]; i < bins.bin_start[bin + 1]; ++i)
        splat_particle(splat, bins.ox[i], bins.oy[i], bins.oz[i], kB * dx, kB * dy, kB * dz, v);
    });
    for (float& x : v) x *= kw;
    bool any_in = false, any_out = false;
    float mx = 0.0f;
    for (const float x : v) {
      any_in |= x > iso;
      any_out |= !(x > iso);
      mx = std::max(mx, x);
    }
    block_max[std::size_t(c)] = mx;
    if (any_in && any_out) kept[std::size_t(c)].assign(v.begin(), v.end());
  });

  for (std::size_t c = 0; c < candidates.size(); ++c) {
    field.max_value = std::max(field.max_value, block_max[c]);
    if (kept[c].empty()) continue;
    field.keys.push_back(candidates[c]);
    field.values.push_back(std::move(kept[c]));
  }
  return field;
}

}  // namespace ff::surface
