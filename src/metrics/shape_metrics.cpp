#include "metrics/shape_metrics.h"

#include "core/parallel.h"
#include "sampling/mesh_field.h"
#include "sampling/samplers.h"

#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace ff::metrics {
namespace {

// Queries per work item. Work is handed out dynamically: queries that fall back to a tree (splashed
// particles, holes) cluster in index ranges and cost ~10× a grid answer. Each item writes only its own slots,
// so the results do not depend on who runs it.
constexpr std::int64_t kQueryChunk = 256;

// Runs f(begin, end) over [0, n) in chunks of kQueryChunk, in parallel.
template <class F>
void for_each_chunk(std::int64_t n, F&& f) {
  const std::int64_t chunks = (n + kQueryChunk - 1) / kQueryChunk;
#pragma omp parallel for schedule(dynamic) if (n >= core::kMinParallel)
  for (std::int64_t c = 0; c < chunks; ++c) f(c * kQueryChunk, std::min(n, (c + 1) * kQueryChunk));
}

}  // namespace

Result<TargetShape> TargetShape::build(const io::TriangleMesh& mesh, std::span<const Vec3f> controls,
                                       float control_spacing) {
  const float d = control_spacing;
  if (!(d > 0.0f) || !std::isfinite(d))
    return param_error(fmt::format("metrics: control spacing {:g} m is not a positive length", d));
  if (controls.empty()) return input_error("metrics: the target has no control samples");
  Aabb box;
  for (const Vec3f& c : controls) {
    if (!c.allFinite()) return input_error("metrics: a control sample has a non-finite position");
    box.extend(c);
  }
  // L normalises E; a target whose samples span nothing has no size to normalise by.
  const float diagonal = box.size().norm();
  if (!(diagonal > 0.0f))
    return input_error("metrics: the control samples span no extent (a single point); E would be undefined");

  FF_TRY(sampling::MeshField field, sampling::MeshField::build(mesh));
  const float margin = 3.0f * d;
  FF_TRY(sampling::SdfGrid grid, sampling::SdfGrid::build(field, sampling::auto_sdf_spacing(field.bounds(), margin, d), margin));
  sampling::ignore_hidden_surfaces(grid);

  TargetShape shape;
  shape.sdf_ = std::make_shared<const sampling::SdfGrid>(std::move(grid));
  shape.grid_ = core::PointGrid(controls, d, box);
  shape.tree_ = std::make_shared<LazyTree>();
  shape.sample_count_ = controls.size();
  shape.box_ = box;
  shape.diagonal_ = diagonal;
  shape.control_spacing_ = d;
  shape.sheet_ = !field.encloses_volume();
  return shape;
}

Result<TargetShape> TargetShape::posed(const TargetShape& bind, sampling::MeshField posed_field,
                                       std::span<const Vec3f> posed_controls) {
  if (posed_controls.size() != bind.sample_count())
    return input_error(fmt::format("metrics: a posed shape needs one position per sample ({}), got {}",
                                   bind.sample_count(), posed_controls.size()));
  Aabb box;
  for (std::size_t i = 0; i < posed_controls.size(); ++i) {
    if (!posed_controls[i].allFinite())
      return input_error(fmt::format("metrics: posed control sample {} has a non-finite position", i));
    box.extend(posed_controls[i]);
  }
  const float diagonal = box.size().norm();
  if (!(diagonal > 0.0f))
    return input_error("metrics: the posed control samples span no extent (a single point); E would be undefined");
  TargetShape shape;
  shape.field_ = std::make_shared<const sampling::MeshField>(std::move(posed_field));
  shape.grid_ = core::PointGrid(posed_controls, bind.control_spacing_, box);
  shape.tree_ = std::make_shared<LazyTree>();
  shape.sample_count_ = posed_controls.size();
  shape.box_ = box;
  shape.diagonal_ = diagonal;
  shape.control_spacing_ = bind.control_spacing_;
  shape.sheet_ = bind.sheet_;
  return shape;
}

float TargetShape::signed_distance(const Vec3f& rest_point) const {
  if (!rest_point.allFinite()) return std::numeric_limits<float>::quiet_NaN();
  const float d = field_ ? field_->signed_distance(rest_point) : sdf_->distance(rest_point);
  return sheet_ ? std::abs(d) - 0.5f * control_spacing_ : d;
}

TargetShape::Where TargetShape::classify(const Vec3f& p, float r) const {
  if (!field_) {
    const float d = signed_distance(p);
    return {d <= r, d > 2.0f * r};
  }
  if (!p.allFinite()) return {};
  if (sheet_) {  // |distance| − d_c/2: only the surface within 2r + d_c/2 can make it inside, or not splash
    const float half = 0.5f * control_spacing_;
    const float d = field_->closest(p, 2.0f * r + half).distance - half;  // +inf beyond
    return {d <= r, d > 2.0f * r};
  }
  if (field_->inside(p)) return {true, false};  // signed distance < 0
  const float d = field_->closest(p, 2.0f * r).distance;  // outside: the distance itself, +inf beyond 2r
  return {d <= r, d > 2.0f * r};
}

float TargetShape::nearest_sample_distance(const Vec3f& rest_point) const {
  const float d2 = grid_.nearest2(rest_point);
  return std::sqrt(std::isnan(d2) ? tree().nearest(rest_point).distance2 : d2);
}

const core::PointTree& TargetShape::tree() const {
  // The grid holds every sample (its region is their box), in cell order: the same set.
  assert(grid_.complete());
  std::call_once(tree_->once, [&] {
    tree_->tree = core::PointTree(grid_.points());
    tree_->built.store(true, std::memory_order_release);
  });
  return tree_->tree;
}

std::size_t TargetShape::bytes() const {
  const bool tree = tree_ && tree_->built.load(std::memory_order_acquire);
  return sizeof(*this) - sizeof(grid_) + (sdf_ ? sdf_->bytes() : 0) + (field_ ? field_->bytes() : 0) + grid_.bytes() +
         (tree ? sizeof(LazyTree) - sizeof(core::PointTree) + tree_->tree.bytes() : 0);
}

namespace {

// Forward: each fluid particle's distance to the nearest sample, and whether it is inside (signed distance ≤ r)
// or splashed (> 2r). A posed shape answers those directly (classify: its exact field is costly to ask for the
// distance); a built one by its grid's signed distance, in world metres (s: world metres per rest metre).
void forward_distances(const TargetShape& shape, const std::vector<Vec3f>& x, double r, double s,
                       std::vector<float>& to_sample, std::vector<std::uint8_t>& in, std::vector<std::uint8_t>& out) {
  to_sample.resize(x.size());
  in.resize(x.size()), out.resize(x.size());
  for_each_chunk(static_cast<std::int64_t>(x.size()), [&](std::int64_t begin, std::int64_t end) {
    for (auto i = static_cast<std::size_t>(begin); i < static_cast<std::size_t>(end); ++i) {
      to_sample[i] = shape.nearest_sample_distance(x[i]);
      if (shape.posed()) {
        const TargetShape::Where w = shape.classify(x[i], static_cast<float>(r / s));
        in[i] = w.inside, out[i] = w.splash;
      } else {
        const double d = double(shape.signed_distance(x[i])) * s;
        in[i] = d <= r, out[i] = d > 2.0 * r;
      }
    }
  });
}

// Backward: each sample's distance to the nearest fluid particle, in the samples' cell order. A grid of one
// fluid spacing over the samples' box (+2 cells) answers where the fluid is near; the rest go to a tree.
std::vector<float> backward_distances(const TargetShape& shape, const std::vector<Vec3f>& x, double r, double s) {
  const core::PointGrid& samples = shape.control_grid();
  const auto m_samples = static_cast<std::int64_t>(samples.points().size());
  const float fluid_cell = r > 0.0 && std::isfinite(r) ? float(2.0 * r / s) : shape.control_spacing();
  Aabb region = shape.sample_bounds();
  region.min.array() -= 2.0f * fluid_cell;
  region.max.array() += 2.0f * fluid_cell;
  const core::PointGrid fluid_grid(x, fluid_cell, region);
  std::vector<float> to_fluid(samples.points().size());
  for_each_chunk(m_samples, [&](std::int64_t begin, std::int64_t end) {
    for (auto j = static_cast<std::size_t>(begin); j < static_cast<std::size_t>(end); ++j)
      to_fluid[j] = fluid_grid.nearest2(samples.points()[j]);
  });
  std::vector<Index> unresolved;
  for (std::size_t j = 0; j < to_fluid.size(); ++j)
    if (std::isnan(to_fluid[j])) unresolved.push_back(static_cast<Index>(j));
  if (!unresolved.empty()) {
    const core::PointTree fluid(x);
    for_each_chunk(static_cast<std::int64_t>(unresolved.size()), [&](std::int64_t begin, std::int64_t end) {
      Index hint = kInvalidIndex;  // consecutive unresolved samples are near each other: each seeds the next
      for (std::int64_t k = begin; k < end; ++k) {
        const Index j = unresolved[static_cast<std::size_t>(k)];
        const core::PointTree::Nearest nb = fluid.nearest(samples.points()[j], hint);
        hint = nb.slot;
        to_fluid[j] = nb.distance2;
      }
    });
  }
  core::parallel_for(m_samples, [&](std::int64_t j) {
    to_fluid[static_cast<std::size_t>(j)] = std::sqrt(to_fluid[static_cast<std::size_t>(j)]);
  });
  return to_fluid;
}

}  // namespace

FrameMetrics measure(const TargetShape& shape, std::uint8_t target_id, std::span<const Vec3f> positions,
                     std::span<const std::uint8_t> target_ids, std::span<const std::uint8_t> controlled,
                     float particle_radius, const Eigen::Affine3f& rest_from_world, float world_scale) {
  assert(target_ids.size() == positions.size() && controlled.size() == positions.size());
  assert(world_scale > 0.0f && std::isfinite(world_scale));
  const std::size_t total = std::min({positions.size(), target_ids.size(), controlled.size()});

  // The target's fluid in the rest frame, in input order (a serial pass: a copy, ~1 ns per particle).
  std::vector<Vec3f> x;
  std::vector<std::uint8_t> ctrl;
  for (std::size_t i = 0; i < total; ++i)
    if (target_ids[i] == target_id && positions[i].allFinite()) {
      x.push_back(rest_from_world * positions[i]);
      ctrl.push_back(controlled[i] != 0 ? 1 : 0);
    }

  FrameMetrics m;
  m.fluid = x.size();
  m.controlled = static_cast<std::size_t>(std::count(ctrl.begin(), ctrl.end(), std::uint8_t{1}));
  if (m.fluid == 0) {
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    m.e_fwd = m.e_bwd = m.error_rate = m.e_fwd_all = m.error_spacings = nan;
    return m;
  }
  const auto n = static_cast<std::int64_t>(m.fluid);
  const double s = world_scale;
  const double r = particle_radius;

  std::vector<float> to_sample;
  std::vector<std::uint8_t> in, out;
  forward_distances(shape, x, r, s, to_sample, in, out);
  const std::vector<float> to_fluid = backward_distances(shape, x, r, s);
  const auto m_samples = static_cast<std::int64_t>(to_fluid.size());

  auto at = [](const std::vector<float>& v, std::int64_t i) { return double(v[static_cast<std::size_t>(i)]); };
  auto is_ctrl = [&](std::int64_t i) { return ctrl[static_cast<std::size_t>(i)] != 0; };
  const double sum_all = core::deterministic_sum(n, [&](std::int64_t i) { return at(to_sample, i); });
  const double sum_ctrl =
      core::deterministic_sum(n, [&](std::int64_t i) { return is_ctrl(i) ? at(to_sample, i) : 0.0; });
  const double inside = core::deterministic_sum(n, [&](std::int64_t i) { return double(in[std::size_t(i)]); });
  const double splash = core::deterministic_sum(n, [&](std::int64_t i) { return double(out[std::size_t(i)]); });
  const double sum_bwd = core::deterministic_sum(m_samples, [&](std::int64_t j) { return at(to_fluid, j); });

  const double count = double(m.fluid);
  m.e_fwd_all = s * sum_all / count;
  m.e_fwd = m.controlled > 0 ? s * sum_ctrl / double(m.controlled) : m.e_fwd_all;
  m.e_bwd = s * sum_bwd / double(m_samples);
  const double L = s * double(shape.diagonal());
  m.error_rate = 100.0 * (m.e_fwd + m.e_bwd) / (2.0 * L);
  m.error_spacings = 0.5 * (m.e_fwd + m.e_bwd) / (2.0 * r);
  m.inside_fraction = inside / count;
  m.splash_fraction = splash / count;
  return m;
}

}  // namespace ff::metrics
