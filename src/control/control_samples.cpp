#include "control/control_samples.h"

#include "core/kernels.h"
#include "core/neighbor_grid.h"
#include "core/parallel.h"

#include <algorithm>
#include <utility>

namespace ff::control {

Status ControlSamples::init(std::vector<ControlTarget> targets, std::string_view who, const SampleOptions& options) {
  options_ = options;
  FF_TRY(CheckedTargets checked, validate_control_targets(std::move(targets), who));
  hc = checked.hc;
  phases_ = std::move(checked.phases);
  start_ = std::move(checked.start);
  strength_ = std::move(checked.strength);
  motion_ = std::move(checked.motion);
  skin_ = std::move(checked.skin);
  target_joints_ = std::move(checked.skin_joints);
  target_weights_ = std::move(checked.skin_weights);
  anchors_ = std::move(checked.anchors);
  moving_ = checked.moving;
  current_.assign(phases_.size(), 0);
  time_ = 0.0;
  flatten();
  if (moving_) pose(time_, 0.0f);
  return {};
}

// The samples of every target's current phase into the SoA arrays. Run at the start and whenever a target swaps its
// mesh.
void ControlSamples::flatten() {
  position.clear(), rho_c.clear(), phi.clear(), target.clear(), mass.clear(), original.clear();
  joints_.clear(), weights_.clear(), skinned_.clear(), anchor_.clear();
  std::vector<std::pair<std::int64_t, Index>> order;
  for (std::size_t t = 0; t < phases_.size(); ++t) {
    const auto& s = phases_[t][current_[t]].set;
    mass.push_back(s.mass);
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (options_.cell_order) {
        // Key: the sample's cell in the global lattice of edge H_c, z-major like NeighborGrid's keys. Sorted by it,
        // consecutive samples share their fluid-grid cell (the grids snap to the same lattice), so a control–fluid
        // query gathers each cell's candidates once, and pair loops walk fluid memory in order.
        const Vec3f c = (s.position[i] / hc).array().floor();
        const auto k = [&](int a) { return static_cast<std::int64_t>(std::clamp(c[a], -1e6f, 1e6f)) + 1'000'000; };
        order.emplace_back((k(2) * 2'000'001 + k(1)) * 2'000'001 + k(0), static_cast<Index>(position.size()));
      }
      position.push_back(s.position[i]);
      const bool skinned = skin_[t] && current_[t] == 0;
      joints_.push_back(skinned ? target_joints_[t][i] : std::array<std::uint16_t, io::kMaxInfluences>{});
      weights_.push_back(skinned ? target_weights_[t][i] : std::array<float, io::kMaxInfluences>{});
      skinned_.push_back(skinned ? 1 : 0);
      anchor_.push_back(skinned && anchors_[t] ? static_cast<Index>(i) : kInvalidIndex);
      rho_c.push_back(s.density[i]);
      phi.push_back(options_.weights ? s.phi[i] : 1.0f);
      target.push_back(static_cast<std::uint8_t>(t));
    }
  }
  original.resize(position.size());
  if (options_.cell_order) {
    std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    auto permute = [&](auto& v) {
      auto old = v;
      for (std::size_t k = 0; k < order.size(); ++k) v[k] = old[order[k].second];
    };
    permute(position), permute(rho_c), permute(phi), permute(target), permute(joints_), permute(weights_), permute(skinned_);
    permute(anchor_);
    for (std::size_t k = 0; k < order.size(); ++k) original[k] = order[k].second;
  } else {
    for (std::size_t k = 0; k < original.size(); ++k) original[k] = static_cast<Index>(k);
  }
  if (options_.normals) {
    // n = −Σ_j m_c ∇W(x_ci − x_cj) over the samples of the same target (eq. 16), outward; g_ref its largest norm,
    // which is found at the target surface (eq. 15 threshold).
    const core::Spiky spiky(hc);
    core::NeighborGrid grid(hc);
    grid.build(position);
    core::NeighborList self;
    grid.query(position, position, hc, self);
    normal.resize(position.size());
    g_ref = static_cast<float>(core::deterministic_max(static_cast<std::int64_t>(position.size()), 0.0, [&](std::int64_t ii) {
      const auto i = static_cast<std::size_t>(ii);
      Vec3f g = Vec3f::Zero();
      for (Index j : self.of(i))
        if (target[j] == target[i]) g += mass[target[i]] * spiky.grad(position[i] - position[j]);
      normal[i] = -g;
      return static_cast<double>(g.norm());
    }));
  }
  rest_position_ = position;
  rest_normal_ = normal;
  velocity.assign(position.size(), Vec3f::Zero());
}

// Samples of moving targets follow their pose; densities keep their rest values (rigid motion keeps them exactly; a
// scale keyframe changes the volume to fill, which the fixed amount of fluid cannot follow). u_c is the pose's
// velocity over the sub-step (forward difference), so a rig that moves drags its fluid along. A skinned target's
// samples are skinned first (pose/skinning.h), then posed by its keyframes: x = Pose(t) · skin(t) · x_bind; those
// anchored to the posed mesh (pose/mesh_anchors.h) are placed from its skinned vertices instead.
// Their densities stay the bind pose's too (measured: see bench/RESULTS.md "Animated characters").
void ControlSamples::pose(double time, float dt) {
  std::vector<pose::Pose> now(motion_.size()), next(options_.velocities ? motion_.size() : 0);
  for (std::size_t t = 0; t < motion_.size(); ++t) now[t] = motion_[t].at(time);
  for (std::size_t t = 0; t < next.size(); ++t) next[t] = motion_[t].at(time + dt);
  now_joints_.resize(skin_.size()), next_joints_.resize(skin_.size());
  now_vertices_.resize(skin_.size()), next_vertices_.resize(skin_.size());
  std::vector<io::Mat4f> K;
  for (std::size_t t = 0; t < skin_.size(); ++t) {
    if (!skin_[t]) continue;
    skin_[t]->world_joint_matrices(time, K);
    now_joints_[t].set(K, skin_[t]->spec.skinning);
    if (anchors_[t]) anchors_[t]->pose_vertices(now_joints_[t], now_vertices_[t]);
    if (options_.velocities) {
      skin_[t]->world_joint_matrices(time + dt, K);
      next_joints_[t].set(K, skin_[t]->spec.skinning);
      if (anchors_[t]) anchors_[t]->pose_vertices(next_joints_[t], next_vertices_[t]);
    }
  }
  // Where a sample is (world, no keyframed pose): placed from the posed mesh, or skinned by its own weights.
  // A sample moved out of a fold's pocket (pose/cage_guard.h) jumps as it goes in and out of it: its velocity is
  // its motion without that move (measured on huesitos: with the jump in u_c, 17 % more sub-steps by the CFL rule).
  const auto skinned_at = [&](std::size_t i, const pose::PosedJoints& joints, const std::vector<Vec3f>& vertices, bool folds) {
    const Index a = anchor_[i];
    return a != kInvalidIndex ? anchors_[target[i]]->place(a, vertices, folds)
                              : joints.apply(joints_[i], weights_[i], rest_position_[i]);
  };
  const float inv_dt = dt > 0.0f ? 1.0f / dt : 0.0f;
  core::parallel_for(static_cast<std::int64_t>(position.size()), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    const auto t = target[i];
    if (skinned_[i]) {
      const Vec3f x = now[t].apply(skinned_at(i, now_joints_[t], now_vertices_[t], true));
      if (options_.normals) {
        // The normal turns with the blended linear part of its sample (a rotation where the skin moves rigidly).
        const io::Mat4f m = io::blend_matrix(now_joints_[t].matrices(), joints_[i], weights_[i]);
        normal[i] = now[t].rotation * (m.topLeftCorner<3, 3>() * rest_normal_[i]);
      }
      if (options_.velocities) {
        const Index a = anchor_[i];
        const bool folds = a != kInvalidIndex && !anchors_[t]->fold_partner.empty() &&
                           anchors_[t]->fold_partner[a] != kInvalidIndex;
        const Vec3f from = folds ? now[t].apply(skinned_at(i, now_joints_[t], now_vertices_[t], false)) : x;
        velocity[i] = (next[t].apply(skinned_at(i, next_joints_[t], next_vertices_[t], false)) - from) * inv_dt;
      }
      position[i] = x;
      return;
    }
    if (!motion_[t].moving()) return;
    position[i] = now[t].apply(rest_position_[i]);
    if (options_.normals) normal[i] = now[t].rotation * rest_normal_[i];
    if (options_.velocities) velocity[i] = (next[t].apply(rest_position_[i]) - position[i]) * inv_dt;
  });
}

bool ControlSamples::update(double time, float dt) {
  time_ = time;
  bool swapped = false;
  for (std::size_t t = 0; t < phases_.size(); ++t)
    while (current_[t] + 1 < phases_[t].size() && time >= phases_[t][current_[t] + 1].time) ++current_[t], swapped = true;
  if (swapped) flatten();
  if (moving_) pose(time, dt);
  return swapped;
}

void ControlSamples::set_target_pose(std::size_t t, const pose::Pose& p) {
  if (t >= motion_.size()) return;
  // The rest pose is kept from the flatten on, so a target that was static can start moving.
  motion_[t].live = p;
  moving_ = true;
}

}  // namespace ff::control
