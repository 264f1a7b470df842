#version 450
#extension GL_GOOGLE_include_directive : require
// Adaptive control on the accelerations of controlled fluid (control/adaptive.cpp, add_accelerations): the boundary
// correction (eq. 15–16: where the nearest bonded sample's normal n is strong, the outward part of a is removed),
// then the speed limit (v* = v + Δt a brought back to the limit through a). On a moving target v* is first pulled
// toward the nearest bonded sample's pose velocity u_c, and the limit holds for v* − u_c (AdaptiveParams::follow).
// This pass reads c0.x as the follow share k = min(1, follow Δt/Δt_ref) (0: no target moves).
layout(local_size_x = 256) in;
#include "control.glsl"
layout(std430, binding = 0) readonly buffer Nearest { uint nearest[]; };
layout(std430, binding = 1) readonly buffer SNormal { vec4 s_normal[]; };
layout(std430, binding = 2) readonly buffer Vel { vec4 vel[]; };
layout(std430, binding = 3) buffer Accel { vec4 accel[]; };
layout(std430, binding = 4) readonly buffer FTarget { uint f_target[]; };
layout(std430, binding = 5) readonly buffer SVel { vec4 s_vel[]; };
layout(std430, binding = 6) readonly buffer TMoving { uint t_moving[]; };  // per target: 1 when it moves
layout(std430, binding = 7) readonly buffer TStrength { float t_strength[]; };  // per target, in this sub-step
layout(std430, binding = 8) readonly buffer TSpeed { vec2 t_speed[]; };  // per target: .x scales the speed limit

void main() {
  const uint j = gl_GlobalInvocationID.x;
  if (j >= uint(C.grid_dims.w)) return;
  const uint i = nearest[j];
  if (i == 0xFFFFFFFFu) return;
  vec3 a = accel[j].xyz;
  const float thr = C.c2.y, vmax = C.c2.z * t_speed[f_target[j]].x, dt = C.c2.w;
  const float s = t_strength[f_target[j]];  // every part scales with the target's strength (1: as written)
  if (thr >= 0.0) {  // < 0: no boundary correction
    const vec3 nrm = s_normal[i].xyz;
    const float len = length(nrm);
    if (len >= thr && len != 0.0) {
      const vec3 nh = nrm / len;
      const float outward = dot(nh, a);
      if (outward > 0.0) a -= s * outward * nh;
    }
  }
  const float k = C.c0.x;
  if (k > 0.0 && t_moving[f_target[j]] != 0u) {  // a static target's fluid (u_c = 0) is not damped
    const vec3 u = s_vel[i].xyz;
    a += (s * k / dt) * (u - (vel[j].xyz + dt * a));
    const vec3 vs = vel[j].xyz + dt * a - u;
    const float s2 = dot(vs, vs);
    if (s2 > vmax * vmax) a += s * (vs * (vmax / sqrt(s2)) - vs) / dt;
  } else {
    const vec3 vs = vel[j].xyz + dt * a;
    const float s2 = dot(vs, vs);
    if (s2 > vmax * vmax) a += s * (vs * (vmax / sqrt(s2)) - vs) / dt;
  }
  accel[j] = vec4(a, 0.0);
}
