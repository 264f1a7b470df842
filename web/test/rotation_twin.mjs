// The JavaScript half of the rotation twin test (tests/core/rotation_test.cpp writes ANGLES.json: a list of
// {deg: [x, y, z], matrix: [9 numbers, row-major]} from core::rotation_from_degrees): web/src/rotation.js must give
// the same matrices to 1e-12. Exits non-zero naming the first difference.
// Usage: node web/test/rotation_twin.mjs ANGLES.json
import fs from 'node:fs';
import { rotationFromDegrees } from '../src/rotation.js';

const cases = JSON.parse(fs.readFileSync(process.argv[2], 'utf8'));
if (!Array.isArray(cases) || cases.length === 0) {
  console.error('rotation twin: no cases');
  process.exit(1);
}
for (const { deg, matrix } of cases) {
  const r = rotationFromDegrees(deg);
  for (let i = 0; i < 9; ++i) {
    if (!(Math.abs(r[i] - matrix[i]) <= 1e-12)) {
      console.error(`rotation twin: angles ${JSON.stringify(deg)}, entry ${i}: js ${r[i]} != c++ ${matrix[i]}`);
      process.exit(1);
    }
  }
}
console.log(`rotation twin ok: ${cases.length} angle sets`);
