// Still pictures (io/picture.h): what the report page shows of target and formed shape, drawn without a GPU. A ball
// covers the disc an orthographic view of it must, sideways and up in the picture are the world's, the nearer of two
// shapes hides the other, and the PNG bytes read back to the same pixels.
#include "io/picture.h"
#include "support/shapes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace ff::io {
namespace {

constexpr std::array<std::uint8_t, 3> kBlue{47, 143, 216}, kOrange{208, 99, 43};

PictureView view_of(float half, int w = 300, int h = 300) {
  PictureView v;
  v.box.min = Vec3f::Constant(-half), v.box.max = Vec3f::Constant(half);
  v.direction = Vec3f(0, 0, 1);  // looking down −z: x right, y up
  v.width = w, v.height = h;
  return v;
}

// The mean pixel position of what is not background.
Vec3f centroid(const Picture& p, const std::array<std::uint8_t, 3>& bg) {
  double sx = 0, sy = 0, n = 0;
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x) {
      const std::uint8_t* c = &p.rgb[(std::size_t(y) * p.width + x) * 3];
      if (c[0] != bg[0] || c[1] != bg[1] || c[2] != bg[2]) sx += x, sy += y, n += 1;
    }
  return Vec3f(float(sx / n), float(sy / n), float(n));
}

TEST(Picture, ABallCoversItsDiscAndSidesAreTheWorlds) {
  const PictureView v = view_of(0.5f);
  const Picture p = render_mesh(test::uv_sphere(0.5f, 64), kBlue, v);
  ASSERT_EQ(p.rgb.size(), 300u * 300u * 3u);
  // The view fits the box's bounding sphere (radius 0.5·√3) into 95 % of the picture: the ball's disc has radius
  // 0.95 · 150 / √3 pixels.
  const double r = 0.95 * 150.0 / std::sqrt(3.0), disc = M_PI * r * r;
  EXPECT_NEAR(double(p.covered(v.background)), disc, 0.03 * disc);
  const Vec3f c = centroid(p, v.background);
  EXPECT_NEAR(c.x(), 149.5f, 1.0f);
  EXPECT_NEAR(c.y(), 149.5f, 1.0f);
  // Moved to +x and +y in the world: right and up (smaller row) in the picture.
  const Picture q = render_mesh(test::translate(test::uv_sphere(0.2f, 32), Vec3f(0.25f, 0.25f, 0.0f)), kBlue, v);
  const Vec3f d = centroid(q, v.background);
  EXPECT_GT(d.x(), 149.5f + 30.0f);
  EXPECT_LT(d.y(), 149.5f - 30.0f);
  // Lit: the middle of the ball (facing the eye) is brighter than its rim.
  const std::uint8_t* mid = &p.rgb[(150u * 300u + 150u) * 3];
  const std::uint8_t* rim = &p.rgb[(150u * 300u + std::size_t(150 + 0.97 * r)) * 3];
  EXPECT_GT(int(mid[2]), int(rim[2]));
}

// A square in the plane z = z0, tilted about the x axis by `tilt` radians (a different shade when tilted).
TriangleMesh square(float half, float z0, float tilt) {
  TriangleMesh m;
  const float c = std::cos(tilt) * half, s = std::sin(tilt) * half;
  m.vertices = {Vec3f(-half, -c, z0 - s), Vec3f(half, -c, z0 - s), Vec3f(half, c, z0 + s), Vec3f(-half, c, z0 + s)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TriangleMesh merged(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh m = a;
  const Index off = static_cast<Index>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto t : b.triangles) m.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  return m;
}

TEST(Picture, TheNearerShapeHidesTheOther) {
  const PictureView v = view_of(0.5f);
  const std::size_t centre = (150u * 300u + 150u) * 3;
  const Picture flat = render_mesh(square(0.4f, 0.0f, 0.0f), kBlue, v);
  const Picture tilted = render_mesh(square(0.2f, 0.0f, 0.8f), kBlue, v);
  ASSERT_NE(flat.rgb[centre + 2], tilted.rgb[centre + 2]) << "the two squares must shade differently for this test";
  // The small tilted square in front of the flat one (towards the eye, +z) shows at the centre; behind it, it does not.
  const Picture front = render_mesh(merged(square(0.4f, 0.0f, 0.0f), square(0.2f, 0.3f, 0.8f)), kBlue, v);
  const Picture back = render_mesh(merged(square(0.4f, 0.0f, 0.0f), square(0.2f, -0.3f, 0.8f)), kBlue, v);
  EXPECT_EQ(front.rgb[centre + 2], tilted.rgb[centre + 2]);
  EXPECT_EQ(back.rgb[centre + 2], flat.rgb[centre + 2]);
  // Whichever order the triangles come in.
  const Picture front2 = render_mesh(merged(square(0.2f, 0.3f, 0.8f), square(0.4f, 0.0f, 0.0f)), kBlue, v);
  EXPECT_EQ(front2.rgb, front.rgb);
}

// Looking straight down (the view's "up" is then not Y) and a triangle reaching far outside the view (liquid splashed
// far from a small target) or to a non-finite point: a picture, not a blank or a crash.
TEST(Picture, StraightDownAndFarOutsideTheView) {
  PictureView v = view_of(0.5f);
  v.direction = Vec3f(0, 1, 0);
  EXPECT_GT(render_mesh(test::uv_sphere(0.4f, 32), kBlue, v).covered(v.background), 10000u);
  v.direction = Vec3f(0, -1, 0);
  EXPECT_GT(render_mesh(test::uv_sphere(0.4f, 32), kBlue, v).covered(v.background), 10000u);
  TriangleMesh far = test::uv_sphere(0.3f, 16);
  far.vertices.push_back(Vec3f(1e30f, 0, 0)), far.vertices.push_back(Vec3f(0, -1e30f, 0));
  far.vertices.push_back(Vec3f(std::numeric_limits<float>::infinity(), 0, 0));
  const auto k = static_cast<Index>(far.vertices.size());
  far.triangles.push_back({0, k - 3, k - 2});
  far.triangles.push_back({0, 1, k - 1});
  // The ball (radius 0.3 m: a disc of ~49 pixels radius, ~7 500 pixels) is drawn whatever the far triangles do.
  EXPECT_GT(render_mesh(far, kBlue, view_of(0.5f)).covered(v.background), 7000u);
}

TEST(Picture, PngBytesReadBackToTheSamePixels) {
  const PictureView v = view_of(0.5f, 120, 80);
  const Picture p = render_mesh(test::uv_sphere(0.4f, 32), kOrange, v);
  auto png = encode_png(p);
  ASSERT_TRUE(png) << png.error().message;
  ASSERT_GT(png->size(), 8u);
  EXPECT_EQ((*png)[1], 'P');
  auto back = decode_png(*png);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->width, 120);
  EXPECT_EQ(back->height, 80);
  EXPECT_EQ(back->rgb, p.rgb);
  const std::vector<std::uint8_t> junk{1, 2, 3, 4, 5};
  EXPECT_FALSE(decode_png(junk));
}

}  // namespace
}  // namespace ff::io
