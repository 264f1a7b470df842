#version 450
#extension GL_GOOGLE_include_directive : require
// Surface tension, step 3 (sim/surface_tension.cpp, smooth_and_accelerate): a surface particle's normal and
// curvature blended with its surface neighbours' (weights 1 − r/h, τ), and a += −(σ/m) κ n̂.
layout(local_size_x = 128) in;
#include "surface.glsl"
layout(std430, binding = 0) readonly buffer Pos { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Cell { uint cell[]; };
layout(std430, binding = 2) readonly buffer Start { uint start[]; };
layout(std430, binding = 3) readonly buffer Items { uint items[]; };
layout(std430, binding = 4) readonly buffer Class { uint cls[]; };
layout(std430, binding = 5) readonly buffer Normal { vec4 normal[]; };
layout(std430, binding = 6) readonly buffer Curv { float curv[]; };
layout(std430, binding = 7) buffer Accel { vec4 accel[]; };

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w) || cls[i] != 1u) return;
  const float h = C.s0.x, h2 = h * h, inv_h = 1.0 / h, tau = C.s2.x;
  const vec3 xi = pos[i].xyz;
  const ivec3 ci = cell_of_index(cell[i]);
  vec3 nsum = vec3(0.0);
  float ksum = 0.0, wsum = 0.0;
  FOR_CELLS_AROUND(ci, 1, c)
    for (uint k = start[c]; k < start[c + 1u]; ++k) {
      const uint j = items[k];
      const vec3 d = pos[j].xyz - xi;
      if (j == i || dot(d, d) >= h2 || cls[j] != 1u) continue;
      const float w = 1.0 - length(d) * inv_h;
      nsum += w * normal[j].xyz;
      ksum += w * curv[j];
      wsum += w;
    }
  END_FOR_CELLS
  const float nlen = length(nsum);
  if (nlen > 0.0) nsum /= nlen;
  const vec3 own = normal[i].xyz;
  vec3 ni = (1.0 - tau) * own + tau * nsum;
  const float ilen = length(ni);
  ni = ilen > 1e-6 ? ni / ilen : own;
  const float ki = ((1.0 - tau) * curv[i] + tau * ksum) / ((1.0 - tau) + tau * wsum);
  accel[i] += vec4((C.s2.y * ki) * ni, 0.0);
}
