#include "sampling/samplers.h"

#include "core/parallel.h"
#include "core/timer.h"
#include "sampling/relax.h"
#include "sampling/sample_elimination.h"
#include "sampling/weights.h"

#include <Eigen/Geometry>  // cross product
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

namespace ff::sampling {
namespace {

// Random streams: one per fixed-size chunk of work, seeded from (seed, chunk), so results do not depend
// on the thread count. Floats from the top 24 bits: the same on every standard library.
std::uint64_t mix(std::uint64_t x) {  // splitmix64 finaliser
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
struct Rng {
  std::mt19937_64 engine;
  Rng(std::uint64_t seed, std::uint64_t stream) : engine(mix(seed ^ mix(stream))) {}
  float uniform() { return static_cast<float>(engine() >> 40) * 0x1.0p-24f; }  // [0, 1)
};

constexpr std::size_t kChunk = 4096;  // random points per stream

// Surface samples: N on the area A for hexagonal packing at spacing d.
double surface_count(double area, float d) { return area / (0.5 * std::sqrt(3.0) * double(d) * d); }

}  // namespace

double estimate_sample_count(bool solid, double volume, double area, float d) {
  return solid ? volume / (double(d) * d * d) : surface_count(area, d);
}

namespace {

std::vector<Vec3f> drop_sparse(std::vector<Vec3f> x, const SparseParams& sparse, std::uint64_t seed) {
  if (!sparse.active()) return x;
  std::vector<Vec3f> kept;
  kept.reserve(x.size());
  for (std::size_t c = 0; c * kChunk < x.size(); ++c) {
    Rng rng(seed, 0x5A5A0000ull + c);
    for (std::size_t i = c * kChunk; i < std::min(x.size(), (c + 1) * kChunk); ++i) {
      const bool in_box = std::any_of(sparse.drop_boxes.begin(), sparse.drop_boxes.end(),
                                      [&](const Aabb& b) { return b.contains(x[i]); });
      const bool dropped = rng.uniform() < sparse.drop_fraction;
      if (!in_box && !dropped) kept.push_back(x[i]);
    }
  }
  return kept;
}

}  // namespace

void ignore_hidden_surfaces(SdfGrid& sdf) {
  // Interface nodes (a 6-neighbour of the other sign) keep their exact distance; every other node gets
  // the distance to them by fast sweeping (Zhao 2005: Gauss–Seidel sweeps of the first-order Eikonal
  // update in the 8 axis orders). Where that distance exceeds the stored one by more than a node
  // spacing, the stored distance was to a surface hidden inside the volume (a face of one part inside
  // another): the swept value replaces it. Elsewhere the exact value stays.
  const Vec3i n = sdf.dims;
  const float h = sdf.spacing;
  const std::size_t total = sdf.value.size();
  constexpr float kFar = std::numeric_limits<float>::max();
  std::vector<float> t(total, kFar);
  // Interface scan, parallel over z-slices (each node writes only its own slot; the flag is a max).
  const bool hidden = core::deterministic_max(n.z(), 0.0, [&](std::int64_t kk) {
    const int k = static_cast<int>(kk);
    double found = 0.0;
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i) {
        const float v = sdf.value[sdf.index(i, j, k)];
        bool interface = false;
        const int nb[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
        for (const auto& c : nb)
          if (c[0] >= 0 && c[1] >= 0 && c[2] >= 0 && c[0] < n.x() && c[1] < n.y() && c[2] < n.z() &&
              (sdf.value[sdf.index(c[0], c[1], c[2])] < 0.0f) != (v < 0.0f))
            interface = true;
        if (interface) t[sdf.index(i, j, k)] = std::abs(v);
        else if (std::abs(v) < 0.5f * h) found = 1.0;  // on a surface with the same sign on both sides
      }
    return found;
  }) > 0.0;
  if (!hidden) return;  // the usual case: every surface is a boundary, nothing to sweep
  auto at = [&](int i, int j, int k) {
    if (i < 0 || j < 0 || k < 0 || i >= n.x() || j >= n.y() || k >= n.z()) return kFar;
    return t[sdf.index(i, j, k)];
  };
  for (int sweep = 0; sweep < 8; ++sweep) {
    const int dx = sweep & 1 ? -1 : 1, dy = sweep & 2 ? -1 : 1, dz = sweep & 4 ? -1 : 1;
    for (int kk = 0; kk < n.z(); ++kk)
      for (int jj = 0; jj < n.y(); ++jj)
        for (int ii = 0; ii < n.x(); ++ii) {
          const int i = dx > 0 ? ii : n.x() - 1 - ii, j = dy > 0 ? jj : n.y() - 1 - jj, k = dz > 0 ? kk : n.z() - 1 - kk;
          float a[3] = {std::min(at(i - 1, j, k), at(i + 1, j, k)), std::min(at(i, j - 1, k), at(i, j + 1, k)),
                        std::min(at(i, j, k - 1), at(i, j, k + 1))};
          std::sort(a, a + 3);
          if (a[0] == kFar) continue;
          // Solve the Godunov upwind update with the smallest neighbours first.
          float u = a[0] + h;
          if (u > a[1]) {
            const float s = a[0] + a[1], q = 2.0f * h * h - (a[0] - a[1]) * (a[0] - a[1]);
            u = 0.5f * (s + std::sqrt(std::max(q, 0.0f)));
            if (u > a[2]) {
              const float s3 = a[0] + a[1] + a[2];
              const float q3 = s3 * s3 - 3.0f * (a[0] * a[0] + a[1] * a[1] + a[2] * a[2] - h * h);
              u = (s3 + std::sqrt(std::max(q3, 0.0f))) / 3.0f;
            }
          }
          float& cur = t[sdf.index(i, j, k)];
          cur = std::min(cur, u);
        }
  }
  core::parallel_for(static_cast<std::int64_t>(total), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    float& v = sdf.value[i];
    if (t[i] != kFar && t[i] > std::abs(v) + h) v = v < 0.0f ? -t[i] : t[i];
  });
}

double enclosed_volume(const SdfGrid& sdf) {
  const double h = sdf.spacing, cell = h * h * h;
  return core::deterministic_sum(static_cast<std::int64_t>(sdf.value.size()), [&](std::int64_t i) {
    return std::clamp(0.5 - double(sdf.value[static_cast<std::size_t>(i)]) / h, 0.0, 1.0);
  }) * cell;
}

float automatic_spacing(const MeshField& field, std::size_t auto_count) {
  const double n = double(std::max<std::size_t>(auto_count, 1));
  if (field.encloses_volume()) return static_cast<float>(std::cbrt(field.volume() / n));
  return static_cast<float>(std::sqrt(field.area() / (0.5 * std::sqrt(3.0) * n)));
}

namespace {

// The cubic lattice of spacing d centred in the field's box: the cell centres of the whole cells that fit (a
// tolerance so that 1.0 / 0.1 counts as 10), widened by `extra` points on every side; points in x-fastest order.
struct CentredLattice {
  Vec3i dims;
  std::vector<Vec3f> point;
};

CentredLattice centred_lattice(const MeshField& field, float d, int extra) {
  const Aabb box = field.bounds();
  const Vec3f size = box.size();
  CentredLattice l{((size / d).array() + 1e-4f).floor().cast<int>().max(1) + 2 * extra, {}};
  const Vec3f origin = box.min + 0.5f * (size - (l.dims.cast<float>() - Vec3f::Ones()) * d);
  l.point.reserve(static_cast<std::size_t>(l.dims.x()) * l.dims.y() * l.dims.z());
  for (int k = 0; k < l.dims.z(); ++k)
    for (int j = 0; j < l.dims.y(); ++j)
      for (int i = 0; i < l.dims.x(); ++i) l.point.push_back(origin + Vec3f(float(i), float(j), float(k)) * d);
  return l;
}

}  // namespace

std::vector<Vec3f> voxel_samples(const MeshField& field, float d) {
  // Centred in the box: a symmetric shape gets a symmetric set, and no sample sits on a face of a box-shaped target.
  const CentredLattice l = centred_lattice(field, d, 0);
  std::vector<std::uint8_t> in(l.point.size());
  field.inside(l.point, in);
  std::vector<Vec3f> out;
  for (std::size_t i = 0; i < l.point.size(); ++i)
    if (in[i]) out.push_back(l.point[i]);
  return out;
}

double LatticeCells::cells() const {
  double n = 0.0;
  for (float v : share) n += double(v);
  return n;
}

LatticeCells lattice_cells(const MeshField& field, float d) {
  // voxel_samples' lattice, one point wider on every side: an outside point there can still cover part of its cell.
  const CentredLattice lattice = centred_lattice(field, d, 1);
  const Vec3i dims = lattice.dims;
  const std::vector<Vec3f>& grid = lattice.point;
  const auto at = [&](int i, int j, int k) {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(dims.x()) * (static_cast<std::size_t>(j) +
                                                                                  static_cast<std::size_t>(dims.y()) * k);
  };
  std::vector<std::uint8_t> in(grid.size());
  field.inside(grid, in);
  // Points next to the surface: a 6-neighbour on the other side (off the lattice counts as outside).
  std::vector<std::size_t> near;
  for (int k = 0; k < dims.z(); ++k)
    for (int j = 0; j < dims.y(); ++j)
      for (int i = 0; i < dims.x(); ++i) {
        const std::uint8_t self = in[at(i, j, k)];
        const auto other = [&](int a, int b, int c) {
          const bool off = a < 0 || b < 0 || c < 0 || a >= dims.x() || b >= dims.y() || c >= dims.z();
          return (off ? std::uint8_t(0) : in[at(a, b, c)]) != self;
        };
        if (other(i - 1, j, k) || other(i + 1, j, k) || other(i, j - 1, k) || other(i, j + 1, k) ||
            other(i, j, k - 1) || other(i, j, k + 1))
          near.push_back(at(i, j, k));
      }
  std::vector<float> near_share(near.size());
#pragma omp parallel for schedule(dynamic, 256)
  for (std::int64_t n = 0; n < static_cast<std::int64_t>(near.size()); ++n) {
    const std::size_t g = near[static_cast<std::size_t>(n)];
    // The surface between two neighbours lies within one spacing of both; a closer face hidden inside another
    // part is the one misread this leaves (it only moves a share, never past 0 or 1).
    const MeshField::Closest c = field.closest(grid[g], 1.5f * d);
    const float s = std::isfinite(c.distance) ? (in[g] ? -c.distance : c.distance) : (in[g] ? -d : d);
    near_share[static_cast<std::size_t>(n)] = std::clamp(0.5f - s / d, 0.0f, 1.0f);
  }
  LatticeCells out;
  std::size_t n = 0;
  for (std::size_t g = 0; g < grid.size(); ++g) {
    float share = in[g] ? 1.0f : 0.0f;
    if (n < near.size() && near[n] == g) share = near_share[n++];
    if (share > 0.0f) out.point.push_back(grid[g]), out.share.push_back(share);
  }
  return out;
}

std::vector<Vec3f> random_interior_points(const SdfGrid& sdf, const Aabb& box, std::size_t count, std::uint64_t seed) {
  std::vector<Vec3f> out;
  out.reserve(count);
  const Vec3f lo = box.min, size = box.size();
  const int T = core::thread_count();
  std::vector<std::vector<Vec3f>> batch(static_cast<std::size_t>(4 * T));
  for (std::uint64_t first = 0; out.size() < count; first += batch.size()) {
    // A batch of streams in parallel, appended in stream order: deterministic for any thread count.
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t b = 0; b < static_cast<std::int64_t>(batch.size()); ++b) {
      auto& pts = batch[static_cast<std::size_t>(b)];
      pts.clear();
      Rng rng(seed, first + static_cast<std::uint64_t>(b));
      for (std::size_t k = 0; k < kChunk; ++k) {
        const Vec3f u(rng.uniform(), rng.uniform(), rng.uniform());
        const Vec3f p = lo + u.cwiseProduct(size);
        if (sdf.distance(p) < 0.0f) pts.push_back(p);
      }
    }
    for (const auto& pts : batch)
      for (const auto& p : pts)
        if (out.size() < count) out.push_back(p);
    if (first > 1'000'000'000ull) break;  // a target of no volume at all: the caller checks the count
  }
  return out;
}

std::vector<Vec3f> random_surface_points(const io::TriangleMesh& mesh, std::size_t count, std::uint64_t seed) {
  // Area-weighted triangle choice by binary search in the cumulative areas, then a uniform point.
  std::vector<double> cdf(mesh.triangles.size());
  double total = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3f &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
    const double area = 0.5 * double((b - a).cross(c - a).norm());
    total += std::isfinite(area) ? area : 0.0;
    cdf[t] = total;
  }
  std::vector<Vec3f> out(count);
  if (total <= 0.0) return {};
  const auto chunks = static_cast<std::int64_t>((count + kChunk - 1) / kChunk);
#pragma omp parallel for schedule(static)
  for (std::int64_t c = 0; c < chunks; ++c) {
    Rng rng(seed, 0xC0FFEE00000ull + static_cast<std::uint64_t>(c));
    const std::size_t b = static_cast<std::size_t>(c) * kChunk, e = std::min(count, b + kChunk);
    for (std::size_t i = b; i < e; ++i) {
      const double r = double(rng.uniform()) * total;
      const auto t = static_cast<std::size_t>(std::upper_bound(cdf.begin(), cdf.end(), r) - cdf.begin());
      const auto& tri = mesh.triangles[std::min(t, cdf.size() - 1)];
      float u = rng.uniform(), v = rng.uniform();
      if (u + v > 1.0f) {
        u = 1.0f - u;
        v = 1.0f - v;
      }
      const Vec3f &a = mesh.vertices[tri[0]], &bb = mesh.vertices[tri[1]], &cc = mesh.vertices[tri[2]];
      out[i] = a + u * (bb - a) + v * (cc - a);
    }
  }
  return out;
}

namespace {

/// The n of `cand` that weighted sample elimination keeps, for the r_max of n samples in the target.
std::vector<Vec3f> eliminate_to(const std::vector<Vec3f>& cand, std::size_t n, double r_max, core::Progress& progress) {
  EliminationParams ep;
  ep.d_max = static_cast<float>(2.0 * r_max);
  const auto keep = eliminate_samples(cand, n, ep, progress);
  std::vector<Vec3f> x;
  x.reserve(keep.size());
  for (Index k : keep) x.push_back(cand[k]);
  return x;
}

/// The blue-noise volume set (METHOD §a.1): 2n random interior candidates, weighted sample elimination down to n,
/// relaxation against the SDF, then a repair that makes the acceptance rules exact.
Result<std::vector<Vec3f>> blue_noise_samples(const io::TriangleMesh& mesh, const MeshField& field, const SdfGrid& sdf,
                                              const SamplingParams& params, float d, std::size_t n, SampleReport& rep,
                                              const core::Stopwatch& watch, core::Progress& progress) {
  rep.candidates = 2 * n;
  const auto cand = random_interior_points(sdf, field.bounds(), rep.candidates, params.seed);
  if (cand.size() < n)
    return input_error(fmt::format("the target's volume could not be sampled ({} of {} interior points found)",
                                   cand.size(), n));
  std::vector<Vec3f> x = eliminate_to(cand, n, volume_r_max(rep.volume, n), progress);
  RelaxParams rp;
  rp.spacing = d;
  rp.steps = params.relax_steps;
  double t = watch.seconds();
  rep.t_init = t - rep.t_sdf - rep.t_field;
  relax_samples(x, sdf, rp, progress);
  rep.t_relax = watch.seconds() - t;
  t = watch.seconds();
  // First the exact inside test (the interpolated grid can disagree by a fraction of a node in thin
  // walls and near a hole's mouth, where the winding number is close to ½).
  // The few outside are moved just below their exact closest surface point, or dropped if that fails.
  std::vector<std::uint8_t> in(x.size());
  field.inside(x, in);
  std::size_t k = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!in[i]) {
      const MeshField::Closest c = field.closest(x[i]);
      const Vec3f moved = c.point - 0.15f * d * c.normal;
      if (!field.inside(moved)) continue;
      x[i] = moved;
    }
    x[k++] = x[i];
  }
  const std::size_t outside = x.size() - k;
  x.resize(k);
  // The acceptance rules of a blue-noise set, made exact: nothing closer than 0.85 d, and thin parts
  // the relaxation emptied get samples back (typically a handful per ten thousand).
  const auto surface_points = static_cast<std::size_t>(std::min(64.0 * rep.area / (double(d) * d), 16e6));
  const auto surface = random_surface_points(mesh, surface_points, params.seed ^ 0x5EEDull);
  rep.repaired_dropped = outside + enforce_spacing(x, sdf, 0.85f * d, surface, &rep.repaired_added);
  rep.t_repair = watch.seconds() - t;
  return x;
}

/// A surface shell: 4n random surface points eliminated down to n (Yuksel 2015's weighted sample elimination).
std::vector<Vec3f> surface_samples(const io::TriangleMesh& mesh, const SamplingParams& params, std::size_t n,
                                   SampleReport& rep, core::Progress& progress) {
  rep.candidates = 4 * n;
  const auto cand = random_surface_points(mesh, rep.candidates, params.seed);
  return eliminate_to(cand, n, surface_r_max(rep.area, n), progress);
}

/// The control set of the sample positions `x`, with their weights (paper eq. 1–4; sampling/weights.h).
Result<ControlSet> weighted_set(const std::vector<Vec3f>& x, const SdfGrid* sdf, const SamplingParams& params, float d,
                                std::uint8_t target, double& weight_seconds) {
  ControlSet set;
  set.target = target;
  set.spacing = d;
  set.resize(x.size());
  std::copy(x.begin(), x.end(), set.position.begin());
  // Depth below the surface per sample (0 for a shell): the weights' interior term.
  std::vector<float> depth(x.size(), 0.0f);
  if (sdf)
    core::parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t i) {
      depth[static_cast<std::size_t>(i)] = std::max(0.0f, -sdf->distance(x[static_cast<std::size_t>(i)]));
    });
  WeightParams wp{params.support_factor, params.phi_offset, params.rest_density};
  core::Stopwatch watch;
  FF_CHECK(compute_weights(set, depth, wp));
  weight_seconds = watch.seconds();
  return set;
}

}  // namespace

Result<ControlSet> sample_target(const io::TriangleMesh& mesh, const SamplingParams& params, std::uint8_t target,
                                 SampleReport* report, core::Progress& progress) {
  FF_CHECK(params.validate());
  core::Stopwatch watch;
  SampleReport rep;
  FF_TRY(MeshField field, MeshField::build(mesh));
  rep.t_field = watch.seconds();
  rep.volume = field.volume();
  rep.area = field.area();
  rep.method = params.method;
  // A closed mesh without volume (a flattened box, coplanar faces) is a broken target, not a sheet.
  if (!field.encloses_volume() && field.stats().boundary_edges == 0)
    return input_error(fmt::format("the mesh is closed but encloses no volume ({:g} m³ for {:g} m² of surface): "
                                   "it is flat or degenerate",
                                   field.volume(), field.area()));
  if (!field.encloses_volume() && params.method != Method::Surface) {
    rep.warnings.push_back(fmt::format(
        "the mesh encloses no volume (an open sheet or a shell with large holes): sampled as a surface shell "
        "instead of {}", method_name(params.method)));
    rep.method = Method::Surface;
  }
  const bool volume = rep.method != Method::Surface;
  const float d = params.spacing > 0.0f ? params.spacing : automatic_spacing(field, params.auto_count);
  rep.spacing = d;
  if (!(d > 0.0f) || !std::isfinite(d))
    return input_error(fmt::format("the target has no usable size (volume {:g} m³, area {:g} m²)", rep.volume, rep.area));
  auto too_many = [&](double estimate) {
    return param_error(fmt::format("sampling.spacing = {:g} m would make about {:.0f} samples, more than the limit of {} "
                                   "(sampling.max_samples); use a larger spacing",
                                   d, estimate, params.max_samples));
  };
  // A first check on the mesh's own volume, before the grid (whose size follows the spacing) is built.
  if (const double rough = estimate_sample_count(volume, rep.volume, rep.area, d);
      rough > 1.5 * double(params.max_samples))
    return too_many(rough);
  std::optional<SdfGrid> sdf;
  if (volume) {
    progress.begin("signed distance grid", 1);
    FF_TRY(SdfGrid grid, SdfGrid::build(field, auto_sdf_spacing(field.bounds(), 2.0f * d, d, kSamplerSdfNodes), 2.0f * d));
    ignore_hidden_surfaces(grid);
    sdf = std::move(grid);
    progress.end();
    rep.t_sdf = watch.seconds() - rep.t_field;
    // The volume the samples fill, from the grid (a smoothed step per node): unlike the mesh's signed
    // volume it counts overlapping parts once and is not fooled by holes.
    rep.volume = enclosed_volume(*sdf);
  }
  const double estimate = estimate_sample_count(volume, rep.volume, rep.area, d);
  if (estimate > double(params.max_samples)) return too_many(estimate);
  const auto n = static_cast<std::size_t>(std::llround(estimate));
  if (n < 1)
    return input_error(fmt::format("the target ({:g} m³) holds no sample at spacing {:g} m; use a smaller spacing",
                                   rep.volume, d));

  std::vector<Vec3f> x;
  switch (rep.method) {
    case Method::Voxel: x = voxel_samples(field, d); break;
    case Method::BlueNoise: {
      FF_TRY(x, blue_noise_samples(mesh, field, *sdf, params, d, n, rep, watch, progress));
      break;
    }
    case Method::Surface: x = surface_samples(mesh, params, n, rep, progress); break;
  }
  const std::size_t before = x.size();
  x = drop_sparse(std::move(x), params.sparse, params.seed);
  rep.dropped = before - x.size();
  if (x.empty())
    return input_error(rep.dropped ? "the sparse-sampling options removed every sample"
                                   : "the target holds no sample at this spacing; use a smaller spacing");

  FF_TRY(ControlSet set, weighted_set(x, sdf ? &*sdf : nullptr, params, d, target, rep.t_weights));
  rep.samples = set.size();
  rep.seconds = watch.seconds();
  if (report) *report = std::move(rep);
  return set;
}

}  // namespace ff::sampling
