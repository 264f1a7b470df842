#include "control/control_targets.h"

#include "core/kernels.h"

#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <string>

namespace ff::control {

Result<CheckedTargets> validate_control_targets(std::vector<ControlTarget> targets, std::string_view who) {
  CheckedTargets c;
  if (targets.empty()) return param_error(fmt::format("controller {}: the scene has no targets", who));
  if (targets.size() > 250) return param_error(fmt::format("controller {}: {} targets, at most 250", who, targets.size()));
  for (const auto& t : targets) {
    if (!t.set.consistent() || t.set.size() == 0 || !(t.set.support > 0.0f) || !(t.set.mass > 0.0f))
      return param_error(fmt::format("controller {}: target {} has no weighted control samples", who, t.set.target));
    if (c.hc > 0.0f && std::abs(t.set.support - c.hc) > 1e-4f * c.hc)
      return param_error(fmt::format("controller {}: targets have different control supports ({} m and {} m); "
                                     "sample them at one spacing", who, c.hc, t.set.support));
    c.hc = std::max(c.hc, t.set.support);
  }
  for (std::size_t t = 0; t < targets.size(); ++t) {
    FF_CHECK(targets[t].motion.validate(fmt::format("targets[{}]", t)));
    FF_CHECK(targets[t].strength.validate(fmt::format("targets[{}]", t)));
    c.start.push_back(targets[t].start);
    c.strength.push_back(targets[t].strength);
    c.motion.push_back(targets[t].motion);
    c.moving = c.moving || targets[t].motion.moving();
    if (const auto& sk = targets[t].skin) {
      const std::size_t n = targets[t].set.size();
      if (targets[t].skin_joints.size() != n || targets[t].skin_weights.size() != n)
        return param_error(fmt::format("targets[{}]: skin weights for {} of {} control samples", t,
                                       targets[t].skin_joints.size(), n));
      // The first influence of `joints`/`weights` that names a joint the skin does not have, as a message.
      const std::size_t nj = sk->skin.joint_nodes.size();
      const auto bad_joint = [&](const auto& joints, const auto& weights, const char* what) -> std::optional<std::string> {
        for (std::size_t i = 0; i < joints.size(); ++i)
          for (int k = 0; k < io::kMaxInfluences; ++k)
            if (weights[i][k] != 0.0f && joints[i][k] >= nj)
              return fmt::format("targets[{}]: {} {} names joint {} of {}", t, what, i, joints[i][k], nj);
        return std::nullopt;
      };
      if (auto bad = bad_joint(targets[t].skin_joints, targets[t].skin_weights, "control sample")) return param_error(*bad);
      if (const auto& a = targets[t].anchors) {
        if (!a->consistent(n))
          return param_error(fmt::format("targets[{}]: mesh anchors that do not match its {} control samples", t, n));
        if (auto bad = bad_joint(a->vertex_joints, a->vertex_weights, "vertex")) return param_error(*bad);
      }
      c.moving = true;
    } else if (targets[t].anchors) {
      return param_error(fmt::format("targets[{}]: mesh anchors without a skin", t));
    }
    c.skin.push_back(targets[t].skin);
    c.anchors.push_back(targets[t].anchors);
    c.skin_joints.push_back(std::move(targets[t].skin_joints));
    c.skin_weights.push_back(std::move(targets[t].skin_weights));
    std::vector<TargetPhase> phases;
    phases.push_back({-INFINITY, std::move(targets[t].set)});
    double last = -INFINITY;
    for (auto& [when, set] : targets[t].swaps) {
      if (!(when > last) || !std::isfinite(when))
        return param_error(fmt::format("targets[{}]: mesh swaps must come at increasing, finite times", t));
      if (!set.consistent() || set.size() == 0 || std::abs(set.support - c.hc) > 1e-4f * c.hc || !(set.mass > 0.0f))
        return param_error(fmt::format("targets[{}]: a swapped-in mesh has no control samples at the target's support", t));
      last = when;
      phases.push_back({when, std::move(set)});
    }
    c.phases.push_back(std::move(phases));
  }
  return c;
}

double full_gradient_sum(float d, float hc, float particle_mass, double rho_ref) {
  const core::Spiky spiky(hc);
  double s0 = 0.0;
  core::for_each_lattice_point(d, hc, [&](int i, int j, int k) {
    if (i || j || k)
      s0 += ((particle_mass / rho_ref) * spiky.grad(Vec3f(float(i), float(j), float(k)) * d).cast<double>()).squaredNorm();
  });
  return s0;
}

}  // namespace ff::control
