#pragma once
// Target-mesh import through Assimp (docs/ARCHITECTURE.md): every format Assimp reads (OBJ, PLY, STL, glTF/GLB,
// FBX, DAE, OFF, 3DS …) becomes one TriangleMesh in the file's own units, node transforms applied and all
// meshes merged. Degenerate triangles and point/line primitives are dropped and counted;
// anything unusable is a one-line Input error naming the file. Only load_mesh.cpp includes
// Assimp.
#include "core/error.h"
#include "core/types.h"
#include "io/triangle_mesh.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace ff::io {

/// The most vertices a mesh may have: indices are `Index` and kInvalidIndex is reserved.
inline constexpr std::size_t kMaxMeshVertices = std::size_t{kInvalidIndex} - 1;  // 2^32 − 2

/// Scale, then rotate (degrees, about x then y then z, i.e. R = Rz*Ry*Rx), then translate:
/// p' = R * (scale ⊙ p) + translate.
struct MeshTransform {
  Vec3f scale{1, 1, 1};       ///< per-axis factor, each finite and non-zero (negative: a mirror)
  Vec3f rotate_deg{0, 0, 0};  ///< degrees about x, y, z (applied in that order), each finite
  Vec3f translate{0, 0, 0};   ///< metres, each finite

  /// True when apply() is exactly the identity (all fields at their defaults).
  bool is_identity() const;
  /// An odd number of negative scales: det(R·S) < 0, a mirror image.
  bool mirrors() const { return (int(scale.x() < 0.0f) + int(scale.y() < 0.0f) + int(scale.z() < 0.0f)) % 2 == 1; }
  /// The transformed point (computed in double, stored as float).
  Vec3f apply(const Vec3f& p) const;
  /// First invalid field as a Param error, e.g. "transform.scale.y = 0 must be finite and non-zero".
  Status validate() const;
};

struct LoadOptions {
  MeshTransform transform;                    ///< applied after import
  std::size_t max_vertices = kMaxMeshVertices;  ///< refuse larger meshes (after welding), [1, 2^32 − 2]
  /// Run Assimp in a child process (io/isolate.h), so that a crash, heap corruption or hang inside Assimp on a
  /// malformed file becomes an Input error naming the file instead of taking the program down. Off only to debug
  /// Assimp itself in one process.
  bool isolate = true;
  double import_timeout_s = 600.0;  ///< an isolated import still running after this long is stopped, (0, 86400]
};

/// Statistics of what import did (logged by the app).
struct MeshLoadStats {
  std::size_t source_meshes = 0;          ///< meshes in the file, before merging
  std::size_t dropped_degenerate = 0;     ///< triangles with a repeated vertex or (near) zero area
  std::size_t dropped_non_triangles = 0;  ///< point and line primitives
};

/// Whether Assimp reads files named like `path` (by its extension, case-insensitive; the file is not opened). JSON
/// is a scene, never a mesh, here.
bool is_mesh_extension(const std::filesystem::path& path);

/// Reads the mesh file at `path` (any format Assimp supports) into one triangle mesh: node transforms applied,
/// all meshes merged, identical positions welded, units kept as in the file, then `options.transform` applied.
/// Degenerate triangles (repeated index, or |cross| ≤ 1e-12 × bbox diagonal²) and non-triangle primitives are
/// dropped and counted in `stats` (when non-null); vertices left unreferenced are removed (order kept).
/// Errors (one line, naming the file): Param for an invalid `options`; Input for a missing file, a directory,
/// an unsupported or malformed file, an empty mesh, points/lines only, a non-finite vertex, only degenerate
/// triangles, more than `options.max_vertices` vertices. Never throws.
Result<TriangleMesh> load_mesh(const std::filesystem::path& path, const LoadOptions& options = {},
                               MeshLoadStats* stats = nullptr);
/// load_mesh() on the bytes of a mesh file in memory (the fuzz targets' way in): `name` stands for the file in
/// messages, and its extension tells Assimp the format ("mesh.obj"); the same checks, the same errors.
Result<TriangleMesh> load_mesh_from_memory(std::span<const std::uint8_t> bytes, const std::filesystem::path& name,
                                           const LoadOptions& options = {}, MeshLoadStats* stats = nullptr);

// ---- load_mesh's own parts, one by one (the fuzz targets reach them without Assimp: fuzz/fuzz_mesh_checks.cpp) ----

/// The checks made on a mesh file's bytes before Assimp sees them (declared counts against the file's size, an OFF
/// file's lines, the end of a PLY header): ok, or the Input error load_mesh_from_memory() gives without importing.
Status check_mesh_bytes(std::span<const std::uint8_t> bytes, const std::filesystem::path& name);
/// What load_mesh() makes of the answer of its import process (io/isolate.h), whatever that process sent: every
/// count checked against the bytes, every index against the vertices, then node-transform overflow,
/// `options.transform` and degenerate triangles as for a file. A garbled answer is an Input error naming `name`.
Result<TriangleMesh> mesh_from_import_answer(std::span<const std::uint8_t> answer, const std::filesystem::path& name,
                                             const LoadOptions& options = {}, MeshLoadStats* stats = nullptr);
/// The answer an import process sends for `result` (a mesh, or the error it ended with) and `stats`.
std::string import_answer(const Result<TriangleMesh>& result, const MeshLoadStats& stats);

/// Applies `t` to every vertex in place; a mirroring `t` (MeshTransform::mirrors) also reverses every triangle's
/// winding, so outward stays outward.
void transform_mesh(TriangleMesh& mesh, const MeshTransform& t);

/// Signed enclosed volume in m³ (divergence theorem: Σ a·(b×c)/6, accumulated in double); positive for a
/// closed mesh with outward (CCW from outside) triangles. Meaningless for open meshes.
double signed_volume(const TriangleMesh& mesh);

}  // namespace ff::io
