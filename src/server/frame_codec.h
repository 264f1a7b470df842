#pragma once
// The binary frame the server sends to the viewer over the WebSocket, one per simulated (or played-back) frame.
// THE layout on the C++ side; web/src/protocol.js is its JavaScript twin, and tests/server/frame_roundtrip checks
// that the two agree (C++ encodes, node decodes). Little-endian, every field at its natural alignment:
//
//   offset  type      field
//   0       u32       magic 0x31504646 (the bytes "FFP1")
//   4       u16       version (1)
//   6       u16       header bytes (64): positions start here
//   8       u32       frame number
//   12      u32       n, particles
//   16      f64       time, s simulated
//   24      f32       step_ms: wall-clock of the frame's simulation (0 in playback)
//   28      f32       error rate, % (NaN: no targets)
//   32      f32       sim_fps: simulated frames per second of wall time, over about the last second
//   36      u32       controlled particles
//   40      f32[3]    lo: the bounding box of the positions
//   52      f32[3]    hi
//   64      u16[3n]   positions quantised in the box: x = lo + q/65535 (hi − lo), per axis
//   64+6n   u8[n]     target of each particle (255: free fluid)
//   ...     0–3 zero bytes to a multiple of 4
//
// Why quantised: 10k particles are 70 KB a frame instead of 130 KB, and 1/65535 of a metre-sized box (~20 µm) is
// far below anything a viewer can show. Non-finite positions are sent as lo.
//
// The live surface (the reconstructed mesh of a recent frame, sent while a viewer shows the mesh), its own binary
// message, told apart by its magic:
//   offset  type      field
//   0       u32       magic 0x314D4646 (the bytes "FFM1")
//   4       u16       version (1)
//   6       u16       header bytes (32): vertices start here
//   8       u32       frame number the surface was made from
//   12      u32       nv, vertices
//   16      f64       time, s simulated
//   24      u32       nt, triangles
//   28      f32       build_ms: wall-clock of the reconstruction
//   32      f32[3nv]  vertex positions, m
//   32+12nv u32[3nt]  triangles (vertex indices, outward winding)
#include "core/error.h"
#include "core/types.h"
#include "io/triangle_mesh.h"

#include <cstdint>
#include <span>
#include <vector>

namespace ff::server {

inline constexpr std::uint32_t kFrameMagic = 0x31504646u;  // "FFP1"
inline constexpr std::uint16_t kFrameVersion = 1;
inline constexpr std::size_t kFrameHeaderBytes = 64;
inline constexpr std::uint32_t kSurfaceMagic = 0x314D4646u;  // "FFM1"
inline constexpr std::uint16_t kSurfaceVersion = 1;
inline constexpr std::size_t kSurfaceHeaderBytes = 32;

struct FrameInfo {
  std::uint32_t frame = 0;
  double time = 0.0;
  float step_ms = 0.0f;
  float error_rate = NAN;
  float sim_fps = 0.0f;
  std::uint32_t controlled = 0;
};

struct DecodedFrame {
  FrameInfo info;
  Vec3f lo{Vec3f::Zero()}, hi{Vec3f::Zero()};
  std::vector<Vec3f> positions;  ///< dequantised
  std::vector<std::uint8_t> targets;
};

/// Encodes one frame. `targets` is empty (all 255) or one per position.
std::vector<std::uint8_t> encode_frame(const FrameInfo& info, std::span<const Vec3f> positions,
                                       std::span<const std::uint8_t> targets);

/// Decodes (for tests and tools). Input error for a wrong magic, version or size.
Result<DecodedFrame> decode_frame(std::span<const std::uint8_t> bytes);

struct SurfaceInfo {
  std::uint32_t frame = 0;
  double time = 0.0;
  float build_ms = 0.0f;
};

struct DecodedSurface {
  SurfaceInfo info;
  io::TriangleMesh mesh;
};

/// Encodes one live surface.
std::vector<std::uint8_t> encode_surface(const SurfaceInfo& info, const io::TriangleMesh& mesh);
/// Decodes (for tests and tools). Input error for a wrong magic, version or size, or an index out of range.
Result<DecodedSurface> decode_surface(std::span<const std::uint8_t> bytes);

/// The largest quantisation error of a box: half a step per axis.
Vec3f quantisation_step(const Vec3f& lo, const Vec3f& hi);

}  // namespace ff::server
