#include "io/picture.h"

#include "io/target_look.h"

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace ff::io {

std::size_t Picture::covered(const std::array<std::uint8_t, 3>& bg) const {
  std::size_t n = 0;
  for (std::size_t i = 0; i + 2 < rgb.size(); i += 3) n += rgb[i] != bg[0] || rgb[i + 1] != bg[1] || rgb[i + 2] != bg[2];
  return n;
}

namespace {

constexpr int kSuper = 2;  // samples per pixel along each axis

// The view's camera frame: right, up, towards the eye; and the scale that fits the box's bounding sphere.
struct Frame {
  Vec3f right, up, back, centre;
  float scale = 1.0f;  // supersampled pixels per metre
};

Frame camera(const PictureView& v) {
  Frame f;
  f.back = v.direction.normalized();
  const Vec3f side = Vec3f::UnitY().cross(f.back);
  f.right = side.squaredNorm() > 1e-12f ? Vec3f(side.normalized()) : Vec3f::UnitX();  // looking straight up or down
  f.up = f.back.cross(f.right);
  // An empty box (nothing to draw) gets a unit one at the origin.
  const Aabb box = v.box.empty() ? Aabb{Vec3f::Constant(-0.5f), Vec3f::Constant(0.5f)} : v.box;
  f.centre = 0.5f * (box.min + box.max);
  const float radius = std::max(0.5f * (box.max - box.min).norm(), 1e-9f);
  f.scale = 0.95f * float(kSuper) * float(std::min(v.width, v.height)) / (2.0f * radius);
  return f;
}

}  // namespace

Picture render_mesh(const TriangleMesh& mesh, const std::array<std::uint8_t, 3>& colour, const PictureView& view) {
  const Frame f = camera(view);
  const int W = view.width * kSuper, H = view.height * kSuper;
  std::vector<float> depth(std::size_t(W) * H, -std::numeric_limits<float>::infinity());
  std::vector<float> shade(std::size_t(W) * H, -1.0f);  // < 0: background
  // A mesh with vertex colours (the liquid's look) is drawn in them, interpolated in linear light, else in `colour`.
  const bool coloured = !mesh.colours.empty() && mesh.colours.size() == mesh.vertices.size();
  std::vector<Vec3f> tone(coloured ? shade.size() : 0);  // per sample: its colour, 0–255 sRGB
  std::vector<Vec3f> p(mesh.vertices.size());          // x, y in supersampled pixels, z towards the eye
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3f d = mesh.vertices[i] - f.centre;
    p[i] = Vec3f(0.5f * float(W) + f.scale * d.dot(f.right), 0.5f * float(H) - f.scale * d.dot(f.up), d.dot(f.back));
  }
  for (const auto& t : mesh.triangles) {
    const Vec3f &a = p[t[0]], &b = p[t[1]], &c = p[t[2]];
    const Vec3f n = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    const float len = n.norm();
    if (!(len > 0.0f)) continue;
    // Two-sided Lambert from a light a little above the eye, plus an ambient term.
    const Vec3f light = (f.back + 0.5f * f.up).normalized();
    const float s = 0.3f + 0.7f * std::abs(n.dot(light)) / len;
    const float area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12f) continue;
    // Clamped in float first: a vertex far outside the view (splashed liquid drawn in the target's view) or not
    // finite must not overflow the conversion to int.
    const auto px_lo = [](float v, int size) { return int(std::floor(std::clamp(v, -1.0f, float(size)))); };
    const auto px_hi = [](float v, int size) { return int(std::ceil(std::clamp(v, -1.0f, float(size)))); };
    if (!(a.allFinite() && b.allFinite() && c.allFinite())) continue;
    const int x0 = std::max(0, px_lo(std::min({a.x(), b.x(), c.x()}), W)),
              x1 = std::min(W - 1, px_hi(std::max({a.x(), b.x(), c.x()}), W)),
              y0 = std::max(0, px_lo(std::min({a.y(), b.y(), c.y()}), H)),
              y1 = std::min(H - 1, px_hi(std::max({a.y(), b.y(), c.y()}), H));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const float px = float(x) + 0.5f, py = float(y) + 0.5f;
        const float w0 = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area,
                    w1 = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area, w2 = 1.0f - w0 - w1;
        if (w0 < 0.0f || w1 < 0.0f || w2 < 0.0f) continue;
        const float z = w0 * a.z() + w1 * b.z() + w2 * c.z();
        const std::size_t k = std::size_t(y) * W + x;
        if (!(z > depth[k])) continue;
        depth[k] = z, shade[k] = s;
        if (coloured) {
          const Vec3f lin = w0 * mesh.colours[t[0]] + w1 * mesh.colours[t[1]] + w2 * mesh.colours[t[2]];
          tone[k] = Vec3f(linear_to_srgb(lin.x()), linear_to_srgb(lin.y()), linear_to_srgb(lin.z()));
        }
      }
  }
  // Down to the picture: the mean of each pixel's samples (a background sample counts as the background colour).
  Picture pic{view.width, view.height, std::vector<std::uint8_t>(std::size_t(view.width) * view.height * 3)};
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x)
      for (int ch = 0; ch < 3; ++ch) {
        float sum = 0.0f;
        for (int sy = 0; sy < kSuper; ++sy)
          for (int sx = 0; sx < kSuper; ++sx) {
            const std::size_t k = std::size_t(y * kSuper + sy) * W + (x * kSuper + sx);
            const float s = shade[k];
            sum += s < 0.0f ? float(view.background[ch]) : s * (coloured ? tone[k][ch] : float(colour[ch]));
          }
        pic.rgb[(std::size_t(y) * view.width + x) * 3 + ch] =
            static_cast<std::uint8_t>(std::clamp(std::lround(sum / float(kSuper * kSuper)), 0L, 255L));
      }
  return pic;
}

namespace {

Result<std::vector<std::uint8_t>> encode_rgb(int width, int height, const std::uint8_t* rgb) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  img.width = static_cast<png_uint_32>(width);
  img.height = static_cast<png_uint_32>(height);
  img.format = PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  if (!png_image_write_get_memory_size(img, size, 0, rgb, 0, nullptr))
    return io_error(fmt::format("PNG encoding failed: {}", img.message));
  std::vector<std::uint8_t> out(size);
  if (!png_image_write_to_memory(&img, out.data(), &size, 0, rgb, 0, nullptr))
    return io_error(fmt::format("PNG encoding failed: {}", img.message));
  out.resize(size);
  return out;
}

}  // namespace

Result<std::vector<std::uint8_t>> encode_png(const Picture& picture) {
  return encode_rgb(picture.width, picture.height, picture.rgb.data());
}

Result<std::vector<std::uint8_t>> encode_png(const Texture& texture) {
  return encode_rgb(texture.width, texture.height, texture.rgb.data());
}

Result<Picture> decode_png(std::span<const std::uint8_t> bytes) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&img, bytes.data(), bytes.size()))
    return input_error(fmt::format("not a PNG: {}", img.message));
  img.format = PNG_FORMAT_RGB;
  Picture pic{int(img.width), int(img.height), std::vector<std::uint8_t>(PNG_IMAGE_SIZE(img))};
  if (!png_image_finish_read(&img, nullptr, pic.rgb.data(), 0, nullptr)) {
    png_image_free(&img);
    return input_error(fmt::format("not a PNG: {}", img.message));
  }
  return pic;
}

}  // namespace ff::io
