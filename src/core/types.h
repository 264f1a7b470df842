#pragma once
// Shared vocabulary types: fixed-size Eigen vectors, the one index type, bounding boxes.
#include <Eigen/Core>

#include <cstdint>
#include <limits>

namespace ff {

using Vec3f = Eigen::Vector3f;
using Vec3d = Eigen::Vector3d;
using Vec3i = Eigen::Vector3i;

/// The one index type for particles, vertices and neighbours.
using Index = std::uint32_t;
inline constexpr Index kInvalidIndex = std::numeric_limits<Index>::max();

/// Axis-aligned box in metres. Empty when min > max on any axis.
struct Aabb {
  Vec3f min{Vec3f::Constant(std::numeric_limits<float>::max())};
  Vec3f max{Vec3f::Constant(std::numeric_limits<float>::lowest())};

  void extend(const Vec3f& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  bool empty() const { return (min.array() > max.array()).any(); }
  Vec3f size() const { return empty() ? Vec3f::Zero() : Vec3f(max - min); }
  bool contains(const Vec3f& p) const { return (p.array() >= min.array()).all() && (p.array() <= max.array()).all(); }
};

}  // namespace ff
