// Mesh import and our checks on it (io/load_mesh.h): the first byte picks the format Assimp is told (OBJ, PLY, STL or
// OFF, the formats whose headers and contents we check) and the transform applied after import; the rest is the
// file. A mesh that loads has triangles, every index in range, no repeated index in a triangle, finite vertices,
// and no vertex that no triangle uses. Assimp runs in a child process (io/isolate.h), as for every user: its own
// bugs (a write past its OBJ vertex array, a leak in its PLY reader) end or stay in the child, and what is fuzzed
// here is that every input, whatever Assimp does with it, comes back as a mesh or as one line naming the file.
#include "mesh_fuzz.h"

FF_FUZZ_TARGET(mesh) {
  using namespace ff;
  if (size == 0) return 0;
  io::MeshLoadStats stats;
  auto m = io::load_mesh_from_memory({data + 1, size - 1}, fuzz::mesh_name(data[0]), fuzz::mesh_options(data[0]), &stats);
  if (!m) {
    fuzz::check_refusal(m.error());
    return 0;
  }
  fuzz::check_loaded_mesh(*m);
  return 0;
}
