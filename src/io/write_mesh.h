#pragma once
// Mesh exports (docs/outputs.md): the editable mesh as Wavefront OBJ, the mesh animation as
// one glTF 2.0 binary (GLB), and the particles as a Blender point cache (PC2 + a frame-0 point mesh).
//
// Axes: fluidform simulates Y-up (gravity along −Y) in metres, which is glTF's convention (+Y up, metres) and
// what Blender's OBJ and glTF importers expect by default (they turn Y-up into Blender's Z-up), so coordinates
// are written as they are. Every file is written atomically (temp file + rename).
#include "core/error.h"
#include "core/types.h"
#include "io/atomic_file.h"
#include "io/triangle_mesh.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace ff::io {

/// Per-vertex unit normals, area-weighted over the incident triangles (a vertex of no triangle gets +Y).
std::vector<Vec3f> vertex_normals(const TriangleMesh& mesh);

/// The water look of exported meshes: a clear, refracting liquid whose colour comes from absorption inside it.
/// glTF: KHR_materials_transmission + _ior + _volume (three.js MeshPhysicalMaterial, Blender's Principled BSDF);
/// OBJ: an MTL with the same figures (Ni, d, Tf, illum 7).
struct WaterMaterial {
  Vec3f tint{0.16f, 0.48f, 0.85f};  ///< linear RGB the liquid absorbs towards (glTF attenuationColor, MTL Kd)
  float ior = 1.33f;                ///< water
  float roughness = 0.05f;
  float attenuation_distance = 0.0f;  ///< m travelled inside before light takes the tint; 0: half the last
                                      ///< frame's box diagonal (the tint then looks the same at any model size)
  /// Not water: an opaque liquid whose colour is the mesh's vertex colours (appearance tint or target; glTF COLOR_0 on
  /// a white base colour, MTL material "liquid").
  bool coloured = false;
};

/// MTL text of two materials: "water" (the clear liquid, Kd the tint) and "liquid" (opaque, white: an OBJ with vertex
/// colours names it); with `texture_file` (an image beside the MTL) a third, "liquid_textured" (map_Kd that file, Kd
/// `texture_factor`), which an OBJ with UVs names.
std::string encode_mtl(const WaterMaterial& material, std::string_view texture_file = {},
                       const Vec3f& texture_factor = Vec3f::Ones());

/// Whether a mesh's UVs (TriangleMesh::corner_uv) can be written: one triple per triangle, finite, and a texture with
/// pixels to index. The writers check it.
Status check_uv(const TriangleMesh& mesh, std::string_view what);

/// OBJ text: `v` lines (`v x y z r g b`, sRGB, when the mesh has colours), then `vt` when the mesh has a texture
/// (TriangleMesh::corner_uv: the vertices are then split at its seams), `vn` (vertex normals, same indexing) when
/// `normals`, then `f a//a b//b c//c` (`f a/a/a …` with UVs); with `mtllib` (a file name beside the OBJ), `mtllib` +
/// `usemtl water` (`usemtl liquid` with colours, `liquid_textured` with UVs) before the faces.
std::string encode_obj(const TriangleMesh& mesh, bool normals = true, std::string_view comment = "fluidform mesh",
                       std::string_view mtllib = {});
Status write_obj(const std::filesystem::path& path, const TriangleMesh& mesh, bool normals = true,
                 std::string_view comment = "fluidform mesh", std::string_view mtllib = {});

struct GlbOptions {
  double fps = 60.0;        ///< frames per second of the animation, > 0
  bool quantize = true;     ///< KHR_mesh_quantization: 16-bit positions, 8-bit normals (about half the size)
  std::vector<double> times;  ///< optional time (s) of each frame; empty: frame k at k / fps
  WaterMaterial material;   ///< the meshes' material (when `materials` is empty)
  /// Several targets: one material each (material k tinted as target k), and per frame the material of each
  /// triangle; a frame's triangles are then one primitive per material. Empty: every triangle is `material`.
  std::vector<WaterMaterial> materials;
  std::vector<std::vector<std::uint8_t>> triangle_material;  ///< [frame][triangle] index into `materials`

  Status validate(std::size_t frames) const;
};

/// The mesh animation as one GLB: one node per frame under a root node, switched by a STEP-interpolated scale
/// animation (frame k has scale 1 from its time until the next frame's, 0 otherwise), so it plays in three.js,
/// Blender and Unity without plugins. Without the animation (a static viewer) only the last frame shows.
/// Empty frames get a node without a mesh. A frame with colours carries COLOR_0; one with a texture (corner_uv)
/// carries TEXCOORD_0 instead, split at its UV seams, with the texture embedded once as PNG under its own material.
Result<std::vector<std::uint8_t>> encode_glb(std::span<const TriangleMesh> frames, const GlbOptions& options);
Status write_glb(const std::filesystem::path& path, std::span<const TriangleMesh> frames, const GlbOptions& options);

/// Blender point cache (PC2, read by the Mesh Cache modifier): `frames[k][i]` is particle i at frame k. Every frame
/// must have the same number of points (the caller pads by particle id); one sample per frame from `start_frame`.
Status write_pc2(const std::filesystem::path& path, std::span<const std::vector<Vec3f>> frames, float start_frame = 0.0f);

/// The same point cache written frame by frame (a long run's frames need not fit in memory). The header's
/// sample count is filled in by finish(), which publishes the file atomically; without it nothing is written.
class Pc2Writer {
 public:
  Status open(const std::filesystem::path& path, std::size_t points, float start_frame = 0.0f);
  Status add(std::span<const Vec3f> frame);
  Status finish();
  std::size_t frames() const { return frames_; }

 private:
  AtomicFileWriter file_;
  std::filesystem::path path_;
  std::size_t points_ = 0, frames_ = 0;
  std::vector<std::uint8_t> buf_;
};

}  // namespace ff::io
