#version 450
#extension GL_GOOGLE_include_directive : require
// Between frames: the largest |v|² (for the CFL sub-step rule) and the lowest index of a particle whose position or
// velocity is not finite (a blow-up). Both are integer atomics on values whose order does not depend on the order
// the invocations run in: |v|² ≥ 0, so its float bits order as unsigned integers, and a minimum is a minimum.
layout(local_size_x = 256) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer X { vec4 x[]; };
layout(std430, binding = 1) readonly buffer Vel { vec4 vel[]; };
layout(std430, binding = 2) buffer Result { uint max_v2_bits; uint first_bad; };

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w)) return;
  const vec3 p = x[i].xyz, v = vel[i].xyz;
  if (any(isnan(p)) || any(isinf(p)) || any(isnan(v)) || any(isinf(v))) {
    atomicMin(first_bad, i);
    return;
  }
  atomicMax(max_v2_bits, floatBitsToUint(dot(v, v)));
}
