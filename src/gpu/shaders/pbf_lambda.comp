#version 450
#extension GL_GOOGLE_include_directive : require
// PBF λ at x* (Macklin & Müller 2013, eqs. 1, 2, 8, 11; sim/pbf_kernels.cpp is the CPU pass): density from Poly6,
// the constraint C = max(ρ/ρ0 − 1, 0), and λ = −C / (Σ_j |∇_j C|² + |Σ_j ∇_j C|² + ε). Gather only: each invocation
// writes its own particle, visiting neighbours in the grid's fixed order.
layout(local_size_x = 128) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Pos { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Cell { uint cell[]; };
layout(std430, binding = 2) readonly buffer Start { uint start[]; };
layout(std430, binding = 3) readonly buffer Items { uint items[]; };
layout(std430, binding = 4) writeonly buffer Density { float density[]; };
layout(std430, binding = 5) writeonly buffer Lambda { float lambda[]; };
// Skipped once the sub-step's sweeps are done (density_decide.comp).
layout(std430, binding = 6) readonly buffer SweepState { uint done; uint sweeps; float mean; uint max_bits; uint total; float last_max; } state;

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (state.done != 0u || i >= uint(C.grid_dims.w)) return;
  const float h = C.k0.x, h2 = C.k0.y, poly6_k = C.k0.z, w0 = C.k0.w;
  const float mass = C.k1.x, rho0 = C.k1.y, epsilon = C.k1.z, cgrad = C.k1.w;
  const vec3 xi = pos[i].xyz;
  const ivec3 ci = cell_of_index(cell[i]);  // the cell the grid was built with
  float sw = 0.0, g2 = 0.0;
  vec3 grad = vec3(0.0);
  FOR_CELLS_AROUND(ci, 1, c)
    for (uint k = start[c]; k < start[c + 1u]; ++k) {
      const uint j = items[k];
      if (j == i) continue;
      const vec3 r = xi - pos[j].xyz;
      const float r2 = dot(r, r);
      if (r2 >= h2) continue;
      const float q2 = h2 - r2;
      sw += q2 * q2 * q2;
      if (r2 > 0.0) {  // a coincident particle adds density but no gradient
        const float len = sqrt(r2);
        const float q = h - len;
        const float cc = cgrad * q * q / len;  // ∇_j C_i = cc · r
        g2 += cc * cc * r2;
        grad += cc * r;
      }
    }
  END_FOR_CELLS
  const float rho = mass * (w0 + poly6_k * sw);
  density[i] = rho;
  const float constraint = max(rho / rho0 - 1.0, 0.0);
  lambda[i] = -constraint / (g2 + dot(grad, grad) + epsilon);
}
