#version 450
#extension GL_GOOGLE_include_directive : require
// Vorticity confinement, step 2 (sim/pbf_solver.cpp, vorticity_confinement): η_i = Σ_j (m/ρ_j) |ω_j| ∇W(x_i − x_j),
// N = η/|η|, v_i += Δt ε_v (N × ω_i). Each invocation writes only its own velocity; ω is vort_omega.comp's.
// k2: x Spiky kgrad, y Δt ε_v.
layout(local_size_x = 128) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer X0 { vec4 x0[]; };  // x at the start of the sub-step (copied out)
layout(std430, binding = 1) readonly buffer Cell { uint cell[]; };
layout(std430, binding = 2) readonly buffer Start { uint start[]; };
layout(std430, binding = 3) readonly buffer Items { uint items[]; };
layout(std430, binding = 4) buffer Vel { vec4 vel[]; };
layout(std430, binding = 5) readonly buffer Density { float density[]; };
layout(std430, binding = 6) readonly buffer Omega { vec4 omega[]; };

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w)) return;
  const float h = C.k0.x, h2 = C.k0.y, mass = C.k1.x, kgrad = C.k2.x;
  const vec3 xi = x0[i].xyz;
  const ivec3 ci = cell_of_index(cell[i]);
  vec3 eta = vec3(0.0);
  FOR_CELLS_AROUND(ci, 1, c)
    for (uint k = start[c]; k < start[c + 1u]; ++k) {
      const uint j = items[k];
      const vec3 r = xi - x0[j].xyz;
      const float r2 = dot(r, r);
      if (r2 >= h2 || r2 <= 0.0) continue;
      eta += ((mass / density[j]) * length(omega[j].xyz)) * spiky_grad(r, r2, h, kgrad);
    }
  END_FOR_CELLS
  const float len = length(eta);
  if (len > 1e-12) vel[i] = vec4(vel[i].xyz + C.k2.y * cross(eta / len, omega[i].xyz), 0.0);
}
