#include "sim/checkpoint.h"

#include <cstring>

namespace ff::sim {
namespace {
constexpr char kMagic[8] = {'F', 'F', 'C', 'K', 'P', 'T', '0', '1'};

struct Writer {
  std::vector<std::uint8_t> out;
  void raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  }
  template <class T>
  void pod(const T& v) { raw(&v, sizeof v); }
};

struct Reader {
  std::span<const std::uint8_t> in;
  std::size_t at = 0;
  bool raw(void* p, std::size_t n) {
    if (n > in.size() - at) return false;
    if (n == 0) return true;  // p may be an empty array's null data(): memcpy must not see it
    std::memcpy(p, in.data() + at, n);
    at += n;
    return true;
  }
  template <class T>
  bool pod(T& v) { return raw(&v, sizeof v); }
};
}  // namespace

std::uint64_t fnv1a(std::span<const std::uint8_t> bytes, std::uint64_t h) {
  for (std::uint8_t b : bytes) {
    h ^= b;
    h *= 1099511628211ull;
  }
  return h;
}

std::vector<std::uint8_t> encode_checkpoint(const Checkpoint& c) {
  Writer w;
  w.raw(kMagic, sizeof kMagic);
  w.pod(c.next_frame);
  w.pod(c.time);
  w.pod(c.scene_hash);
  w.pod(static_cast<std::uint64_t>(c.particles.size()));
  c.particles.for_each_state_array([&](const auto& a) {
    w.pod(static_cast<std::uint32_t>(sizeof(a[0])));
    w.raw(a.data(), a.size() * sizeof(a[0]));
  });
  w.pod(static_cast<std::uint64_t>(c.extra.size()));
  w.raw(c.extra.data(), c.extra.size());
  w.pod(fnv1a(w.out));
  return std::move(w.out);
}

Result<Checkpoint> decode_checkpoint(std::span<const std::uint8_t> bytes) {
  if (bytes.size() < sizeof kMagic + 8 || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    return input_error("checkpoint: not a fluidform checkpoint (or an older version)");
  std::uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + bytes.size() - 8, 8);
  if (fnv1a(bytes.first(bytes.size() - 8)) != stored) return input_error("checkpoint: checksum mismatch (file is corrupt)");
  Reader r{bytes.first(bytes.size() - 8), sizeof kMagic};
  Checkpoint c;
  std::uint64_t n = 0;
  if (!r.pod(c.next_frame) || !r.pod(c.time) || !r.pod(c.scene_hash) || !r.pod(n) || n > (1ull << 32))
    return input_error("checkpoint: truncated header");
  // The count is checked against the bytes there are before anything is allocated for it.
  std::size_t per_particle = 0;
  c.particles.for_each_state_array([&](const auto& a) { per_particle += sizeof(a[0]); });
  if (n > (r.in.size() - r.at) / per_particle) return input_error("checkpoint: truncated particle data");
  c.particles.resize(static_cast<std::size_t>(n));
  bool ok = true;
  c.particles.for_each_state_array([&](auto& a) {
    std::uint32_t elem = 0;
    ok = ok && r.pod(elem) && elem == sizeof(a[0]) && r.raw(a.data(), a.size() * sizeof(a[0]));
  });
  std::uint64_t extra = 0;
  if (!ok || !r.pod(extra) || extra > bytes.size()) return input_error("checkpoint: truncated particle data");
  c.extra.resize(static_cast<std::size_t>(extra));
  if (!r.raw(c.extra.data(), c.extra.size())) return input_error("checkpoint: truncated");
  return c;
}

}  // namespace ff::sim
