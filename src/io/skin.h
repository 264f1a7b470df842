#pragma once
// Skinned, animated targets (issue 19): the skeleton, the per-vertex skin weights and the animation clips of a mesh
// file, read through Assimp (glTF/GLB, FBX, Collada, X, SMD, …) beside the bind-pose mesh load_mesh gives.
//
// Spaces. The file's scene space is where load_mesh puts the mesh before the scene's transform T (MeshTransform):
// each mesh's node transforms applied. The skeleton lives there too: node i's global matrix is the product of the
// local matrices from the root down. inverse_bind[j] maps the file's scene space at bind pose to joint j's space
// (Assimp's bone offset matrix times the inverse of its mesh's node matrix), so that at any pose
//   x_scene(t) = Σ_j w_j · G_{node(j)}(t) · inverse_bind[j] · x_bind_scene
// and in the world x(t) = T · x_scene(t). At the bind pose G · inverse_bind = I for every joint of a well-formed
// file, and x(t) is load_mesh's mesh.
//
// Only skin.cpp includes Assimp (as load_mesh.cpp).
#include "core/error.h"
#include "core/types.h"
#include "io/load_mesh.h"
#include "io/triangle_mesh.h"

#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace ff::io {

using Mat4f = Eigen::Matrix4f;
using Quatf = Eigen::Quaternionf;

/// Weights per vertex: the four largest of the file's, renormalised to sum 1 (glTF's JOINTS_0 / WEIGHTS_0).
inline constexpr int kMaxInfluences = 4;

/// One node of the file's hierarchy. Parents come before their children (nodes[i].parent < i).
struct SkinNode {
  std::string name;
  int parent = -1;                   ///< index in Skin::nodes, −1 for the root
  Vec3f translation{Vec3f::Zero()};  ///< rest local transform, as TRS (glTF's node fields)
  Quatf rotation{Quatf::Identity()};
  Vec3f scale{Vec3f::Ones()};
  Mat4f local() const;               ///< T · R · S
};

/// The keys of one node in one clip (seconds, increasing). Missing paths keep the node's rest value.
struct NodeChannel {
  int node = -1;
  std::vector<double> translation_times, rotation_times, scale_times;
  std::vector<Vec3f> translations;
  std::vector<Quatf> rotations;
  std::vector<Vec3f> scales;
};

struct AnimationClip {
  std::string name;        ///< as in the file (may be empty: then refer to it by index)
  double duration = 0.0;   ///< s (the last key's time when the file says less)
  std::vector<NodeChannel> channels;
};

struct Skin {
  std::vector<SkinNode> nodes;
  std::vector<int> joint_nodes;      ///< node of each joint (bone)
  std::vector<Mat4f> inverse_bind;   ///< per joint, see the header comment
  /// Per vertex of the mesh load_mesh returned for the same file (same order): joint indices and weights, which
  /// sum to 1. A vertex no bone reaches (a mesh without bones beside skinned ones, a vertex a skin left out)
  /// follows its mesh's node rigidly: it is bound with weight 1 to a joint made for that node.
  std::vector<std::array<std::uint16_t, kMaxInfluences>> joints;
  std::vector<std::array<float, kMaxInfluences>> weights;
  std::vector<AnimationClip> clips;
  std::vector<std::string> warnings;  ///< what the file got wrong and how it was read (logged by the caller)

  /// The clip named `name`, or by index when `name` is a whole number; an Input error naming the clips there are.
  Result<std::size_t> find_clip(const std::string& name) const;
  /// Every node's global matrix (file scene space) at the rest pose (no clip). A clip's poses are pose/skin_eval.h's.
  void rest_matrices(std::vector<Mat4f>& out) const;
};

/// T · R · S: a node's local matrix from its translation, rotation (normalised here) and scale.
Mat4f trs(const Vec3f& t, const Quatf& r, const Vec3f& s);

/// T of a MeshTransform as a matrix: x' = R · (scale ⊙ x) + translate.
Mat4f transform_matrix(const MeshTransform& t);

/// Σ_k w_k · K[j_k]: the blended skinning matrix of one vertex (LBS); its inverse maps a posed point back to bind.
inline Mat4f blend_matrix(const std::vector<Mat4f>& K, const std::array<std::uint16_t, kMaxInfluences>& j,
                          const std::array<float, kMaxInfluences>& w) {
  Mat4f m = Mat4f::Zero();
  for (int k = 0; k < kMaxInfluences; ++k)
    if (w[k] != 0.0f) m += w[k] * K[j[k]];
  return m;
}

/// Linear blend skinning of one point: Σ_k w_k · K[j_k] · x.
inline Vec3f skin_point(const std::vector<Mat4f>& K, const std::array<std::uint16_t, kMaxInfluences>& j,
                        const std::array<float, kMaxInfluences>& w, const Vec3f& x) {
  const Mat4f m = blend_matrix(K, j, w);
  return m.topLeftCorner<3, 3>() * x + m.topRightCorner<3, 1>();
}

/// Reads the skeleton, the weights and the clips of the file at `path`, for `mesh`: what load_mesh(path, options)
/// returned (vertices in the world, options.transform applied). Each vertex of `mesh` takes the weights of the
/// file's vertex at its bind position (they are welded by position, so the nearest one; vertices welded from
/// several take the first's). Returns nullopt for a file without bones (a mesh without a skin behaves as today).
/// Errors (one line naming the file): Input for a NaN or negative weight, a bone naming a node the file lacks,
/// a non-finite matrix or key, more than 65535 joints; an unreadable file as load_mesh says it.
/// `isolate`: read in a child process (io/isolate.h), as load_mesh does by default, so that Assimp crashing on the
/// file is an Input error naming it; false reads it in this process.
Result<std::optional<Skin>> load_skin(const std::filesystem::path& path, const TriangleMesh& mesh,
                                      const MeshTransform& transform, bool isolate = true);

}  // namespace ff::io
