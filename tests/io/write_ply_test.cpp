#include "io/write_ply.h"

#include "support/test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace ff::io {
namespace {

ParticleFrameView view(std::span<const Vec3f> x, std::span<const Vec3f> v, std::span<const std::uint8_t> t) {
  ParticleFrameView f;
  f.positions = x;
  f.velocities = v;
  f.targets = t;
  return f;
}

TEST(WritePly, RoundTripWithAndWithoutOptionalProperties) {
  const auto dir = test::temp_dir("ply");
  std::vector<Vec3f> x{{1, 2, 3}, {-4, 5.5f, 6}}, v{{0.1f, 0.2f, 0.3f}, {7, 8, 9}};
  std::vector<std::uint8_t> t{0, 255};
  ASSERT_TRUE(write_particles_ply(dir / "a.ply", view(x, v, t)).ok());
  auto a = read_particles_ply(dir / "a.ply");
  ASSERT_TRUE(a.has_value()) << a.error().message;
  EXPECT_EQ(a->positions, x);
  EXPECT_EQ(a->velocities, v);
  EXPECT_EQ(a->targets, t);
  ASSERT_TRUE(write_particles_ply(dir / "b.ply", view(x, {}, {})).ok());
  auto b = read_particles_ply(dir / "b.ply");
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->positions, x);
  EXPECT_TRUE(b->velocities.empty());
  // Header is the documented one: binary little endian, float x y z.
  std::ifstream in(dir / "b.ply");
  std::string l1, l2;
  std::getline(in, l1);
  std::getline(in, l2);
  EXPECT_EQ(l1, "ply");
  EXPECT_EQ(l2, "format binary_little_endian 1.0");
  // No temp file is left behind.
  for (const auto& e : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(WritePly, MismatchedSizesAndTruncatedFilesAreErrors) {
  const auto dir = test::temp_dir("ply2");
  std::vector<Vec3f> x{{1, 2, 3}}, v{{0, 0, 0}, {1, 1, 1}};
  EXPECT_FALSE(write_particles_ply(dir / "bad.ply", view(x, v, {})).ok());
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.ply"));
  ASSERT_TRUE(write_particles_ply(dir / "c.ply", view(x, {}, {})).ok());
  std::filesystem::resize_file(dir / "c.ply", std::filesystem::file_size(dir / "c.ply") - 4);
  EXPECT_FALSE(read_particles_ply(dir / "c.ply").has_value());
}

TEST(WritePly, DecodedFromMemoryAsFromTheFile) {
  const auto dir = test::temp_dir("ply-memory");
  std::vector<Vec3f> x{{1, 2, 3}, {-4, 5.5f, 6}}, v{{0.1f, 0.2f, 0.3f}, {7, 8, 9}};
  std::vector<std::uint8_t> t{3, 255};
  const auto bytes = encode_particles_ply(view(x, v, t));
  ASSERT_TRUE(write_particles_ply(dir / "a.ply", view(x, v, t)).ok());
  auto m = decode_particles_ply(bytes, "a.ply");
  auto f = read_particles_ply(dir / "a.ply");
  ASSERT_TRUE(m && f);
  EXPECT_EQ(m->positions, f->positions);
  EXPECT_EQ(m->velocities, f->velocities);
  EXPECT_EQ(m->targets, t);
  // A cut file: the same error, naming what stands for the file.
  auto cut = decode_particles_ply(std::span(bytes).first(bytes.size() - 4), "cut.ply");
  ASSERT_FALSE(cut.has_value());
  EXPECT_TRUE(cut.error().message.starts_with("cut.ply: truncated")) << cut.error().message;
}

TEST(WritePly, UnwritableFolderIsAnErrorNamingThePath) {
  const std::vector<Vec3f> one{{0, 0, 0}};
  auto st = write_particles_ply("/proc/fluidform-nope/a.ply", view(one, {}, {}));
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("/proc/fluidform-nope/a.ply"), std::string::npos);
}

}  // namespace
}  // namespace ff::io
