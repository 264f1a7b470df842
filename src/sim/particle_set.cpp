#include "sim/particle_set.h"

#include "core/neighbor_grid.h"

namespace ff::sim {

void ParticleSet::push_back(const Vec3f& x, const Vec3f& v, std::uint8_t target_id) {
  const auto n = static_cast<Index>(size());
  resize(size() + 1);
  position[n] = x;
  velocity[n] = v;
  target[n] = target_id;
  id[n] = n;
}

void ParticleSet::resize(std::size_t n) {
  position.resize(n, Vec3f::Zero());
  velocity.resize(n, Vec3f::Zero());
  bound_control.resize(n, kInvalidIndex);
  target.resize(n, kFreeFluid);
  id.resize(n, kInvalidIndex);
  acceleration.resize(n, Vec3f::Zero());
  predicted.resize(n, Vec3f::Zero());
  density.resize(n, 0.0f);
  lambda.resize(n, 0.0f);
  shift.resize(n, Vec3f::Zero());
}

bool ParticleSet::consistent() const {
  bool ok = true;
  const std::size_t n = size();
  for_each_array([&](const auto& a) { ok = ok && a.size() == n; });
  return ok;
}

std::size_t ParticleSet::bytes() const {
  std::size_t b = 0;
  for_each_array([&](const auto& a) { b += a.capacity() * sizeof(a[0]); });
  return b;
}

namespace {
std::vector<Vec3f>& scratch_for(ReorderScratch& s, const std::vector<Vec3f>&) { return s.v3; }
[[maybe_unused]] std::vector<float>& scratch_for(ReorderScratch& s, const std::vector<float>&) { return s.f32; }
std::vector<Index>& scratch_for(ReorderScratch& s, const std::vector<Index>&) { return s.u32; }
std::vector<std::uint8_t>& scratch_for(ReorderScratch& s, const std::vector<std::uint8_t>&) { return s.u8; }
}  // namespace

void reorder(ParticleSet& p, std::span<const Index> perm, ReorderScratch& scratch) {
  p.for_each_state_array([&](auto& a) { core::apply_permutation(a, perm, scratch_for(scratch, a)); });
  p.resize(p.size());
}

void sorted_by_id(const ParticleSet& p, std::vector<Vec3f>& x, std::vector<Vec3f>& v, std::vector<std::uint8_t>& t) {
  const std::size_t n = p.size();
  x.resize(n);
  v.resize(n);
  t.resize(n);
  // ids are a permutation of [0, n) (particles are never removed), so this is a scatter by id.
  for (std::size_t i = 0; i < n; ++i) {
    const Index k = p.id[i];
    x[k] = p.position[i];
    v[k] = p.velocity[i];
    t[k] = p.target[i];
  }
}

}  // namespace ff::sim
