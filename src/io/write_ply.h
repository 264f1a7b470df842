#pragma once
// Particle frames as binary little-endian PLY (docs/outputs.md): `float x y z`,
// optionally `float vx vy vz` and `uchar target`. Readable by Blender, MeshLab, Open3D, splashsurf.
#include "core/error.h"
#include "core/types.h"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ff::io {

/// A named per-particle float property (e.g. a control particle's weight), written after the others.
struct NamedScalars {
  std::string_view name;        ///< PLY property name: [A-Za-z_][A-Za-z0-9_]*
  std::span<const float> values;
};

/// What one particle frame holds. Empty optional arrays are not written.
struct ParticleFrameView {
  std::span<const Vec3f> positions;            ///< metres
  std::span<const Vec3f> velocities;           ///< m/s, empty or same size as positions
  std::span<const std::uint8_t> targets;       ///< target id per particle (255 = free fluid), empty or same size
  std::span<const NamedScalars> scalars;       ///< extra float properties, each the same size as positions
  std::string_view comment = "fluidform particles";  ///< header comment lines ('\n' separates several)
};

/// Encodes a frame as binary little-endian PLY bytes.
std::vector<std::uint8_t> encode_particles_ply(const ParticleFrameView& frame);

/// Writes a frame atomically (temp file + rename).
Status write_particles_ply(const std::filesystem::path& path, const ParticleFrameView& frame);

/// A frame read back (for `mesh`, tests and tools).
struct ParticleFrame {
  std::vector<Vec3f> positions, velocities;
  std::vector<std::uint8_t> targets;
  std::vector<std::pair<std::string, std::vector<float>>> scalars;  ///< other float properties, in file order
  std::vector<std::string> comments;                               ///< header comment lines, without "comment "

  /// The values of scalar property `name`, or nullptr.
  const std::vector<float>* scalar(std::string_view name) const {
    for (const auto& [n, v] : scalars)
      if (n == name) return &v;
    return nullptr;
  }
};

/// Reads a binary little-endian PLY written by write_particles_ply (vertex element with float x y z and
/// optional float vx vy vz / uchar target, in any order). Other layouts give an Input error.
Result<ParticleFrame> read_particles_ply(const std::filesystem::path& path);
/// The same from the bytes of such a file; `name` stands for the file in messages.
Result<ParticleFrame> decode_particles_ply(std::span<const std::uint8_t> bytes, std::string_view name);

}  // namespace ff::io
