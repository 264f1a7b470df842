#version 450
#extension GL_GOOGLE_include_directive : require
// The end of a sub-step (sim/pbf_solver.cpp, substep()): v = (x* − x − shift)/Δt, x = x*; shift is the part of the
// corrections that is not to become velocity (kinematic control), else 0. Per particle, its own values only.
layout(local_size_x = 256) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Pos { vec4 pos[]; };
layout(std430, binding = 1) buffer X { vec4 x[]; };
layout(std430, binding = 2) writeonly buffer Vel { vec4 vel[]; };
layout(std430, binding = 3) readonly buffer Shift { vec4 shift[]; };

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w)) return;
  const vec3 xs = pos[i].xyz;
  vel[i] = vec4((xs - x[i].xyz - shift[i].xyz) * (1.0 / C.k2.w), 0.0);
  x[i] = vec4(xs, 0.0);
}
