#include "sampling/control_io.h"

#include "io/write_ply.h"

#include <fmt/format.h>

#include <array>
#include <cstdio>
#include <sstream>

namespace ff::sampling {

Status write_controls_ply(const std::filesystem::path& path, const ControlSet& set, std::uint64_t key) {
  if (!set.consistent()) return input_error("write_controls_ply: the control set's arrays differ in size");
  const std::array<io::NamedScalars, 3> scalars{{{"density", set.density}, {"weight", set.weight}, {"phi", set.phi}}};
  // %a: exact hexadecimal floats, so a cached set reads back bit for bit.
  const std::string comment = fmt::format(
      "fluidform controls\nfluidform-controls target={} spacing={:a} support={:a} mass={:a} centre={:a},{:a},{:a} key={:016x}",
      set.target, set.spacing, set.support, set.mass, set.centre.x(), set.centre.y(), set.centre.z(), key);
  io::ParticleFrameView view;
  view.positions = set.position;
  view.scalars = scalars;
  view.comment = comment;
  return io::write_particles_ply(path, view);
}

Result<ControlSet> read_controls_ply(const std::filesystem::path& path, std::uint64_t* key) {
  FF_TRY(io::ParticleFrame f, io::read_particles_ply(path));
  ControlSet set;
  bool have_meta = false;
  std::uint64_t stored = 0;
  for (const auto& c : f.comments) {
    if (c.rfind("fluidform-controls ", 0) != 0) continue;
    unsigned target = 0;
    float cx = 0, cy = 0, cz = 0;
    unsigned long long k = 0;
    if (std::sscanf(c.c_str(), "fluidform-controls target=%u spacing=%a support=%a mass=%a centre=%a,%a,%a key=%llx",
                    &target, &set.spacing, &set.support, &set.mass, &cx, &cy, &cz, &k) == 8 && target < 256) {
      set.target = static_cast<std::uint8_t>(target);
      set.centre = Vec3f(cx, cy, cz);
      stored = k;
      have_meta = true;
    }
  }
  const auto* density = f.scalar("density");
  const auto* weight = f.scalar("weight");
  const auto* phi = f.scalar("phi");
  if (!have_meta || !density || !weight || !phi)
    return input_error(fmt::format("{}: not a fluidform control-particle file (no density/weight/phi or header values)",
                                   path.string()));
  set.resize(f.positions.size());
  set.position = std::move(f.positions);
  set.density = *density;
  set.weight = *weight;
  set.phi = *phi;
  if (key) *key = stored;
  return set;
}

}  // namespace ff::sampling
