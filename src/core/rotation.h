#pragma once
// The one rotation from Euler angles in degrees that every part of fluidform uses: R = Rz · Ry · Rx (x first), in
// double. The scene's mesh transform (io/load_mesh), the keyframed pose of a target (pose/target_motion), the skin's
// scene transform (io::transform_matrix) and the rigged GLB's root (io/write_rigged_glb) all take it; the viewer's
// twin is web/src/rotation.js, tested against this one on the same angles (tests/core/rotation_test.cpp). It lives
// in core, not pose/, because io (below pose) applies the scene transform when it loads a mesh.
#include "core/types.h"

#include <Eigen/Geometry>

#include <numbers>

namespace ff::core {

/// R = Rz(z) · Ry(y) · Rx(x) for angles (x, y, z) in degrees.
inline Eigen::Matrix3d rotation_from_degrees(const Vec3d& deg) {
  const Vec3d r = deg * (std::numbers::pi / 180.0);
  return (Eigen::AngleAxisd(r.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(r.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(r.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

}  // namespace ff::core
