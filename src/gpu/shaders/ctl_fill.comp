#version 450
#extension GL_GOOGLE_include_directive : require
// Adaptive control, start of a sub-step, per sample i (control/adaptive.cpp, fill_samples): ρ_p,i = m_p Σ_j W(x_ci − x_j,
// H_c) over the fluid of its target at x (eq. 8), the fill ratio ρ_p,i/ρ_c,i and the bond radius² H_c*,i² (eq. 19).
layout(local_size_x = 128) in;
#include "control.glsl"
layout(std430, binding = 0) readonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = 1) readonly buffer SCell { uint s_cell[]; };
layout(std430, binding = 2) readonly buffer SRho { float s_rho_c[]; };
layout(std430, binding = 3) readonly buffer STarget { uint s_target[]; };
layout(std430, binding = 4) readonly buffer FX { vec4 f_x[]; };
layout(std430, binding = 5) readonly buffer FStart { uint f_start[]; };
layout(std430, binding = 6) readonly buffer FItems { uint f_items[]; };
layout(std430, binding = 7) readonly buffer FTarget { uint f_target[]; };
layout(std430, binding = 8) writeonly buffer SFill { float s_fill[]; };
layout(std430, binding = 9) writeonly buffer SBond { float s_bond_r2[]; };
layout(std430, binding = 10) readonly buffer TStrength { float t_strength[]; };  // per target, in this sub-step

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.c3.x)) return;
  const float hc2 = C.c0.y;
  const uint t = s_target[i];
  if (t_strength[t] <= 0.0) {  // a target not acting (not started, or released): fill 0, no bonds (−1 < any r²)
    s_fill[i] = 0.0;
    s_bond_r2[i] = -1.0;
    return;
  }
  const vec3 xc = s_pos[i].xyz;
  const ivec3 ci = cell_of_index(s_cell[i]);
  float sw = 0.0;
  FOR_CELLS_AROUND(ci, C.c3.y, c)
    for (uint k = f_start[c]; k < f_start[c + 1u]; ++k) {
      const uint j = f_items[k];
      if ((C.c3.w & SEVERAL_TARGETS) != 0 && f_target[j] != t) continue;
      const vec3 r = xc - f_x[j].xyz;
      const float r2 = dot(r, r);
      if (r2 >= hc2) continue;
      const float q2 = hc2 - r2;
      sw += q2 * q2 * q2;
    }
  END_FOR_CELLS
  const float f = C.c1.x * (C.c0.z * sw) / s_rho_c[i];
  s_fill[i] = f;
  // H_c* = H_c · scale: over-full (default) min(1, 2/(1 + f)), the paper's 1/(1 + f), or H_c without bond breaking.
  const float scale = C.c3.z == 0 ? min(1.0, 2.0 / (1.0 + f)) : C.c3.z == 1 ? 1.0 / (1.0 + f) : 1.0;
  s_bond_r2[i] = hc2 * scale * scale;
}
