// End-to-end tests of meshing: `fluidform mesh` on particle frames, `run`'s final mesh of the formed
// default bunny judged against the target, and the exports opened where users open them (three.js and the
// Khronos validator through node, Blender headless).
#include "e2e/cli_support.h"
#include "pipeline/report_page.h"
#include "io/load_mesh.h"
#include "io/write_ply.h"
#include "pipeline/run.h"
#include "sampling/mesh_field.h"
#include "support/test_support.h"
#include "surface/mesh_check.h"
#include "surface/reconstruct.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#ifdef FF_HAVE_OPENVDB
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#endif
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <random>

namespace ff {
namespace {
namespace fs = std::filesystem;
using namespace e2e;

using test::shell;

// The JSON line a checker script printed after `prefix` (or the whole output when there is no prefix).
nlohmann::json json_line(const std::string& out, const std::string& prefix = "") {
  std::size_t at = prefix.empty() ? (out.rfind("\n{") == std::string::npos ? 0 : out.rfind("\n{") + 1) : out.find(prefix);
  if (at == std::string::npos) return nlohmann::json::parse("x", nullptr, false);
  if (!prefix.empty()) at += prefix.size();
  const std::size_t end = out.find('\n', at);
  return nlohmann::json::parse(out.substr(at, end == std::string::npos ? std::string::npos : end - at), nullptr, false);
}

// Particles on a cubic lattice of spacing d filling a ball of radius r at c.
std::vector<Vec3f> ball(float d, float r, const Vec3f& c) {
  std::vector<Vec3f> x;
  const int n = static_cast<int>(std::ceil(r / d));
  for (int k = -n; k <= n; ++k)
    for (int j = -n; j <= n; ++j)
      for (int i = -n; i <= n; ++i) {
        const Vec3f p = d * Vec3f(float(i), float(j), float(k));
        if (p.norm() <= r) x.push_back(c + p);
      }
  return x;
}

void write_frame(const fs::path& p, const std::vector<Vec3f>& x, const std::string& comment) {
  io::ParticleFrameView v;
  v.positions = x;
  v.comment = comment;
  ASSERT_TRUE(io::write_particles_ply(p, v).ok());
}

// Mean and max distance from points sampled on `a` (vertices and triangle centroids) to the surface of `b`.
std::pair<double, double> one_sided(const io::TriangleMesh& a, const sampling::MeshField& b) {
  std::vector<Vec3f> pts = a.vertices;
  for (const auto& t : a.triangles) pts.push_back((a.vertices[t[0]] + a.vertices[t[1]] + a.vertices[t[2]]) / 3.0f);
  double sum = 0.0, worst = 0.0;
  for (const auto& p : pts) {
    const double dist = b.closest(p).distance;
    sum += dist, worst = std::max(worst, dist);
  }
  return {sum / double(pts.size()), worst};
}

struct Distance {
  double mean = 0, max = 0;  // symmetric: mean of the two one-sided means, max of the two maxima
};

Distance symmetric(const io::TriangleMesh& a, const io::TriangleMesh& b) {
  auto fa = sampling::MeshField::build(a);
  auto fb = sampling::MeshField::build(b);
  EXPECT_TRUE(fa.has_value() && fb.has_value());
  if (!fa || !fb) return {1e9, 1e9};
  const auto ab = one_sided(a, *fb), ba = one_sided(b, *fa);
  return {0.5 * (ab.first + ba.first), std::max(ab.second, ba.second)};
}

TEST(MeshCommand, FramesGiveWatertightObjsAValidGlbAndAPointCache) {
  const auto dir = test::temp_dir("mesh");
  const float d = 0.05f;
  fs::create_directories(dir / "particles");
  std::size_t n = 0;
  for (int k = 0; k < 6; ++k) {
    const auto x = ball(d, 0.3f, Vec3f(0.05f * float(k), 0.5f, 0.0f));
    n = x.size();
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.ply", k);
    write_frame(dir / "particles" / name, x, "fluidform particles\nspacing 0.05");
  }
  const auto r = run({"mesh", dir.string(), "-o", (dir / "out").string(), "--every", "2"});
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* f : {"frame_00000.obj", "frame_00002.obj", "frame_00004.obj", "frame_00005.obj", "final.obj"})
    EXPECT_TRUE(fs::exists(dir / "out" / "mesh" / f)) << f;
  EXPECT_FALSE(fs::exists(dir / "out" / "mesh" / "frame_00001.obj"));
  auto fin = io::load_mesh(dir / "out" / "mesh" / "final.obj");
  ASSERT_TRUE(fin.has_value()) << fin.error().message;
  const auto check = surface::check_mesh(*fin);
  EXPECT_TRUE(check.ok()) << check.summary();
  EXPECT_EQ(check.components, 1u);
  EXPECT_EQ(check.genus, 0);
  // The surface lies within half a spacing of the ball the lattice fills (radius 0.3 m).
  for (const auto& v : fin->vertices) EXPECT_NEAR((v - Vec3f(0.25f, 0.5f, 0.0f)).norm(), 0.3f, 0.5f * d);
  // The point cache: 6 frames of n points after a 32-byte header; the point mesh has the first frame's points.
  EXPECT_EQ(fs::file_size(dir / "out" / "particles.pc2"), 32u + 6u * n * 12u);
  auto p0 = io::read_particles_ply(dir / "out" / "particles_frame0.ply");
  ASSERT_TRUE(p0.has_value());
  EXPECT_EQ(p0->positions.size(), n);
  // The GLB: Khronos validator and three.js.
  const auto [rc, out] = shell("node '" + (test::source_dir() / "scripts" / "check_glb.mjs").string() + "' '" +
                               (dir / "out" / "animation.glb").string() + "'");
  ASSERT_EQ(rc, 0) << out;
  const auto j = json_line(out);
  ASSERT_FALSE(j.is_discarded()) << out;
  EXPECT_EQ(j["errors"], 0) << out;
  EXPECT_EQ(j["three"]["meshes"], 4) << out;
  EXPECT_EQ(j["three"]["visible_at_end"], 1) << out;
  EXPECT_FALSE(fs::exists(dir / "out" / pipeline::kPageAnimationFile)) << "a small animation needs no copy for the page";
  expect_no_temp_files(dir / "out");

#ifdef FF_HAVE_OPENVDB
  // --vdb: each meshed frame's level set, read back with OpenVDB: negative inside, zero on the OBJ's surface.
  const auto rv = run({"mesh", dir.string(), "-o", (dir / "vdb_out").string(), "--every", "2", "--vdb"});
  ASSERT_EQ(rv.code, 0) << rv.err;
  for (const char* f : {"frame_00000.vdb", "frame_00002.vdb", "frame_00004.vdb", "frame_00005.vdb"})
    EXPECT_TRUE(fs::exists(dir / "vdb_out" / "vdb" / f)) << f;
  EXPECT_FALSE(fs::exists(dir / "vdb_out" / "vdb" / "frame_00001.vdb"));
  expect_no_temp_files(dir / "vdb_out");
  openvdb::initialize();
  openvdb::io::File vf((dir / "vdb_out" / "vdb" / "frame_00005.vdb").string());
  vf.open();
  auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(vf.readGrid("surface"));
  vf.close();
  ASSERT_TRUE(grid);
  EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
  EXPECT_NEAR(grid->voxelSize()[0], 0.5 * d, 1e-6);  // the meshing grid's cell
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(*grid);
  auto phi = [&](const Vec3f& p) { return sampler.wsSample(openvdb::Vec3d(p.x(), p.y(), p.z())); };
  EXPECT_LT(phi(Vec3f(0.25f, 0.5f, 0.0f)), 0.0f);  // the ball's centre (frame 5)
  EXPECT_GT(phi(Vec3f(0.25f, 0.5f, 0.0f) + Vec3f(0.6f, 0, 0)), 0.0f);
  for (std::size_t i = 0; i < fin->vertices.size(); i += 11) EXPECT_NEAR(phi(fin->vertices[i]), 0.0f, 0.25f * d);
#endif

  // The same frames by regularised marching tetrahedra (--extraction rmt): as closed, and as close to the ball.
  const auto rt = run({"mesh", dir.string(), "-o", (dir / "rmt").string(), "--final-only", "--extraction", "rmt"});
  ASSERT_EQ(rt.code, 0) << rt.err;
  EXPECT_NE(rt.err.find("from marching tetrahedra"), std::string::npos) << rt.err;
  auto rfin = io::load_mesh(dir / "rmt" / "mesh" / "final.obj");
  ASSERT_TRUE(rfin.has_value()) << rfin.error().message;
  const auto rcheck = surface::check_mesh(*rfin);
  EXPECT_TRUE(rcheck.ok()) << rcheck.summary();
  EXPECT_EQ(rcheck.components, 1u);
  EXPECT_EQ(rcheck.genus, 0);
  for (const auto& v : rfin->vertices) EXPECT_NEAR((v - Vec3f(0.25f, 0.5f, 0.0f)).norm(), 0.3f, 0.5f * d);

  // Without the header's spacing it is estimated from the particles (a lattice: exactly d).
  fs::create_directories(dir / "bare");
  write_frame(dir / "bare" / "frame_00000.ply", ball(d, 0.3f, Vec3f::Zero()), "no spacing here");
  const auto e = run({"mesh", (dir / "bare").string(), "-o", (dir / "bare_out").string()});
  ASSERT_EQ(e.code, 0) << e.err;
  EXPECT_NE(e.err.find("estimated"), std::string::npos) << e.err;
  EXPECT_NE(e.err.find("0.05 m"), std::string::npos) << e.err;
}

// Two targets' fluid (target ids 0 and 1) meshed from a run's folder: the GLB gets one water material per target,
// tinted as the report's targets[].tint, and each triangle the material of the target whose fluid it bounds.
// An animation.glb larger than report.html carries (2 MiB) gets a lighter copy beside it for the page: fewer frames,
// decimated, under the limit, valid, ending on the last frame.
TEST(MeshCommand, ALargeAnimationGetsALighterCopyForThePage) {
  const auto dir = test::temp_dir("mesh-page-copy");
  const float d = 0.025f;
  fs::create_directories(dir / "particles");
  for (int k = 0; k < 16; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.ply", k);
    write_frame(dir / "particles" / name, ball(d, 0.45f, Vec3f(0.02f * float(k), 0.5f, 0.0f)), "fluidform particles\nspacing 0.025");
  }
  const auto r = run({"mesh", dir.string(), "-o", (dir / "out").string(), "--no-quantize"});
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_GT(fs::file_size(dir / "out" / "animation.glb"), pipeline::kPageAnimationBytes) << "the test needs a large one";
  const fs::path copy = dir / "out" / pipeline::kPageAnimationFile;
  ASSERT_TRUE(fs::exists(copy));
  EXPECT_LE(fs::file_size(copy), pipeline::kPageAnimationBytes);
  const auto [rc, out] = shell("node '" + (test::source_dir() / "scripts" / "check_glb.mjs").string() + "' '" + copy.string() + "'");
  ASSERT_EQ(rc, 0) << out;
  const auto j = json_line(out);
  ASSERT_FALSE(j.is_discarded()) << out;
  EXPECT_EQ(j["errors"], 0) << out;
  EXPECT_GE(j["three"]["meshes"].get<int>(), 2) << out;
  EXPECT_EQ(j["three"]["visible_at_end"], 1) << out;
  EXPECT_NEAR(j["three"]["duration"].get<double>(), 16.0 / 60.0, 1e-3) << out << " (the last frame, held 1/60 s)";
  expect_no_temp_files(dir / "out");
}

TEST(MeshCommand, TwoTargetsGetTheirOwnTintInTheGlb) {
  const auto dir = test::temp_dir("tint");
  const float d = 0.05f;
  fs::create_directories(dir / "particles");
  auto a = ball(d, 0.25f, Vec3f(-0.5f, 0.5f, 0.0f)), b = ball(d, 0.25f, Vec3f(0.5f, 0.5f, 0.0f));
  std::vector<Vec3f> x = a;
  x.insert(x.end(), b.begin(), b.end());
  std::vector<std::uint8_t> ids(a.size(), 0);
  ids.resize(x.size(), 1);
  for (int k = 0; k < 2; ++k) {
    io::ParticleFrameView v;
    v.positions = x;
    v.targets = ids;
    v.comment = "fluidform particles\nspacing 0.05";
    ASSERT_TRUE(io::write_particles_ply(dir / "particles" / (k ? "frame_00001.ply" : "frame_00000.ply"), v).ok());
  }
  {
    std::ofstream r(dir / "report.json");
    r << R"({"scene": {"targets": [{"mesh": "a.obj", "tint": [0.9, 0.1, 0.1]}, {"mesh": "b.obj", "tint": [0.1, 0.8, 0.2]}]}})";
  }
  const auto r = run({"mesh", dir.string(), "-o", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  // The GLB's JSON chunk: two materials with the tints, and in each frame one primitive per ball.
  std::ifstream in(dir / "out" / "animation.glb", std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 20u);
  std::uint32_t json_len = 0;
  std::memcpy(&json_len, bytes.data() + 12, 4);
  const auto doc = nlohmann::json::parse(std::string(bytes.data() + 20, json_len));
  ASSERT_EQ(doc["materials"].size(), 2u);
  EXPECT_EQ(doc["materials"][0]["extensions"]["KHR_materials_volume"]["attenuationColor"][0].get<double>(), 0.9f);
  EXPECT_EQ(doc["materials"][1]["extensions"]["KHR_materials_volume"]["attenuationColor"][1].get<double>(), 0.8f);
  ASSERT_EQ(doc["meshes"].size(), 2u);
  for (const auto& m : doc["meshes"]) {
    ASSERT_EQ(m["primitives"].size(), 2u) << m.dump();
    EXPECT_EQ(m["primitives"][0]["material"], 0);
    EXPECT_EQ(m["primitives"][1]["material"], 1);
    // The two balls have the same size: each primitive holds half the triangles (within a few).
    const auto n0 = doc["accessors"][m["primitives"][0]["indices"].get<int>()]["count"].get<double>();
    const auto n1 = doc["accessors"][m["primitives"][1]["indices"].get<int>()]["count"].get<double>();
    EXPECT_NEAR(n0 / n1, 1.0, 0.05);
  }
  const auto [rc, out] = shell("node '" + (test::source_dir() / "scripts" / "check_glb.mjs").string() + "' '" +
                               (dir / "out" / "animation.glb").string() + "'");
  ASSERT_EQ(rc, 0) << out;
  EXPECT_EQ(json_line(out)["errors"], 0) << out;
}

TEST(MeshCommand, BadInputIsOneLineAndWritesNoMesh) {
  const auto dir = test::temp_dir("meshbad");
  const auto missing = run({"-q", "mesh", (dir / "nope").string(), "-o", (dir / "o1").string()});
  EXPECT_NE(missing.code, 0);
  EXPECT_EQ(count_lines(missing.err), 1u) << missing.err;
  EXPECT_NE(missing.err.find("no such file"), std::string::npos) << missing.err;

  fs::create_directories(dir / "empty");
  const auto empty = run({"-q", "mesh", (dir / "empty").string(), "-o", (dir / "o2").string()});
  EXPECT_NE(empty.code, 0);
  EXPECT_EQ(count_lines(empty.err), 1u) << empty.err;
  EXPECT_NE(empty.err.find("no particle frames"), std::string::npos) << empty.err;

  auto x = ball(0.05f, 0.2f, Vec3f::Zero());
  x[7].y() = NAN;
  write_frame(dir / "nan.ply", x, "fluidform particles\nspacing 0.05");
  const auto nan = run({"-q", "mesh", (dir / "nan.ply").string(), "-o", (dir / "o3").string()});
  EXPECT_NE(nan.code, 0);
  EXPECT_EQ(count_lines(nan.err), 1u) << nan.err;
  EXPECT_NE(nan.err.find("finite"), std::string::npos) << nan.err;
  EXPECT_FALSE(fs::exists(dir / "o3" / "mesh" / "final.obj"));

  const auto bad_every = run({"-q", "mesh", (dir / "nan.ply").string(), "-o", (dir / "o4").string(), "--every", "0"});
  EXPECT_NE(bad_every.code, 0);
  EXPECT_EQ(count_lines(bad_every.err), 1u) << bad_every.err;

  const auto bad_ex =
      run({"-q", "mesh", (dir / "nan.ply").string(), "-o", (dir / "o5").string(), "--extraction", "mt"});
  EXPECT_EQ(bad_ex.code, 2);
  EXPECT_EQ(count_lines(bad_ex.err), 1u) << bad_ex.err;
  EXPECT_NE(bad_ex.err.find("--extraction 'mt' is not a surface extraction (mc or rmt)"), std::string::npos)
      << bad_ex.err;
  EXPECT_FALSE(fs::exists(dir / "o5" / "mesh" / "final.obj"));
  expect_no_temp_files(dir);
}

// The meshing acceptance on the formed default bunny: final.obj is watertight, manifold, one component, ≤ 20k
// triangles and within 1 d of the target; reduction + decimation cut ≥ 40 % of plain marching cubes' triangles at
// equal or better distance; Blender imports it and auto-rigs it, and plays the GLB and the point cache.
TEST(MeshAcceptance, FormedDefaultBunny) {
  const auto dir = test::temp_dir("bunnymesh");
  const auto scene = test::source_dir() / "examples" / "default_scene.json";
  ASSERT_TRUE(fs::exists(test::source_dir() / "examples" / "bunny.obj")) << "run scripts/setup (it writes examples/bunny.obj)";
  // The default run, as the README's first command: it leaves the forming as animation.glb and the point cache.
  const auto r = run({"run", scene.string(), "-o", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(fs::exists(dir / "out" / "animation.glb"));
  EXPECT_LE(fs::file_size(dir / "out" / "animation.glb"), 20'000'000u);
  EXPECT_TRUE(fs::exists(dir / "out" / "particles.pc2"));
  EXPECT_FALSE(fs::exists(dir / "out" / "mesh" / "frame_00000.obj")) << "per-frame OBJs only with --mesh-every";
  auto target = io::load_mesh(test::source_dir() / "examples" / "bunny.obj");
  ASSERT_TRUE(target.has_value());
  for (auto& v : target->vertices) v *= 0.1f;  // the scene's scale
  auto fin = io::load_mesh(dir / "out" / "mesh" / "final.obj");
  ASSERT_TRUE(fin.has_value()) << fin.error().message;
  const auto check = surface::check_mesh(*fin);
  EXPECT_TRUE(check.ok()) << check.summary();
  EXPECT_EQ(check.components, 1u) << check.summary();
  EXPECT_LE(fin->triangles.size(), 20'000u);
  // The particle spacing of the run, from the last frame's header.
  std::vector<fs::path> frames;
  for (const auto& e : fs::directory_iterator(dir / "out" / "particles")) frames.push_back(e.path());
  std::sort(frames.begin(), frames.end());
  auto last = io::read_particles_ply(frames.back());
  ASSERT_TRUE(last.has_value());
  float d = 0.0f;
  for (const auto& c : last->comments)
    if (c.rfind("spacing ", 0) == 0) d = std::stof(c.substr(8));
  ASSERT_GT(d, 0.0f);
  const Distance dist = symmetric(*fin, *target);
  std::printf("final.obj: %zu triangles, symmetric distance to the target: mean %.3f d, max %.3f d\n",
              fin->triangles.size(), dist.mean / d, dist.max / d);
  EXPECT_LE(dist.mean, 1.0 * d);

  // Plain marching cubes of the same field (same smoothing, no reduction, no decimation) against the default.
  surface::SurfaceParams plain;
  plain.reduction = surface::Reduction::None;
  plain.decimate_error = 0.0f;
  plain.max_triangles = 0;
  auto mc = surface::reconstruct(last->positions, d, plain);
  ASSERT_TRUE(mc.has_value()) << mc.error().message;
  const Distance dist_mc = symmetric(*mc, *target);
  std::printf("plain marching cubes: %zu triangles, mean %.3f d; reduced + decimated: %zu triangles (%.0f %% fewer)\n",
              mc->triangles.size(), dist_mc.mean / d, fin->triangles.size(),
              100.0 * (1.0 - double(fin->triangles.size()) / double(mc->triangles.size())));
  EXPECT_LE(double(fin->triangles.size()), 0.6 * double(mc->triangles.size()));
  EXPECT_LE(dist.mean, dist_mc.mean * 1.02 + 1e-6);  // equal (within 2 %) or better

  // The GLB passes the validator and loads in three.js.
  const auto [rc, out] = shell("node '" + (test::source_dir() / "scripts" / "check_glb.mjs").string() + "' '" +
                               (dir / "out" / "animation.glb").string() + "'");
  ASSERT_EQ(rc, 0) << out;
  EXPECT_EQ(json_line(out)["errors"], 0) << out;
  // The water material, as three.js makes it (MeshPhysicalMaterial with transmission and absorption).
  const auto mat = json_line(out)["three"]["material"];
  EXPECT_EQ(mat["type"], "MeshPhysicalMaterial") << out;
  EXPECT_EQ(mat["transmission"], 1.0) << out;
  EXPECT_NEAR(mat["ior"].get<double>(), 1.33, 1e-3) << out;
  EXPECT_GT(mat["attenuation_distance"].get<double>(), 0.0) << out;
  // Every k-th frame of the run and its last (pipeline::animation_every).
  const std::size_t nf = frames.size(), k = static_cast<std::size_t>(pipeline::animation_every(static_cast<int>(nf)));
  EXPECT_EQ(json_line(out)["three"]["meshes"].get<std::size_t>(), (nf + k - 1) / k + ((nf - 1) % k != 0 ? 1 : 0)) << out;

  // Blender (Debian's package; scripts/test installs it).
  if (shell("PATH=/usr/bin:$PATH command -v blender").first != 0)
    GTEST_SKIP() << "Blender is not installed and could not be installed (apt-get install blender): the Blender "
                    "import and auto-rig checks did not run";
  const auto [brc, bout] = shell(
      "PATH=/usr/bin:$PATH timeout 600 blender -b --factory-startup -noaudio --python-exit-code 1 -P '" +
      (test::source_dir() / "scripts" / "blender_check.py").string() + "' -- --obj '" +
      (dir / "out" / "mesh" / "final.obj").string() + "' --glb '" + (dir / "out" / "animation.glb").string() +
      "' --points '" + (dir / "out" / "particles_frame0.ply").string() + "' --pc2 '" +
      (dir / "out" / "particles.pc2").string() + "'");
  ASSERT_EQ(brc, 0) << bout;
  EXPECT_EQ(bout.find("Bone Heat Weighting"), std::string::npos) << bout;
  const auto b = json_line(bout, "FLUIDFORM_CHECK ");
  ASSERT_FALSE(b.is_discarded()) << bout;
  EXPECT_EQ(b["obj"]["objects"], 1) << bout;
  EXPECT_EQ(b["obj"]["faces"], fin->triangles.size()) << bout;
  EXPECT_EQ(b["obj"]["parent_result"], nlohmann::json::array({"FINISHED"})) << bout;
  EXPECT_EQ(b["obj"]["unweighted_vertices"], 0) << bout;
  EXPECT_GT(b["glb"]["meshes"].get<int>(), 1) << bout;
  EXPECT_EQ(b["glb"]["actions"], b["glb"]["meshes"]) << bout;
  // Blender reads the water material from both files: a transmissive Principled BSDF with water's IOR.
  for (const char* f : {"glb", "obj"}) {
    SCOPED_TRACE(f);
    const auto& m = b[f]["material"];
    ASSERT_TRUE(m.is_object()) << bout;
    EXPECT_GT(m["transmission"].get<double>(), 0.9) << bout;
    EXPECT_NEAR(m["ior"].get<double>(), 1.33, 1e-2) << bout;
  }
  EXPECT_LT(b["pc2"]["max_difference_last_frame"].get<double>(), 1e-5) << bout;
#ifdef FF_HAVE_OPENVDB
  // The final frame's --vdb level set in Blender: a volume object with the "surface" grid, which Blender's Volume to
  // Mesh turns back into the formed bunny (bounds within a spacing of final.obj's, imported the same way up).
  const auto rv = run({"mesh", (dir / "out").string(), "-o", (dir / "vdb").string(), "--final-only", "--vdb"});
  ASSERT_EQ(rv.code, 0) << rv.err;
  std::vector<fs::path> vdbs;
  for (const auto& e : fs::directory_iterator(dir / "vdb" / "vdb")) vdbs.push_back(e.path());
  ASSERT_EQ(vdbs.size(), 1u);
  const auto [vrc, vout] = shell("PATH=/usr/bin:$PATH timeout 600 blender -b --factory-startup -noaudio --python-exit-code 1 -P '" +
                                 (test::source_dir() / "scripts" / "blender_check.py").string() + "' -- --vdb '" +
                                 vdbs[0].string() + "'");
  ASSERT_EQ(vrc, 0) << vout;
  auto v = json_line(vout, "FLUIDFORM_CHECK ")["vdb"];  // not const: a missing key reads as null
  ASSERT_TRUE(v.is_object()) << vout;
  EXPECT_EQ(v["grids"], nlohmann::json::array({"surface"})) << vout;
  EXPECT_EQ(v["loaded"], true) << vout;
  EXPECT_GT(v["faces"].get<int>(), 1000) << vout;
  for (int side = 0; side < 2; ++side)
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(v["bounds"][side][a].get<double>(), b["obj"]["bounds"][side][a].get<double>(), d) << vout;
#endif
  EXPECT_EQ(b["pc2"]["points"], last->positions.size()) << bout;
}

}  // namespace
}  // namespace ff
