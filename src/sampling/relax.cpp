#include "sampling/relax.h"

#include "core/neighbor_grid.h"
#include "core/pair_loop.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace ff::sampling {

namespace {

// One sample shallower than `depth` back to that depth. Two Newton-like passes: the interpolated SDF is
// not exactly a distance away from the surface.
void push_one(Vec3f& p, const SdfGrid& sdf, float depth) {
  for (int k = 0; k < 2; ++k) {
    const SdfGrid::Sample s = sdf.sample(p);
    if (s.distance <= -depth) break;
    const float g = s.gradient.norm();
    if (!(g > 0.0f)) break;  // on a medial ridge: no direction to move in
    p -= ((s.distance + depth) / g) * s.gradient;
  }
}

}  // namespace

void push_inside(std::span<Vec3f> x, const SdfGrid& sdf, float depth) {
  core::parallel_for(static_cast<std::int64_t>(x.size()),
                     [&](std::int64_t i) { push_one(x[static_cast<std::size_t>(i)], sdf, depth); });
}

namespace {

// The repair's grids have cells of 0.85–0.88 d, smaller than the spacing: a bunny's box holds ~6 of them per sample,
// past the grid's default limit for dense keys, and hashed keys made its separating and dropping 4–6× slower at 1M
// samples.
constexpr double kRepairCellsPerSample = 8.0;

// Cell-sorts x (the grid built on it) and finds its neighbour lists within the grid's radius.
void sort_and_find_neighbors(std::vector<Vec3f>& x, core::NeighborGrid& grid, core::NeighborList& nb,
                             std::vector<Vec3f>& scratch) {
  grid.build(x);
  core::apply_permutation(x, std::span<const Index>(grid.sorted()), scratch);
  grid.points_were_sorted();
  grid.neighbors(x, nb);
}

// Step 1 of enforce_spacing: pairs a little too close are pushed apart (hard distance constraints to 1.03× the
// minimum, Jacobi with averaging, a few sweeps), staying inside.
void separate_close_pairs(std::vector<Vec3f>& x, const SdfGrid& sdf, float min_distance, core::NeighborList& nb,
                          std::vector<Vec3f>& scratch) {
  const float target = 1.03f * min_distance, depth = 0.0f;
  core::NeighborGrid grid(target, kRepairCellsPerSample);
  std::vector<Vec3f> delta(x.size());
  const float m2 = min_distance * min_distance;
  for (int sweep = 0; sweep < 10; ++sweep) {
    sort_and_find_neighbors(x, grid, nb, scratch);
    // Done when no pair violates the minimum itself (pairs between it and the target are fine).
    const bool violated = core::deterministic_max(static_cast<std::int64_t>(x.size()), 0.0, [&](std::int64_t ii) {
      const auto i = static_cast<std::size_t>(ii);
      for (Index j : nb.of(i))
        if ((x[i] - x[j]).squaredNorm() < m2) return 1.0;
      return 0.0;
    }) > 0.0;
    if (!violated) break;
    core::parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t ii) {
      const auto i = static_cast<std::size_t>(ii);
      Vec3f dx = Vec3f::Zero();
      int active = 0;
      for (Index j : nb.of(i)) {
        const Vec3f r = x[i] - x[j];
        const float len = r.norm();
        if (len <= 1e-7f * target) continue;
        dx += (0.5f * (target - len) / len) * r;
        ++active;
      }
      delta[i] = active ? Vec3f(dx / float(active)) : Vec3f::Zero();
    });
    // Only the samples that moved can have left the volume.
    core::parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t i) {
      if (delta[i].isZero()) return;
      x[i] += delta[i];
      push_one(x[i], sdf, depth);
    });
  }
}

// Step 2: in cell order, a sample is kept unless an earlier kept sample is closer than min_distance. x is left
// cell-sorted; returns the kept samples.
std::vector<Vec3f> drop_close_samples(std::vector<Vec3f>& x, float min_distance, core::NeighborList& nb,
                                      std::vector<Vec3f>& scratch) {
  const float m2 = min_distance * min_distance;
  core::NeighborGrid grid(min_distance, kRepairCellsPerSample);
  sort_and_find_neighbors(x, grid, nb, scratch);
  std::vector<std::uint8_t> keep(x.size(), 1);
  for (std::size_t i = 0; i < x.size(); ++i)
    for (Index j : nb.of(i))
      if (j < i && keep[j] && (x[i] - x[j]).squaredNorm() < m2) {
        keep[i] = 0;
        break;
      }
  std::vector<Vec3f> kept;
  kept.reserve(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    if (keep[i]) kept.push_back(x[i]);
  return kept;
}

// Step 3: an inside grid node with no sample within min_distance gets one (greedily, in node order, each new sample
// at least min_distance from all others). This is where thin tips get covered. Returns the new samples.
std::vector<Vec3f> fill_gaps(const std::vector<Vec3f>& kept, const SdfGrid& sdf, float min_distance,
                             std::span<const Vec3f> surface) {
  const float m2 = min_distance * min_distance;
  std::vector<Vec3f> nodes;
  for (int k = 0; k < sdf.dims.z(); ++k)
    for (int j = 0; j < sdf.dims.y(); ++j)
      for (int i = 0; i < sdf.dims.x(); ++i)
        // Inside nodes within two spacings of the surface: deeper voids were never seen after the
        // relaxation (20 seeds × 7 shapes), and the interior is most of the nodes of a big target.
        if (const float v = sdf.value[sdf.index(i, j, k)]; v < 0.0f && v > -2.0f * min_distance)
          nodes.push_back(sdf.node(i, j, k));
  // Surface points reach into tips thinner than the node spacing.
  nodes.insert(nodes.end(), surface.begin(), surface.end());
  core::NeighborGrid kg(min_distance, kRepairCellsPerSample);
  kg.build(kept);
  constexpr std::size_t kChunk = std::size_t(1) << 16;
  std::vector<Vec3f> fresh;
  std::unordered_map<std::uint64_t, std::vector<Index>> added_cells;
  auto cell_key = [](const Vec3i& c) {
    return (std::uint64_t(std::uint32_t(c.x()) & 0x1FFFFF) << 42) | (std::uint64_t(std::uint32_t(c.y()) & 0x1FFFFF) << 21) |
           std::uint64_t(std::uint32_t(c.z()) & 0x1FFFFF);
  };
  std::vector<std::uint8_t> covered;
  for (std::size_t a = 0; a < nodes.size(); a += kChunk) {
    const std::size_t b = std::min(nodes.size(), a + kChunk);
    // "Is any kept sample within min_distance?" stops at the first one (listing them all was most of the 1M
    // bunny's repair: 9.2 s, 5.5 s with this alone).
    kg.any_within(kept, std::span<const Vec3f>(nodes).subspan(a, b - a), min_distance, covered);
    for (std::size_t q = a; q < b; ++q) {
      if (covered[q - a]) continue;
      // Check against the samples added so far (a hash of their cells: thin targets add thousands).
      const Vec3f p = nodes[q];
      const Vec3i c = (p / min_distance).array().floor().cast<int>();
      bool clear = true;
      for (int dz = -1; dz <= 1 && clear; ++dz)
        for (int dy = -1; dy <= 1 && clear; ++dy)
          for (int dx = -1; dx <= 1 && clear; ++dx) {
            const auto it = added_cells.find(cell_key(c + Vec3i(dx, dy, dz)));
            if (it == added_cells.end()) continue;
            for (Index f : it->second)
              if ((fresh[f] - p).squaredNorm() < m2) {
                clear = false;
                break;
              }
          }
      if (clear) {
        added_cells[cell_key(c)].push_back(static_cast<Index>(fresh.size()));
        fresh.push_back(p);
      }
    }
  }
  return fresh;
}

}  // namespace

std::size_t enforce_spacing(std::vector<Vec3f>& x, const SdfGrid& sdf, float min_distance,
                            std::span<const Vec3f> surface, std::size_t* added) {
  // 1. Separate: this settles nearly all close pairs without opening a hole.
  core::NeighborList nb;
  std::vector<Vec3f> scratch;
  separate_close_pairs(x, sdf, min_distance, nb, scratch);
  // 2. Drop.
  std::vector<Vec3f> kept = drop_close_samples(x, min_distance, nb, scratch);
  const std::size_t dropped = x.size() - kept.size();
  // 3. Fill.
  const std::vector<Vec3f> fresh = fill_gaps(kept, sdf, min_distance, surface);
  const std::size_t inserted = fresh.size();
  kept.insert(kept.end(), fresh.begin(), fresh.end());
  x.swap(kept);
  if (added) *added = inserted;
  return dropped;
}

namespace {

// Samples' depths are re-evaluated for all every kRefresh steps of relax_samples.
constexpr int kRefresh = 5;

// One step's forces F_i = −∇_i E, E = Σ_pairs (1 − r/r_c)³ / 3 · r_c: a soft repulsion that reaches past the
// nearest neighbours, so a void is closed by the samples around it, plus the mirror images' near the surface;
// refreshes the cached depths it evaluates.
void relax_forces(const std::vector<Vec3f>& x, const core::NeighborList& nb, const SdfGrid& sdf,
                  const RelaxParams& params, int step, float shell, std::vector<float>& cached,
                  std::vector<Vec3f>& force) {
  const auto ni = static_cast<std::int64_t>(x.size());
  const float d = params.spacing, rc = params.reach * d;
  const __m128 zero = _mm_setzero_ps(), rc4 = _mm_set1_ps(rc), inv_rc = _mm_set1_ps(1.0f / rc),
               one = _mm_set1_ps(1.0f), tiny = _mm_set1_ps(1e-7f * d);
  core::parallel_for(ni, [&](std::int64_t ii) {
    using namespace core::simd;
    const auto i = static_cast<Index>(ii);
    const __m128 px = broadcast(x[i].x()), py = broadcast(x[i].y()), pz = broadcast(x[i].z());
    __m128 fx = zero, fy = zero, fz = zero;
    // Four pairs at a time; coincident samples exert no force here (enforce_spacing separates them).
    core::for_neighbors4(nb.of(i), i, [&](const Index* j, __m128 lanes) {
      const V3 xj = gather(x.data(), j[0], j[1], j[2], j[3]);
      const __m128 rx = _mm_sub_ps(px, xj.x), ry = _mm_sub_ps(py, xj.y), rz = _mm_sub_ps(pz, xj.z);
      const __m128 len = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz)));
      const __m128 use = _mm_and_ps(lanes, _mm_and_ps(_mm_cmplt_ps(len, rc4), _mm_cmpgt_ps(len, tiny)));
      const __m128 q = _mm_sub_ps(one, _mm_mul_ps(len, inv_rc));
      const __m128 c = select(use, _mm_div_ps(_mm_mul_ps(q, q), len));
      fx = _mm_add_ps(fx, _mm_mul_ps(c, rx));
      fy = _mm_add_ps(fy, _mm_mul_ps(c, ry));
      fz = _mm_add_ps(fz, _mm_mul_ps(c, rz));
    });
    Vec3f f(hsum(fx), hsum(fy), hsum(fz));
    // The sample's mirror image across the surface repels it too (at half strength): samples keep off
    // the surface by about half a spacing, so the layers of a thin wall sit near its middle.
    if (step % kRefresh == 0 || cached[i] < shell) {
      const SdfGrid::Sample s = sdf.sample(x[i]);
      cached[i] = -s.distance;
      const float g = s.gradient.norm(), l = 2.0f * std::max(-s.distance, 0.0f);
      if (params.mirror > 0.0f && g > 0.0f && l < rc) {
        const float q = 1.0f - l / rc;
        f -= (params.mirror * q * q / g) * s.gradient;
      }
    }
    force[i] = f;
  });
}

}  // namespace

void relax_samples(std::vector<Vec3f>& x, const SdfGrid& sdf, const RelaxParams& params, core::Progress& progress) {
  const std::size_t n = x.size();
  const auto ni = static_cast<std::int64_t>(n);
  const float d = params.spacing, rc = params.reach * d, depth = params.boundary_depth * d;
  // Verlet lists: neighbours within r_c + skin are found again only when some sample has moved half the skin
  // since the last search (measured: a step's move is capped at max_move·d, but the projection can add to it).
  const float skin = 0.5f * d;
  core::NeighborGrid grid(rc + skin);
  core::NeighborList nb;
  std::vector<Vec3f> scratch, force(n), at_search;
  // The surface matters only to samples near it. Each sample's depth is cached; every kRefresh steps all
  // are re-evaluated, in between only those that can be within reach of the surface by then (a sample
  // moves at most max_move·d per step).
  const float shell = 0.5f * rc + (kRefresh + 1) * params.max_move * d + depth;
  std::vector<float> cached(n, 0.0f), fscratch;
  std::vector<Vec3f> move(n, Vec3f::Zero());  // each sample's last move, kept in its order
  progress.begin("blue-noise relaxation", static_cast<std::size_t>(params.steps));
  for (int step = 0; step < params.steps; ++step) {
    const bool stale = at_search.empty() || core::deterministic_max(ni, 0.0, [&](std::int64_t i) {
      return double((x[i] - at_search[i]).squaredNorm());
    }) > double(0.25f * skin * skin);
    if (stale) {
      grid.build(x);
      core::apply_permutation(cached, std::span<const Index>(grid.sorted()), fscratch);
      core::apply_permutation(x, std::span<const Index>(grid.sorted()), scratch);
      core::apply_permutation(move, std::span<const Index>(grid.sorted()), scratch);
      grid.points_were_sorted();
      grid.neighbors(x, nb);
      at_search = x;
    }
    relax_forces(x, nb, sdf, params, step, shell, cached, force);
    // Gradient descent with a step that moves the mean sample by `step_size`·d, annealed to a fifth of
    // it over the run, plus `momentum` times the sample's last move (Polyak's heavy ball: the long-wavelength
    // modes, a denser region spreading over the whole shape, converge in far fewer steps), each sample's move
    // capped at `max_move`·d.
    const double mean = core::deterministic_sum(ni, [&](std::int64_t i) { return double(force[i].norm()); }) / double(n);
    const float anneal = 1.0f - 0.8f * float(step) / float(std::max(1, params.steps));
    const float k = mean > 0.0 ? static_cast<float>(params.step_size * anneal * d / mean) : 0.0f;
    const float cap = params.max_move * d;
    core::parallel_for(ni, [&](std::int64_t i) {
      Vec3f dx = k * force[i] + params.momentum * move[i];
      const float len = dx.norm();
      if (len > cap) dx *= cap / len;
      move[i] = dx;
      x[i] += dx;
    });
    core::parallel_for(ni, [&](std::int64_t i) {
      if (cached[i] < shell) push_one(x[static_cast<std::size_t>(i)], sdf, depth);
    });
    if (!progress.tick(static_cast<std::size_t>(step + 1))) break;
  }
  progress.end();
}

}  // namespace ff::sampling
