#version 450
#extension GL_GOOGLE_include_directive : require
// The gather steering's field, step 2, one pass of jump flooding (Rong & Tan, "Jump Flooding in GPU with Applications
// to Voronoi Diagram and Distance Transform", I3D 2006): each cell takes, of its own seed and those of the 26 cells
// a jump away, the one nearest its centre (ties: the lower sample index). Jumps halve from half the field down to 1,
// then one more pass of 1; the result is the nearest seed up to a cell's size, as the CPU's raster sweeps give it.
// Reads one buffer, writes the other: a gather.
layout(local_size_x = 128) in;
#include "control.glsl"
layout(std430, binding = 0) readonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = 1) readonly buffer SeedIn { uint seed_in[]; };
layout(std430, binding = 2) writeonly buffer SeedOut { uint seed_out[]; };

void main() {
  const uint cells = field_cells();
  const uint g = gl_GlobalInvocationID.x;
  if (g >= cells * uint(C.field_dims.w)) return;
  const uint t = g / cells, c = g % cells;
  const ivec3 here = field_cell(c);
  const vec3 centre = field_centre(here);
  const int jump = C.c3.y;
  uint best_s = seed_in[g];
  float best = 1.0 / 0.0;
  if (best_s != 0xFFFFFFFFu) {
    const vec3 r = s_pos[best_s].xyz - centre;
    best = dot(r, r);
  }
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const ivec3 o = here + jump * ivec3(dx, dy, dz);
        if ((dx == 0 && dy == 0 && dz == 0) || any(lessThan(o, ivec3(0))) || any(greaterThanEqual(o, C.field_dims.xyz))) continue;
        const uint s = seed_in[t * cells + field_index(o)];
        if (s == 0xFFFFFFFFu) continue;
        const vec3 r = s_pos[s].xyz - centre;
        const float d2 = dot(r, r);
        if (d2 < best || (d2 == best && s < best_s)) {
          best = d2;
          best_s = s;
        }
      }
  seed_out[g] = best_s;
}
