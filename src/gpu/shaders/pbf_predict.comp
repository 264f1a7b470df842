#version 450
#extension GL_GOOGLE_include_directive : require
// The prediction of a sub-step (sim/pbf_solver.cpp, substep()): v* = v + Δt a, x* = clamp(x + Δt v*) into the walls.
layout(local_size_x = 256) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer X { vec4 x[]; };
layout(std430, binding = 1) readonly buffer Vel { vec4 vel[]; };
layout(std430, binding = 2) readonly buffer Accel { vec4 accel[]; };
layout(std430, binding = 3) writeonly buffer Pos { vec4 pos[]; };

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w)) return;
  const float dt = C.k2.w;
  const vec3 vs = vel[i].xyz + dt * accel[i].xyz;
  pos[i] = vec4(clamp(x[i].xyz + dt * vs, C.wall_lo.xyz, C.wall_hi.xyz), 0.0);
}
