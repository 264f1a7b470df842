// The wire format between `fluidform serve` and the viewer: THE layout on the JavaScript side. Its C++ twin is
// src/server/frame_codec.h (server → viewer frames) and src/server/messages.h (viewer → server commands); the
// round-trip test (tests/server/frame_codec_test.cpp + web/test/protocol_roundtrip.mjs) keeps the two in step.
// Plain ES module without DOM access: the browser and node both import it.
//
// Binary frame, little-endian (one WebSocket binary message per simulated or played-back frame):
//   offset  type      field
//   0       u32       magic 0x31504646 (the bytes "FFP1")
//   4       u16       version (1)
//   6       u16       header bytes (64): positions start here
//   8       u32       frame number
//   12      u32       n, particles
//   16      f64       time, s simulated
//   24      f32       step_ms: wall-clock of the frame's simulation (0 in playback)
//   28      f32       error rate, % (NaN: no targets)
//   32      f32       sim_fps: simulated frames per second of wall time, over about the last second
//   36      u32       controlled particles
//   40      f32[3]    lo: the bounding box of the positions
//   52      f32[3]    hi
//   64      u16[3n]   positions quantised in the box: x = lo + q/65535 (hi − lo), per axis
//   64+6n   u8[n]     target of each particle (255: free fluid)
//   ...     0–3 zero bytes to a multiple of 4
//
// Text messages are JSON objects with a "type": from the server "hello" (the scene: targets, meshes, controllers,
// mode), "pose" (a target's applied transform), "error"; to the server the commands below.

export const FRAME_MAGIC = 0x31504646;
export const FRAME_VERSION = 1;
export const FRAME_HEADER_BYTES = 64;
export const FREE_FLUID = 255;

/**
 * Decodes one binary frame. `out` (optional) is a previous result whose arrays are reused when large enough.
 * Throws on a wrong magic, version or size.
 * @param {ArrayBuffer} buffer
 */
export function decodeFrame(buffer, out = null) {
  if (buffer.byteLength < FRAME_HEADER_BYTES) throw new Error('frame: shorter than its header');
  const v = new DataView(buffer);
  if (v.getUint32(0, true) !== FRAME_MAGIC) throw new Error('frame: wrong magic');
  if (v.getUint16(4, true) !== FRAME_VERSION) throw new Error('frame: unknown version');
  const header = v.getUint16(6, true);
  const n = v.getUint32(12, true);
  if (header < FRAME_HEADER_BYTES || buffer.byteLength < header + 7 * n) throw new Error('frame: shorter than its particles');
  const lo = [v.getFloat32(40, true), v.getFloat32(44, true), v.getFloat32(48, true)];
  const hi = [v.getFloat32(52, true), v.getFloat32(56, true), v.getFloat32(60, true)];
  const f = out ?? {};
  f.frame = v.getUint32(8, true);
  f.count = n;
  f.time = v.getFloat64(16, true);
  f.stepMs = v.getFloat32(24, true);
  f.errorRate = v.getFloat32(28, true);
  f.simFps = v.getFloat32(32, true);
  f.controlled = v.getUint32(36, true);
  f.lo = lo;
  f.hi = hi;
  if (!f.positions || f.positions.length < 3 * n) f.positions = new Float32Array(3 * n);
  const s = [(hi[0] - lo[0]) / 65535, (hi[1] - lo[1]) / 65535, (hi[2] - lo[2]) / 65535];
  // header is even, so the u16 array is aligned; one typed-array view instead of 3n DataView calls.
  const q = new Uint16Array(buffer, header, 3 * n);
  const p = f.positions;
  for (let i = 0; i < 3 * n; i += 3) {
    p[i] = lo[0] + s[0] * q[i];
    p[i + 1] = lo[1] + s[1] * q[i + 1];
    p[i + 2] = lo[2] + s[2] * q[i + 2];
  }
  f.targets = new Uint8Array(buffer, header + 6 * n, n);
  return f;
}

// Commands (src/server/messages.h checks each one).
export const play = () => JSON.stringify({ type: 'play' });
export const pause = () => JSON.stringify({ type: 'pause' });
export const restart = () => JSON.stringify({ type: 'restart' });
export const setController = (name) => JSON.stringify({ type: 'controller', name });
export const setMesh = (target, mesh) => JSON.stringify({ type: 'mesh', target, mesh });
/** A target's pose about its pivot: translate (m), rotate (degrees about x, y, z; R = Rz Ry Rx), uniform scale. */
export const setPose = (target, translate, rotate = [0, 0, 0], scale = 1) =>
  JSON.stringify({ type: 'pose', target, translate, rotate, scale });
