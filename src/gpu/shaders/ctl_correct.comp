#version 450
#extension GL_GOOGLE_include_directive : require
// Adaptive control, every sweep, per controlled particle j (control/adaptive.cpp, gather_correction; eq. 10, METHOD
// §a.3): Δx_j = α Σ_{i ∈ B(j)} coef_i (H_c − |r|)² r / |r|, r = x_ci − x*_j, clamped to the largest step, into x*_j.
// Reads and writes only its own x* (and shift).
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
layout(std430, binding = 9) readonly buffer SCoef { float s_coef[]; };
layout(std430, binding = 10) buffer Pos { vec4 pos[]; };
layout(std430, binding = 11) readonly buffer SVel { vec4 s_vel[]; };  // u_c: 0 on a static target
layout(std430, binding = 12) readonly buffer TSpeed { vec2 t_speed[]; };  // per target: .y scales the clamp
layout(std430, binding = 13) buffer Shift { vec4 shift[]; };  // the fluid's: written only with KINEMATIC

void main() {
  const uint j = gl_GlobalInvocationID.x;
  if (j >= uint(C.grid_dims.w) || nearest[j] == 0xFFFFFFFFu) return;
  const float hc = C.c0.x, hc2 = C.c0.y;
  const uint t = f_target[j];
  const float alpha = C.c1.z, max_dx = C.c1.w * t_speed[t].y;
  const vec3 x0 = f_x[j].xyz, xs = pos[j].xyz;
  const ivec3 cj = cell_of_index(f_cell[j]);
  vec3 d = vec3(0.0);
  FOR_CELLS_AROUND(cj, C.c3.y, c)
    for (uint k = s_start[c]; k < s_start[c + 1u]; ++k) {
      const uint i = s_items[k];
      const float coef = s_coef[i];
      if (!(coef > 0.0) || ((C.c3.w & SEVERAL_TARGETS) != 0 && s_target[i] != t)) continue;
      const vec3 xc = s_pos[i].xyz;
      const vec3 b = xc - x0;
      if (dot(b, b) > s_bond_r2[i] || dot(b, b) >= hc2) continue;  // bonded at the start of the sub-step
      const vec3 r = xc + C.c2.w * s_vel[i].xyz - xs;  // the sample at the end of the sub-step, as x*
      const float r2 = dot(r, r);
      if (r2 >= hc2 || r2 <= 0.0) continue;
      const float len = sqrt(r2);
      const float q = hc - len;
      d += (coef * q * q / len) * r;
    }
  END_FOR_CELLS
  if (dot(d, d) > 0.0) {
    d *= alpha;
    const float d2 = dot(d, d);
    if (d2 > max_dx * max_dx) d *= max_dx / sqrt(d2);
    pos[j] = vec4(xs + d, 0.0);
    if ((C.c3.w & KINEMATIC) != 0) shift[j] = vec4(shift[j].xyz + d, 0.0);
  }
}
