#version 450
#extension GL_GOOGLE_include_directive : require
// After a sweep's λ pass: the compression C_i = max(ρ_i/ρ0 − 1, 0) summed per workgroup by a fixed-shape tree in
// shared memory (the same additions in the same order on every run), and its largest value (its float bits order as
// integers, C ≥ 0). Skipped once the sub-step's sweeps are done (sweep_state.done).
layout(local_size_x = 256) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Density { float density[]; };
layout(std430, binding = 1) writeonly buffer Partial { float partial[]; };
layout(std430, binding = 2) buffer SweepState { uint done; uint sweeps; float mean; uint max_bits; uint total; float last_max; } state;
shared float part[256];

void main() {
  if (state.done != 0u) return;
  const uint i = gl_GlobalInvocationID.x, t = gl_LocalInvocationID.x;
  const float c = i < uint(C.grid_dims.w) ? max(density[i] / C.k1.y - 1.0, 0.0) : 0.0;
  part[t] = c;
  if (c > 0.0) atomicMax(state.max_bits, floatBitsToUint(c));
  barrier();
  for (uint s = 128u; s > 0u; s >>= 1) {
    if (t < s) part[t] += part[t + s];
    barrier();
  }
  if (t == 0u) partial[gl_WorkGroupID.x] = part[0];
}
