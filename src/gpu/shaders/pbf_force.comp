#version 450
#extension GL_GOOGLE_include_directive : require
// The sub-step's forces (sim/pbf_solver.cpp: xsph_accelerations), at x on the grid built on x:
// a = g + (η/Δt) Σ_j (m/ρ_j) W_ij (v_j − v_i) (XSPH as an acceleration, METHOD.md §c.2), plus the air drag of
// Gissler et al. (sim/drag.h, METHOD.md §a.4 eq. 14) from the neighbour count and the occlusion by the neighbours
// downwind, gathered in the same loop. Reads x (pos), v and ρ(x); writes only its own a. A controller's
// accelerations come next (ctl_accel.comp), then pbf_predict.comp.
// This pass reads the walls' slots as the drag's coefficients: wall_lo = L, y, Re coefficients and d², wall_hi.x =
// s ½ ρ_a / m (0: no drag).
layout(local_size_x = 128) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Pos { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Cell { uint cell[]; };
layout(std430, binding = 2) readonly buffer Start { uint start[]; };
layout(std430, binding = 3) readonly buffer Items { uint items[]; };
layout(std430, binding = 4) readonly buffer Vel { vec4 vel[]; };
layout(std430, binding = 5) readonly buffer Density { float density[]; };
layout(std430, binding = 6) writeonly buffer Accel { vec4 accel[]; };

// DragModel::acceleration (sim/drag.cpp), term for term.
vec3 drag_acceleration(vec3 v, float speed2, uint count, float best) {
  const float w = clamp(1.0 - sqrt(best), 0.0, 1.0);  // eq. (15)
  if (w == 0.0) return vec3(0.0);
  const float L = C.wall_lo.x, y_coeff = C.wall_lo.y, re_coeff = C.wall_lo.z, d2 = C.wall_lo.w, acc = C.wall_hi.x;
  const float full = 38.0 * 2.0 / 3.0;  // ⅔ of a full neighbourhood
  const float speed = sqrt(speed2);
  const float phi = min(float(count), full) / full;
  float cd = 1.0, area = d2;
  if (phi < 1.0) {
    const float y = min(speed2 * y_coeff, 1.0);                                    // eq. (8)
    const float re = 2.0 * max(re_coeff * speed, 0.1);
    const float cd_sphere = re <= 1000.0 ? 24.0 / re * (1.0 + pow(re, 2.0 / 3.0) / 6.0) : 0.424;
    const float cd_liu = cd_sphere * (1.0 + 2.632 * y);                            // eq. (9)
    cd = count == 0u ? cd_liu : (1.0 - phi) * cd_liu + phi;                        // eq. (10)
    const float r = L * (1.0 + 0.5 * y);                                           // L + C_b L y
    area = (1.0 - phi) * 3.14159265358979 * r * r + phi * d2;                      // eqs. (12), (13)
  }
  return (-acc * speed * cd * area * w) * v;  // eq. (14)
}

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w)) return;
  const float h2 = C.k0.y;
  const vec3 g = C.k2.xyz;
  const float xsph = C.k3.x, mk = C.k3.y;
  const vec3 xi = pos[i].xyz, vi = vel[i].xyz;
  const float drag_acc = C.wall_hi.x;
  const float speed2 = dot(vi, vi);
  const bool drag = drag_acc != 0.0 && speed2 > 1e-12;
  const vec3 dir = drag ? -vi / sqrt(speed2) : vec3(0.0);  // v̂_rel: air at rest
  vec3 s = vec3(0.0);
  float best = 0.0;  // max over neighbours downwind of (v̂_rel · r)² / |r|²
  uint count = 0u;
  if (xsph != 0.0 || drag) {
    const ivec3 ci = cell_of_index(cell[i]);
    FOR_CELLS_AROUND(ci, 1, c)
      for (uint k = start[c]; k < start[c + 1u]; ++k) {
        const uint j = items[k];
        const vec3 r = xi - pos[j].xyz;
        const float r2 = dot(r, r);
        if (j == i || r2 >= h2) continue;
        const float q2 = h2 - r2;
        s += (mk * q2 * q2 * q2 / density[j]) * (vel[j].xyz - vi);  // (m/ρ_j) W_ij (v_j − v_i)
        ++count;
        const float d = dot(dir, r);
        if (r2 > 0.0 && d > 0.0) best = max(best, d * d / r2);
      }
    END_FOR_CELLS
  }
  vec3 a = g + xsph * s;
  if (drag) a += drag_acceleration(vi, speed2, count, best);
  accel[i] = vec4(a, 0.0);
}
