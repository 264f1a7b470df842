#pragma once
// Exact geometric queries on one target mesh (docs/ARCHITECTURE.md): inside/outside by the generalized
// winding number, closest surface point and signed distance. Built once per target, then queried by the
// samplers millions of times, from many threads.
//
// Inside/outside. The generalized winding number w(p) = (1/4π) Σ_t Ω_t(p) (Jacobson, Kavan, Sorkine-Hornung
// 2013, "Robust Inside-Outside Segmentation using Generalized Winding Numbers") is 1 inside and 0 outside a
// closed, outward-oriented mesh, and degrades gracefully on holes, overlaps and non-manifold parts: a small
// hole lowers w only near the hole, overlapping closed parts add up (w ≥ 1 in the overlap, so "w > 0.5" is
// their union). It is evaluated hierarchically (Barill, Dickson, Schmidt, Levin, Jacobson 2018, "Fast Winding
// Numbers for Soups and Clouds"): a BVH over the triangles, each node carrying the Taylor expansion (to second
// order) of its triangles' contribution about its area-weighted centroid p̃; a node whose bounding sphere about
// p̃ (radius r) is far enough (|p − p̃| > β·r, β = 2) is evaluated by its expansion, nearer leaves exactly by
// the solid angle of each triangle (Van Oosterom & Strackee 1983). Cost: O(log n) per query in practice.
//
// Orientation. The winding number needs outward normals, and flipped ones are common in real files, so build()
// first makes the winding consistent across every manifold edge (an edge with exactly two triangles), which
// splits the mesh into patches (the majority winding of a patch wins), and then flips each patch whose signed
// volume, taken about the box centre of its vertex-connected component, is negative: for a closed patch the
// origin does not matter, for an open one (a cap, a sphere with a hole) that centre is the natural inside.
// Open and non-manifold meshes are kept as they are otherwise.
//
// Closed meshes (closed(): every edge walked as often each way, seams welded by position) are asked inside() by a
// ray instead: the signed count of its crossings is their winding number exactly, and one ray through the BVH's
// boxes is ~10× cheaper than the hierarchical sum, which a point among many overlapping parts must open deeply.
//
// Closest point: the same BVH (node boxes), nearest child first, exact point-triangle distance in the leaves.
//
// Determinism: build() is serial; every query is a pure function of the point, so the parallel batch queries
// give the same bits for any thread count.
#include "core/error.h"
#include "core/types.h"
#include "io/triangle_mesh.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace ff::sampling {

/// What build() found and changed (logged by the app).
struct MeshFieldStats {
  std::size_t triangles = 0;             ///< triangles kept
  std::size_t dropped_degenerate = 0;    ///< zero-area triangles dropped (they add nothing to any query)
  std::size_t components = 0;            ///< vertex-connected components
  std::size_t patches = 0;               ///< triangles joined by manifold edges (one per closed part)
  std::size_t flipped_patches = 0;       ///< patches reversed because their signed volume was negative
  std::size_t reoriented_triangles = 0;  ///< reversed to agree with the majority of their patch
  std::size_t boundary_edges = 0;        ///< edges with one triangle (holes, open borders)
  std::size_t nonmanifold_edges = 0;     ///< edges with more than two triangles
  double hole_area = 0.0;                ///< m², Σ over boundary loops of the area of their spanning vector
};

class MeshField {
 public:
  /// Accuracy of the far-field expansion: a BVH node is expanded when |p − p̃| > kBeta · r (Barill et al.).
  static constexpr float kBeta = 2.0f;
  /// A mesh whose holes span more than this fraction of its area does not enclose a volume.
  static constexpr double kMaxHoleFraction = 0.25;

  /// Builds the field of `mesh` (metres). Drops zero-area triangles; orients the rest (see the file comment).
  /// Errors (Input, one line): no vertices, no triangles, a triangle index out of range, a non-finite vertex,
  /// zero total area. Cost: O(n log n) time, ~190 bytes per triangle (bytes()).
  static Result<MeshField> build(const io::TriangleMesh& mesh);

  Aabb bounds() const { return bounds_; }
  /// Surface area, m².
  double area() const { return area_; }
  /// Enclosed volume estimate, m³: Σ over patches of their (oriented, so positive) signed volume, taken about
  /// their component's box centre. Exact for disjoint closed parts; overlaps count twice.
  double volume() const { return volume_; }
  /// False for an open sheet, a cap, or a zero-volume mesh: holes spanning more than kMaxHoleFraction of the
  /// area, or a volume below 1e-6·area^1.5. Closed meshes and ones with small holes enclose a volume.
  bool encloses_volume() const { return encloses_volume_; }
  const MeshFieldStats& stats() const { return stats_; }
  /// True when the kept, oriented triangles walk every edge as often one way as the other (vertices welded by
  /// exact position): the surface then bounds its volume exactly (overlapping and nested closed parts included),
  /// its winding number is an integer off the surface, and inside() counts it along a ray (ray_winding). An open
  /// or holed mesh is not closed and keeps the generalized winding number. moved() keeps it only while the
  /// vertices welded at build() still coincide.
  bool closed() const { return closed_; }

  /// The same mesh moved: `vertices` replace the positions of the mesh given to build() (same count, same order), the
  /// triangles, their orientation and the BVH's tree are kept, and the node boxes, normals and far-field expansions
  /// are refitted. Every query stays exact (a looser tree costs time, not accuracy); ~6× cheaper than build() on the
  /// 6.8k-triangle demo character (what a skinned target's posed metrics do every frame). area() and bounds() are
  /// the moved mesh's; volume(), encloses_volume() and stats() stay build()'s. A triangle the move collapses to zero
  /// area is kept and adds nothing. `far_field` false skips the far-field expansions (most of the refit's time) when
  /// the moved mesh is closed(), for callers that ask inside() and closest() only: there inside() counts rays, and
  /// winding_number() falls back to the exact O(n) sum (do not hand such a field to bulk winding-number users such
  /// as SdfGrid::build). Errors (Input, one line): a different vertex count, a
  /// non-finite vertex.
  Result<MeshField> moved(std::span<const Vec3f> vertices, bool far_field = true) const;

  /// Generalized winding number at `p` (1 inside, 0 outside a closed mesh; ~0.5 on the surface).
  float winding_number(const Vec3f& p) const;
  /// Whether p is inside: ray_winding(p) > 0 on a closed() mesh, where a ray answers; else winding_number(p) > 0.5.
  /// Both agree off the surface of a closed mesh; the ray is exact, and 10× the rate of the hierarchical sum on the
  /// bunny, 13× on 16 overlapping parts such as a skinned character's (bench_mesh_field, BM_Inside*).
  bool inside(const Vec3f& p) const;
  /// The winding number of a closed() mesh at p, exactly (for the mesh's float vertices; p within about an ulp of
  /// the surface may read either side): the signed count of the surface's crossings along an axis-aligned ray from
  /// p (+1 where the ray exits, the normal along it; −1 where it enters), the shortest axis direction out of the
  /// bounds first. A crossing is decided by the signs of the three edge functions of
  /// the triangle projected along the ray, each taken from the edge's two float vertices in double, so the two
  /// triangles of an edge see exactly opposite values and a ray near an edge counts exactly one of them. A ray
  /// that meets an edge, a vertex, a face edge-on or the surface at p itself (a zero edge function or hit
  /// distance) is cast along the next axis direction; nullopt when all six do so (p on the surface) or the mesh is not closed().
  std::optional<int> ray_winding(const Vec3f& p) const;

  /// The closest surface point, the unit normal of its triangle (outward after orientation), the distance and
  /// the triangle's index in the mesh given to build().
  struct Closest {
    Vec3f point;
    Vec3f normal;
    float distance;
    Index triangle;
  };
  Closest closest(const Vec3f& p) const;
  /// As closest(p), but only looks within `max_distance` (metres): returns triangle = kInvalidIndex and
  /// distance = +inf when no surface point is that close. Much cheaper for far points.
  Closest closest(const Vec3f& p, float max_distance) const;
  /// As closest(p), warm-started from `hint`, the triangle a nearby point found (Closest::triangle): the same
  /// distance, found faster when the hint is good (a particle's previous answer). Any hint is safe.
  Closest closest_near(const Vec3f& p, Index hint) const;
  /// Distance to the surface, m.
  float unsigned_distance(const Vec3f& p) const { return closest(p).distance; }
  /// Negative inside, positive outside; |value| = distance to the surface (m).
  float signed_distance(const Vec3f& p) const;

  /// Batch versions (OpenMP): out[i] = inside(p[i]) ? 1 : 0, resp. signed_distance(p[i]). Spans of equal size.
  void inside(std::span<const Vec3f> p, std::span<std::uint8_t> out) const;
  void winding_number(std::span<const Vec3f> p, std::span<float> out) const;
  void signed_distance(std::span<const Vec3f> p, std::span<float> out) const;

  /// Winding number by summing every triangle's solid angle in double: the O(n) reference for tests.
  double winding_number_exact(const Vec3f& p) const;

  /// The kept triangles, oriented, in the field's internal (BVH) order, for stages that rasterise the surface
  /// (SdfGrid); source_triangle(k) is the index of triangles()[k] in the mesh given to build().
  struct Triangle {
    Vec3f a, b, c;
  };
  std::span<const Triangle> triangles() const { return tris_; }
  Index source_triangle(Index k) const { return source_[k]; }
  std::size_t triangle_count() const { return tris_.size(); }
  std::size_t bytes() const;

 private:
  // BVH node. Leaf: count > 0 triangles from `first` (in BVH order). Inner: count = 0, children first, first+1.
  struct Node {
    Vec3f lo{Vec3f::Zero()};
    Index first = 0;
    Vec3f hi{Vec3f::Zero()};
    Index count = 0;
  };
  // Far-field expansion of a node's triangles about their area-weighted centroid (see mesh_field.cpp).
  struct Expansion {
    Vec3f center;             // p̃
    float radius2;            // (β·r)²: expand when |p − p̃|² exceeds it
    Vec3f n;                  // Σ a_t n_t (vector area)
    float trace_m;            // tr M
    std::array<float, 9> m;   // M_ij = Σ a_t n_ti (c_t − p̃)_j, row-major
    Vec3f v;                  // 2u + τ of the Hessian term (u_k = Σ_i T_iik, τ_i = Σ_j T_ijj)
    std::array<float, 18> t;  // T_i (symmetric 3×3, xx xy xz yy yz zz) for i = x, y, z
  };
  MeshField() = default;
  void build_bvh(std::vector<Triangle> tris, std::vector<Index> source, std::vector<std::array<Index, 3>> corners);
  void build_node(Index self, std::vector<Index>& order, Index begin, Index end, const std::vector<Triangle>& all,
                  std::vector<std::array<Index, 2>>& range, int depth);
  void build_expansions(const std::vector<std::array<Index, 2>>& range);
  static float far_solid_angle(const Expansion& e, const Vec3f& r, float l2);
  Closest closest_bounded(const Vec3f& p, float best2, Index hint) const;

  Aabb bounds_;
  double area_ = 0.0;
  double volume_ = 0.0;
  bool encloses_volume_ = false;
  MeshFieldStats stats_;
  std::vector<Node> nodes_;           // nodes_[0] is the root
  std::vector<Expansion> expansion_;  // per node
  std::vector<Triangle> tris_;        // BVH order, oriented
  std::vector<Vec3f> normal_;         // per triangle (BVH order), unit
  std::vector<Index> source_;         // per triangle (BVH order): index in the input mesh
  std::vector<Index> bvh_index_;      // per input triangle: its BVH-order index (kInvalidIndex if dropped)
  std::vector<std::array<Index, 3>> corners_;  // per triangle (BVH order): its vertices in the input mesh, oriented
  std::size_t vertex_count_ = 0;               // of the input mesh (moved() must be given as many)
  bool closed_ = false;                        // see closed()
  // closed_ only: per input vertex, the first vertex at its exact position (shared by the moved copies)
  std::shared_ptr<const std::vector<Index>> weld_;
};

/// The point of triangle (a, b, c) closest to p (exact up to float rounding; safe on needle triangles).
Vec3f closest_point_on_triangle(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c);

/// Inside test by ray parity: an odd number of crossings of a ray from `p` means inside. A ray that passes
/// within a relative 1e-9 of an edge, a vertex or the triangle's plane (grazing, or `p` on the surface) is
/// re-cast in the next of a fixed list of directions; after 16 grazing rays p is taken to be on the surface
/// (false).
/// Correct only for closed meshes without self-intersections; it is the tests' oracle. Cost O(triangles).
bool inside_by_ray_parity(const io::TriangleMesh& mesh, const Vec3f& p);
/// The parity along one direction of that list (k in [0, 16)), or -1 when the ray grazes.
int ray_parity(const io::TriangleMesh& mesh, const Vec3f& p, int k);

}  // namespace ff::sampling
