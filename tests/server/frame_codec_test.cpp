// The frame layout both ways: C++ encode → C++ decode (quantisation within half a step), and C++ encode → node
// decode with web/src/protocol.js (web/test/protocol_roundtrip.mjs), so the two documented layouts cannot drift.
#include "server/frame_codec.h"
#include "support/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
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

// C++ encodes, node decodes with web/src/protocol.js and compares with what C++ decoded (to 1e-6 relative).
TEST(FrameCodec, NodeDecodesWhatCppEncodes) {
  if (std::system("node --version > /dev/null 2>&1") != 0) GTEST_SKIP() << "node is not installed (scripts/setup installs it)";
  const fs::path dir = test::temp_dir("frame-codec");
  const auto x = sample_positions(5003);
  std::vector<std::uint8_t> t(x.size());
  for (std::size_t i = 0; i < t.size(); ++i) t[i] = std::uint8_t(i % 5 == 4 ? 255 : i % 4);
  const FrameInfo info{7, 123.456789012345, 3.5f, NAN, 61.25f, 4000};
  const auto bytes = encode_frame(info, x, t);
  std::ofstream(dir / "frame.bin", std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
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
  const std::string cmd = "node '" + (test::source_dir() / "web" / "test" / "protocol_roundtrip.mjs").string() + "' '" +
                          (dir / "frame.bin").string() + "' '" + (dir / "expected.json").string() + "' 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  const int rc = ::pclose(p);
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("protocol round trip ok"), std::string::npos) << out;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ff::server
