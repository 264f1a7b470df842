#version 450
#extension GL_GOOGLE_include_directive : require
// Counting sort, step 4: each cell's run sorted by particle index (insertion sort: a cell of edge h holds ~30
// particles at rest density), so the order in which every later pass visits neighbours, and with it every float
// sum, is fixed: two runs on one device give the same bits.
layout(local_size_x = 256) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Start { uint start[]; };
layout(std430, binding = 1) buffer Items { uint items[]; };

void main() {
  const uint c = gl_GlobalInvocationID.x;
  if (c >= grid_cells()) return;
  const uint b = start[c], e = start[c + 1u];
  for (uint k = b + 1u; k < e; ++k) {
    const uint v = items[k];
    uint m = k;
    while (m > b && items[m - 1u] > v) {
      items[m] = items[m - 1u];
      --m;
    }
    items[m] = v;
  }
}
