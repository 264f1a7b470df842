#version 450
#extension GL_GOOGLE_include_directive : require
// After a sweep: the mean compression from the workgroups' partial sums (one workgroup, a fixed-shape sum), one more
// sweep counted, and the sub-step's sweeps done once at least `iterations` have run and the mean is at most the
// target (sim/pbf_solver.cpp, substep(): SPlisHSPlasH's stopping rule). k3.z: iterations, k3.w: the target.
layout(local_size_x = 256) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Partial { float partial[]; };
layout(std430, binding = 1) buffer SweepState { uint done; uint sweeps; float mean; uint max_bits; uint total; float last_max; } state;
shared float part[256];

void main() {
  if (state.done != 0u) return;
  const uint t = gl_LocalInvocationID.x;
  const uint n = uint(C.grid_dims.w), groups = (n + 255u) / 256u;
  float s = 0.0;
  for (uint g = t; g < groups; g += 256u) s += partial[g];
  part[t] = s;
  barrier();
  for (uint k = 128u; k > 0u; k >>= 1) {
    if (t < k) part[t] += part[t + k];
    barrier();
  }
  if (t == 0u) {
    const float mean = part[0] / float(n);
    state.mean = mean;
    state.last_max = uintBitsToFloat(state.max_bits);  // this sweep's; the next sweep's starts from 0
    state.max_bits = 0u;
    state.sweeps += 1u;
    state.total += 1u;
    if (state.sweeps >= uint(C.k3.z) && mean <= C.k3.w) state.done = 1u;
  }
}
