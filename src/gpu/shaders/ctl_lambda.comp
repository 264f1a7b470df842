#version 450
#extension GL_GOOGLE_include_directive : require
// Adaptive control, every sweep, per sample i (control/adaptive.cpp, sample_lambdas; eq. 6–9, METHOD §a.3): the
// unilateral density constraint C_i = min(ρ_p,i/ρ_c,i − 1, 0) at x* over the fluid of its target that was within
// H_c at the start of the sub-step, λ_i = −C_i / (Σ_j |g_ij|² + ε_c), and the sample's coefficient of the Δx pass,
// φ̃_i λ_i (m_p/ρ_c,i) (−kgrad) (0 when it is full).
layout(local_size_x = 128) in;
#include "control.glsl"
layout(std430, binding = 0) readonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = 1) readonly buffer SCell { uint s_cell[]; };
layout(std430, binding = 2) readonly buffer SRho { float s_rho_c[]; };
layout(std430, binding = 3) readonly buffer STarget { uint s_target[]; };
layout(std430, binding = 4) readonly buffer SPhi { float s_phi[]; };
layout(std430, binding = 5) readonly buffer FX { vec4 f_x[]; };
layout(std430, binding = 6) readonly buffer Pos { vec4 pos[]; };
layout(std430, binding = 7) readonly buffer FStart { uint f_start[]; };
layout(std430, binding = 8) readonly buffer FItems { uint f_items[]; };
layout(std430, binding = 9) readonly buffer FTarget { uint f_target[]; };
layout(std430, binding = 10) writeonly buffer SCoef { float s_coef[]; };
layout(std430, binding = 11) readonly buffer SVel { vec4 s_vel[]; };  // u_c: 0 on a static target
layout(std430, binding = 12) readonly buffer TStrength { float t_strength[]; };  // per target, in this sub-step

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.c3.x)) return;
  const float hc = C.c0.x, hc2 = C.c0.y, poly6_k = C.c0.z, kgrad = C.c0.w;
  const float mp = C.c1.x, eps = C.c1.y;
  const uint t = s_target[i];
  if (t_strength[t] <= 0.0) {  // a target not acting: no correction (nor are its samples bonded)
    s_coef[i] = 0.0;
    return;
  }
  const vec3 xc = s_pos[i].xyz;
  const vec3 xe = xc + C.c2.w * s_vel[i].xyz;  // the sample at the end of the sub-step, as x*
  const ivec3 ci = cell_of_index(s_cell[i]);
  float sw = 0.0, g2 = 0.0;
  FOR_CELLS_AROUND(ci, C.c3.y, c)
    for (uint k = f_start[c]; k < f_start[c + 1u]; ++k) {
      const uint j = f_items[k];
      if ((C.c3.w & SEVERAL_TARGETS) != 0 && f_target[j] != t) continue;
      const vec3 b = xc - f_x[j].xyz;
      if (dot(b, b) >= hc2) continue;  // the pair was not within H_c at the start (the CPU's pair list)
      const vec3 r = xe - pos[j].xyz;
      const float r2 = dot(r, r);
      if (r2 >= hc2) continue;
      const float q2 = hc2 - r2;
      sw += q2 * q2 * q2;
      const float q = hc - sqrt(r2);
      const float qq = q * q;
      g2 += qq * qq;  // |∇W|² = kgrad² (H_c − r)⁴
    }
  END_FOR_CELLS
  const float rho_c = s_rho_c[i];
  const float cst = mp * poly6_k * sw / rho_c - 1.0;
  float coef = 0.0;
  if (cst < 0.0) {
    const float kk = mp / rho_c * kgrad;
    const float lambda = -cst / (kk * kk * g2 + eps);
    coef = t_strength[t] * s_phi[i] * lambda * mp / rho_c * (-kgrad);
  }
  s_coef[i] = coef;
}
