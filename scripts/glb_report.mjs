// What check_glb.mjs and check_rigged_glb.mjs both do first: read a GLB, run the Khronos validator on it, and give
// the report's head and the bytes as an ArrayBuffer for three.js's GLTFLoader.
import fs from 'node:fs';
import validator from 'gltf-validator';

export async function validate_glb(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const report = await validator.validateBytes(bytes, { maxIssues: 200 });
  const out = {
    errors: report.issues.numErrors,
    warnings: report.issues.numWarnings,
    messages: report.issues.messages.slice(0, 10).map((m) => `${m.code} ${m.pointer ?? ''}: ${m.message}`),
  };
  const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
  return { out, buffer };
}
