#include "control/nearest_seed_field.h"

#include <algorithm>
#include <cmath>

namespace ff::control {

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
  const int nx = dims_.x(), ny = dims_.y(), nz = dims_.z();
  auto at = [&](int i, int j, int k) { return static_cast<std::size_t>(i) + std::size_t(nx) * (j + std::size_t(ny) * k); };
  auto centre = [&](int i, int j, int k) {
    return Vec3f(lo_.x() + cell_ * (float(i) + 0.5f), lo_.y() + cell_ * (float(j) + 0.5f), lo_.z() + cell_ * (float(k) + 0.5f));
  };
  for (Index s : seeds) {  // in order: ties keep the first seed, so the field is deterministic
    const Vec3f& x = points[s];
    const Vec3i c = cell_of(x);
    const std::size_t k = at(c.x(), c.y(), c.z());
    const float d2 = (x - centre(c.x(), c.y(), c.z())).squaredNorm();
    if (d2 < dist2_[k]) dist2_[k] = d2, seed_[k] = s;
  }
  auto relax = [&](int i, int j, int k, int di, int dj, int dk) {
    const int a = i + di, b = j + dj, c = k + dk;
    if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) return;
    const Index s = seed_[at(a, b, c)];
    if (s == kInvalidIndex) return;
    const std::size_t here = at(i, j, k);
    const float d2 = (points[s] - centre(i, j, k)).squaredNorm();
    if (d2 < dist2_[here]) dist2_[here] = d2, seed_[here] = s;
  };
  // Forward: neighbours earlier in raster order; backward: later ones. Two passes each way settle
  // the cases one pass misses (a seed reached only through a turn).
  for (int pass = 0; pass < 2; ++pass) {
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i)
          for (int dk = -1; dk <= 0; ++dk)
            for (int dj = -1; dj <= 1; ++dj)
              for (int di = -1; di <= 1; ++di)
                if (dk < 0 || dj < 0 || (dj == 0 && di < 0)) relax(i, j, k, di, dj, dk);
    for (int k = nz - 1; k >= 0; --k)
      for (int j = ny - 1; j >= 0; --j)
        for (int i = nx - 1; i >= 0; --i)
          for (int dk = 0; dk <= 1; ++dk)
            for (int dj = -1; dj <= 1; ++dj)
              for (int di = -1; di <= 1; ++di)
                if (dk > 0 || dj > 0 || (dj == 0 && di > 0)) relax(i, j, k, di, dj, dk);
  }
}

}  // namespace ff::control
