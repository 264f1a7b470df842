#include "sim/emitter.h"

#include <fmt/format.h>

#include <cmath>
#include <unordered_set>

namespace ff::sim {
namespace {

struct Lattice {
  Vec3f origin;   // first lattice point: domain.min + r
  float d;        // spacing
  Vec3i count;    // lattice points per axis inside the walls
};

Lattice lattice_of(const Domain& domain, float r) {
  const float d = 2.0f * r;
  Lattice l{domain.min + Vec3f::Constant(r), d, Vec3i::Zero()};
  for (int a = 0; a < 3; ++a)
    l.count[a] = static_cast<int>(std::floor((domain.max[a] - r - l.origin[a]) / d + 1e-4f)) + 1;
  return l;
}

// Inclusive index range of lattice points along axis a whose coordinate lies in [lo, hi].
void index_range(const Lattice& l, int a, float lo, float hi, int& i0, int& i1) {
  i0 = std::max(0, static_cast<int>(std::ceil((lo - l.origin[a]) / l.d - 1e-4f)));
  i1 = std::min(l.count[a] - 1, static_cast<int>(std::floor((hi - l.origin[a]) / l.d + 1e-4f)));
}

template <class F>
void for_each_point(const FluidSource& s, const Lattice& l, F&& f) {
  const Vec3f lo = s.shape == FluidSource::Shape::Box ? s.min : Vec3f(s.center - Vec3f::Constant(s.radius));
  const Vec3f hi = s.shape == FluidSource::Shape::Box ? s.max : Vec3f(s.center + Vec3f::Constant(s.radius));
  int b[3], e[3];
  for (int a = 0; a < 3; ++a) index_range(l, a, lo[a], hi[a], b[a], e[a]);
  const float r2 = s.radius * s.radius;
  for (int k = b[2]; k <= e[2]; ++k)
    for (int j = b[1]; j <= e[1]; ++j)
      for (int i = b[0]; i <= e[0]; ++i) {
        const Vec3f x = l.origin + l.d * Vec3f(float(i), float(j), float(k));
        if (s.shape == FluidSource::Shape::Sphere && (x - s.center).squaredNorm() > r2) continue;
        f(i, j, k, x);
      }
}

}  // namespace

std::size_t estimate_particle_count(std::span<const FluidSource> sources, const Domain& domain, float spacing) {
  const Lattice l = lattice_of(domain, 0.5f * spacing);
  double total = 0.0;
  for (const auto& s : sources) {
    const Vec3f lo = s.shape == FluidSource::Shape::Box ? s.min : Vec3f(s.center - Vec3f::Constant(s.radius));
    const Vec3f hi = s.shape == FluidSource::Shape::Box ? s.max : Vec3f(s.center + Vec3f::Constant(s.radius));
    double n = 1.0;
    for (int a = 0; a < 3; ++a) {
      int i0, i1;
      index_range(l, a, lo[a], hi[a], i0, i1);
      n *= std::max(0, i1 - i0 + 1);
    }
    if (s.shape == FluidSource::Shape::Sphere) n *= 3.14159265 / 6.0;  // ball / bounding cube
    total += n;
  }
  return static_cast<std::size_t>(std::min(total, 1e18));
}

std::vector<FluidSource> boxes_for_count(const FluidSource& column, const Domain& domain, float r, std::size_t count) {
  const Lattice l = lattice_of(domain, r);
  int b[3], e[3];
  for (int a = 0; a < 3; ++a) index_range(l, a, column.min[a], column.max[a], b[a], e[a]);
  const auto nx = static_cast<std::size_t>(std::max(0, e[0] - b[0] + 1)), nz = static_cast<std::size_t>(std::max(0, e[2] - b[2] + 1));
  std::vector<FluidSource> out;
  if (count == 0 || nx == 0 || nz == 0 || b[1] >= l.count[1]) return out;
  // Lattice coordinate of index i along axis a, and a box edge half a spacing outside it.
  const auto at = [&](int a, std::size_t i) { return l.origin[a] + l.d * float(i); };
  const float h = 0.5f * l.d;
  const auto box = [&](std::size_t x0, std::size_t x1, std::size_t y0, std::size_t y1, std::size_t z0, std::size_t z1) {
    FluidSource s = column;
    s.shape = FluidSource::Shape::Box;
    s.min = Vec3f(at(0, x0) - h, at(1, y0) - h, at(2, z0) - h);
    s.max = Vec3f(at(0, x1) + h, at(1, y1) + h, at(2, z1) + h);
    out.push_back(s);
  };
  const auto x0 = std::size_t(b[0]), y0 = std::size_t(b[1]), z0 = std::size_t(b[2]);
  const std::size_t layer = nx * nz, layers = count / layer, rows = (count % layer) / nx, rest = count % nx;
  if (layers > 0) box(x0, x0 + nx - 1, y0, y0 + layers - 1, z0, z0 + nz - 1);
  if (rows > 0) box(x0, x0 + nx - 1, y0 + layers, y0 + layers, z0, z0 + rows - 1);
  if (rest > 0) box(x0, x0 + rest - 1, y0 + layers, y0 + layers, z0 + rows, z0 + rows);
  return out;
}

Status fill_sources(std::span<const FluidSource> sources, const Domain& domain, float r, ParticleSet& p,
                    std::size_t max_particles) {
  const std::size_t estimate = estimate_particle_count(sources, domain, 2.0f * r);
  if (estimate + p.size() > max_particles)
    return param_error(fmt::format("the fluid sources would make about {} particles, more than the limit of {}; "
                                   "increase solver.particle_radius or shrink the sources",
                                   estimate + p.size(), max_particles));
  const Lattice l = lattice_of(domain, r);
  std::unordered_set<std::uint64_t> taken;
  taken.reserve(estimate);
  for (std::size_t s = 0; s < sources.size(); ++s) {
    std::size_t added = 0;
    for_each_point(sources[s], l, [&](int i, int j, int k, const Vec3f& x) {
      const std::uint64_t key = (std::uint64_t(k) << 42) | (std::uint64_t(j) << 21) | std::uint64_t(i);
      if (!taken.insert(key).second) return;
      p.push_back(x, sources[s].velocity);
      ++added;
    });
    if (added == 0)
      return param_error(fmt::format("fluid[{}] holds no particle inside the domain (is it outside the domain box, "
                                     "or smaller than the particle spacing {} m?)",
                                     s, 2.0f * r));
  }
  // push_back grew the arrays geometrically: give the slack back (it would count as solver memory).
  p.for_each_array([](auto& a) { a.shrink_to_fit(); });
  return {};
}

}  // namespace ff::sim
