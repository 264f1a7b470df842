#version 450
#extension GL_GOOGLE_include_directive : require
// Adaptive control, first sweep of a sub-step, per controlled particle j (control/adaptive.cpp, adaptive_spring; eq.
// 17–18 as METHOD §a.5): x*_j += γ Σ_i w f r / Σ_i w over its bonds i, w = (H_c² − |r|²)³, r = x_ci − x*_j,
// f = 1 / (1 + fill_i |r| / H_c). Reads and writes only its own x* (and shift).
layout(local_size_x = 128) in;
#include "control.glsl"
layout(std430, binding = 0) readonly buffer FX { vec4 f_x[]; };
layout(std430, binding = 1) readonly buffer FCell { uint f_cell[]; };
layout(std430, binding = 2) readonly buffer FTarget { uint f_target[]; };
layout(std430, binding = 3) readonly buffer Nearest { uint nearest[]; };
layout(std430, binding = 4) readonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = 5) readonly buffer SStart { uint s_start[]; };
layout(std430, binding = 6) readonly buffer SItems { uint s_items[]; };
layout(std430, binding = 7) readonly buffer STarget { uint s_target[]; };
layout(std430, binding = 8) readonly buffer SBond { float s_bond_r2[]; };
layout(std430, binding = 9) readonly buffer SFill { float s_fill[]; };
layout(std430, binding = 10) buffer Pos { vec4 pos[]; };
layout(std430, binding = 11) readonly buffer SVel { vec4 s_vel[]; };  // u_c: 0 on a static target
layout(std430, binding = 12) readonly buffer TStrength { float t_strength[]; };  // per target, in this sub-step
layout(std430, binding = 13) buffer Shift { vec4 shift[]; };  // the fluid's: written only with KINEMATIC

void main() {
  const uint j = gl_GlobalInvocationID.x;
  if (j >= uint(C.grid_dims.w) || nearest[j] == 0xFFFFFFFFu) return;
  const float hc = C.c0.x, hc2 = C.c0.y, inv_hc = 1.0 / C.c0.x;
  const uint t = f_target[j];
  const vec3 x0 = f_x[j].xyz, xs = pos[j].xyz;
  const ivec3 cj = cell_of_index(f_cell[j]);
  vec3 num = vec3(0.0);
  float den = 0.0;
  FOR_CELLS_AROUND(cj, C.c3.y, c)
    for (uint k = s_start[c]; k < s_start[c + 1u]; ++k) {
      const uint i = s_items[k];
      const vec3 xc = s_pos[i].xyz;
      const vec3 b = xc - x0;
      // Bonded at the start of the sub-step.
      if ((C.c3.w & SEVERAL_TARGETS) != 0 && s_target[i] != t) continue;
      if (dot(b, b) > s_bond_r2[i] || dot(b, b) >= hc2) continue;
      const vec3 r = xc + C.c2.w * s_vel[i].xyz - xs;  // the sample at the end of the sub-step, as x*
      const float r2 = dot(r, r);
      if (r2 >= hc2) continue;
      const float q2 = hc2 - r2;
      const float w = q2 * q2 * q2;
      const float f = 1.0 / (1.0 + s_fill[i] * (sqrt(r2) * inv_hc));
      num += (w * f) * r;
      den += w;
    }
  END_FOR_CELLS
  if (den > 0.0) {
    const vec3 dx = (C.c2.x * t_strength[t] / den) * num;
    pos[j] = vec4(xs + dx, 0.0);
    if ((C.c3.w & KINEMATIC) != 0) shift[j] = vec4(shift[j].xyz + dx, 0.0);
  }
}
