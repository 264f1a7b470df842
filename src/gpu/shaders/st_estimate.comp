#version 450
#extension GL_GOOGLE_include_directive : require
// Surface tension of Zorilla et al., steps 1 and 2 (sim/surface_tension.h), per particle at x: the classifier from
// the neighbour count and offset sum, then for a candidate the Monte-Carlo normal and curvature from the points of
// the shared spherical Fibonacci set (turned by the particle's random rotation) that no neighbour covers. Writes its
// own class (0 interior, 1 surface, 2 covered), normal and curvature.
layout(local_size_x = 64) in;
#include "surface.glsl"
layout(std430, binding = 0) readonly buffer Pos { vec4 pos[]; };
layout(std430, binding = 1) readonly buffer Cell { uint cell[]; };
layout(std430, binding = 2) readonly buffer Start { uint start[]; };
layout(std430, binding = 3) readonly buffer Items { uint items[]; };
layout(std430, binding = 4) readonly buffer Id { uint ids[]; };
layout(std430, binding = 5) readonly buffer Points { vec4 points[]; };
layout(std430, binding = 6) writeonly buffer Class { uint cls[]; };
layout(std430, binding = 7) writeonly buffer Normal { vec4 normal[]; };
layout(std430, binding = 8) writeonly buffer Curv { float curv[]; };

const uint kHeld = 96u;  // neighbours held for the point loop; a particle with more (never seen) walks the grid again
vec4 held[kHeld];        // per neighbour: its offset in the points' frame / h, and the covering threshold

// Whether any neighbour covers point p (the slow path, for a particle with more than kHeld neighbours).
bool covered_by_grid(vec3 p, uint i, vec3 xi, ivec3 ci, mat3 rot, float inv_h, float h2, float half_gap) {
  FOR_CELLS_AROUND(ci, 1, c)
    for (uint k = start[c]; k < start[c + 1u]; ++k) {
      const uint j = items[k];
      const vec3 d = pos[j].xyz - xi;
      if (j == i || dot(d, d) >= h2) continue;
      const vec3 r = d * inv_h;
      if (dot(p, transpose(rot) * r) >= 0.5 * dot(r, r) + half_gap) return true;
    }
  END_FOR_CELLS
  return false;
}

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w)) return;
  const float h = C.s0.x, h2 = h * h, inv_h = 1.0 / h, ratio = C.s0.y;
  const float half_gap = 0.5 * (1.0 - ratio * ratio);
  const vec3 xi = pos[i].xyz;
  const ivec3 ci = cell_of_index(cell[i]);
  // Step 1: the classifier over the neighbours within h.
  uint count = 0u;
  vec3 offsets = vec3(0.0);
  FOR_CELLS_AROUND(ci, 1, c)
    for (uint k = start[c]; k < start[c + 1u]; ++k) {
      const uint j = items[k];
      const vec3 d = pos[j].xyz - xi;
      if (j == i || dot(d, d) >= h2) continue;
      offsets += d;
      ++count;
    }
  END_FOR_CELLS
  cls[i] = 0u;
  normal[i] = vec4(0.0);
  curv[i] = 0.0;
  const float n = float(count);
  if (count == 0u || !(n <= C.s0.z * (length(offsets) / (h * n)) + C.s0.w)) return;
  // Step 2: the neighbours in the frame of the rotated points, scaled to the unit sphere.
  const mat3 rot = random_rotation(ids[i], C.s1.xy);
  const mat3 inv_rot = transpose(rot);
  if (count <= kHeld) {
    uint m = 0u;
    FOR_CELLS_AROUND(ci, 1, c)
      for (uint k = start[c]; k < start[c + 1u]; ++k) {
        const uint j = items[k];
        const vec3 d = pos[j].xyz - xi;
        if (j == i || dot(d, d) >= h2) continue;
        const vec3 r = d * inv_h;
        held[m++] = vec4(inv_rot * r, 0.5 * dot(r, r) + half_gap);
      }
    END_FOR_CELLS
  }
  uint free_count = 0u;
  vec3 free_sum = vec3(0.0);
  const uint points_n = C.s1.z;
  for (uint k = 0u; k < points_n; ++k) {
    const vec3 p = points[k].xyz;
    bool covered = false;
    if (count <= kHeld) {
      for (uint m = 0u; m < count; ++m) covered = covered || dot(p, held[m].xyz) >= held[m].w;
    } else {
      covered = covered_by_grid(p, i, xi, ci, rot, inv_h, h2, half_gap);
    }
    if (!covered) {
      ++free_count;
      free_sum += p;
    }
  }
  const vec3 dir = rot * free_sum;
  const float len = length(dir);
  if (free_count == 0u || !(len > 1e-6)) {  // no free point, or no net direction: a false positive
    cls[i] = 2u;
    return;
  }
  cls[i] = 1u;
  normal[i] = vec4(dir / len, 0.0);
  const float f = float(free_count) / float(points_n);
  curv[i] = C.s2.z * cos(acos(1.0 - 2.0 * f) + C.s2.w);
}
