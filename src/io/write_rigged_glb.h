#pragma once
// The rigged output of a skinned target (issue 19, item 3): the formed mesh in bind pose with the target's skeleton,
// skin and clips, as one glTF 2.0 binary that plays in three.js, Blender and Unity with no rigging step.
//
// Layout of the file (Y up, metres, as every fluidform export):
//   scene nodes: [0] "fluidform_rig": the scene transform T (MeshTransform) as TRS (translation, R = Rz·Ry·Rx as a
//                    quaternion, scale; a mirroring T keeps its negative scale), parent of the skeleton's root nodes;
//                [last] "fluidform_mesh": the skinned mesh, at the scene root with no transform of its own (glTF
//                    ignores a skinned mesh node's transform and three.js does not, so it is the identity for both).
//   nodes 1 … n: the skeleton's nodes (Skin::nodes, in order): names, rest TRS, hierarchy.
//   mesh: POSITION (float, the file's scene space: T⁻¹ of the world bind mesh), NORMAL (float, outward in the world
//         also under a mirroring T), JOINTS_0 (UNSIGNED_SHORT), WEIGHTS_0 (FLOAT), 16- or 32-bit indices; one water
//         material tinted `tint` (io/write_mesh.h's WaterMaterial, as animation.glb).
//   skin: joints = the nodes of Skin::joint_nodes, inverseBindMatrices = Skin::inverse_bind, skeleton = node 0.
//   animations: one per clip (its name, or "clip_K"), LINEAR samplers, translation / rotation / scale channels per
//         node, times in seconds; every channel is held to the clip's duration with a last key (glTF's clip length is
//         its last key), rotations are made hemisphere-continuous (q and −q are the same rotation; linear and slerp
//         interpolators then all take the short arc, as Skin::global_matrices does). A clip without channels gets one
//         key of the first node's rest rotation, so it keeps its name.
// A vertex posed by a player is then Σ w_j · (T · G_j(t)) · inverse_bind[j] · T⁻¹ · x_world_bind, the world pose of
// Skin::joint_matrices conjugated by T: what pose/skin_transfer.h inverts.
#include "core/error.h"
#include "core/types.h"
#include "io/skin.h"
#include "io/triangle_mesh.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace ff::io {

/// The GLB bytes. Weights are checked (finite, ≥ 0, some > 0 per vertex) and renormalised so their float sum is 1
/// within the validator's tolerance; a zero weight is written with joint 0. Errors (Input, one line): sizes that
/// differ from the mesh's vertex count, a joint index out of the skin's range, a bad weight, a non-finite vertex,
/// a triangle index out of range, a skin whose inverse_bind / joint_nodes / node parents do not fit, a non-finite
/// or decreasing key time, a T that does not validate.
Result<std::vector<std::uint8_t>> encode_rigged_glb(const TriangleMesh& bind_mesh_world,
                                                    const std::vector<std::array<std::uint16_t, kMaxInfluences>>& joints,
                                                    const std::vector<std::array<float, kMaxInfluences>>& weights,
                                                    const Skin& skin, const MeshTransform& transform, const Vec3f& tint);

/// encode_rigged_glb written atomically to `path` (io/atomic_file.h); a file system error is an Io error naming it.
Status write_rigged_glb(const std::filesystem::path& path, const TriangleMesh& bind_mesh_world,
                        const std::vector<std::array<std::uint16_t, kMaxInfluences>>& joints,
                        const std::vector<std::array<float, kMaxInfluences>>& weights, const Skin& skin,
                        const MeshTransform& transform, const Vec3f& tint);

}  // namespace ff::io
