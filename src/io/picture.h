#pragma once
// Still pictures of meshes, without a GPU or a display: a z-buffered rasteriser with two-sided Lambert shading and 2×2
// supersampling, and PNG encoding through libpng. The report page's pictures of target and formed shape
// (pipeline/report_page.h) and the tests that compare silhouettes use it, so what a page shows is what was tested.
#include "core/error.h"
#include "core/types.h"
#include "io/triangle_mesh.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace ff::io {

/// An 8-bit RGB image, rows top to bottom.
struct Picture {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< width · height · 3
  /// Pixels that are not the background colour `bg`.
  std::size_t covered(const std::array<std::uint8_t, 3>& bg) const;
};

/// A view of a box of the world: looking at its centre from `direction` (from the centre towards the eye), Y up, an
/// orthographic projection that fits the whole box (so pictures of two meshes from one view are at one scale).
struct PictureView {
  Aabb box;
  Vec3f direction{0.55f, 0.35f, 0.9f};
  int width = 360, height = 300;
  std::array<std::uint8_t, 3> background{243, 245, 248};
};

/// `mesh` drawn in `colour`, or in its vertex colours when it has them (shaded by the angle to the view direction, both
/// sides lit), over the background.
Picture render_mesh(const TriangleMesh& mesh, const std::array<std::uint8_t, 3>& colour, const PictureView& view);

/// The picture as PNG bytes (libpng); an Io error when libpng fails.
Result<std::vector<std::uint8_t>> encode_png(const Picture& picture);
/// A texture as PNG bytes: the liquid's texture beside the OBJs and inside the GLBs, one encoder for both.
Result<std::vector<std::uint8_t>> encode_png(const Texture& texture);
/// PNG bytes back to RGB (for the tests); an Input error for bytes that are not a PNG.
Result<Picture> decode_png(std::span<const std::uint8_t> bytes);

}  // namespace ff::io
