// The C++ → JavaScript half of the frame round trip (tests/server/frame_codec_test.cpp writes both files):
// decodes FRAME.bin with web/src/protocol.js and compares every field with EXPECTED.json (what the C++ decoder
// read). Exits non-zero with the first difference. With --surface, the same for a live surface (exact).
// Usage: node web/test/protocol_roundtrip.mjs [--surface] FILE.bin EXPECTED.json
import fs from 'node:fs';
import { decodeFrame, decodeSurface, isSurface } from '../src/protocol.js';

const surface = process.argv[2] === '--surface';
const [file, expectedFile] = process.argv.slice(surface ? 3 : 2);
const bytes = fs.readFileSync(file);
// A Buffer may be a view into a shared pool: the decoder wants its own ArrayBuffer (as a WebSocket gives it).
const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
const want = JSON.parse(fs.readFileSync(expectedFile, 'utf8'));
const fail = (msg) => {
  console.error(`protocol round trip: ${msg}`);
  process.exit(1);
};
if (surface) {
  if (!isSurface(buffer)) fail('not recognised as a surface');
  const s = decodeSurface(buffer);
  if (s.frame !== want.frame || s.time !== want.time || s.buildMs !== want.buildMs) fail(`header: ${JSON.stringify(s)}`);
  if (s.vertices !== want.positions.length || s.triangles !== want.triangles.length) fail('counts');
  // Float32 on both sides: the JSON holds the float values C++ wrote, so they compare exactly after rounding.
  want.positions.forEach((p, i) => p.forEach((v, a) => { if (s.positions[3 * i + a] !== Math.fround(v)) fail(`vertex ${i}.${a}`); }));
  want.triangles.forEach((t, i) => t.forEach((v, a) => { if (s.indices[3 * i + a] !== v) fail(`triangle ${i}.${a}`); }));
  console.log(`surface round trip ok: ${s.vertices} vertices, ${s.triangles} triangles, frame ${s.frame}`);
  process.exit(0);
}
if (isSurface(buffer)) fail('a particle frame recognised as a surface');
const f = decodeFrame(buffer);

const close = (a, b, rel = 1e-6) => Math.abs(a - b) <= rel * Math.max(1, Math.abs(a), Math.abs(b));
for (const k of ['frame', 'count', 'controlled']) if (f[k] !== want[k]) fail(`${k}: ${f[k]} != ${want[k]}`);
for (const k of ['time', 'stepMs', 'simFps']) if (!close(f[k], want[k], 1e-7)) fail(`${k}: ${f[k]} != ${want[k]}`);
if (want.errorRate === null ? !Number.isNaN(f.errorRate) : !close(f.errorRate, want.errorRate)) fail(`errorRate: ${f.errorRate}`);
for (let i = 0; i < want.count; ++i) {
  for (let a = 0; a < 3; ++a)
    if (!close(f.positions[3 * i + a], want.positions[i][a])) fail(`position ${i}.${a}: ${f.positions[3 * i + a]} != ${want.positions[i][a]}`);
  if (f.targets[i] !== want.targets[i]) fail(`target ${i}: ${f.targets[i]} != ${want.targets[i]}`);
}
console.log(`protocol round trip ok: ${f.count} particles, frame ${f.frame}, t = ${f.time}`);
