// Particle frames (io/write_ply.h): any bytes as a particle PLY file, as `mesh`, `serve`'s playback and the control
// particle cache read them. A frame that reads must hold one entry per particle in every array, and must come back
// the same through the writer.
#include "fuzz_target.h"
#include "io/write_ply.h"

#include <cstring>

FF_FUZZ_TARGET(ply) {
  using namespace ff;
  auto f = io::decode_particles_ply({data, size}, "frame_00000.ply");
  if (!f) {
    fuzz::check_refusal(f.error());
    return 0;
  }
  const std::size_t n = f->positions.size();
  FF_FUZZ_CHECK(f->velocities.empty() || f->velocities.size() == n);
  FF_FUZZ_CHECK(f->targets.empty() || f->targets.size() == n);
  for (const auto& [name, values] : f->scalars) FF_FUZZ_CHECK(values.size() == n);

  io::ParticleFrameView view;
  view.positions = f->positions;
  view.velocities = f->velocities;
  view.targets = f->targets;
  const auto bytes = io::encode_particles_ply(view);
  auto back = io::decode_particles_ply(bytes, "again.ply");
  FF_FUZZ_CHECK(back.has_value());
  FF_FUZZ_CHECK(back->positions.size() == n && back->velocities.size() == f->velocities.size() &&
                back->targets == f->targets);
  // Bit for bit (NaN payloads included): compare the bytes, not the floats.
  FF_FUZZ_CHECK(n == 0 || std::memcmp(back->positions.data(), f->positions.data(), 12 * n) == 0);
  FF_FUZZ_CHECK(f->velocities.empty() || std::memcmp(back->velocities.data(), f->velocities.data(), 12 * n) == 0);
  return 0;
}
