#pragma once
// The one rotation from Euler angles in degrees that every part of fluidform uses: R = Rz · Ry · Rx (x first), in
// the angles' precision (double for the scene and skin transforms, float for a keyframed target's pose, as each
// computed it before they shared this one definition, so no result changed). The scene's mesh transform (io/load_mesh), the keyframed pose of a target (pose/target_motion), the skin's
// scene transform (io::transform_matrix) and the rigged GLB's root (io/write_rigged_glb) all take it; the viewer's
// twin is web/src/rotation.js, tested against this one on the same angles (tests/core/rotation_test.cpp). It lives
// in core, not pose/, because io (below pose) applies the scene transform when it loads a mesh.
#include "core/types.h"

#include <Eigen/Geometry>

#include <numbers>

namespace ff::core {

/// R = Rz(z) · Ry(y) · Rx(x) for angles (x, y, z) in degrees, in T (float or double).
template <class T>
Eigen::Matrix<T, 3, 3> rotation_from_degrees(const Eigen::Matrix<T, 3, 1>& deg) {
  using Axis = Eigen::AngleAxis<T>;
  using V = Eigen::Matrix<T, 3, 1>;
  const V r = deg * static_cast<T>(std::numbers::pi / 180.0);
  return (Axis(r.z(), V::UnitZ()) * Axis(r.y(), V::UnitY()) * Axis(r.x(), V::UnitX())).toRotationMatrix();
}

}  // namespace ff::core
