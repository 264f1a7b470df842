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
#include "mesh_fuzz.h"

#include <cstring>
#include <string>

FF_FUZZ_TARGET(mesh_checks) {
  using namespace ff;
  if (size == 0) return 0;
  const std::span<const std::uint8_t> rest(data + 1, size - 1);
  const char* name = fuzz::mesh_name(data[0]);
  if ((data[0] & 0x10) == 0) {
    if (auto s = io::check_mesh_bytes(rest, name); !s.ok()) fuzz::check_refusal(s.error());
    return 0;
  }

  io::MeshLoadStats stats;
  auto m = io::mesh_from_import_answer(rest, name, fuzz::mesh_options(data[0]), &stats);
  if (!m) {
    fuzz::check_refusal(m.error());
    return 0;
  }
  fuzz::check_loaded_mesh(*m);

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
