#version 450
#extension GL_GOOGLE_include_directive : require
// PBF Δx (Macklin & Müller 2013, eqs. 12–14; sim/pbf_kernels.cpp is the CPU pass): next = clamp(x* + (m/ρ0)
// Σ_j (λ_i + λ_j + s_corr) ∇W_ij) into the walls, s_corr = −k (W/W(Δq))ⁿ / S_0. Jacobi: reads x*, writes `next`.
layout(local_size_x = 128) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Pos { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Cell { uint cell[]; };
layout(std430, binding = 2) readonly buffer Start { uint start[]; };
layout(std430, binding = 3) readonly buffer Items { uint items[]; };
layout(std430, binding = 4) readonly buffer Lambda { float lambda[]; };
layout(std430, binding = 5) writeonly buffer Next { vec4 next[]; };
// Skipped once the sub-step's sweeps are done (density_decide.comp).
layout(std430, binding = 6) readonly buffer SweepState { uint done; uint sweeps; float mean; uint max_bits; uint total; float last_max; } state;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (state.done != 0u || i >= uint(C.grid_dims.w)) return;
  const float h = C.k0.x, h2 = C.k0.y;
  const float kgrad = C.k2.x, w_ratio = C.k2.y, scorr_c = C.k2.z;
  const int scorr_n = int(C.k2.w);
  const vec3 xi = pos[i].xyz;
  const float lam_i = lambda[i];
  const ivec3 ci = cell_of_index(cell[i]);  // the cell the grid was built with
  vec3 d = vec3(0.0);
  FOR_CELLS_AROUND(ci, 1, c)
    for (uint k = start[c]; k < start[c + 1u]; ++k) {
      const uint j = items[k];
      const vec3 r = xi - pos[j].xyz;
      const float r2 = dot(r, r);
      if (r2 >= h2 || r2 <= 0.0) continue;  // no gradient beyond h, none at r = 0 (itself included)
      const float len = sqrt(r2);
      float l = lam_i + lambda[j];
      if (scorr_n > 0) {
        const float q2 = h2 - r2;
        const float ratio = w_ratio * q2 * q2 * q2;
        float pw = ratio;
        for (int e = 1; e < scorr_n; ++e) pw *= ratio;
        l += scorr_c * pw;
      }
      const float q = h - len;
      d += (l * kgrad * q * q / len) * r;
    }
  END_FOR_CELLS
  next[i] = vec4(clamp(xi + C.wall_lo.w * d, C.wall_lo.xyz, C.wall_hi.xyz), 0.0);
}
