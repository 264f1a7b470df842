#include "control/nearest_seed_field.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace ff::control {

namespace {

// The centre of cell (i, j, k) of a grid whose corner is `lo` (compute's seeding and sweep's comparisons must agree).
Vec3f cell_centre(const Vec3f& lo, float cell, int i, int j, int k) {
  return Vec3f(lo.x() + cell * (float(i) + 0.5f), lo.y() + cell * (float(j) + 0.5f), lo.z() + cell * (float(k) + 0.5f));
}

}  // namespace

void NearestSeedField::reset(const Vec3f& lo, const Vec3f& hi, float cell, std::size_t max_cells) {
  lo_ = lo;
  const Vec3f ext = (hi - lo).cwiseMax(Vec3f::Constant(1e-6f));
  cell_ = std::max(cell, 1e-6f);
  // Coarsen until the grid fits the cell budget (a huge domain must not cost memory per step).
  for (;;) {
    dims_ = (ext / cell_).array().ceil().cast<int>().cwiseMax(1);
    if (double(dims_.x()) * dims_.y() * dims_.z() <= double(max_cells)) break;
    cell_ *= 1.25f;
  }
  const auto n = static_cast<std::size_t>(dims_.x()) * dims_.y() * dims_.z();
  seed_.assign(n, kInvalidIndex);
  dist2_.assign(n, INFINITY);
  empty_ = true;
}

Vec3i NearestSeedField::cell_of(const Vec3f& p) const {
  Vec3i c;
  for (int a = 0; a < 3; ++a) c[a] = std::clamp(static_cast<int>(std::floor((p[a] - lo_[a]) / cell_)), 0, dims_[a] - 1);
  return c;
}

Index NearestSeedField::nearest(const Vec3f& p) const {
  if (empty_) return kInvalidIndex;
  const Vec3i c = cell_of(p);
  return seed_[static_cast<std::size_t>(c.x()) + static_cast<std::size_t>(dims_.x()) * (c.y() + std::size_t(dims_.y()) * c.z())];
}

void NearestSeedField::compute(std::span<const Vec3f> points, std::span<const Index> seeds) {
  std::fill(seed_.begin(), seed_.end(), kInvalidIndex);
  std::fill(dist2_.begin(), dist2_.end(), INFINITY);
  empty_ = seeds.empty();
  if (empty_) return;
  const int nx = dims_.x(), ny = dims_.y();
  auto at = [&](int i, int j, int k) { return static_cast<std::size_t>(i) + std::size_t(nx) * (j + std::size_t(ny) * k); };
  for (Index s : seeds) {  // in order: ties keep the first seed, so the field is deterministic
    const Vec3f& x = points[s];
    const Vec3i c = cell_of(x);
    const std::size_t k = at(c.x(), c.y(), c.z());
    const float d2 = (x - cell_centre(lo_, cell_, c.x(), c.y(), c.z())).squaredNorm();
    if (d2 < dist2_[k]) dist2_[k] = d2, seed_[k] = s;
  }
  // Forward: the 13 neighbours earlier in raster order; backward: the 13 later ones, each in the order the loops
  // dk, dj, di visit them. Two passes each way settle the cases one pass misses (a seed reached only through a turn).
  std::array<Vec3i, 13> fwd, bwd;
  int nf = 0, nb = 0;
  for (int dk = -1; dk <= 1; ++dk)
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        if (dk < 0 || (dk == 0 && (dj < 0 || (dj == 0 && di < 0)))) fwd[std::size_t(nf++)] = Vec3i(di, dj, dk);
        if (dk > 0 || (dk == 0 && (dj > 0 || (dj == 0 && di > 0)))) bwd[std::size_t(nb++)] = Vec3i(di, dj, dk);
      }
  for (int pass = 0; pass < 2; ++pass) {
    sweep(points, fwd, true);
    sweep(points, bwd, false);
  }
}

// One raster sweep (forward: cells in raster order, backward: reversed): each cell takes the closest of its own seed
// and those of `offsets`' neighbours, in that order (the first of equals stays). Cells not on the grid's border skip
// the bounds checks; the result is that of checking every neighbour one by one, bit for bit (the same comparisons in
// the same order), at a fraction of the cost: the gather term recomputes this field every sub-step.
void NearestSeedField::sweep(std::span<const Vec3f> points, const std::array<Vec3i, 13>& offsets, bool forward) {
  const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
  const std::ptrdiff_t sy = nx, sz = std::ptrdiff_t(nx) * ny;
  std::array<std::ptrdiff_t, 13> step{};
  for (std::size_t o = 0; o < offsets.size(); ++o)
    step[o] = offsets[o].x() + sy * offsets[o].y() + sz * offsets[o].z();
  for (int kk = 0; kk < nz; ++kk) {
    const int k = forward ? kk : nz - 1 - kk;
    for (int jj = 0; jj < ny; ++jj) {
      const int j = forward ? jj : ny - 1 - jj;
      const bool inner_jk = j > 0 && j < ny - 1 && k > 0 && k < nz - 1;
      for (int ii = 0; ii < nx; ++ii) {
        const int i = forward ? ii : nx - 1 - ii;
        const std::ptrdiff_t here = i + sy * j + sz * k;
        const Vec3f centre = cell_centre(lo_, cell_, i, j, k);
        const bool inner = inner_jk && i > 0 && i < nx - 1;
        for (std::size_t o = 0; o < offsets.size(); ++o) {
          if (!inner) {
            const int a = i + offsets[o].x(), b = j + offsets[o].y(), c = k + offsets[o].z();
            if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
          }
          const Index s = seed_[std::size_t(here + step[o])];
          if (s == kInvalidIndex) continue;
          const float d2 = (points[s] - centre).squaredNorm();
          if (d2 < dist2_[std::size_t(here)]) dist2_[std::size_t(here)] = d2, seed_[std::size_t(here)] = s;
        }
      }
    }
  }
}

}  // namespace ff::control
