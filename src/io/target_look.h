#pragma once
// A target mesh's look (issue 46, `targets[].appearance: "target"`): its triangles with what colours them, read
// through Assimp: per-vertex UVs and colours, each triangle's material (base colour, base-colour texture), and the
// textures decoded (stb_image: PNG, JPEG, TGA, BMP … from the model's folder or embedded in a glTF/FBX file).
//
// The triangles are Assimp's own, not welded (load_mesh welds identical positions, which would merge the two sides of
// a UV seam), node transforms baked and the scene's transform applied, so a point of the target in the world finds
// its triangle here. The colour of a surface point (colour_at): base = the texture at its UV (bilinear, wrapping,
// decoded from sRGB to linear) when its material has one, else white when the mesh has vertex colours, else the
// material colour; then × the vertex colours (interpolated); then × the glTF base colour factor when the file is glTF
// (glTF's own rule: factor × texture × COLOR_0). Colours are linear RGB in [0, 1]: glTF's vertex colours are linear,
// every other format's (PLY, OBJ, Collada, FBX) are read as sRGB display values and converted.
//
// Bad input. The mesh itself was read by load_mesh before (its errors are load_mesh's); here a texture that is
// missing, unreadable or larger than kMaxTextureSide is a warning (TargetLook::warnings), and its material keeps its
// colour: the run goes on. The import runs in a child process as load_mesh's does (io/isolate.h), texture decoding
// included, so a malformed image cannot take the program down either.
#include "core/error.h"
#include "core/types.h"
#include "io/load_mesh.h"
#include "io/texture.h"
#include "io/triangle_mesh.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ff::io {

struct LookMaterial {
  Vec3f colour{0.8f, 0.8f, 0.8f};  ///< linear RGB: the base (or diffuse) colour
  int texture = -1;                ///< index into TargetLook::textures, −1: none
  bool factor_with_texture = false;  ///< glTF: the texture and the vertex colours are multiplied by `colour`
};

struct TargetLook {
  TriangleMesh mesh;                    ///< the file's triangles, not welded, in the world (scene transform applied)
  std::vector<Vec2f> uv;                ///< per vertex of `mesh` (first UV channel); empty when the file has none
  std::vector<Vec3f> colours;           ///< per vertex, linear RGB (first colour channel); empty when none
  std::vector<std::uint16_t> material;  ///< per triangle: index into `materials`
  std::vector<LookMaterial> materials;  ///< at least one
  std::vector<Texture> textures;
  std::vector<std::string> warnings;    ///< one line each: a texture that could not be used, and why

  /// The colour of triangle `t` at barycentric coordinates `bary` (a, b, c weights summing to 1), linear RGB.
  Vec3f colour_at(Index t, const Vec3f& bary) const;
  /// Whether anything varies over the surface (a texture or vertex colours), or every material is one colour.
  bool textured() const { return !textures.empty() || !colours.empty(); }
};

/// Textures larger than this on a side are refused (a warning, the material colour is used).
inline constexpr int kMaxTextureSide = 16384;

/// Reads the look of the mesh file at `path`, `transform` applied as load_mesh applies it. Errors (Input, one line,
/// naming the file) as load_mesh's: a missing or unreadable file, no triangles, a non-finite vertex; textures only
/// warn. Never throws.
Result<TargetLook> load_target_look(const std::filesystem::path& path, const MeshTransform& transform = {},
                                    double import_timeout_s = 600.0);

/// sRGB 8-bit → linear, and linear → sRGB 8-bit (rounded, clamped), the standard transfer function.
float srgb_to_linear(std::uint8_t c);
std::uint8_t linear_to_srgb(float c);

}  // namespace ff::io
