// Surface tension's passes (sim/surface_tension.h is the CPU's): their push-constant block, and the counter-based
// random rotation of a particle in a sub-step, bit for bit the CPU's SplitMix64 (64-bit integers as two 32-bit words,
// which every Vulkan device has).
#define FF_OWN_CONSTANTS
layout(push_constant) uniform SurfaceConstants {
  vec4 grid_lo;     // as common.glsl
  ivec4 grid_dims;  // xyz cells, w: particles n
  vec4 s0;          // h (r1), r2/r1, classifier slope k, classifier offset d_c
  uvec4 s1;         // the sub-step's key (low, high word), points N, 0
  vec4 s2;          // τ, −σ/m, κ scale −(2/r1)(1 − r2²/r1²)^(−1/2), κ shift arcsin(r2/r1)
} C;
#include "common.glsl"

uvec2 add64(uvec2 a, uvec2 b) {
  uint carry;
  const uint lo = uaddCarry(a.x, b.x, carry);
  return uvec2(lo, a.y + b.y + carry);
}
uvec2 shr64(uvec2 a, uint s) {  // 0 < s < 32
  return uvec2((a.x >> s) | (a.y << (32u - s)), a.y >> s);
}
uvec2 mul64(uvec2 a, uvec2 b) {  // the low 64 bits of a · b
  uint hi, lo;
  umulExtended(a.x, b.x, hi, lo);
  return uvec2(lo, hi + a.x * b.y + a.y * b.x);
}
// SplitMix64's finaliser (sim/surface_tension.cpp, mix64).
uvec2 mix64(uvec2 z) {
  z = add64(z, uvec2(0x7f4a7c15u, 0x9e3779b9u));
  z = mul64(z ^ shr64(z, 30u), uvec2(0x1ce4e5b9u, 0xbf58476du));
  z = mul64(z ^ shr64(z, 27u), uvec2(0x133111ebu, 0x94d049bbu));
  return z ^ shr64(z, 31u);
}
float unit_float(uvec2 bits) { return float(bits.y >> 8) * (1.0 / 16777216.0); }  // the top 24 bits

// Shoemake's uniform random rotation for particle `id` in the sub-step of `key` (random_rotation on the CPU), as the
// matrix Eigen's Quaternion::toRotationMatrix makes.
mat3 random_rotation(uint id, uvec2 key) {
  const uvec2 s = mix64(key ^ mix64(add64(uvec2(id, 0u), uvec2(0xd9b4e019u, 0x632be59bu))));
  const float u1 = unit_float(mix64(add64(s, uvec2(1u, 0u)))), u2 = unit_float(mix64(add64(s, uvec2(2u, 0u)))),
              u3 = unit_float(mix64(add64(s, uvec2(3u, 0u))));
  const float a = sqrt(1.0 - u1), b = sqrt(u1);
  const float two_pi = 6.2831853071795864769;
  const float t2 = two_pi * u2, t3 = two_pi * u3;
  const float w = b * cos(t3), x = a * sin(t2), y = a * cos(t2), z = b * sin(t3);
  const float tx = 2.0 * x, ty = 2.0 * y, tz = 2.0 * z;
  const float twx = tx * w, twy = ty * w, twz = tz * w, txx = tx * x, txy = ty * x, txz = tz * x, tyy = ty * y,
              tyz = tz * y, tzz = tz * z;
  // GLSL matrices are column-major: mat3(column 0, column 1, column 2).
  return mat3(vec3(1.0 - (tyy + tzz), txy + twz, txz - twy),
              vec3(txy - twz, 1.0 - (txx + tzz), tyz + twx),
              vec3(txz + twy, tyz - twx, 1.0 - (txx + tyy)));
}
