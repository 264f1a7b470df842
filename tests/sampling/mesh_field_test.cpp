// Inside/outside and signed distance of target meshes (sampling/mesh_field, sampling/sdf_grid), tested as
// properties over a family of shapes against independent oracles: ray parity on closed meshes, the O(n) winding
// number sum, analytic spheres, brute-force closest points; then holes, overlaps, flipped parts, open sheets,
// the Stanford bunny (open at the bottom), the grid against exact distances, and thread-count independence.
#include "io/load_mesh.h"
#include "sampling/mesh_field.h"
#include "sampling/sdf_grid.h"
#include "support/shapes.h"
#include "support/test_support.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <omp.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

// One source, two scales: sampling_test (label fast, also run under ASan) uses small meshes and few probes;
// sampling_slow_test (label slow, release only) is built with FF_SAMPLING_FULL_SIZE and checks the acceptance
// sizes (≥ 2000 probes per shape, the 81920-triangle sphere, fine grids).
#ifdef FF_SAMPLING_FULL_SIZE
#define FF_SUITE(name) name##Full
constexpr bool kFull = true;
#else
#define FF_SUITE(name) name
constexpr bool kFull = false;
#endif

namespace ff::sampling {
namespace {

using io::TriangleMesh;

constexpr std::size_t kProbes = kFull ? 2000 : 300;  // random points per shape and property
constexpr int kSegments = kFull ? 48 : 24;           // resolution of the procedural shapes
constexpr float kCoarse = kFull ? 1.0f : 2.0f;       // grid spacings are multiplied by this

TriangleMesh test_vase() { return kFull ? test::vase() : test::vase(1.0f, 0.35f, 0.05f, 32, 16); }

struct NamedMesh {
  std::string name;
  TriangleMesh mesh;
};

// Closed, watertight, outward shapes: ray parity is an exact oracle for them.
std::vector<NamedMesh> closed_shapes() {
  return {{"sphere", test::uv_sphere(1.0f, kSegments)},
          {"box", test::box(Vec3f(0.5f, 0.3f, 0.8f), 3)},
          {"torus", test::torus(1.0f, 0.3f, kSegments, kSegments / 2)},
          {"vase", test_vase()}};
}

MeshField field_of(const TriangleMesh& mesh) {
  auto r = MeshField::build(mesh);
  if (!r) {  // every caller passes a valid mesh: stop loudly rather than touch an empty Result
    std::fprintf(stderr, "MeshField::build failed: %s\n", r.error().message.c_str());
    std::abort();
  }
  return std::move(r).value();
}

/// n uniform points in the mesh's box grown by `grow` × its size on every side.
std::vector<Vec3f> probes(const TriangleMesh& mesh, std::size_t n, unsigned seed, float grow = 0.1f) {
  const Aabb b = mesh.bounds();
  const Vec3f lo = b.min - grow * b.size(), hi = b.max + grow * b.size();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Vec3f> p(n);
  for (auto& x : p) x = lo + Vec3f(u(rng), u(rng), u(rng)).cwiseProduct(hi - lo);
  return p;
}

std::string str(const Vec3f& p) { return fmt::format("({}, {}, {})", p.x(), p.y(), p.z()); }

// Independent closest-point oracle, in double: the projection onto the plane when it falls inside the triangle,
// else the nearest of the three edges.
double distance_to_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d n = (b - a).cross(c - a);
  const Vec3d q = p - n * (p - a).dot(n) / n.squaredNorm();
  const bool in =
      (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 && (a - c).cross(q - c).dot(n) >= 0;
  if (in) return (p - q).norm();
  auto seg = [&](const Vec3d& x, const Vec3d& y) {
    const double t = std::clamp((p - x).dot(y - x) / (y - x).squaredNorm(), 0.0, 1.0);
    return (p - (x + t * (y - x))).norm();
  };
  return std::min({seg(a, b), seg(b, c), seg(c, a)});
}

double brute_distance(const TriangleMesh& m, const Vec3f& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles)
    best = std::min(best, distance_to_triangle(p.cast<double>(), m.vertices[t[0]].cast<double>(),
                                               m.vertices[t[1]].cast<double>(), m.vertices[t[2]].cast<double>()));
  return best;
}

TriangleMesh bunny_or_fail() {
  auto r = test::stanford_bunny();
  if (!r) {
    ADD_FAILURE() << r.error().message;
    return {};
  }
  return std::move(r).value();
}

// ---- build ---------------------------------------------------------------------------------------------

void expect_input_error(const TriangleMesh& m, const std::string& reason) {
  const auto r = MeshField::build(m);
  ASSERT_FALSE(r.has_value()) << "built, expected: " << reason;
  EXPECT_EQ(r.error().kind, Error::Kind::Input);
  EXPECT_NE(r.error().message.find(reason), std::string::npos) << r.error().message;
  EXPECT_EQ(r.error().message.find('\n'), std::string::npos) << r.error().message;
}

TEST(FF_SUITE(MeshField), RejectsUnusableMeshesWithOneLineReason) {
  expect_input_error({}, "no vertices");
  TriangleMesh m = test::box(Vec3f::Ones());
  TriangleMesh no_tris = m;
  no_tris.triangles.clear();
  expect_input_error(no_tris, "no triangles");
  TriangleMesh nan = m;
  nan.vertices[3].y() = std::numeric_limits<float>::quiet_NaN();
  expect_input_error(nan, "vertex 3 is not finite");
  TriangleMesh bad_index = m;
  bad_index.triangles[5][1] = 99;
  expect_input_error(bad_index, "references vertex 99");
  TriangleMesh flat;
  flat.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.triangles = {{0, 1, 2}, {0, 0, 1}};
  expect_input_error(flat, "zero area");
}

TEST(FF_SUITE(MeshField), DropsDegenerateTrianglesAndReportsAreaAndVolume) {
  TriangleMesh m = test::box(Vec3f(0.5f, 1.0f, 1.5f));
  m.triangles.push_back({0, 0, 1});
  const MeshField f = field_of(m);
  EXPECT_EQ(f.stats().dropped_degenerate, 1u);
  EXPECT_EQ(f.stats().triangles, 12u);
  EXPECT_NEAR(f.area(), 2.0 * (1 * 2 + 2 * 3 + 1 * 3), 1e-5);
  EXPECT_NEAR(f.volume(), 6.0, 1e-5);
  EXPECT_EQ(f.stats().boundary_edges, 0u);
  EXPECT_EQ(f.stats().flipped_patches, 0u);
}

// ---- inside/outside ------------------------------------------------------------------------------------

TEST(FF_SUITE(MeshField), InsideAgreesWithRayParityOnClosedShapes) {
  for (const auto& [name, mesh] : closed_shapes()) {
    const MeshField f = field_of(mesh);
    const auto p = probes(mesh, kProbes, 7);
    std::size_t disagree = 0, in = 0;
    for (const auto& x : p) {
      const bool oracle = inside_by_ray_parity(mesh, x);
      in += oracle;
      if (f.inside(x) != oracle && disagree++ < 3)
        ADD_FAILURE() << name << ": at " << str(x) << " parity says " << oracle << ", w = " << f.winding_number(x);
    }
    EXPECT_EQ(disagree, 0u) << name;
    // The oracle itself must see the shape: the inside fraction of the probe box matches the mesh volume.
    const Vec3f box = 1.2f * mesh.bounds().size();
    const double expected = io::signed_volume(mesh) / (double(box.x()) * box.y() * box.z());
    const double sigma = std::sqrt(expected * (1 - expected) / double(p.size()));
    EXPECT_NEAR(double(in) / double(p.size()), expected, 4 * sigma + 1e-3) << name;
  }
}

TEST(FF_SUITE(MeshField), HierarchicalWindingNumberMatchesExactSum) {
  auto shapes = closed_shapes();
  shapes.push_back({"sphere with hole", test::sphere_with_hole(6)});
  shapes.push_back({"sheet", test::plane_sheet(10)});
  shapes.push_back({"bunny", bunny_or_fail()});
  for (const auto& [name, mesh] : shapes) {
    if (mesh.triangles.empty()) continue;  // the bunny's absence already failed
    const MeshField f = field_of(mesh);
    auto p = probes(mesh, kProbes / 4, 11);
    // Also points just off the surface, where near-field and far-field clusters meet.
    std::mt19937 rng(3);
    std::normal_distribution<float> jitter(0.0f, 0.01f * mesh.bounds().size().norm());
    for (std::size_t i = 0; i < mesh.vertices.size(); i += mesh.vertices.size() / 100 + 1)
      p.push_back(mesh.vertices[i] + Vec3f(jitter(rng), jitter(rng), jitter(rng)));
    double worst = 0.0;
    for (const auto& x : p) worst = std::max(worst, std::abs(double(f.winding_number(x)) - f.winding_number_exact(x)));
    EXPECT_LT(worst, 0.02) << name;  // β = 2; without the second-order term it is 0.035–0.06
  }
}

// moved(): a skinned target's posed metrics move the bind field's vertices instead of building it again. Bent and
// twisted (a non-rigid move), every shape must answer as a field built from the moved mesh does: the same closest
// distance (exact in both, up to rounding), inside where ray parity says inside (closed shapes), winding numbers within the
// expansion's accuracy; wrong sizes and non-finite vertices are one-line Input errors.
TEST(FF_SUITE(MeshField), MovedFieldAnswersAsOneBuiltFromTheMovedMesh) {
  auto shapes = closed_shapes();
  shapes.push_back({"sheet", test::plane_sheet(10)});
  shapes.push_back({"overlapping spheres", test::two_overlapping_spheres()});
  for (const auto& [name, mesh] : shapes) {
    const MeshField bind = field_of(mesh);
    const Aabb b = mesh.bounds();
    TriangleMesh bent = mesh;
    int a = 0;  // along the longest axis a: twist about it by up to 0.6 rad, bend by t², stretch by 20 %
    b.size().maxCoeff(&a);
    for (Vec3f& v : bent.vertices) {
      const float t = (v[a] - b.min[a]) / b.size()[a];
      const Eigen::AngleAxisf twist(0.6f * t, Vec3f::Unit(a));
      v = twist * v;
      v[(a + 1) % 3] += 0.3f * b.size().norm() * t * t;
      v[(a + 2) % 3] *= 1.2f;
    }
    auto moved = bind.moved(bent.vertices);
    ASSERT_TRUE(moved.has_value()) << name << ": " << moved.error().message;
    const MeshField built = field_of(bent);
    EXPECT_NEAR(moved->area(), built.area(), 1e-6 * built.area()) << name;
    EXPECT_TRUE(moved->bounds().min.isApprox(built.bounds().min) && moved->bounds().max.isApprox(built.bounds().max))
        << name;
    const auto p = probes(bent, kProbes, 13);
    std::size_t parity_disagree = 0;
    double worst_w = 0.0;
    for (const auto& x : p) {
      // Equal up to rounding (a triangle's corners may be taken in another order, the sheet's orientation flipped).
      EXPECT_NEAR(moved->closest(x).distance, built.closest(x).distance, 1e-6f * b.size().norm()) << name << " at " << str(x);
      worst_w = std::max(worst_w, std::abs(double(moved->winding_number(x)) - moved->winding_number_exact(x)));
      if (name != "sheet" && name != "overlapping spheres")
        parity_disagree += moved->inside(x) != inside_by_ray_parity(bent, x);
    }
    EXPECT_LT(worst_w, 0.02) << name;
    EXPECT_EQ(parity_disagree, 0u) << name;
  }
  const MeshField f = field_of(test::uv_sphere(1.0f, 8));
  const auto few = f.moved(std::vector<Vec3f>(3, Vec3f::Zero()));
  ASSERT_FALSE(few.has_value());
  EXPECT_EQ(few.error().kind, Error::Kind::Input);
  EXPECT_NE(few.error().message.find("vertices"), std::string::npos) << few.error().message;
  auto nan = test::uv_sphere(1.0f, 8).vertices;
  nan[5].y() = std::numeric_limits<float>::quiet_NaN();
  const auto bad = f.moved(nan);
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().kind, Error::Kind::Input);
  EXPECT_NE(bad.error().message.find("vertex 5"), std::string::npos) << bad.error().message;
}

TEST(FF_SUITE(MeshField), SphereWithHoleStillReadsAsSolid) {
  const TriangleMesh mesh = test::sphere_with_hole(6, 1.0f, kSegments);
  const MeshField f = field_of(mesh);
  EXPECT_GT(f.stats().boundary_edges, 0u);
  EXPECT_TRUE(f.encloses_volume());
  std::size_t interior = 0, interior_in = 0, exterior = 0, exterior_in = 0;
  for (const auto& x : probes(mesh, 2 * kProbes, 5)) {
    const float r = x.norm();
    if (r < 0.95f) interior++, interior_in += f.inside(x);
    if (r > 1.05f) exterior++, exterior_in += f.inside(x);
  }
  EXPECT_GE(double(interior_in), 0.99 * double(interior));
  EXPECT_LE(double(exterior_in), 0.01 * double(exterior));
  // The hole's own neighbourhood: just inside it is still inside, just outside it outside.
  EXPECT_TRUE(f.inside(Vec3f(0.9f, 0, 0)));
  EXPECT_FALSE(f.inside(Vec3f(1.1f, 0, 0)));
}

TEST(FF_SUITE(MeshField), OverlappingClosedPartsReadAsTheirUnion) {
  const TriangleMesh a = test::translate(test::uv_sphere(0.5f, kSegments), Vec3f(-0.25f, 0, 0));
  const TriangleMesh b = test::translate(test::uv_sphere(0.5f, kSegments), Vec3f(0.25f, 0, 0));
  const TriangleMesh both = test::merge(a, b);
  const MeshField f = field_of(both);
  EXPECT_EQ(f.stats().components, 2u);
  std::size_t disagree = 0, overlap = 0;
  for (const auto& x : probes(both, kProbes, 9)) {
    const bool in_a = inside_by_ray_parity(a, x), in_b = inside_by_ray_parity(b, x);
    overlap += in_a && in_b;
    if (f.inside(x) != (in_a || in_b) && disagree++ < 3)
      ADD_FAILURE() << "at " << str(x) << ", w = " << f.winding_number(x);
  }
  EXPECT_EQ(disagree, 0u);
  EXPECT_GT(overlap, kProbes / 40);  // the case parity of the merged mesh gets wrong is really exercised
}

// Parts that touch, as CAD exports them (an open-top bin of five slabs sharing their corner edges): a loader welds
// their coincident vertices, the edges where three or four faces meet split the slabs into open patches, and the
// bin's inner faces face the centre of the whole. The volume rule alone turned one of them round and filled the
// bottom of the bin (the sampler put 31 % of its samples there); what the patch sees out of keeps it as it is.
TEST(FF_SUITE(MeshField), PartsWeldedWhereTheyTouchKeepTheirInnerFaces) {
  const TriangleMesh bin = test::open_box(Vec3f(0.5f, 0.35f, 0.4f), 0.037f);
  const auto dir = test::temp_dir("welded_bin");
  test::write_obj(dir / "bin.obj", bin);
  auto loaded = io::load_mesh(dir / "bin.obj");
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  ASSERT_LT(loaded->vertices.size(), bin.vertices.size()) << "the loader welds the parts' shared corners";
  const MeshField welded = field_of(*loaded), parts = field_of(bin);
  EXPECT_EQ(welded.stats().flipped_patches, 0u);
  EXPECT_TRUE(welded.closed()) << "every edge walked as often each way once no patch is turned round";
  EXPECT_NEAR(welded.volume(), parts.volume(), 1e-3 * parts.volume()) << "the slabs' volume, not the box's";
  for (const float y : {-0.3f, -0.25f, -0.2f, -0.1f, 0.0f, 0.2f})
    EXPECT_FALSE(welded.inside(Vec3f(0.01f, y, 0.02f))) << "in the bin at y = " << y << ", w = " << welded.winding_number(Vec3f(0.01f, y, 0.02f));
  std::size_t disagree = 0;
  for (const auto& x : probes(bin, kProbes, 5))
    if (welded.inside(x) != parts.inside(x) && disagree++ < 3) ADD_FAILURE() << "at " << str(x);
  EXPECT_LE(disagree, kProbes / 200) << "the winding number of a mesh with T-junctions is not exact at its seams";
}

// ray_winding(): on a closed mesh the signed count of crossings along a ray is the winding number, exactly. Checked
// against the O(n) solid-angle sum (an integer off the surface) on closed shapes, on overlapping parts (2 in the
// overlap), on a triangle soup closed only through its welded seams, and on a box partly turned inside out by moving its
// vertices (moved() keeps the orientation, so the turned part reads −1, as linear blend skinning's folds do). Open meshes and
// seams a move splits are not closed, and a point whose six rays all graze an edge falls back to the winding number.
TEST(FF_SUITE(MeshField), RayWindingIsTheExactWindingNumberOfClosedMeshes) {
  auto soup = [](const TriangleMesh& m) {  // every triangle its own three vertices: closed by position only
    TriangleMesh s;
    for (const auto& t : m.triangles) {
      const auto base = static_cast<Index>(s.vertices.size());
      for (const Index v : t) s.vertices.push_back(m.vertices[v]);
      s.triangles.push_back({base, base + 1, base + 2});
    }
    return s;
  };
  auto check = [](const MeshField& f, const TriangleMesh& mesh, const std::string& name, std::set<int>* seen) {
    ASSERT_TRUE(f.closed()) << name;
    std::size_t answered = 0, compared = 0;
    for (const auto& x : probes(mesh, kProbes, 17)) {
      const double w = f.winding_number_exact(x);
      if (std::abs(w - std::round(w)) > 1e-3) continue;  // within rounding of the surface
      ++compared;
      const std::optional<int> r = f.ray_winding(x);
      if (!r) continue;
      ++answered;
      EXPECT_EQ(*r, int(std::round(w))) << name << " at " << str(x);
      EXPECT_EQ(f.inside(x), *r > 0) << name << " at " << str(x);
      if (seen) seen->insert(*r);
    }
    EXPECT_GT(compared, kProbes * 9 / 10) << name;
    EXPECT_EQ(answered, compared) << name;  // random points never graze
  };
  auto shapes = closed_shapes();
  shapes.push_back({"box soup", soup(test::box(Vec3f(0.5f, 0.3f, 0.8f), 3))});
  for (const auto& [name, mesh] : shapes) check(field_of(mesh), mesh, name, nullptr);
  std::set<int> overlap;
  const TriangleMesh spheres = test::two_overlapping_spheres();
  check(field_of(spheres), spheres, "overlapping spheres", &overlap);
  EXPECT_TRUE(overlap.count(2)) << "the overlap was not probed";

  // Folded: the part beyond x = 0.2 is mirrored back and lifted clear of the box, turned inside out (winding −1).
  const TriangleMesh box = test::box(Vec3f(0.5f, 0.3f, 0.8f), 6);
  TriangleMesh folded = box;
  for (Vec3f& v : folded.vertices)
    if (v.x() > 0.2f) v.x() = 0.4f - v.x(), v.y() += 0.8f;
  auto moved = field_of(box).moved(folded.vertices, /*far_field=*/false);
  ASSERT_TRUE(moved.has_value()) << moved.error().message;
  std::set<int> fold;
  check(*moved, folded, "folded box", &fold);
  EXPECT_TRUE(fold.count(-1)) << "no probe in the fold";
  // Without the far field the winding number is the exact sum.
  for (const auto& x : probes(folded, 20, 5))
    EXPECT_NEAR(moved->winding_number(x), moved->winding_number_exact(x), 1e-5) << str(x);

  // Not closed: an open sheet, a holed sphere, a soup whose seam a move opens.
  EXPECT_FALSE(field_of(test::plane_sheet(4)).closed());
  EXPECT_FALSE(field_of(test::sphere_with_hole(2, 1.0f, kSegments)).closed());
  EXPECT_FALSE(field_of(test::plane_sheet(4)).ray_winding(Vec3f::Zero()).has_value());
  const TriangleMesh s = soup(test::box(Vec3f(0.5f, 0.5f, 0.5f), 1));
  const MeshField sf = field_of(s);
  ASSERT_TRUE(sf.closed());
  TriangleMesh cracked = s;
  cracked.vertices[0].x() += 1e-4f;
  auto opened = sf.moved(cracked.vertices, /*far_field=*/false);
  ASSERT_TRUE(opened.has_value());
  EXPECT_FALSE(opened->closed());
  EXPECT_FALSE(opened->ray_winding(Vec3f(0.1f, 0.2f, 0.3f)).has_value());
  EXPECT_TRUE(opened->inside(Vec3f(0.1f, 0.2f, 0.3f)));  // by the (far-field) winding number

  // Grazing: the centre of a box whose faces' diagonals cross there meets an edge along all six axis rays.
  const MeshField cube = field_of(test::box(Vec3f(0.5f, 0.5f, 0.5f), 1));
  EXPECT_FALSE(cube.ray_winding(Vec3f::Zero()).has_value());
  EXPECT_TRUE(cube.inside(Vec3f::Zero()));
  EXPECT_EQ(cube.ray_winding(Vec3f(0.1f, 0.2f, 0.3f)), std::optional<int>(1));
  EXPECT_EQ(cube.ray_winding(Vec3f(0.7f, 0.2f, 0.3f)), std::optional<int>(0));
}

void expect_same_inside(const TriangleMesh& reference, const TriangleMesh& variant, const std::string& what) {
  const MeshField fr = field_of(reference), fv = field_of(variant);
  std::size_t disagree = 0;
  for (const auto& x : probes(reference, kProbes, 13))
    if (fr.inside(x) != fv.inside(x) && disagree++ < 3) ADD_FAILURE() << what << ": at " << str(x);
  EXPECT_EQ(disagree, 0u) << what;
  EXPECT_NEAR(fr.volume(), fv.volume(), 1e-6 * fr.volume()) << what;
}

TEST(FF_SUITE(MeshField), FlippedNormalsAreRepaired) {
  const TriangleMesh torus = test::torus(1.0f, 0.3f, kSegments, kSegments / 2);
  expect_same_inside(torus, test::flip(torus), "globally flipped torus");
  EXPECT_EQ(field_of(test::flip(torus)).stats().flipped_patches, 1u);

  const TriangleMesh sphere = test::uv_sphere(0.5f, kSegments);
  const TriangleMesh box = test::translate(test::box(Vec3f(0.3f, 0.4f, 0.5f), 2), Vec3f(1.2f, 0, 0));
  expect_same_inside(test::merge(sphere, box), test::merge(sphere, test::flip(box)), "one component flipped");

  // Scattered flipped triangles (a broken exporter): the winding is made consistent across manifold edges.
  TriangleMesh scattered = test_vase();
  std::mt19937 rng(17);
  std::size_t flipped = 0;
  for (auto& t : scattered.triangles)
    if (rng() % 10 < 3) std::swap(t[1], t[2]), ++flipped;
  expect_same_inside(test_vase(), scattered, "30 % of the vase's triangles flipped");
  EXPECT_EQ(field_of(scattered).stats().reoriented_triangles, flipped);
}

TEST(FF_SUITE(MeshField), OpenSheetsDoNotEncloseAVolume) {
  for (const auto& [name, mesh] :
       std::vector<NamedMesh>{{"sheet", test::plane_sheet(8)},
                              {"hemisphere", test::hemisphere(1.0f, 32)},
                              {"flipped hemisphere", test::flip(test::hemisphere(1.0f, 32))}}) {
    const MeshField f = field_of(mesh);
    EXPECT_FALSE(f.encloses_volume()) << name << ": hole area " << f.stats().hole_area << " of " << f.area();
    EXPECT_GT(f.stats().boundary_edges, 0u) << name;
  }
  for (const auto& [name, mesh] : closed_shapes()) EXPECT_TRUE(field_of(mesh).encloses_volume()) << name;
  EXPECT_TRUE(field_of(test::sphere_with_hole(6)).encloses_volume());
  EXPECT_TRUE(field_of(test::two_overlapping_spheres()).encloses_volume());
  // A sheet never reads as inside, whichever side is up.
  const MeshField sheet = field_of(test::plane_sheet(8));
  for (const auto& x : probes(test::plane_sheet(8), 200, 1, 0.5f)) EXPECT_FALSE(sheet.inside(x)) << str(x);
}

// ---- distances -----------------------------------------------------------------------------------------

TEST(FF_SUITE(MeshField), SignedDistanceOfASphereIsRadialDistance) {
  const float r = 2.0f;
  // Icosphere: 81920 triangles whose facets sag < 1e-4·R (full size), or 5120 that sag < 2e-3·R.
  const TriangleMesh mesh = test::sphere_mesh(r, kFull ? 6 : 4);
  const float tolerance = (kFull ? 1e-4f : 2e-3f) * r;
  const MeshField f = field_of(mesh);
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> u(-2.0f * r, 2.0f * r);
  std::vector<Vec3f> p(kProbes / 4);
  for (auto& x : p) x = Vec3f(u(rng), u(rng), u(rng));
  std::vector<float> batch(p.size());
  f.signed_distance(p, batch);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const float expected = p[i].norm() - r;
    EXPECT_NEAR(f.signed_distance(p[i]), expected, tolerance) << str(p[i]);
    EXPECT_EQ(batch[i], f.signed_distance(p[i]));
  }
}

TEST(FF_SUITE(MeshField), ClosestPointMatchesBruteForce) {
  std::vector<NamedMesh> shapes{{"torus", test::torus(1.0f, 0.3f, kSegments, kSegments / 2)},
                                {"vase", test_vase()},
                                {"sheet", test::plane_sheet(6)},
                                {"bunny", bunny_or_fail()}};
  for (const auto& [name, mesh] : shapes) {
    if (mesh.triangles.empty()) continue;
    const MeshField f = field_of(mesh);
    const float scale = mesh.bounds().size().norm();
    for (const auto& x : probes(mesh, kProbes / 10, 23, 0.5f)) {
      const auto c = f.closest(x);
      const double brute = brute_distance(mesh, x);
      ASSERT_NE(c.triangle, kInvalidIndex) << name;
      EXPECT_NEAR(c.distance, brute, 2e-6 * scale) << name << " at " << str(x);
      EXPECT_NEAR((c.point - x).norm(), c.distance, 2e-6 * scale) << name;
      // The point lies on the triangle reported, and the normal is that triangle's (up to orientation).
      const auto& t = mesh.triangles[c.triangle];
      const Vec3f a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], cc = mesh.vertices[t[2]];
      EXPECT_NEAR(distance_to_triangle(c.point.cast<double>(), a.cast<double>(), b.cast<double>(), cc.cast<double>()),
                  0.0, 2e-6 * scale)
          << name;
      EXPECT_NEAR(std::abs(c.normal.dot((b - a).cross(cc - a).normalized())), 1.0f, 1e-4f) << name;
      // The bounded query finds it just beyond its distance and nothing just short of it.
      EXPECT_EQ(f.closest(x, 1.001f * c.distance + 1e-6f).triangle, c.triangle) << name;
      if (c.distance > 1e-3f * scale) {
        EXPECT_EQ(f.closest(x, 0.999f * c.distance).triangle, kInvalidIndex) << name;
      }
    }
  }
}

// ---- the Stanford bunny -------------------------------------------------------------------------------

// The npm `bunny` (1839 vertices, 3674 triangles) is watertight: ray parity is an exact oracle for it.
TEST(FF_SUITE(MeshField), StanfordBunnyAgreesWithRayParity) {
  const TriangleMesh bunny = bunny_or_fail();
  if (bunny.triangles.empty()) return;
  const MeshField f = field_of(bunny);
  EXPECT_TRUE(f.encloses_volume());
  ASSERT_EQ(f.stats().boundary_edges, 0u) << "this bunny has holes: only the test below applies to it";
  std::size_t disagree = 0;
  for (const auto& x : probes(bunny, kProbes, 29))
    if (f.inside(x) != inside_by_ray_parity(bunny, x) && disagree++ < 3)
      ADD_FAILURE() << "at " << str(x) << ", w = " << f.winding_number(x);
  EXPECT_EQ(disagree, 0u);
}

// The scanned bunny's bottom is open in the original data: cut the lowest triangles away and check the points
// that are clearly inside or outside (three ray directions agree; a ray escaping through the hole breaks the
// agreement) read so.
TEST(FF_SUITE(MeshField), StanfordBunnyWithHolesReadsAsSolid) {
  TriangleMesh bunny = bunny_or_fail();
  if (bunny.triangles.empty()) return;
  auto low = [&](const std::array<Index, 3>& t) {
    return bunny.vertices[t[0]].y() + bunny.vertices[t[1]].y() + bunny.vertices[t[2]].y();
  };
  std::stable_sort(bunny.triangles.begin(), bunny.triangles.end(),
                   [&](const auto& a, const auto& b) { return low(a) < low(b); });
  bunny.triangles.erase(bunny.triangles.begin(), bunny.triangles.begin() + 40);
  const MeshField f = field_of(bunny);
  EXPECT_GT(f.stats().boundary_edges, 10u);
  EXPECT_TRUE(f.encloses_volume());
  std::size_t in = 0, in_ok = 0, out = 0, out_ok = 0;
  for (const auto& x : probes(bunny, kProbes, 29)) {
    const int a = ray_parity(bunny, x, 0), b = ray_parity(bunny, x, 5), c = ray_parity(bunny, x, 11);
    if (a < 0 || a != b || b != c) continue;
    if (a == 1)
      in++, in_ok += f.inside(x);
    else
      out++, out_ok += !f.inside(x);
  }
  EXPECT_GT(in, kProbes / 10);
  EXPECT_GE(double(in_ok), 0.99 * double(in)) << in_ok << " of " << in;
  EXPECT_GE(double(out_ok), 0.99 * double(out)) << out_ok << " of " << out;
}

// ---- the signed distance grid --------------------------------------------------------------------------

// Every node's sign is the winding number's; near the surface the interpolated distance is within h/2 of the
// exact one and the projection lands within h/2 of the surface; the sign is right wherever |d| > h. Points
// within `skip_radius` of `skip` are left out of the random probes: across a hole the signed distance itself
// jumps (from −d to +d on the w = 1/2 sheet), which no interpolation can follow.
void check_grid(const std::string& name, const TriangleMesh& mesh, float h, const Vec3f& skip = Vec3f::Zero(),
                float skip_radius = 0.0f) {
  const MeshField f = field_of(mesh);
  SdfGridStats stats;
  auto r = SdfGrid::build(f, h, 3 * h, core::null_progress(), &stats);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  const SdfGrid& g = r.value();
  ASSERT_EQ(g.value.size(), std::size_t(g.dims.x()) * g.dims.y() * g.dims.z());
  EXPECT_LT(stats.winding_evaluations, g.value.size() / 2) << name << ": the sign pass should skip far nodes";
  // Nodes: exact in the band, an upper bound within one spacing beyond it, and the winding number's sign.
  std::size_t wrong_sign = 0, band = 0;
  float worst_band = 0.0f, worst_far = 0.0f, below = 0.0f;
  const float band_width = SdfGrid::kBandCells * h, eps = 1e-6f * mesh.bounds().size().norm();
  const int step = kFull ? 1 : 2;  // every node, or every other row and slab
  for (int k = 0; k < g.dims.z(); k += step)
    for (int j = 0; j < g.dims.y(); j += step)
      for (int i = 0; i < g.dims.x(); ++i) {
        const float v = g.value[g.index(i, j, k)];
        const Vec3f x = g.node(i, j, k);
        const float exact = f.unsigned_distance(x);
        below = std::max(below, exact - std::abs(v));
        if (exact <= band_width - eps)
          ++band, worst_band = std::max(worst_band, std::abs(std::abs(v) - exact));
        else
          worst_far = std::max(worst_far, std::abs(v) - exact);
        if (std::abs(v) < 1e-4f * h) continue;  // on the surface: either sign is right
        if ((v < 0) != f.inside(x) && wrong_sign++ < 3)
          ADD_FAILURE() << name << ": node sign at " << str(x) << " d = " << v;
      }
  EXPECT_EQ(wrong_sign, 0u) << name;
  EXPECT_LE(worst_band, eps) << name;
  EXPECT_LE(below, eps) << name;
  EXPECT_LE(worst_far, h) << name;
  EXPECT_NEAR(double(stats.band_nodes), double(step * step * band), 0.1 * double(stats.band_nodes)) << name;
  std::size_t near = 0, far = 0, far_wrong = 0;
  float worst_distance = 0.0f, worst_projection = 0.0f;
  for (const auto& x : probes(mesh, kProbes, 31)) {
    if ((x - skip).norm() < skip_radius) continue;
    const float exact = f.signed_distance(x), d = g.distance(x);
    if (std::abs(exact) < 2 * h) {
      ++near;
      worst_distance = std::max(worst_distance, std::abs(d - exact));
      worst_projection = std::max(worst_projection, f.unsigned_distance(g.project_to_surface(x)));
    }
    if (std::abs(exact) > h) ++far, far_wrong += (d < 0) != (exact < 0);
    EXPECT_NEAR(g.gradient(x).norm(), 1.0f, 1e-4f) << name;
  }
  EXPECT_GT(near, kProbes / 20) << name;
  EXPECT_GT(far, kProbes / 2) << name;
  EXPECT_EQ(far_wrong, 0u) << name;
  EXPECT_LE(worst_distance, 0.5f * h) << name;
  EXPECT_LE(worst_projection, 0.5f * h) << name;
  std::printf(
      "%s: %zu nodes, %zu in the band, %zu winding numbers; far nodes ≤ %.3f h over; near the surface: "
      "|Δd| ≤ %.3f h, projection ≤ %.3f h\n",
      name.c_str(), g.value.size(), stats.band_nodes, stats.winding_evaluations, worst_far / h, worst_distance / h,
      worst_projection / h);
}

TEST(FF_SUITE(SdfGrid), MatchesExactSignedDistance) {
  check_grid("torus", test::torus(1.0f, 0.35f, 2 * kSegments, kSegments), kCoarse * 0.06f);
  check_grid("vase", test_vase(), kCoarse * 0.03f);
  check_grid("sphere with hole", test::sphere_with_hole(6, 1.0f, kSegments), kCoarse * 0.08f, Vec3f(1, 0, 0), 0.4f);
  const TriangleMesh bunny = bunny_or_fail();
  if (!bunny.triangles.empty()) check_grid("bunny", bunny, kCoarse * bunny.bounds().size().norm() / 48.0f);
}

TEST(FF_SUITE(SdfGrid), GradientIsTheOutwardNormalNearTheSurface) {
  const TriangleMesh mesh = test::torus(1.0f, 0.35f, 2 * kSegments, kSegments);
  const MeshField f = field_of(mesh);
  const float h = kCoarse * 0.04f;
  const SdfGrid g = SdfGrid::build(f, h, 3 * h).value();
  std::size_t checked = 0;
  for (const auto& x : probes(mesh, kProbes, 37)) {
    const auto c = f.closest(x);
    if (c.distance < h || c.distance > 3 * h) continue;
    const Vec3f exact = (f.inside(x) ? -1.0f : 1.0f) * (x - c.point).normalized();
    EXPECT_GT(g.gradient(x).dot(exact), kFull ? 0.98f : 0.95f) << str(x);
    ++checked;
  }
  EXPECT_GT(checked, kProbes / 20);
}

TEST(FF_SUITE(SdfGrid), OutsideTheBoxStaysPositiveAndPointsAway) {
  const MeshField f = field_of(test::uv_sphere(1.0f, 32));
  const SdfGrid g = SdfGrid::build(f, 0.1f, 0.3f).value();
  for (const Vec3f& x : {Vec3f(5, 0, 0), Vec3f(-3, 4, 1), Vec3f(0.2f, -9, 0.1f)}) {
    const float exact = f.signed_distance(x);
    EXPECT_GE(g.distance(x), exact - 0.05f);  // value at the box + distance to the box ≥ distance
    EXPECT_LE(g.distance(x), exact + 0.1f * exact);
    EXPECT_GT(g.gradient(x).dot(x.normalized()), 0.7f);
  }
}

TEST(FF_SUITE(SdfGrid), RejectsBadParameters) {
  const MeshField f = field_of(test::uv_sphere(1.0f, 16));
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (const auto& [spacing, margin, key] :
       std::vector<std::tuple<float, float, std::string>>{{0.0f, 0.1f, "spacing"},
                                                          {-1.0f, 0.1f, "spacing"},
                                                          {nan, 0.1f, "spacing"},
                                                          {inf, 0.1f, "spacing"},
                                                          {0.1f, -1.0f, "margin"},
                                                          {0.1f, nan, "margin"},
                                                          {1e-4f, 0.1f, "spacing"}}) {
    const auto r = SdfGrid::build(f, spacing, margin);
    ASSERT_FALSE(r.has_value()) << spacing << " " << margin;
    EXPECT_EQ(r.error().kind, Error::Kind::Param);
    EXPECT_NE(r.error().message.find(key), std::string::npos) << r.error().message;
  }
}

TEST(FF_SUITE(SdfGrid), CancelledByProgress) {
  struct Stop : core::Progress {
    bool tick(std::size_t) override { return false; }
  } stop;
  const MeshField f = field_of(test::uv_sphere(1.0f, 16));
  const auto r = SdfGrid::build(f, 0.1f, 0.2f, stop);
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().kind, Error::Kind::Cancelled);
}

// ---- determinism ---------------------------------------------------------------------------------------

TEST(FF_SUITE(MeshField), ResultsDoNotDependOnThreadCount) {
  const TriangleMesh mesh = test_vase();
  const MeshField f = field_of(mesh);
  const auto p = probes(mesh, kProbes, 41);
  const int threads = omp_get_max_threads();
  auto run = [&](int n) {
    omp_set_num_threads(n);
    std::vector<float> w(p.size()), sd(p.size());
    std::vector<std::uint8_t> in(p.size());
    f.winding_number(p, w);
    f.signed_distance(p, sd);
    f.inside(p, in);
    const SdfGrid g = SdfGrid::build(f, kCoarse * 0.04f, 0.1f).value();
    omp_set_num_threads(threads);
    return std::make_tuple(w, sd, in, g.value);
  };
  const auto one = run(1), four = run(4);
  EXPECT_TRUE(std::get<0>(one) == std::get<0>(four));
  EXPECT_TRUE(std::get<1>(one) == std::get<1>(four));
  EXPECT_TRUE(std::get<2>(one) == std::get<2>(four));
  EXPECT_TRUE(std::memcmp(std::get<3>(one).data(), std::get<3>(four).data(), std::get<3>(one).size() * sizeof(float)) ==
              0);
}

}  // namespace
}  // namespace ff::sampling
