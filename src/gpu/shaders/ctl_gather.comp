#version 450
#extension GL_GOOGLE_include_directive : require
// The gather steering (ours, METHOD §a.10; control/adaptive.cpp, gather): an unbonded particle whose
// target has under-filled samples is steered toward the nearest of them (the seed field at its cell) at a limited
// speed, with gravity cancelled: a += −g + (v_des − v)/τ, v_des = speed · (x_s − x)/|x_s − x|. On a moving target
// the seed's pose velocity u is added and the approach is at least gather_chase |u| (c1.z; c1.w = 1 when a target
// moves).
layout(local_size_x = 256) in;
#include "control.glsl"
layout(std430, binding = 0) readonly buffer FX { vec4 f_x[]; };
layout(std430, binding = 1) readonly buffer FTarget { uint f_target[]; };
layout(std430, binding = 2) readonly buffer Nearest { uint nearest[]; };
layout(std430, binding = 3) readonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = 4) readonly buffer Seed { uint seed[]; };
layout(std430, binding = 5) readonly buffer Vel { vec4 vel[]; };
layout(std430, binding = 6) buffer Accel { vec4 accel[]; };
layout(std430, binding = 7) readonly buffer SVel { vec4 s_vel[]; };
layout(std430, binding = 8) readonly buffer TStrength { float t_strength[]; };  // per target, in this sub-step
layout(std430, binding = 9) readonly buffer TSpeed { vec2 t_speed[]; };  // per target: .x scales the steering speed

void main() {
  const uint j = gl_GlobalInvocationID.x;
  if (j >= uint(C.grid_dims.w) || nearest[j] != 0xFFFFFFFFu) return;
  const uint t = f_target[j];
  if (t >= uint(C.field_dims.w)) return;
  const vec3 xj = f_x[j].xyz;
  const uint s = seed[t * field_cells() + field_index(field_coord(xj))];
  if (s == 0xFFFFFFFFu) return;
  const vec3 to = s_pos[s].xyz - xj;
  const float len = length(to);
  if (len <= 0.0) return;
  const float speed = C.c0.w * t_speed[t].x;
  vec3 v_des;
  if (C.c1.w != 0.0) {  // chase: closing in at least at a share of the seed's own speed, on top of following it
    const vec3 u = s_vel[s].xyz;
    v_des = (max(speed, C.c1.z * length(u)) / len) * to + u;
  } else {
    v_des = (speed / len) * to;
  }
  accel[j] += vec4(t_strength[t] * (-C.c0.xyz + C.c1.x * (v_des - vel[j].xyz)), 0.0);
}
