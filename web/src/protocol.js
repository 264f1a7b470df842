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
// Live surface (the reconstructed mesh of a recent frame, while a viewer asked for it), told apart by its magic:
//   offset  type      field
//   0       u32       magic 0x314D4646 (the bytes "FFM1")
//   4       u16       version (1)
//   6       u16       header bytes (32): vertices start here
//   8       u32       frame number the surface was made from
//   12      u32       nv, vertices
//   16      f64       time, s simulated
//   24      u32       nt, triangles
//   28      f32       build_ms: wall-clock of the reconstruction
//   32      f32[3nv]  vertex positions, m
//   32+12nv u32[3nt]  triangles (vertex indices, outward winding)
//
// Text messages are JSON objects with a "type": from the server "hello" (the scene: targets, meshes, controllers,
// mode), "pose" (a target's applied transform), "error"; to the server the commands below.

export const FRAME_MAGIC = 0x31504646;
export const FRAME_VERSION = 1;
export const FRAME_HEADER_BYTES = 64;
export const FREE_FLUID = 255;
export const SURFACE_MAGIC = 0x314d4646;
export const SURFACE_VERSION = 1;
export const SURFACE_HEADER_BYTES = 32;

/** Whether a binary message is a live surface (else a particle frame). */
export const isSurface = (buffer) => buffer.byteLength >= 4 && new DataView(buffer).getUint32(0, true) === SURFACE_MAGIC;

/**
 * Decodes one live surface: {frame, time, buildMs, positions: Float32Array(3nv), indices: Uint32Array(3nt)}.
 * Throws on a wrong magic, version or size, or an index out of range.
 * @param {ArrayBuffer} buffer
 */
export function decodeSurface(buffer) {
  if (buffer.byteLength < SURFACE_HEADER_BYTES) throw new Error('surface: shorter than its header');
  const v = new DataView(buffer);
  if (v.getUint32(0, true) !== SURFACE_MAGIC) throw new Error('surface: wrong magic');
  if (v.getUint16(4, true) !== SURFACE_VERSION) throw new Error('surface: unknown version');
  const header = v.getUint16(6, true), nv = v.getUint32(12, true), nt = v.getUint32(24, true);
  if (header < SURFACE_HEADER_BYTES || header % 4 || buffer.byteLength < header + 12 * nv + 12 * nt)
    throw new Error('surface: shorter than its mesh');
  const positions = new Float32Array(buffer, header, 3 * nv);
  const indices = new Uint32Array(buffer, header + 12 * nv, 3 * nt);
  for (let i = 0; i < indices.length; ++i) if (indices[i] >= nv) throw new Error('surface: a triangle names a vertex out of range');
  return { frame: v.getUint32(8, true), time: v.getFloat64(16, true), buildMs: v.getFloat32(28, true),
           vertices: nv, triangles: nt, positions, indices };
}

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
/** Live surface on or off (the server reconstructs the fluid about twice a second while on). */
export const setSurface = (on) => JSON.stringify({ type: 'surface', on: Boolean(on) });
/** Playback of a finished run: go on from frame `frame` (the server clamps it to the last; live mode answers an error). */
export const seek = (frame) => JSON.stringify({ type: 'seek', frame: Math.max(0, Math.round(Number(frame) || 0)) });
/** A target's pose about its pivot: translate (m), rotate (degrees about x, y, z; R = Rz Ry Rx), uniform scale. */
export const setPose = (target, translate, rotate = [0, 0, 0], scale = 1) =>
  JSON.stringify({ type: 'pose', target, translate, rotate, scale });
