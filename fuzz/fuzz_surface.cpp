// The live viewer's surface message (server/frame_codec.h): any bytes through decode_surface, whose triangles must
// all name vertices it has; and the same bytes as a mesh to send (vertices from floats, indices folded into range)
// through encode_surface and back, which must give the mesh bit for bit.
#include "fuzz_target.h"
#include "server/frame_codec.h"

#include <cstring>

FF_FUZZ_TARGET(surface) {
  using namespace ff;
  if (auto s = server::decode_surface({data, size}); !s) {
    fuzz::check_refusal(s.error());
  } else {
    for (const auto& tri : s->mesh.triangles)
      for (const Index v : tri) FF_FUZZ_CHECK(v < s->mesh.vertices.size());
  }

  // The first half of the bytes as vertices, the second as triangles.
  io::TriangleMesh mesh;
  const std::size_t nv = size / 24, nt = nv == 0 ? 0 : (size - 12 * nv) / 12;
  mesh.vertices.resize(nv);
  if (nv) std::memcpy(static_cast<void*>(mesh.vertices.data()), data, 12 * nv);
  mesh.triangles.resize(nt);
  for (std::size_t k = 0; k < nt; ++k)
    for (int c = 0; c < 3; ++c) {
      Index v = 0;
      std::memcpy(&v, data + 12 * nv + 12 * k + 4 * std::size_t(c), 4);
      mesh.triangles[k][std::size_t(c)] = static_cast<Index>(v % nv);
    }
  server::SurfaceInfo info;
  info.frame = static_cast<std::uint32_t>(size);
  const auto bytes = server::encode_surface(info, mesh);
  auto back = server::decode_surface(bytes);
  FF_FUZZ_CHECK(back.has_value());
  FF_FUZZ_CHECK(back->info.frame == info.frame && back->mesh.triangles == mesh.triangles &&
                back->mesh.vertices.size() == nv);
  FF_FUZZ_CHECK(nv == 0 || std::memcmp(back->mesh.vertices.data(), mesh.vertices.data(), 12 * nv) == 0);
  return 0;
}
