// The live viewer's particle frame (server/frame_codec.h): any bytes through decode_frame (what a tool or test reads),
// and the same bytes as a frame to send (positions from its floats, targets from its bytes) through encode_frame and
// back, which must give every finite position to within half a quantisation step and every target exactly.
#include "fuzz_target.h"
#include "server/frame_codec.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <vector>

FF_FUZZ_TARGET(frame) {
  using namespace ff;
  if (auto f = server::decode_frame({data, size}); !f) {
    fuzz::check_refusal(f.error());
  } else {
    FF_FUZZ_CHECK(f->targets.size() == f->positions.size());
  }

  // 13 bytes a particle: three floats and a target.
  const std::size_t n = size / 13;
  std::vector<Vec3f> x(n);
  std::vector<std::uint8_t> t(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::memcpy(x[i].data(), data + 13 * i, 12);
    t[i] = data[13 * i + 12];
  }
  const bool with_targets = size % 2 == 0;  // also the frame without targets (all free fluid)
  server::FrameInfo info;
  info.frame = static_cast<std::uint32_t>(size);
  const auto bytes = server::encode_frame(info, x, with_targets ? std::span<const std::uint8_t>(t) : std::span<const std::uint8_t>());
  FF_FUZZ_CHECK(bytes.size() % 4 == 0);
  auto back = server::decode_frame(bytes);
  FF_FUZZ_CHECK(back.has_value());
  FF_FUZZ_CHECK(back->positions.size() == n && back->info.frame == info.frame);
  for (std::size_t i = 0; i < n; ++i) FF_FUZZ_CHECK(back->targets[i] == (with_targets ? t[i] : 255));
  const Vec3f lo = back->lo, hi = back->hi;
  if (!((hi - lo).allFinite())) return 0;  // a box wider than the float range: no step to promise
  const Vec3f half_step = server::quantisation_step(lo, hi);
  constexpr float eps = std::numeric_limits<float>::epsilon();
  for (std::size_t i = 0; i < n; ++i) {
    if (!x[i].allFinite()) continue;  // sent as lo
    for (int a = 0; a < 3; ++a) {
      const float tol = 1.01f * half_step[a] + 4.0f * eps * (std::abs(lo[a]) + std::abs(hi[a])) +
                        std::numeric_limits<float>::denorm_min();
      if (!(std::abs(back->positions[i][a] - x[i][a]) <= tol))
        std::fprintf(stderr, "particle %zu axis %d: sent %.9g, got %.9g (box %.9g .. %.9g, tolerance %.9g)\n", i, a,
                     double(x[i][a]), double(back->positions[i][a]), double(lo[a]), double(hi[a]), double(tol));
      FF_FUZZ_CHECK(std::abs(back->positions[i][a] - x[i][a]) <= tol);
    }
  }
  return 0;
}
