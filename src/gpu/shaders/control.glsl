// The adaptive controller's passes (control/adaptive.cpp is the CPU reference; gpu/adaptive_device.h): their
// push-constant block, and the seed field's cells (the loop over the grid cells around a cell is common.glsl's).
#define FF_OWN_CONSTANTS
layout(push_constant) uniform ControlConstants {
  vec4 grid_lo;     // as common.glsl
  ivec4 grid_dims;  // xyz cells, w: fluid particles n
  vec4 c0;          // H_c, H_c², Poly6 k at H_c, Spiky kgrad at H_c
  vec4 c1;          // m_p, ε_c, α, the largest |Δx| per iteration
  vec4 c2;          // γ of the spring (scaled to Δt), |n| threshold of the boundary correction, speed limit, Δt
  ivec4 c3;         // samples m, reach in cells (⌈H_c / cell⌉), bond radius rule (0 over-full, 1 paper, 2 none),
                    // flags: SEVERAL_TARGETS, KINEMATIC (below)
  vec4 field_lo;    // the seed field's grid (the gather steering): xyz its corner, w 1 / its cell edge
  ivec4 field_dims; // xyz its cells per axis, w the number of targets
} C;
// The gather passes (ctl_seed_*.comp, ctl_gather.comp) read c0 and c1 as their own: c0 = gravity xyz and the steering
// speed (m/s), c1 = x: 1 / the steering time constant, y: the fill below which a sample is a seed; c3.y = the jump of
// a flood pass.
#include "common.glsl"
// c3.w's flags: several targets (a particle bonds only to its own target's samples); kinematic corrections (the
// spring's and the density constraint's Δx also go into the fluid's shift, so they do not become velocity).
const int SEVERAL_TARGETS = 1, KINEMATIC = 2;


// The seed field: cell of a position (clamped) and the centre of a cell.
ivec3 field_coord(vec3 p) {
  return clamp(ivec3(floor((p - C.field_lo.xyz) * C.field_lo.w)), ivec3(0), C.field_dims.xyz - 1);
}
uint field_cells() { return uint(C.field_dims.x) * uint(C.field_dims.y) * uint(C.field_dims.z); }
uint field_index(ivec3 c) { return uint(c.x + C.field_dims.x * (c.y + C.field_dims.y * c.z)); }
ivec3 field_cell(uint c) {
  const uint nx = uint(C.field_dims.x), ny = uint(C.field_dims.y);
  return ivec3(int(c % nx), int((c / nx) % ny), int(c / (nx * ny)));
}
vec3 field_centre(ivec3 c) { return C.field_lo.xyz + (vec3(c) + 0.5) / C.field_lo.w; }
