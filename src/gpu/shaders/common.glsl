// What every pass of the PBF sub-step shares: the push constants (one block for all passes, 128 bytes, the least
// every Vulkan device offers) and the uniform grid's cell of a position. The host fills the block from
// PbfDevice::Constants (gpu/pbf_device.cpp); the two layouts are checked against each other by a static_assert there.
// A pass with a block of its own (the controller's, control.glsl) defines FF_OWN_CONSTANTS and declares it as C,
// beginning with the same grid_lo and grid_dims.
#ifndef FF_OWN_CONSTANTS
layout(push_constant) uniform Constants {
  vec4 grid_lo;      // xyz: the grid's lower corner, w: 1 / cell edge
  ivec4 grid_dims;   // xyz: cells per axis, w: particle count n
  vec4 k0;           // h, h², Poly6 k, W(0)
  vec4 k1;           // mass, ρ0, ε, cgrad = (m/ρ0)·Spiky kgrad
  vec4 k2;           // Δx pass: Spiky kgrad, Poly6 k / W(Δq), −k_corr / S_0, s_corr exponent n (0: no s_corr);
                     // force and update passes: gravity xyz, w: Δt
  vec4 wall_lo;      // xyz: the walls' lower corner, w: m/ρ0
  vec4 wall_hi;      // xyz: the walls' upper corner
  vec4 k3;           // force pass: x: XSPH η/Δt, y: m · Poly6 k; z: the least sweeps, w: the target mean compression
} C;
#endif

uint grid_cells() { return uint(C.grid_dims.x) * uint(C.grid_dims.y) * uint(C.grid_dims.z); }

// Cells are cubes of edge h (the support), so a particle's neighbours lie in the 27 cells around its own. Positions
// outside the grid are clamped into its border cells: the distance test still decides, so nothing is lost, only
// searched more slowly.
ivec3 cell_coord(vec3 p) {
  ivec3 c = ivec3(floor((p - C.grid_lo.xyz) * C.grid_lo.w));
  return clamp(c, ivec3(0), C.grid_dims.xyz - 1);
}
uint cell_index(ivec3 c) { return uint(c.x + C.grid_dims.x * (c.y + C.grid_dims.y * c.z)); }

// Every cell within `reach` cells of c on each axis, clamped to the grid, z outermost and x innermost (the order,
// and with it every float sum over neighbours, is fixed): reach 1 gives the 27 cells around c, which hold every
// neighbour within a cell edge.
#define FOR_CELLS_AROUND(c, reach, CELL)                                                              \
  for (int dz = max(c.z - reach, 0); dz <= min(c.z + reach, C.grid_dims.z - 1); ++dz)                 \
    for (int dy = max(c.y - reach, 0); dy <= min(c.y + reach, C.grid_dims.y - 1); ++dy)               \
      for (int dx = max(c.x - reach, 0); dx <= min(c.x + reach, C.grid_dims.x - 1); ++dx) {            \
        const uint CELL = cell_index(ivec3(dx, dy, dz));
#define END_FOR_CELLS }

// Spiky ∇W(r) (core::Spiky::grad) for r = x_i − x_j with r² = |r|² in (0, h²): kgrad (h − |r|)² r̂.
vec3 spiky_grad(vec3 r, float r2, float h, float kgrad) {
  const float len = sqrt(r2), q = h - len;
  return (kgrad * q * q / len) * r;
}

ivec3 cell_of_index(uint c) {
  const uint nx = uint(C.grid_dims.x), ny = uint(C.grid_dims.y);
  return ivec3(int(c % nx), int((c / nx) % ny), int(c / (nx * ny)));
}
