// Our own checks on imported meshes, without Assimp (io/load_mesh.h): fuzz_mesh runs the whole import, Assimp in a
// child process included, and so goes at the speed of a fork and a fresh Assimp per input (~150/s under ASan; Assimp's
// OBJ reader alone zeroes a 16 MB buffer in every fresh process). This target fuzzes the code of ours that reads
// untrusted bytes on the way, in this process, at the speed of that code:
// - bit 4 of the first byte clear: the input is a mesh file, given to the checks made before Assimp sees it
//   (declared counts, an OFF file's lines, the end of a PLY header; bits 0-1 pick the extension). Ok or one line.
// - bit 4 set: the input is what an import process answered (any bytes: a child whose heap Assimp corrupted may
//   still answer), given to what load_mesh does with it; bits 2-3 pick the transform. A mesh that comes back has
//   triangles, every index in range, no repeated index in a triangle, finite vertices, no vertex that no triangle
//   uses, and is a fixed point: sent again as an answer, it comes back the same.
#include "fuzz_target.h"
#include "io/load_mesh.h"

#include <array>
#include <cstring>
#include <string>
#include <vector>

FF_FUZZ_TARGET(mesh_checks) {
  using namespace ff;
  if (size == 0) return 0;
  static constexpr std::array<const char*, 4> kNames{"mesh.obj", "mesh.ply", "mesh.stl", "mesh.off"};
  const std::span<const std::uint8_t> rest(data + 1, size - 1);
  const char* name = kNames[data[0] & 3];
  if ((data[0] & 0x10) == 0) {
    if (auto s = io::check_mesh_bytes(rest, name); !s.ok()) fuzz::check_refusal(s.error());
    return 0;
  }

  io::LoadOptions options;
  switch ((data[0] >> 2) & 3) {
    case 1: options.transform.scale = {-2.0f, 1.0f, 1.0f}; break;  // a mirror: the windings are reversed
    case 2: options.transform.rotate_deg = {30.0f, 45.0f, 60.0f}, options.transform.translate = {1e3f, 0, 0}; break;
    case 3: options.transform.scale = {1e30f, 1e30f, 1e30f}; break;  // may overflow to Inf: refused
    default: break;
  }
  io::MeshLoadStats stats;
  auto m = io::mesh_from_import_answer(rest, name, options, &stats);
  if (!m) {
    fuzz::check_refusal(m.error());
    return 0;
  }
  FF_FUZZ_CHECK(!m->triangles.empty() && !m->vertices.empty());
  std::vector<bool> used(m->vertices.size(), false);
  for (const auto& t : m->triangles) {
    for (const Index i : t) {
      FF_FUZZ_CHECK(i < m->vertices.size());
      used[i] = true;
    }
    FF_FUZZ_CHECK(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
  }
  for (std::size_t i = 0; i < m->vertices.size(); ++i) FF_FUZZ_CHECK(used[i] && m->vertices[i].allFinite());

  // Nothing is left to drop or to refuse in a mesh that came back: as an answer again, it comes back bit for bit.
  const std::string again = io::import_answer(*m, stats);
  io::MeshLoadStats stats2;
  auto m2 = io::mesh_from_import_answer({reinterpret_cast<const std::uint8_t*>(again.data()), again.size()}, name,
                                        io::LoadOptions{}, &stats2);
  FF_FUZZ_CHECK(m2.has_value());
  FF_FUZZ_CHECK(stats2.dropped_degenerate == 0);
  FF_FUZZ_CHECK(m2->triangles == m->triangles);
  FF_FUZZ_CHECK(m2->vertices.size() == m->vertices.size());
  FF_FUZZ_CHECK(std::memcmp(m2->vertices.data(), m->vertices.data(), m->vertices.size() * sizeof(Vec3f)) == 0);
  return 0;
}
