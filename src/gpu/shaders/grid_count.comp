#version 450
#extension GL_GOOGLE_include_directive : require
// Counting sort, step 1: each particle's cell, and the number of particles in every cell (integer atomics: the
// counts do not depend on the order the atomics run in).
layout(local_size_x = 256) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Pos { vec4 pos[]; };
layout(std430, binding = 1) writeonly buffer Cell { uint cell[]; };
layout(std430, binding = 2) buffer Count { uint count[]; };

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= uint(C.grid_dims.w)) return;
  const uint c = cell_index(cell_coord(pos[i].xyz));
  cell[i] = c;
  atomicAdd(count[c], 1u);
}
