#pragma once
// Checkpoints for `run --resume`: every state array of the ParticleSet (through its one field list,
// in the current order, so the continued run repeats the uninterrupted one bit for bit), the clock,
// and an opaque text block for the caller (the app stores its per-frame metrics there).
#include "core/error.h"
#include "sim/particle_set.h"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace ff::sim {

struct Checkpoint {
  std::int64_t next_frame = 0;  ///< first output frame still to simulate
  double time = 0.0;            ///< simulated seconds at that frame
  std::uint64_t scene_hash = 0; ///< hash of the scene the run started from (resume refuses a changed scene)
  std::string extra;            ///< caller's data (JSON)
  ParticleSet particles;
};

/// Serialises a checkpoint (magic, version, sizes, arrays, FNV-1a checksum).
std::vector<std::uint8_t> encode_checkpoint(const Checkpoint& c);
/// Parses bytes written by encode_checkpoint; a truncated or corrupt file is an Input error.
Result<Checkpoint> decode_checkpoint(std::span<const std::uint8_t> bytes);

/// FNV-1a 64-bit hash.
std::uint64_t fnv1a(std::span<const std::uint8_t> bytes, std::uint64_t seed = 14695981039346656037ull);

}  // namespace ff::sim
