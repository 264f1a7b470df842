#pragma once
// Marching-cubes case table (METHOD.md §c.8), generated at first use rather than typed in: for every inside
// mask of the 8 corners and every choice of the ambiguous faces, the iso-curve on each cube face is a set of
// segments decided by that face alone (the asymptotic decider at run time), the segments are chained into
// closed loops around the inside part of the cube's surface, and each loop is triangulated.
//
// Why generated. Lorensen & Cline's 15 hand-made cases disagree on ambiguous faces, which leaves holes;
// deciding every face from its own four values makes two cubes that share a face draw the same segments,
// so the mesh is watertight by construction. Triangulation: a loop is fanned from a vertex none of whose
// chords joins two vertices on one cube face (such a chord could be drawn by the neighbouring cube too, giving
// an edge with four triangles); a loop with no such vertex is fanned around an added centre vertex. Every
// chord then lies strictly inside its cube, so every mesh edge has exactly two triangles and every vertex's
// triangles form one fan (vertices sit on grid edges: the four cubes around the edge close the fan).
//
// Conventions. Corner c ∈ [0, 8) sits at (c & 1, c >> 1 & 1, c >> 2 & 1). Edge e ∈ [0, 12) runs along axis
// a = e / 4; its other two axes p < q carry the bits (e & 1, e >> 1 & 1). Face f ∈ [0, 6) is axis f / 2 at
// side f & 1. Triangles are wound counter-clockwise seen from outside (the side where φ < iso).
#include <array>
#include <cstdint>
#include <vector>

namespace ff::surface {

/// One cube's triangles for one inside mask and one choice at its ambiguous faces.
struct CubeTriangulation {
  std::uint8_t triangle_count = 0;
  std::uint8_t centre_count = 0;  ///< loops fanned around an added centre vertex (rare)
  /// Vertex refs: 0–11 the vertex on that cube edge, 12 + k the centre of centre loop k.
  std::array<std::array<std::uint8_t, 3>, 12> triangles{};
  /// For centre k: bit e set when edge e's vertex is on its loop (the centre is their mean).
  std::array<std::uint16_t, 4> centre_edges{};
};

/// The lower and upper corner of each edge.
struct CubeEdge {
  std::uint8_t axis, c0, c1;
};

class McTable {
 public:
  /// The table, built once (656 entries: one per mask and choice at its ambiguous faces; 140 of them fan a loop
  /// around a centre) and immutable afterwards; safe to share between threads.
  static const McTable& get();

  static constexpr CubeEdge edge(int e) {
    const int a = e / 4;
    const int p = a == 0 ? 1 : 0, q = a == 2 ? 1 : 2;
    const int c0 = ((e & 1) << p) | (((e >> 1) & 1) << q);
    return {std::uint8_t(a), std::uint8_t(c0), std::uint8_t(c0 | (1 << a))};
  }

  /// Faces of mask `m` with four crossing edges (an inside diagonal and an outside one), in increasing order.
  int ambiguous_count(int m) const { return ambiguous_count_[m]; }
  int ambiguous_face(int m, int j) const { return ambiguous_faces_[m][j]; }

  /// Triangulation of mask `m` (bit c = corner c inside) with `centres` bit j set when the centre of the j-th
  /// ambiguous face of m is inside (see face_centre_inside()).
  const CubeTriangulation& cube(int m, int centres) const { return cases_[base_[m] + centres]; }

  std::size_t size() const { return cases_.size(); }

 private:
  McTable();
  std::array<std::uint8_t, 256> ambiguous_count_{};
  std::array<std::array<std::uint8_t, 6>, 256> ambiguous_faces_{};
  std::array<std::uint32_t, 256> base_{};
  std::vector<CubeTriangulation> cases_;
};

/// Asymptotic decider: is the saddle of the bilinear interpolant over a face inside (value > 0)? `v00 … v11`
/// are φ − iso at the face's corners, indexed by its two in-plane axes (lower axis first). Both cubes that
/// share the face pass the same values in the same order, so they decide the same way.
inline bool face_centre_inside(float v00, float v10, float v01, float v11) {
  const float num = v00 * v11 - v10 * v01;
  const float den = v00 + v11 - v10 - v01;
  return den > 0.0f ? num > 0.0f : num < 0.0f;
}

}  // namespace ff::surface
