#pragma once
// A skin's clips evaluated (io/skin.h holds what the file says: nodes, joints, weights, keys): every node's global
// matrix at a clip time, the joints' skinning matrices, and a clip baked to play back and forth.
#include "io/skin.h"

#include <vector>

namespace ff::pose {

/// Every node's global matrix (file scene space) with clip `clip` of `skin` at time `t` (s, clamped to
/// [0, duration]); clip −1 is the rest pose (io::Skin::rest_matrices). Keys are interpolated linearly (rotations by
/// slerp, the shorter arc).
void global_matrices(const io::Skin& skin, int clip, double t, std::vector<io::Mat4f>& out);
/// Skinning matrices G_{node(j)}(t) · inverse_bind[j] per joint (file scene space).
void joint_matrices(const io::Skin& skin, int clip, double t, std::vector<io::Mat4f>& out);

/// `clip` played forwards and then backwards, as one clip of twice its duration named "NAME pingpong" ("clip
/// pingpong" for a clip without a name): each key at time t is kept and mirrored to 2·duration − t. Looping it never
/// jumps, as pose::ClipWrap::PingPong plays.
io::AnimationClip pingpong_clip(const io::AnimationClip& clip);

}  // namespace ff::pose
