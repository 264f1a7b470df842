#version 450
#extension GL_GOOGLE_include_directive : require
// The sub-step's forces (sim/pbf_solver.cpp: xsph_accelerations), at x on the grid built on x:
// a = g + (η/Δt) Σ_j (m/ρ_j) W_ij (v_j − v_i) (XSPH as an acceleration, METHOD.md §c.2). Reads x (pos), v and ρ(x);
// writes only its own a. A controller's accelerations come next (ctl_accel.comp), then pbf_predict.comp.
layout(local_size_x = 128) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Pos { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Cell { uint cell[]; };
layout(std430, binding = 2) readonly buffer Start { uint start[]; };
layout(std430, binding = 3) readonly buffer Items { uint items[]; };
layout(std430, binding = 4) readonly buffer Vel { vec4 vel[]; };
layout(std430, binding = 5) readonly buffer Density { float density[]; };
layout(std430, binding = 6) writeonly buffer Accel { vec4 accel[]; };

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w)) return;
  const float h2 = C.k0.y;
  const vec3 g = C.k2.xyz;
  const float xsph = C.k3.x, mk = C.k3.y;
  const vec3 xi = pos[i].xyz, vi = vel[i].xyz;
  vec3 s = vec3(0.0);
  if (xsph != 0.0) {
    const ivec3 ci = cell_of_index(cell[i]);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const ivec3 cj = ci + ivec3(dx, dy, dz);
          if (any(lessThan(cj, ivec3(0))) || any(greaterThanEqual(cj, C.grid_dims.xyz))) continue;
          const uint c = cell_index(cj);
          for (uint k = start[c]; k < start[c + 1u]; ++k) {
            const uint j = items[k];
            const vec3 r = xi - pos[j].xyz;
            const float r2 = dot(r, r);
            if (j == i || r2 >= h2) continue;
            const float q2 = h2 - r2;
            s += (mk * q2 * q2 * q2 / density[j]) * (vel[j].xyz - vi);  // (m/ρ_j) W_ij (v_j − v_i)
          }
        }
  }
  accel[i] = vec4(g + xsph * s, 0.0);
}
