#include "sim/particle_set.h"

#include "core/neighbor_grid.h"
#include "sim/checkpoint.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace ff::sim {
namespace {

ParticleSet random_set(std::size_t n) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  ParticleSet p;
  for (std::size_t i = 0; i < n; ++i) p.push_back(Vec3f(u(rng), u(rng), u(rng)), Vec3f(u(rng), u(rng), u(rng)),
                                                  static_cast<std::uint8_t>(i % 3));
  for (std::size_t i = 0; i < n; ++i) p.bound_control[i] = static_cast<Index>(i * 7);
  return p;
}

TEST(ParticleSet, EveryArrayHasSize) {
  auto p = random_set(100);
  EXPECT_TRUE(p.consistent());
  p.resize(150);
  EXPECT_TRUE(p.consistent());
  EXPECT_EQ(p.bound_control[149], kInvalidIndex);
  p.position.push_back(Vec3f::Zero());
  EXPECT_FALSE(p.consistent());
}

TEST(ParticleSet, ReorderThenInverseIsIdentity) {
  const auto original = random_set(500);
  auto p = original;
  std::vector<Index> perm(p.size());
  for (Index i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), std::mt19937(3));
  ReorderScratch s;
  reorder(p, perm, s);
  EXPECT_EQ(p.id[0], original.id[perm[0]]);
  EXPECT_EQ(p.position[5], original.position[perm[5]]);
  reorder(p, core::inverse_permutation(perm), s);
  EXPECT_EQ(p.position, original.position);
  EXPECT_EQ(p.velocity, original.velocity);
  EXPECT_EQ(p.bound_control, original.bound_control);
  EXPECT_EQ(p.target, original.target);
  EXPECT_EQ(p.id, original.id);
  EXPECT_TRUE(p.consistent());
}

TEST(ParticleSet, SortedByIdUndoesAnyOrder) {
  const auto original = random_set(300);
  auto p = original;
  std::vector<Index> perm(p.size());
  for (Index i = 0; i < perm.size(); ++i) perm[i] = Index(perm.size() - 1 - i);
  ReorderScratch s;
  reorder(p, perm, s);
  std::vector<Vec3f> x, v;
  std::vector<std::uint8_t> t;
  sorted_by_id(p, x, v, t);
  EXPECT_EQ(x, original.position);
  EXPECT_EQ(v, original.velocity);
  EXPECT_EQ(t, original.target);
}

TEST(Checkpoint, RoundTripsEveryStateArray) {
  Checkpoint c{42, 0.7, 0x1234, "{\"rows\":[]}", random_set(257)};
  const auto bytes = encode_checkpoint(c);
  auto back = decode_checkpoint(bytes);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->next_frame, 42);
  EXPECT_EQ(back->time, 0.7);
  EXPECT_EQ(back->scene_hash, 0x1234u);
  EXPECT_EQ(back->extra, c.extra);
  EXPECT_EQ(back->particles.position, c.particles.position);
  EXPECT_EQ(back->particles.velocity, c.particles.velocity);
  EXPECT_EQ(back->particles.id, c.particles.id);
  EXPECT_EQ(back->particles.bound_control, c.particles.bound_control);
  EXPECT_EQ(back->particles.target, c.particles.target);
}

TEST(Checkpoint, CorruptOrTruncatedIsAnError) {
  Checkpoint c{1, 0.0, 0, "", random_set(10)};
  auto bytes = encode_checkpoint(c);
  auto flipped = bytes;
  flipped[40] ^= 0xff;
  EXPECT_FALSE(decode_checkpoint(flipped).has_value());
  bytes.resize(bytes.size() / 2);
  EXPECT_FALSE(decode_checkpoint(bytes).has_value());
  EXPECT_FALSE(decode_checkpoint(std::vector<std::uint8_t>{}).has_value());
}

}  // namespace
}  // namespace ff::sim
