#version 450
#extension GL_GOOGLE_include_directive : require
// The end of a Jacobi sweep: x* ← next (skipped once the sub-step's sweeps are done).
layout(local_size_x = 256) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Next { vec4 next[]; };
layout(std430, binding = 1) writeonly buffer Pos { vec4 pos[]; };
layout(std430, binding = 2) readonly buffer SweepState { uint done; uint sweeps; float mean; uint max_bits; uint total; float last_max; } state;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (state.done != 0u || i >= uint(C.grid_dims.w)) return;
  pos[i] = next[i];
}
