// How a looped clip starts over (pose::ClipWrap): repeated, it jumps back to its first pose; played back and forth
// (pingpong), its clip time runs forwards and backwards and never jumps; pose::pingpong_clip bakes that into one clip of
// twice the duration, which rigged.glb carries. The skeleton is the hand-built bar of tests/support/skin_bar.h: its
// "bend" clip ends far from where it starts (the root slid 0.2 m, the upper half turned 90°).
#include "pose/skinning.h"
#include "pose/skin_eval.h"
#include "io/skin.h"
#include "support/skin_bar.h"

#include <gtest/gtest.h>

namespace ff::pose {
namespace {

TargetSkin bend_skin(bool loop, bool pingpong) {
  TargetSkin s;
  s.skin = test::bar_skin(test::bar_mesh(4, 8));
  s.clip = 0;  // "bend", 1 s
  s.spec.clip = "bend";
  s.spec.loop = loop;
  s.spec.speed = 2.0;
  s.spec.start = 0.5;
  s.pingpong = pingpong;
  return s;
}

TEST(ClipWrap, ClipTimeRepeatsHoldsOrRunsBackAndForth) {
  const TargetSkin repeat = bend_skin(true, false), hold = bend_skin(false, false), pingpong = bend_skin(true, true);
  // τ = 2 (t − 0.5): before the start, the first pose.
  for (const TargetSkin* s : {&repeat, &hold, &pingpong}) EXPECT_DOUBLE_EQ(s->clip_time(0.2), 0.0);
  // t = 0.6, 1.1, 1.4, 1.9, 2.6 → τ unwrapped 0.2, 1.2, 1.8, 2.8, 4.2
  const double t[] = {0.6, 1.1, 1.4, 1.9, 2.6};
  const double want_repeat[] = {0.2, 0.2, 0.8, 0.8, 0.2};
  const double want_hold[] = {0.2, 1.0, 1.0, 1.0, 1.0};
  const double want_pingpong[] = {0.2, 0.8, 0.2, 0.8, 0.2};
  // At the clip's ends: repeated, τ = 1 starts over at 0; back and forth, it turns at 1 and is back at 0 at τ = 2.
  EXPECT_DOUBLE_EQ(repeat.clip_time(1.0), 0.0);
  EXPECT_DOUBLE_EQ(pingpong.clip_time(1.0), 1.0);
  EXPECT_DOUBLE_EQ(pingpong.clip_time(1.5), 0.0);
  EXPECT_DOUBLE_EQ(hold.clip_time(1.5), 1.0);
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(repeat.clip_time(t[k]), want_repeat[k], 1e-12) << t[k];
    EXPECT_NEAR(hold.clip_time(t[k]), want_hold[k], 1e-12) << t[k];
    EXPECT_NEAR(pingpong.clip_time(t[k]), want_pingpong[k], 1e-12) << t[k];
  }
  // Through the wraps (τ = 1, 2, 3, …), played back and forth the clip time moves by the same small step each frame;
  // repeated it jumps by the whole clip.
  double worst_pingpong = 0.0, worst_repeat = 0.0;
  const double dt = 1.0 / 600.0;
  for (double time = 0.5; time < 3.0; time += dt) {
    worst_pingpong = std::max(worst_pingpong, std::abs(pingpong.clip_time(time + dt) - pingpong.clip_time(time)));
    worst_repeat = std::max(worst_repeat, std::abs(repeat.clip_time(time + dt) - repeat.clip_time(time)));
  }
  EXPECT_LE(worst_pingpong, 2.0 * dt + 1e-9);
  EXPECT_GT(worst_repeat, 0.9);
}

TEST(ClipWrap, APingpongClipPlaysTheClipThenItsMirror) {
  const io::Skin skin = test::bar_skin(test::bar_mesh(4, 8));
  for (int c = 0; c < 2; ++c) {
    const io::AnimationClip& clip = skin.clips[static_cast<std::size_t>(c)];
    io::Skin baked = skin;
    baked.clips.push_back(pose::pingpong_clip(clip));
    const int p = static_cast<int>(baked.clips.size()) - 1;
    EXPECT_EQ(baked.clips.back().name, clip.name + " pingpong");
    EXPECT_DOUBLE_EQ(baked.clips.back().duration, 2.0 * clip.duration);
    for (const io::NodeChannel& ch : baked.clips.back().channels)
      for (const auto* times : {&ch.translation_times, &ch.rotation_times, &ch.scale_times})
        for (std::size_t k = 1; k < times->size(); ++k) EXPECT_LT((*times)[k - 1], (*times)[k]) << clip.name;
    // A key at the clip's end is not doubled: every channel ends at 2 · duration with its first key's value.
    for (const io::NodeChannel& ch : baked.clips.back().channels)
      if (!ch.rotation_times.empty()) {
        EXPECT_DOUBLE_EQ(ch.rotation_times.back(), 2.0 * clip.duration);
        EXPECT_TRUE(ch.rotations.back().isApprox(ch.rotations.front()));
      }
    std::vector<io::Mat4f> a, b;
    for (int k = 0; k <= 40; ++k) {
      const double s = 2.0 * clip.duration * k / 40.0;
      pose::global_matrices(baked, p, s, a);
      pose::global_matrices(skin, c, s <= clip.duration ? s : 2.0 * clip.duration - s, b);
      for (std::size_t n = 0; n < a.size(); ++n) EXPECT_TRUE(a[n].isApprox(b[n], 1e-5f)) << clip.name << " at " << s;
    }
  }
}

TEST(ClipWrap, KeysInsideTheClipAndANamelessClip) {
  // Keys at 0.25 and 0.5 s of a 1 s clip: held before and after, mirrored about 1 s; a clip without a name.
  io::AnimationClip clip;
  clip.duration = 1.0;
  io::NodeChannel ch;
  ch.node = 2;
  ch.rotation_times = {0.25, 0.5};
  ch.rotations = {test::about(Vec3f::UnitZ(), 10), test::about(Vec3f::UnitZ(), 60)};
  clip.channels = {ch};
  const io::AnimationClip p = pose::pingpong_clip(clip);
  EXPECT_EQ(p.name, "clip pingpong");
  ASSERT_EQ(p.channels[0].rotation_times.size(), 4u);
  const double want[] = {0.25, 0.5, 1.5, 1.75};
  for (int k = 0; k < 4; ++k) EXPECT_DOUBLE_EQ(p.channels[0].rotation_times[static_cast<std::size_t>(k)], want[k]);
  io::Skin skin = test::bar_skeleton();
  skin.clips = {clip, p};
  std::vector<io::Mat4f> a, b;
  for (double s : {0.0, 0.1, 0.4, 0.75, 1.0, 1.25, 1.6, 1.9, 2.0}) {
    pose::global_matrices(skin, 1, s, a);
    pose::global_matrices(skin, 0, s <= 1.0 ? s : 2.0 - s, b);
    for (std::size_t n = 0; n < a.size(); ++n) EXPECT_TRUE(a[n].isApprox(b[n], 1e-5f)) << s;
  }
}

}  // namespace
}  // namespace ff::pose
