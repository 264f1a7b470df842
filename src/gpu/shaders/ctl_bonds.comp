#version 450
#extension GL_GOOGLE_include_directive : require
// Adaptive control, start of a sub-step, per fluid particle j (control/adaptive.cpp, build_bonds): its bonds are the
// samples i of its target with |x_ci − x_j| ≤ H_c*,i (METHOD §a.5); kept here is only the nearest (ties: the lower
// sample index), or none (0xFFFFFFFF): a particle is controlled iff it has a bond. The passes that walk the bonds
// find them again the same way (gather only, no lists to store).
layout(local_size_x = 128) in;
#include "control.glsl"
layout(std430, binding = 0) readonly buffer FX { vec4 f_x[]; };
layout(std430, binding = 1) readonly buffer FCell { uint f_cell[]; };
layout(std430, binding = 2) readonly buffer FTarget { uint f_target[]; };
layout(std430, binding = 3) readonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = 4) readonly buffer SStart { uint s_start[]; };
layout(std430, binding = 5) readonly buffer SItems { uint s_items[]; };
layout(std430, binding = 6) readonly buffer STarget { uint s_target[]; };
layout(std430, binding = 7) readonly buffer SBond { float s_bond_r2[]; };
layout(std430, binding = 8) writeonly buffer Nearest { uint nearest[]; };

void main() {
  const uint j = gl_GlobalInvocationID.x;
  if (j >= uint(C.grid_dims.w)) return;
  const uint t = f_target[j];
  const vec3 xj = f_x[j].xyz;
  const ivec3 cj = cell_of_index(f_cell[j]);
  float best = 1.0 / 0.0;
  uint best_i = 0xFFFFFFFFu;
  FOR_CELLS_AROUND(cj, C.c3.y, c)
    for (uint k = s_start[c]; k < s_start[c + 1u]; ++k) {
      const uint i = s_items[k];
      // One target: every fluid particle is its (as the CPU).
      if ((C.c3.w & SEVERAL_TARGETS) != 0 && s_target[i] != t) continue;
      const vec3 r = s_pos[i].xyz - xj;
      const float r2 = dot(r, r);
      if (r2 > s_bond_r2[i] || r2 >= C.c0.y) continue;  // within H_c*,i, and a pair (< H_c)
      if (r2 < best || (r2 == best && i < best_i)) {
        best = r2;
        best_i = i;
      }
    }
  END_FOR_CELLS
  nearest[j] = best_i;
}
