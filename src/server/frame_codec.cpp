#include "server/frame_codec.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
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

// Both messages start alike: magic, version, header bytes.
void put_preamble(std::vector<std::uint8_t>& b, std::uint32_t magic, std::uint16_t version, std::size_t header) {
  put(b, 0, magic);
  put(b, 4, version);
  put(b, 6, static_cast<std::uint16_t>(header));
}

// Checks the preamble of a `what` message; its header bytes (where the body starts).
Result<std::size_t> read_preamble(std::span<const std::uint8_t> b, std::uint32_t magic, std::uint16_t version,
                                  std::size_t min_header, const char* what) {
  if (b.size() < min_header) return input_error(fmt::format("{}: shorter than its header", what));
  if (get<std::uint32_t>(b, 0) != magic) return input_error(fmt::format("{}: wrong magic", what));
  if (get<std::uint16_t>(b, 4) != version) return input_error(fmt::format("{}: unknown version", what));
  const std::size_t header = get<std::uint16_t>(b, 6);
  if (header < min_header) return input_error(fmt::format("{}: header shorter than its fields", what));
  return header;
}

// Vertices (three floats) and triangles (three u32) go as they lie in memory.
static_assert(sizeof(Vec3f) == 12 && sizeof(std::array<Index, 3>) == 12 && sizeof(Index) == 4);
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
  put_preamble(b, kFrameMagic, kFrameVersion, kFrameHeaderBytes);
  put(b, 8, info.frame);
  put(b, 12, static_cast<std::uint32_t>(n));
  put(b, 16, info.time);
  put(b, 24, info.step_ms);
  put(b, 28, info.error_rate);
  put(b, 32, info.sim_fps);
  put(b, 36, info.controlled);
  for (int a = 0; a < 3; ++a) put(b, 40 + 4 * std::size_t(a), lo[a]), put(b, 52 + 4 * std::size_t(a), hi[a]);
  // In double: 65535 / (hi − lo) overflows a float for a box thinner than about 2e-34 (every particle then went to hi).
  Vec3d inv;
  for (int a = 0; a < 3; ++a) inv[a] = hi[a] > lo[a] ? 65535.0 / (double(hi[a]) - double(lo[a])) : 0.0;
  std::uint8_t* q = b.data() + kFrameHeaderBytes;
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      const double v = std::isfinite(x[i][a]) ? std::clamp((double(x[i][a]) - lo[a]) * inv[a], 0.0, 65535.0) : 0.0;
      const auto u = static_cast<std::uint16_t>(std::lround(v));
      std::memcpy(q + 6 * i + 2 * std::size_t(a), &u, 2);
    }
  std::uint8_t* t = b.data() + kFrameHeaderBytes + 6 * n;
  if (targets.size() == n) std::copy(targets.begin(), targets.end(), t);
  else std::fill(t, t + n, std::uint8_t{255});
  return b;
}

Result<DecodedFrame> decode_frame(std::span<const std::uint8_t> b) {
  FF_TRY(const std::size_t header, read_preamble(b, kFrameMagic, kFrameVersion, kFrameHeaderBytes, "frame"));
  const std::size_t n = get<std::uint32_t>(b, 12);
  if (b.size() < header + 7 * n) return input_error("frame: shorter than its particles");
  DecodedFrame f;
  f.info.frame = get<std::uint32_t>(b, 8);
  f.info.time = get<double>(b, 16);
  f.info.step_ms = get<float>(b, 24);
  f.info.error_rate = get<float>(b, 28);
  f.info.sim_fps = get<float>(b, 32);
  f.info.controlled = get<std::uint32_t>(b, 36);
  for (int a = 0; a < 3; ++a) f.lo[a] = get<float>(b, 40 + 4 * std::size_t(a)), f.hi[a] = get<float>(b, 52 + 4 * std::size_t(a));
  f.positions.resize(n);
  // In double, as the viewer does (web/src/protocol.js): in float the step of a very thin box is a denormal that
  // has lost its precision, and hi − lo of a very wide one overflows.
  const Vec3d lo = f.lo.cast<double>(), step = (f.hi.cast<double>() - lo) / 65535.0;
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a)
      f.positions[i][a] =
          static_cast<float>(lo[a] + step[a] * double(get<std::uint16_t>(b, header + 6 * i + 2 * std::size_t(a))));
  f.targets.assign(b.begin() + std::ptrdiff_t(header + 6 * n), b.begin() + std::ptrdiff_t(header + 7 * n));
  return f;
}

std::vector<std::uint8_t> encode_surface(const SurfaceInfo& info, const io::TriangleMesh& mesh) {
  const std::size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  std::vector<std::uint8_t> b(kSurfaceHeaderBytes + 12 * nv + 12 * nt, 0);
  put_preamble(b, kSurfaceMagic, kSurfaceVersion, kSurfaceHeaderBytes);
  put(b, 8, info.frame);
  put(b, 12, static_cast<std::uint32_t>(nv));
  put(b, 16, info.time);
  put(b, 24, static_cast<std::uint32_t>(nt));
  put(b, 28, info.build_ms);
  if (nv) std::memcpy(b.data() + kSurfaceHeaderBytes, mesh.vertices.data(), 12 * nv);
  if (nt) std::memcpy(b.data() + kSurfaceHeaderBytes + 12 * nv, mesh.triangles.data(), 12 * nt);
  return b;
}

Result<DecodedSurface> decode_surface(std::span<const std::uint8_t> b) {
  FF_TRY(const std::size_t header, read_preamble(b, kSurfaceMagic, kSurfaceVersion, kSurfaceHeaderBytes, "surface"));
  const std::size_t nv = get<std::uint32_t>(b, 12), nt = get<std::uint32_t>(b, 24);
  if (b.size() < header + 12 * nv + 12 * nt) return input_error("surface: shorter than its mesh");
  DecodedSurface s;
  s.info.frame = get<std::uint32_t>(b, 8);
  s.info.time = get<double>(b, 16);
  s.info.build_ms = get<float>(b, 28);
  s.mesh.vertices.resize(nv);
  s.mesh.triangles.resize(nt);
  if (nv) std::memcpy(static_cast<void*>(s.mesh.vertices.data()), b.data() + header, 12 * nv);  // float triples
  if (nt) std::memcpy(s.mesh.triangles.data(), b.data() + header + 12 * nv, 12 * nt);
  for (const auto& t : s.mesh.triangles)
    for (const Index v : t)
      if (v >= nv) return input_error("surface: a triangle names a vertex out of range");
  return s;
}

}  // namespace ff::server
