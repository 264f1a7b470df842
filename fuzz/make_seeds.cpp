// Writes the binary seeds of fuzz/corpus/ with the project's own writers, so that each is a real (tiny) file of its
// kind: particle PLY frames, a checkpoint as `run` writes it, a particle frame and a surface message as `serve`
// sends them. The text seeds (scenes, messages, requests, meshes) are plain files in fuzz/corpus/. Built by the fuzz
// preset; run by hand when a format changes:  build/fuzz/fuzz/fuzz_make_seeds fuzz/corpus
#include "io/atomic_file.h"
#include "io/load_mesh.h"
#include "io/write_ply.h"
#include "metrics/report.h"
#include "server/frame_codec.h"
#include "sim/checkpoint.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace {
namespace fs = std::filesystem;
using namespace ff;

bool write(const fs::path& file, std::span<const std::uint8_t> bytes) {
  fs::create_directories(file.parent_path());
  if (auto s = io::write_file_atomic(file, bytes); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.error().message.c_str());
    return false;
  }
  std::printf("%s (%zu bytes)\n", file.c_str(), bytes.size());
  return true;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_seeds CORPUS_DIR\n");
    return 2;
  }
  const fs::path dir = argv[1];
  bool ok = true;
  const std::vector<Vec3f> x{{0.0f, 0.0f, 0.0f}, {0.1f, 0.2f, 0.3f}, {-1.5f, 2.0f, 0.25f}};
  const std::vector<Vec3f> v{{0.0f, -1.0f, 0.0f}, {0.5f, 0.0f, 0.0f}, {0.0f, 0.0f, 2.0f}};
  const std::vector<std::uint8_t> t{255, 0, 1};
  const std::vector<float> w{1.0f, 0.5f, 0.25f};

  // Particle frames: positions only; as `run` writes them (velocities, targets); a control-particle cache (a weight).
  io::ParticleFrameView pos;
  pos.positions = x;
  ok &= write(dir / "ply" / "positions.ply", io::encode_particles_ply(pos));
  io::ParticleFrameView run = pos;
  run.velocities = v;
  run.targets = t;
  ok &= write(dir / "ply" / "run_frame.ply", io::encode_particles_ply(run));
  const io::NamedScalars weight{"weight", w};
  io::ParticleFrameView ctl = pos;
  ctl.scalars = std::span<const io::NamedScalars>(&weight, 1);
  ctl.comment = "fluidform control particles\nspacing 0.02";
  ok &= write(dir / "ply" / "control.ply", io::encode_particles_ply(ctl));

  // A checkpoint as pipeline/run.cpp writes it: three particles, one frame row and one target row in "extra".
  sim::Checkpoint ck;
  ck.next_frame = 2;
  ck.time = 1.0 / 60.0;
  ck.scene_hash = 0x1234567890abcdefull;
  for (std::size_t i = 0; i < x.size(); ++i) ck.particles.push_back(x[i], v[i], t[i]);
  ck.particles.bound_control[1] = 7;
  metrics::FrameRow row;
  row.frame = 1, row.time = ck.time, row.particles = 3, row.step_seconds = 0.01, row.substeps = 2, row.iterations = 8;
  row.controlled = 2, row.error_rate = 12.5, row.e_fwd = 0.01, row.e_bwd = 0.02, row.e_fwd_all = 0.015;
  metrics::TargetRow trow;
  trow.frame = 1, trow.target = 0;
  trow.m.fluid = 3, trow.m.controlled = 2, trow.m.error_rate = 12.5;
  ck.extra = nlohmann::json{{"rows", metrics::rows_to_json({row})}, {"target_rows", metrics::target_rows_to_json({trow})}}.dump();
  ok &= write(dir / "checkpoint" / "state.ffck", sim::encode_checkpoint(ck));
  sim::Checkpoint empty;
  empty.extra = "{}";
  ok &= write(dir / "checkpoint" / "empty.ffck", sim::encode_checkpoint(empty));

  // A live frame (with targets, and without: all free fluid) and a live surface (a tetrahedron).
  server::FrameInfo info;
  info.frame = 3, info.time = 0.05, info.step_ms = 4.0f, info.error_rate = 12.5f, info.sim_fps = 30.0f, info.controlled = 2;
  ok &= write(dir / "frame" / "targets.bin", server::encode_frame(info, x, t));
  info.error_rate = NAN;
  ok &= write(dir / "frame" / "free_fluid.bin", server::encode_frame(info, x, {}));
  io::TriangleMesh tetra;
  tetra.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetra.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  ok &= write(dir / "surface" / "tetra.bin", server::encode_surface({3, 0.05, 2.0f}, tetra));
  ok &= write(dir / "surface" / "empty.bin", server::encode_surface({0, 0.0, 0.0f}, io::TriangleMesh{}));

  // Import processes' answers (fuzz_mesh_checks: first byte 0x10 | transform << 2 | format): the tetrahedron; with a
  // degenerate triangle and a vertex no triangle uses; mirrored; an error. (Its mesh-file seeds are fuzz_mesh's.)
  const auto answer = [&](const char* file, std::uint8_t first, const Result<io::TriangleMesh>& r,
                          const io::MeshLoadStats& stats) {
    std::string bytes = io::import_answer(r, stats);
    bytes.insert(bytes.begin(), static_cast<char>(first));
    return write(dir / "mesh_checks" / file, {reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()});
  };
  io::MeshLoadStats stats;
  stats.source_meshes = 1;
  ok &= answer("answer_tetra.bin", 0x10, tetra, stats);
  io::TriangleMesh untidy = tetra;
  untidy.vertices.push_back({5, 5, 5});
  untidy.triangles.push_back({0, 1, 1});
  stats.dropped_non_triangles = 2;
  ok &= answer("answer_untidy.bin", 0x10, untidy, stats);
  ok &= answer("answer_tetra_mirrored.bin", 0x10 | (1 << 2), tetra, stats);
  ok &= answer("answer_error.bin", 0x10, Error{Error::Kind::Input, "mesh.obj: contains no meshes"}, stats);
  return ok ? 0 : 1;
}
