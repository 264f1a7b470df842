#include "surface/marching_cubes.h"

#include "surface/block_loop.h"
#include "surface/crossed_edges.h"
#include "surface/mc_table.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>

namespace ff::surface {
namespace {

constexpr int kB = SparseField::kBlockCells;
using Edges = CrossedEdges<3>;  // 1536 owned edges per block
constexpr Index kCentreFlag = Index(1) << 31;  // marks a block-local centre id until the final numbering

constexpr int node_edge(int i, int j, int k, int axis) { return ((k * kB + j) * kB + i) * 3 + axis; }
constexpr std::array<int, 3> kSteps = {1, 2, 4};  // edge `axis` of a node: one node along x, y or z

int corner_local(int i, int j, int k, int c) {
  return SparseField::local(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
}

// Pass 2 for block b: its cells' triangles (bt) and loop centres (bc, numbered block-locally under kCentreFlag),
// edge vertices looked up in their owning blocks; `broken` is set when one is missing.
void triangulate_block(const SparseField& field, const McTable& table, std::int64_t b, const Edges& edges,
                       const std::vector<std::array<std::int64_t, 8>>& up, const std::vector<Vec3f>& vertices,
                       std::vector<std::array<Index, 3>>& bt, std::vector<Vec3f>& bc, std::atomic<bool>& broken) {
  const float iso = field.iso;
  const float* v = field.values[std::size_t(b)].data();
  auto vertex_of = [&](int i, int j, int k, int e) -> Index {
    const CubeEdge ce = McTable::edge(e);
    const std::int64_t id = cell_edge_vertex(edges, up[std::size_t(b)], i, j, k, ce.c0,
                                             [&](const int* n) { return node_edge(n[0], n[1], n[2], ce.axis); });
    if (id < 0) {
      broken = true;
      return 0;
    }
    return Index(id);
  };
  for (int k = 0; k < kB; ++k)
    for (int j = 0; j < kB; ++j)
      for (int i = 0; i < kB; ++i) {
        float cv[8];
        int mask = 0;
        for (int c = 0; c < 8; ++c) {
          cv[c] = v[corner_local(i, j, k, c)];
          mask |= int(cv[c] > iso) << c;
        }
        if (mask == 0 || mask == 255) continue;
        int centres_in = 0;
        for (int q = 0; q < table.ambiguous_count(mask); ++q) {
          const int f = table.ambiguous_face(mask, q), a = f / 2;
          const int u = a == 0 ? 1 : 0, w = a == 2 ? 1 : 2;
          const int c00 = (f & 1) << a, c10 = c00 | (1 << u), c01 = c00 | (1 << w), c11 = c10 | (1 << w);
          if (face_centre_inside(cv[c00] - iso, cv[c10] - iso, cv[c01] - iso, cv[c11] - iso)) centres_in |= 1 << q;
        }
        const CubeTriangulation& ct = table.cube(mask, centres_in);
        std::array<Index, 16> ref{};
        for (int e = 0; e < 12; ++e) {
          const CubeEdge ce = McTable::edge(e);
          if (((mask >> ce.c0) & 1) != ((mask >> ce.c1) & 1)) ref[std::size_t(e)] = vertex_of(i, j, k, e);
        }
        for (int q = 0; q < ct.centre_count; ++q) {
          Vec3f sum = Vec3f::Zero();
          int m = 0;
          for (int e = 0; e < 12; ++e)
            if ((ct.centre_edges[std::size_t(q)] >> e) & 1) {
              sum += vertices[ref[std::size_t(e)]];
              ++m;
            }
          ref[std::size_t(12 + q)] = kCentreFlag | Index(bc.size());
          bc.push_back(sum / float(m));
        }
        for (int t = 0; t < ct.triangle_count; ++t) {
          const auto& tr = ct.triangles[std::size_t(t)];
          bt.push_back({ref[tr[0]], ref[tr[1]], ref[tr[2]]});
        }
      }
}

// The blocks' triangles and centres appended to `out` in block order, the centres after all edge vertices.
Status concatenate_blocks(std::vector<std::vector<std::array<Index, 3>>>& tris,
                          const std::vector<std::vector<Vec3f>>& centres, std::uint64_t edge_vertices, McMesh& out) {
  std::size_t total_tris = 0, total_centres = 0;
  for (std::size_t b = 0; b < tris.size(); ++b) {
    total_tris += tris[b].size();
    total_centres += centres[b].size();
  }
  if (edge_vertices + total_centres >= kCentreFlag)
    return numerical_error("surface: more than 2^31 marching-cubes vertices");
  out.mesh.triangles.reserve(total_tris);
  out.mesh.vertices.reserve(edge_vertices + total_centres);
  out.cluster.reserve(edge_vertices + total_centres);
  for (std::size_t b = 0; b < tris.size(); ++b) {
    const auto base = Index(out.mesh.vertices.size());
    for (auto t : tris[b]) {
      for (auto& x : t)
        if (x & kCentreFlag) x = base + (x & ~kCentreFlag);
      out.mesh.triangles.push_back(t);
    }
    out.mesh.vertices.insert(out.mesh.vertices.end(), centres[b].begin(), centres[b].end());
    out.cluster.insert(out.cluster.end(), centres[b].size(), kNoCluster);
    std::vector<std::array<Index, 3>>().swap(tris[b]);
  }
  out.centre_vertices = total_centres;
  return {};
}

}  // namespace

Result<McMesh> marching_cubes(const SparseField& field) {
  const auto nb = std::int64_t(field.keys.size());
  const McTable& table = McTable::get();

  // Kept neighbours at +x, +y, +z and their combinations (index = dx + 2 dy + 4 dz), −1 when absent.
  const std::vector<std::array<std::int64_t, 8>> up = field.upper_neighbors();

  // --- pass 1: which owned edges are crossed (edges from nodes [0, 8)³ of the block) -------------------------------
  Edges edges(field.keys.size());
  const std::uint64_t edge_vertices = mark_crossed_edges(field, kSteps, edges);
  if (edge_vertices >= kCentreFlag)
    return numerical_error(fmt::format("surface: {} marching-cubes vertices exceed 2^31", edge_vertices));

  McMesh out;
  out.mesh.vertices.resize(edge_vertices);
  out.cluster.resize(edge_vertices);

  // --- pass 1b: vertex positions and regularisation cells, in bit order -------------------------------------------
  place_crossed_vertices(field, kSteps, edges, out.mesh.vertices, out.cluster);

  // --- pass 2: triangles per block, vertices looked up in the owning block --------------------------------------
  std::vector<std::vector<std::array<Index, 3>>> tris(field.keys.size());
  std::vector<std::vector<Vec3f>> centres(field.keys.size());
  std::atomic<bool> broken{false};
  for_each_block(nb, [&](std::int64_t b) {
    triangulate_block(field, table, b, edges, up, out.mesh.vertices, tris[std::size_t(b)], centres[std::size_t(b)], broken);
  });
  if (broken) return numerical_error("surface: marching cubes found an edge missing from its block (internal error)");

  // --- concatenate in block order; centres after all edge vertices ---------------------------------------------------
  FF_CHECK(concatenate_blocks(tris, centres, edge_vertices, out));
  return out;
}

}  // namespace ff::surface
