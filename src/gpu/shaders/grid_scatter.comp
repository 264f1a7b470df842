#version 450
#extension GL_GOOGLE_include_directive : require
// Counting sort, step 3: every particle into its cell's run of `items`. The slot an atomic hands out depends on
// the order the invocations run in; grid_order.comp then sorts each run by particle index, so nothing downstream
// sees that order.
layout(local_size_x = 256) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Cell { uint cell[]; };
layout(std430, binding = 1) readonly buffer Start { uint start[]; };
layout(std430, binding = 2) buffer Cursor { uint cursor[]; };
layout(std430, binding = 3) writeonly buffer Items { uint items[]; };

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w)) return;
  const uint c = cell[i];
  items[start[c] + atomicAdd(cursor[c], 1u)] = i;
}
