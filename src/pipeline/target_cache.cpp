#include "pipeline/target_cache.h"

#include "io/load_mesh.h"
#include "sampling/control_io.h"
#include "sim/checkpoint.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstring>
#include <fstream>
#include <iterator>

namespace ff::pipeline {
namespace fs = std::filesystem;
namespace {

// Bumped whenever sampling changes what it makes for the same inputs, so stale caches are not reused.
// 2: MeshField keeps the inner faces of parts welded where they touch; 3: the relaxation's momentum (30 steps).
constexpr std::uint64_t kSamplingVersion = 3;

template <class T>
void put(std::vector<std::uint8_t>& b, const T& v) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
  b.insert(b.end(), p, p + sizeof(T));
}
void put_vec(std::vector<std::uint8_t>& b, const Vec3f& v) {
  for (int a = 0; a < 3; ++a) put(b, v[a]);
}

}  // namespace

Result<std::uint64_t> sampling_key(const scene::TargetSpec& target, const sampling::SamplingParams& p) {
  std::ifstream in(target.mesh, std::ios::binary);
  if (!in) return input_error(fmt::format("{}: cannot open the target mesh", target.mesh.string()));
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::uint64_t h = sim::fnv1a(bytes);
  std::vector<std::uint8_t> b;
  put(b, kSamplingVersion);
  put_vec(b, target.transform.scale);
  put_vec(b, target.transform.rotate_deg);
  put_vec(b, target.transform.translate);
  put(b, static_cast<int>(p.method));
  put(b, p.spacing);
  put(b, static_cast<std::uint64_t>(p.auto_count));
  put(b, p.seed);
  put(b, p.relax_steps);
  put(b, p.support_factor);
  put(b, p.phi_offset);
  put(b, p.rest_density);
  put(b, p.sparse.drop_fraction);
  for (const auto& box : p.sparse.drop_boxes) {
    put_vec(b, box.min);
    put_vec(b, box.max);
  }
  return sim::fnv1a(b, h);
}

Result<TargetControls> sample_target_cached(const scene::TargetSpec& target, const sampling::SamplingParams& params,
                                      std::uint8_t id, const fs::path& cache_dir, core::Progress& progress) {
  FF_TRY(const std::uint64_t key, sampling_key(target, params));
  TargetControls out;
  out.cache_file = cache_dir / fmt::format("controls_{:016x}.ply", key);
  std::error_code ec;
  if (fs::exists(out.cache_file, ec)) {
    std::uint64_t stored = 0;
    auto cached = sampling::read_controls_ply(out.cache_file, &stored);
    if (cached && stored == key) {
      out.set = std::move(*cached);
      out.set.target = id;
      out.from_cache = true;
      return out;
    }
    spdlog::warn("{}: unreadable or stale sample cache, sampling again", out.cache_file.string());
  }
  FF_TRY(io::TriangleMesh mesh, io::load_mesh(target.mesh, io::LoadOptions{target.transform}));
  FF_TRY(out.set, sampling::sample_target(mesh, params, id, &out.report, progress));
  fs::create_directories(cache_dir, ec);
  if (auto st = sampling::write_controls_ply(out.cache_file, out.set, key); !st.ok())
    spdlog::warn("could not write the sample cache {}: {}", out.cache_file.string(), st.error().message);
  return out;
}

}  // namespace ff::pipeline
