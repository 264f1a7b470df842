#include "server/frame_codec.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

namespace ff::server {

static_assert(std::endian::native == std::endian::little, "the frame layout is little-endian; so is every target");

namespace {
template <class T>
void put(std::vector<std::uint8_t>& b, std::size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof(T));
}
template <class T>
T get(std::span<const std::uint8_t> b, std::size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof(T));
  return v;
}
}  // namespace

Vec3f quantisation_step(const Vec3f& lo, const Vec3f& hi) { return 0.5f * (hi - lo) / 65535.0f; }

std::vector<std::uint8_t> encode_frame(const FrameInfo& info, std::span<const Vec3f> x,
                                       std::span<const std::uint8_t> targets) {
  const std::size_t n = x.size();
  Vec3f lo = Vec3f::Constant(INFINITY), hi = Vec3f::Constant(-INFINITY);
  for (const auto& p : x)
    if (p.allFinite()) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  if (!(lo.x() <= hi.x())) lo = hi = Vec3f::Zero();  // no finite position
  const std::size_t body = kFrameHeaderBytes + 7 * n;
  std::vector<std::uint8_t> b((body + 3) / 4 * 4, 0);
  put(b, 0, kFrameMagic);
  put(b, 4, kFrameVersion);
  put(b, 6, static_cast<std::uint16_t>(kFrameHeaderBytes));
  put(b, 8, info.frame);
  put(b, 12, static_cast<std::uint32_t>(n));
  put(b, 16, info.time);
  put(b, 24, info.step_ms);
  put(b, 28, info.error_rate);
  put(b, 32, info.sim_fps);
  put(b, 36, info.controlled);
  for (int a = 0; a < 3; ++a) put(b, 40 + 4 * std::size_t(a), lo[a]), put(b, 52 + 4 * std::size_t(a), hi[a]);
  Vec3f inv;
  for (int a = 0; a < 3; ++a) inv[a] = hi[a] > lo[a] ? 65535.0f / (hi[a] - lo[a]) : 0.0f;
  std::uint8_t* q = b.data() + kFrameHeaderBytes;
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      const float v = std::isfinite(x[i][a]) ? std::clamp((x[i][a] - lo[a]) * inv[a], 0.0f, 65535.0f) : 0.0f;
      const auto u = static_cast<std::uint16_t>(std::lround(v));
      std::memcpy(q + 6 * i + 2 * std::size_t(a), &u, 2);
    }
  std::uint8_t* t = b.data() + kFrameHeaderBytes + 6 * n;
  if (targets.size() == n) std::copy(targets.begin(), targets.end(), t);
  else std::fill(t, t + n, std::uint8_t{255});
  return b;
}

Result<DecodedFrame> decode_frame(std::span<const std::uint8_t> b) {
  if (b.size() < kFrameHeaderBytes) return input_error("frame: shorter than its header");
  if (get<std::uint32_t>(b, 0) != kFrameMagic) return input_error("frame: wrong magic");
  if (get<std::uint16_t>(b, 4) != kFrameVersion) return input_error("frame: unknown version");
  const std::size_t header = get<std::uint16_t>(b, 6);
  const std::size_t n = get<std::uint32_t>(b, 12);
  if (header < kFrameHeaderBytes || b.size() < header + 7 * n) return input_error("frame: shorter than its particles");
  DecodedFrame f;
  f.info.frame = get<std::uint32_t>(b, 8);
  f.info.time = get<double>(b, 16);
  f.info.step_ms = get<float>(b, 24);
  f.info.error_rate = get<float>(b, 28);
  f.info.sim_fps = get<float>(b, 32);
  f.info.controlled = get<std::uint32_t>(b, 36);
  for (int a = 0; a < 3; ++a) f.lo[a] = get<float>(b, 40 + 4 * std::size_t(a)), f.hi[a] = get<float>(b, 52 + 4 * std::size_t(a));
  f.positions.resize(n);
  const Vec3f step = (f.hi - f.lo) / 65535.0f;
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a)
      f.positions[i][a] = f.lo[a] + step[a] * float(get<std::uint16_t>(b, header + 6 * i + 2 * std::size_t(a)));
  f.targets.assign(b.begin() + std::ptrdiff_t(header + 6 * n), b.begin() + std::ptrdiff_t(header + 7 * n));
  return f;
}

std::vector<std::uint8_t> encode_surface(const SurfaceInfo& info, const io::TriangleMesh& mesh) {
  const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  std::vector<std::uint8_t> b(kSurfaceHeaderBytes + 12 * nv + 12 * nt, 0);
  put(b, 0, kSurfaceMagic);
  put(b, 4, kSurfaceVersion);
  put(b, 6, static_cast<std::uint16_t>(kSurfaceHeaderBytes));
  put(b, 8, info.frame);
  put(b, 12, static_cast<std::uint32_t>(nv));
  put(b, 16, info.time);
  put(b, 24, static_cast<std::uint32_t>(nt));
  put(b, 28, info.build_ms);
  for (std::size_t i = 0; i < nv; ++i)
    for (int a = 0; a < 3; ++a) put(b, kSurfaceHeaderBytes + 12 * i + 4 * std::size_t(a), mesh.vertices[i][a]);
  const std::size_t tri = kSurfaceHeaderBytes + 12 * nv;
  for (std::size_t i = 0; i < nt; ++i)
    for (int a = 0; a < 3; ++a) put(b, tri + 12 * i + 4 * std::size_t(a), static_cast<std::uint32_t>(mesh.triangles[i][a]));
  return b;
}

Result<DecodedSurface> decode_surface(std::span<const std::uint8_t> b) {
  if (b.size() < kSurfaceHeaderBytes) return input_error("surface: shorter than its header");
  if (get<std::uint32_t>(b, 0) != kSurfaceMagic) return input_error("surface: wrong magic");
  if (get<std::uint16_t>(b, 4) != kSurfaceVersion) return input_error("surface: unknown version");
  const std::size_t header = get<std::uint16_t>(b, 6);
  const std::size_t nv = get<std::uint32_t>(b, 12), nt = get<std::uint32_t>(b, 24);
  if (header < kSurfaceHeaderBytes || b.size() < header + 12 * nv + 12 * nt) return input_error("surface: shorter than its mesh");
  DecodedSurface s;
  s.info.frame = get<std::uint32_t>(b, 8);
  s.info.time = get<double>(b, 16);
  s.info.build_ms = get<float>(b, 28);
  s.mesh.vertices.resize(nv);
  for (std::size_t i = 0; i < nv; ++i)
    for (int a = 0; a < 3; ++a) s.mesh.vertices[i][a] = get<float>(b, header + 12 * i + 4 * std::size_t(a));
  s.mesh.triangles.resize(nt);
  const std::size_t tri = header + 12 * nv;
  for (std::size_t i = 0; i < nt; ++i)
    for (int a = 0; a < 3; ++a) {
      const std::uint32_t v = get<std::uint32_t>(b, tri + 12 * i + 4 * std::size_t(a));
      if (v >= nv) return input_error("surface: a triangle names a vertex out of range");
      s.mesh.triangles[i][a] = static_cast<Index>(v);
    }
  return s;
}

}  // namespace ff::server
