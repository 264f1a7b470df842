// R = Rz · Ry · Rx from Euler angles in degrees (x first): the viewer's twin of core::rotation_from_degrees
// (src/core/rotation.h), the rotation the server poses targets with. tests/core/rotation_test.cpp runs
// web/test/rotation_twin.mjs on the C++ matrices of the same angles.

/**
 * @param {number[]} deg angles about x, y, z in degrees
 * @returns {number[]} the 3×3 matrix R, row-major
 */
export function rotationFromDegrees(deg) {
  const k = Math.PI / 180;
  const [cx, sx] = [Math.cos(deg[0] * k), Math.sin(deg[0] * k)];
  const [cy, sy] = [Math.cos(deg[1] * k), Math.sin(deg[1] * k)];
  const [cz, sz] = [Math.cos(deg[2] * k), Math.sin(deg[2] * k)];
  return [
    cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx,
    sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx,
    -sy, cy * sx, cy * cx,
  ];
}
