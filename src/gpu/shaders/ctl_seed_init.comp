#version 450
#extension GL_GOOGLE_include_directive : require
// The gather steering's field (control/nearest_seed_field.h is the CPU's), step 1, per target t and field cell c:
// of the seeds in c (samples of t whose fill is below gather_fill), the one nearest the cell's centre (ties: the
// lower sample index), or none. Then ctl_seed_flood.comp spreads the seeds over the field.
layout(local_size_x = 128) in;
#include "control.glsl"
layout(std430, binding = 0) readonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = 1) readonly buffer STarget { uint s_target[]; };
layout(std430, binding = 2) readonly buffer SFill { float s_fill[]; };
layout(std430, binding = 3) readonly buffer FieldStart { uint field_start[]; };  // the samples in the field's cells
layout(std430, binding = 4) readonly buffer FieldItems { uint field_items[]; };
layout(std430, binding = 5) writeonly buffer Seed { uint seed[]; };                 // targets × cells
layout(std430, binding = 6) readonly buffer TStrength { float t_strength[]; };     // per target, in this sub-step

void main() {
  const uint cells = field_cells();
  const uint g = gl_GlobalInvocationID.x;
  if (g >= cells * uint(C.field_dims.w)) return;
  const uint t = g / cells, c = g % cells;
  if (!(t_strength[t] > 0.0)) {  // a target not acting (not started, or released) has no seeds, as it has no bonds
    seed[g] = 0xFFFFFFFFu;
    return;
  }
  const vec3 centre = field_centre(field_cell(c));
  float best = 1.0 / 0.0;
  uint best_s = 0xFFFFFFFFu;
  for (uint k = field_start[c]; k < field_start[c + 1u]; ++k) {
    const uint s = field_items[k];
    if (s_target[s] != t || !(s_fill[s] < C.c1.y)) continue;
    const vec3 r = s_pos[s].xyz - centre;
    const float d2 = dot(r, r);
    if (d2 < best || (d2 == best && s < best_s)) {
      best = d2;
      best_s = s;
    }
  }
  seed[g] = best_s;
}
