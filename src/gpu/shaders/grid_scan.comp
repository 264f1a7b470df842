#version 450
#extension GL_GOOGLE_include_directive : require
// Counting sort, step 2: the exclusive prefix sum of the cell counts, start[c] = Σ_{c' < c} count[c'], and
// start[cells] = n. One workgroup: each invocation sums a contiguous run of cells, the run totals are scanned in
// shared memory (Hillis–Steele), then each invocation writes its run's starts. Integer sums: exact, so the result
// is the same however the device schedules it.
layout(local_size_x = 1024) in;
#include "common.glsl"
layout(std430, binding = 0) readonly buffer Count { uint count[]; };
layout(std430, binding = 1) writeonly buffer Start { uint start[]; };
shared uint run_total[1024];

void main() {
  const uint t = gl_LocalInvocationID.x;
  const uint cells = grid_cells();
  const uint per = (cells + 1023u) / 1024u;
  const uint b = min(t * per, cells), e = min(b + per, cells);
  uint s = 0u;
  for (uint c = b; c < e; ++c) s += count[c];
  run_total[t] = s;
  barrier();
  for (uint off = 1u; off < 1024u; off <<= 1) {
    const uint add = t >= off ? run_total[t - off] : 0u;
    barrier();
    run_total[t] += add;
    barrier();
  }
  uint acc = run_total[t] - s;  // exclusive: the runs before this one
  for (uint c = b; c < e; ++c) {
    start[c] = acc;
    acc += count[c];
  }
  if (t == 1023u) start[cells] = run_total[1023];
}
