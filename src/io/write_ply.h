#pragma once
// Particle frames as binary little-endian PLY (DESIGN.md output contract): `float x y z`,
// optionally `float vx vy vz` and `uchar target`. Readable by Blender, MeshLab, Open3D, splashsurf.
#include "core/error.h"
#include "core/types.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace ff::io {

/// What one particle frame holds. Empty optional arrays are not written.
struct ParticleFrameView {
  std::span<const Vec3f> positions;            ///< metres
  std::span<const Vec3f> velocities;           ///< m/s, empty or same size as positions
  std::span<const std::uint8_t> targets;       ///< target id per particle (255 = free fluid), empty or same size
};

/// Encodes a frame as binary little-endian PLY bytes.
std::vector<std::uint8_t> encode_particles_ply(const ParticleFrameView& frame);

/// Writes a frame atomically (temp file + rename).
Status write_particles_ply(const std::filesystem::path& path, const ParticleFrameView& frame);

/// A frame read back (for `mesh`, tests and tools).
struct ParticleFrame {
  std::vector<Vec3f> positions, velocities;
  std::vector<std::uint8_t> targets;
};

/// Reads a binary little-endian PLY written by write_particles_ply (vertex element with float x y z and
/// optional float vx vy vz / uchar target, in any order). Other layouts give an Input error.
Result<ParticleFrame> read_particles_ply(const std::filesystem::path& path);

}  // namespace ff::io
