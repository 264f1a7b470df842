#pragma once
// The control particles of one target (docs/ARCHITECTURE.md "Data between stages"): SoA with one field list, as
// ParticleSet. Built by sampling/, read by the controllers; header-only so that sim/ can use the type
// without linking the sampling stage.
#include "core/types.h"

#include <cstdint>
#include <vector>

namespace ff::sampling {

struct ControlSet {
  // Per control particle.
  std::vector<Vec3f> position;  ///< x_c, metres (target space, transform applied)
  std::vector<Vec3f> velocity;  ///< v_c, m/s (0 for a static target)
  std::vector<float> density;   ///< ρ_c (eq. 9), kg/m³, self included
  std::vector<float> weight;    ///< ω (eq. 2), Shepard self-weight in (0, 1]
  std::vector<float> phi;       ///< φ̃ (eq. 4), normalised distance from x̄ plus c, in [c, 1 + c]
  // Per target.
  std::uint8_t target = 0;      ///< target id
  float spacing = 0.0f;         ///< d_c, the sampling spacing, m
  float support = 0.0f;         ///< H_c, control kernel support, m
  float mass = 0.0f;            ///< m_c, calibrated control mass, kg (§a.3)
  Vec3f centre{Vec3f::Zero()};  ///< x̄ (eq. 1), the ω-weighted centroid, m

  std::size_t size() const { return position.size(); }

  template <class F>
  void for_each_array(F&& f) {
    f(position); f(velocity); f(density); f(weight); f(phi);
  }
  template <class F>
  void for_each_array(F&& f) const {
    f(position); f(velocity); f(density); f(weight); f(phi);
  }
  /// Resizes every per-particle array (new entries zero).
  void resize(std::size_t n) {
    position.resize(n, Vec3f::Zero());
    velocity.resize(n, Vec3f::Zero());
    density.resize(n, 0.0f);
    weight.resize(n, 0.0f);
    phi.resize(n, 0.0f);
  }
  bool consistent() const {
    bool ok = true;
    for_each_array([&](const auto& a) { ok = ok && a.size() == position.size(); });
    return ok;
  }
};

}  // namespace ff::sampling
