#version 450
#extension GL_GOOGLE_include_directive : require
// Vorticity confinement, step 1 (sim/pbf_solver.cpp, vorticity_confinement; Fedkiw 2001 as PBF uses it), after the
// update: per particle i, ω_i = Σ_j (m/ρ_j)(v_j − v_i) × ∇W(x_i − x_j) over its neighbours at x (the start of the
// sub-step, where the grid was built), with the new velocities and the last sweep's densities. Gather only.
// k2: x Spiky kgrad (the sweeps' block; the update's constants are not this pass's).
layout(local_size_x = 128) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer X0 { vec4 x0[]; };  // x at the start of the sub-step (copied out)
layout(std430, binding = 1) readonly buffer Cell { uint cell[]; };
layout(std430, binding = 2) readonly buffer Start { uint start[]; };
layout(std430, binding = 3) readonly buffer Items { uint items[]; };
layout(std430, binding = 4) readonly buffer Vel { vec4 vel[]; };
layout(std430, binding = 5) readonly buffer Density { float density[]; };
layout(std430, binding = 6) writeonly buffer Omega { vec4 omega[]; };

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w)) return;
  const float h = C.k0.x, h2 = C.k0.y, mass = C.k1.x, kgrad = C.k2.x;
  const vec3 xi = x0[i].xyz, vi = vel[i].xyz;
  const ivec3 ci = cell_of_index(cell[i]);
  vec3 w = vec3(0.0);
  FOR_CELLS_AROUND(ci, 1, c)
    for (uint k = start[c]; k < start[c + 1u]; ++k) {
      const uint j = items[k];
      const vec3 r = xi - x0[j].xyz;
      const float r2 = dot(r, r);
      if (r2 >= h2 || r2 <= 0.0) continue;  // ∇W is 0 there (core::Spiky::grad)
      w += (mass / density[j]) * cross(vel[j].xyz - vi, spiky_grad(r, r2, h, kgrad));
    }
  END_FOR_CELLS
  omega[i] = vec4(w, 0.0);
}
