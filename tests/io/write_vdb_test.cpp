// The VDB export read back with OpenVDB: one level-set grid named "surface", negative inside, zero on the mesh,
// written atomically; bad options and an empty mesh are one-line errors.
#include "io/write_vdb.h"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <cmath>
#include <filesystem>
#include <numbers>

namespace ff::io {
namespace {
namespace fs = std::filesystem;

// A UV sphere of radius r about c, outward wound.
TriangleMesh sphere(float r, const Vec3f& c, int rings = 24, int segments = 48) {
  TriangleMesh m;
  m.vertices.push_back(c + Vec3f(0, 0, r));
  for (int i = 1; i < rings; ++i) {
    const double th = std::numbers::pi * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double ph = 2 * std::numbers::pi * j / segments;
      m.vertices.push_back(c + r * Vec3f(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)),
                                         float(std::cos(th))));
    }
  }
  m.vertices.push_back(c + Vec3f(0, 0, -r));
  const auto ring = [&](int i, int j) { return Index(1 + (i - 1) * segments + (j % segments)); };
  const Index south = Index(m.vertices.size() - 1);
  for (int j = 0; j < segments; ++j) m.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  for (int j = 0; j < segments; ++j) m.triangles.push_back({ring(rings - 1, j), south, ring(rings - 1, j + 1)});
  return m;
}

fs::path temp_dir(const char* name) {
  const fs::path d = fs::temp_directory_path() / (std::string("ff_vdb_") + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(WriteVdb, SphereReadsBackAsALevelSetWithItsZeroOnTheMesh) {
  if (!vdb_available()) GTEST_SKIP() << "this build has no OpenVDB";
  const fs::path dir = temp_dir("sphere");
  const fs::path file = dir / "frame_00007.vdb";
  const Vec3f c(0.3f, -0.2f, 1.0f);
  const float r = 0.5f, voxel = 0.02f;
  const TriangleMesh m = sphere(r, c);
  ASSERT_TRUE(write_level_set_vdb(file, m, {voxel, 3.0f, "surface"}).ok());
  for (const auto& e : fs::directory_iterator(dir)) EXPECT_EQ(e.path(), file) << "a temporary file was left";

  openvdb::initialize();
  openvdb::io::File f(file.string());
  f.open();
  const auto grids = f.getGrids();
  f.close();
  ASSERT_EQ(grids->size(), 1u);
  auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>((*grids)[0]);
  ASSERT_TRUE(grid);
  EXPECT_EQ(grid->getName(), "surface");
  EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
  EXPECT_NEAR(grid->voxelSize()[0], voxel, 1e-7);
  EXPECT_NEAR(grid->background(), 3.0f * voxel, 1e-6f);

  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> s(*grid);
  auto at = [&](const Vec3f& p) { return s.wsSample(openvdb::Vec3d(p.x(), p.y(), p.z())); };
  // Zero at the vertices (within the trilinear interpolation of a sphere, a small part of a voxel).
  for (std::size_t i = 0; i < m.vertices.size(); i += 37) EXPECT_NEAR(at(m.vertices[i]), 0.0f, 0.25f * voxel);
  // Signed distance in the band: one voxel inside is −voxel, one outside +voxel (negative inside).
  const Vec3f dir_out = Vec3f(1, 2, 2).normalized();
  EXPECT_NEAR(at(c + (r - voxel) * dir_out), -voxel, 0.25f * voxel);
  EXPECT_NEAR(at(c + (r + voxel) * dir_out), voxel, 0.25f * voxel);
  // Deep inside: the interior background (−band), far outside: +band.
  EXPECT_LT(at(c), 0.0f);
  EXPECT_GT(at(c + Vec3f(2 * r, 0, 0)), 0.0f);
  fs::remove_all(dir);
}

TEST(WriteVdb, BadOptionsAndAnEmptyMeshAreOneLineErrors) {
  const fs::path dir = temp_dir("bad");
  const TriangleMesh m = sphere(0.5f, Vec3f::Zero());
  auto st = write_level_set_vdb(dir / "a.vdb", m, {0.0f, 3.0f, "surface"});
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("voxel size"), std::string::npos);
  st = write_level_set_vdb(dir / "a.vdb", m, {0.01f, 0.5f, "surface"});
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("half width"), std::string::npos);
  st = write_level_set_vdb(dir / "a.vdb", TriangleMesh{}, {0.01f, 3.0f, "surface"});
  ASSERT_FALSE(st.ok());
  EXPECT_TRUE(st.error().is_input());
  if (vdb_available()) {
    st = write_level_set_vdb(dir / "missing" / "a.vdb", m, {0.01f, 3.0f, "surface"});
    ASSERT_FALSE(st.ok());
    EXPECT_EQ(st.error().kind, Error::Kind::Io);
    EXPECT_EQ(st.error().message.find('\n'), std::string::npos);
  }
  EXPECT_TRUE(fs::is_empty(dir));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ff::io
