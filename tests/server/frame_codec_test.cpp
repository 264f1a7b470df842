// The frame and live-surface layouts both ways: C++ encode → C++ decode (frames: quantisation within half a step;
// surfaces: exact), and C++ encode → node decode with web/src/protocol.js (web/test/protocol_roundtrip.mjs), so the
// two documented layouts cannot drift.
#include "server/frame_codec.h"
#include "support/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <fstream>

namespace ff::server {
namespace {
namespace fs = std::filesystem;

std::vector<Vec3f> sample_positions(std::size_t n) {
  std::vector<Vec3f> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float t = static_cast<float>(i);
    x[i] = Vec3f(0.01f * t - 0.3f, 1.5f * std::sin(0.1f * t), -0.002f * t * t / float(n));
  }
  return x;
}

TEST(FrameCodec, RoundTripWithinHalfAStep) {
  const auto x = sample_positions(1001);
  std::vector<std::uint8_t> t(x.size());
  for (std::size_t i = 0; i < t.size(); ++i) t[i] = i % 7 == 0 ? 255 : std::uint8_t(i % 3);
  const FrameInfo info{42, 0.7, 12.5f, 3.25f, 59.0f, 900};
  const auto bytes = encode_frame(info, x, t);
  EXPECT_EQ(bytes.size() % 4, 0u);
  EXPECT_EQ(bytes.size(), (kFrameHeaderBytes + 7 * x.size() + 3) / 4 * 4);
  auto d = decode_frame(bytes);
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->info.frame, 42u);
  EXPECT_DOUBLE_EQ(d->info.time, 0.7);
  EXPECT_FLOAT_EQ(d->info.step_ms, 12.5f);
  EXPECT_FLOAT_EQ(d->info.error_rate, 3.25f);
  EXPECT_FLOAT_EQ(d->info.sim_fps, 59.0f);
  EXPECT_EQ(d->info.controlled, 900u);
  EXPECT_EQ(d->targets, t);
  const Vec3f tol = quantisation_step(d->lo, d->hi) * 1.01f + Vec3f::Constant(1e-6f);
  for (std::size_t i = 0; i < x.size(); ++i)
    for (int a = 0; a < 3; ++a) ASSERT_NEAR(d->positions[i][a], x[i][a], tol[a]) << i;
}

TEST(FrameCodec, EmptyNonFiniteAndTruncated) {
  auto e = decode_frame(encode_frame(FrameInfo{}, {}, {}));
  ASSERT_TRUE(e);
  EXPECT_TRUE(e->positions.empty());
  EXPECT_TRUE(std::isnan(e->info.error_rate));  // no targets
  std::vector<Vec3f> x{Vec3f(1, 2, 3), Vec3f(NAN, 0, 0), Vec3f(2, 3, 4)};
  auto bytes = encode_frame(FrameInfo{}, x, {});
  auto d = decode_frame(bytes);
  ASSERT_TRUE(d);
  EXPECT_TRUE(d->positions[1].allFinite());  // sent as lo, never NaN on the wire
  EXPECT_EQ(d->targets, std::vector<std::uint8_t>(3, 255));
  bytes.resize(kFrameHeaderBytes + 5);
  EXPECT_FALSE(decode_frame(bytes));
  bytes[0] ^= 1;
  EXPECT_FALSE(decode_frame(bytes));
}

io::TriangleMesh sample_mesh() {
  io::TriangleMesh m;
  for (int i = 0; i < 300; ++i) m.vertices.push_back(Vec3f(0.001f * float(i), std::cos(0.3f * float(i)), -1.25f + 0.5f * float(i % 7)));
  for (Index i = 0; i + 2 < 300; ++i) m.triangles.push_back({i, i + 1, i + 2});
  return m;
}

TEST(SurfaceCodec, RoundTripIsExact) {
  const auto mesh = sample_mesh();
  const SurfaceInfo info{17, 2.25, 93.5f};
  const auto bytes = encode_surface(info, mesh);
  EXPECT_EQ(bytes.size(), kSurfaceHeaderBytes + 12 * mesh.vertices.size() + 12 * mesh.triangles.size());
  EXPECT_FALSE(decode_frame(bytes)) << "a surface is not a particle frame";
  auto d = decode_surface(bytes);
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->info.frame, 17u);
  EXPECT_DOUBLE_EQ(d->info.time, 2.25);
  EXPECT_FLOAT_EQ(d->info.build_ms, 93.5f);
  EXPECT_EQ(d->mesh.vertices, mesh.vertices);
  EXPECT_EQ(d->mesh.triangles, mesh.triangles);
  auto empty = decode_surface(encode_surface(SurfaceInfo{}, io::TriangleMesh{}));
  ASSERT_TRUE(empty);
  EXPECT_TRUE(empty->mesh.vertices.empty());
  // Truncated, a wrong magic, a triangle naming a vertex that is not there: refused.
  auto cut = bytes;
  cut.resize(cut.size() - 1);
  EXPECT_FALSE(decode_surface(cut));
  auto bad = bytes;
  const std::uint32_t far = 300;
  std::memcpy(bad.data() + kSurfaceHeaderBytes + 12 * 300, &far, 4);
  EXPECT_FALSE(decode_surface(bad));
  bad = bytes;
  bad[0] ^= 1;
  EXPECT_FALSE(decode_surface(bad));
  EXPECT_FALSE(decode_surface(encode_frame(FrameInfo{}, sample_positions(10), {})));
}

// Runs web/test/protocol_roundtrip.mjs (`mode`: "" for a frame, "--surface" for a surface) on the bytes C++ wrote
// and the values C++ expects; its exit code and output.
std::pair<int, std::string> node_roundtrip(const fs::path& dir, const std::string& mode) {
  return test::shell("node '" + (test::source_dir() / "web" / "test" / "protocol_roundtrip.mjs").string() + "' " + mode +
                     " '" + (dir / "data.bin").string() + "' '" + (dir / "expected.json").string() + "'");
}

void write_bytes(const fs::path& file, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// C++ encodes, node decodes with web/src/protocol.js and compares with what C++ decoded (to 1e-6 relative).
TEST(FrameCodec, NodeDecodesWhatCppEncodes) {
  if (std::system("node --version > /dev/null 2>&1") != 0) GTEST_SKIP() << "node is not installed (scripts/setup installs it)";
  const fs::path dir = test::temp_dir("frame-codec");
  const auto x = sample_positions(5003);
  std::vector<std::uint8_t> t(x.size());
  for (std::size_t i = 0; i < t.size(); ++i) t[i] = std::uint8_t(i % 5 == 4 ? 255 : i % 4);
  const FrameInfo info{7, 123.456789012345, 3.5f, NAN, 61.25f, 4000};
  const auto bytes = encode_frame(info, x, t);
  write_bytes(dir / "data.bin", bytes);
  auto d = decode_frame(bytes);
  ASSERT_TRUE(d);
  nlohmann::json want = {{"frame", 7}, {"count", x.size()}, {"time", info.time}, {"stepMs", 3.5}, {"errorRate", nullptr},
                         {"simFps", 61.25}, {"controlled", 4000}};
  nlohmann::json pos = nlohmann::json::array(), tg = nlohmann::json::array();
  for (std::size_t i = 0; i < x.size(); ++i) {
    pos.push_back({d->positions[i].x(), d->positions[i].y(), d->positions[i].z()});
    tg.push_back(t[i]);
  }
  want["positions"] = pos;
  want["targets"] = tg;
  std::ofstream(dir / "expected.json") << want.dump();
  const auto [rc, out] = node_roundtrip(dir, "");
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("protocol round trip ok"), std::string::npos) << out;
  fs::remove_all(dir);
}

// The live surface the same way: C++ encodes, node decodes (exactly: floats and indices go as they are).
TEST(SurfaceCodec, NodeDecodesWhatCppEncodes) {
  if (std::system("node --version > /dev/null 2>&1") != 0) GTEST_SKIP() << "node is not installed (scripts/setup installs it)";
  const fs::path dir = test::temp_dir("surface-codec");
  const auto mesh = sample_mesh();
  const auto bytes = encode_surface(SurfaceInfo{5, 1.0 / 3.0, 12.75f}, mesh);
  write_bytes(dir / "data.bin", bytes);
  nlohmann::json pos = nlohmann::json::array(), idx = nlohmann::json::array();
  for (const auto& v : mesh.vertices) pos.push_back({v.x(), v.y(), v.z()});
  for (const auto& t : mesh.triangles) idx.push_back({t[0], t[1], t[2]});
  const nlohmann::json want = {{"frame", 5}, {"time", 1.0 / 3.0}, {"buildMs", 12.75}, {"positions", pos}, {"triangles", idx}};
  std::ofstream(dir / "expected.json") << want.dump();
  const auto [rc, out] = node_roundtrip(dir, "--surface");
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("surface round trip ok"), std::string::npos) << out;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ff::server
