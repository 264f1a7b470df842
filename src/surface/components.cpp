#include "surface/components.h"

#include "surface/mesh_topology.h"

#include <Eigen/Geometry>

#include <cmath>

namespace ff::surface {

ComponentCleanup remove_small_components(io::TriangleMesh& mesh, double min_volume, bool remove_cavities) {
  ComponentCleanup out;
  if ((!(min_volume > 0.0) && !remove_cavities) || mesh.triangles.empty()) return out;
  const Components comp = connected_components(mesh);
  std::vector<double> vol(comp.count, 0.0);
  for (const auto& t : mesh.triangles) {
    const Vec3d a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
                c = mesh.vertices[t[2]].cast<double>();
    vol[comp.of_vertex[t[0]]] += a.dot(b.cross(c)) / 6.0;
  }
  std::vector<unsigned char> drop(comp.count, 0);
  for (std::size_t c = 0; c < comp.count; ++c) {
    drop[c] = std::abs(vol[c]) < min_volume || (remove_cavities && !(vol[c] > 0.0));
    out.removed_components += drop[c];
  }
  if (out.removed_components == 0) return out;
  std::vector<unsigned char> keep(mesh.triangles.size(), 1);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    if (drop[comp.of_vertex[mesh.triangles[f][0]]]) {
      keep[f] = 0;
      ++out.removed_triangles;
    }
  out.vertex_map = keep_triangles(mesh, keep);
  return out;
}

}  // namespace ff::surface
