#pragma once
// Textures as stages hand them on: a target's decoded base-colour texture (io/target_look.h) and the texture a formed
// mesh's UVs index when the liquid wears it (TriangleMesh::texture, pipeline/liquid_look.h, written by the OBJ and GLB
// writers).
#include "core/types.h"

#include <cstdint>
#include <vector>

namespace ff::io {

using Vec2f = Eigen::Vector2f;

/// A decoded texture: 8-bit sRGB, rows from the top.
struct Texture {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< width × height × 3
};

/// The texture a mesh's UVs index: its image, times `factor` (linear RGB; glTF's baseColorFactor).
struct MeshTexture {
  Texture image;
  Vec3f factor = Vec3f::Ones();
};

/// The texture at `uv` (OpenGL's convention, as Assimp reads them: origin bottom-left; bilinear, wrapping as glTF's
/// default sampler), in linear light.
Vec3f sample_texture(const Texture& t, Vec2f uv);

}  // namespace ff::io
