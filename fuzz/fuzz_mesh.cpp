// Mesh import and our checks on it (io/load_mesh.h): the first byte picks the format Assimp is told (OBJ, PLY, STL or
// OFF, the formats whose headers and contents we check) and the transform applied after import; the rest is the
// file. A mesh that loads has triangles, every index in range, no repeated index in a triangle, finite vertices,
// and no vertex that no triangle uses. Assimp runs in a child process (io/isolate.h), as for every user: its own
// bugs (a write past its OBJ vertex array, a leak in its PLY reader) end or stay in the child, and what is fuzzed
// here is that every input, whatever Assimp does with it, comes back as a mesh or as one line naming the file.
#include "fuzz_target.h"
#include "io/load_mesh.h"

#include <array>
#include <vector>

FF_FUZZ_TARGET(mesh) {
  using namespace ff;
  if (size == 0) return 0;
  static constexpr std::array<const char*, 4> kNames{"mesh.obj", "mesh.ply", "mesh.stl", "mesh.off"};
  io::LoadOptions options;
  switch ((data[0] >> 2) & 3) {
    case 1: options.transform.scale = {-2.0f, 1.0f, 1.0f}; break;  // a mirror: the windings are reversed
    case 2: options.transform.rotate_deg = {30.0f, 45.0f, 60.0f}, options.transform.translate = {1e3f, 0, 0}; break;
    case 3: options.transform.scale = {1e30f, 1e30f, 1e30f}; break;  // may overflow to Inf: refused
    default: break;
  }
  io::MeshLoadStats stats;
  auto m = io::load_mesh_from_memory({data + 1, size - 1}, kNames[data[0] & 3], options, &stats);
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
  return 0;
}
