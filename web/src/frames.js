// Turning the server's binary messages into what the render loop takes: one particle frame as a header object and two
// transferable buffers (dequantised positions, targets), or one live surface. The same code runs in the frame Worker
// (frame_worker.js, the default) and on the main thread (the old path, `?decode=main`, kept to measure the
// difference). Plain ES module without DOM access: a Worker, the page and node all import it.
import { decodeFrame, decodeSurface, isSurface } from './protocol.js';

/** Buffers handed back by the render loop once it has copied a frame into its GPU attributes, reused by the decoder. */
export class BufferPool {
  constructor(keep = 4) {
    this.keep = keep;
    this.free = [];  // ArrayBuffers
  }
  /** An ArrayBuffer of at least `bytes` (a returned one when one is large enough). */
  take(bytes) {
    for (let i = 0; i < this.free.length; ++i) {
      if (this.free[i].byteLength >= bytes) {
        const b = this.free[i];
        this.free[i] = this.free[this.free.length - 1];
        this.free.pop();
        return b;
      }
    }
    // 1/8 headroom: a frame a few particles larger (an emitter, a mesh swap) still fits the next time round.
    return new ArrayBuffer(Math.ceil((bytes * 9) / 8 / 16) * 16);
  }
  give(buffer) {
    if (buffer && buffer.byteLength > 0 && this.free.length < this.keep) this.free.push(buffer);
  }
}

/**
 * Decodes one binary WebSocket message. Returns {kind: 'frame', frame, transfer} or {kind: 'surface', surface,
 * transfer}; throws on a malformed message. A frame's `positions` (Float32Array, 3n) and `targets` (Uint8Array, n)
 * are views of pooled buffers (`transfer` lists them, to post to the page without a copy); the header fields and the
 * fluid's centroid (the browser test checks that the formed shape followed a dragged target) come along.
 */
export function decodeMessage(buffer, pool) {
  if (isSurface(buffer)) {
    const s = decodeSurface(buffer);
    // Copies into buffers of their own (the message's buffer also holds the header); a surface comes twice a second.
    const positions = s.positions.slice(), indices = s.indices.slice();
    const surface = { frame: s.frame, time: s.time, buildMs: s.buildMs, vertices: s.vertices, triangles: s.triangles,
                      positions, indices, bytes: buffer.byteLength };
    return { kind: 'surface', surface, transfer: [positions.buffer, indices.buffer] };
  }
  const head = new DataView(buffer, 0, Math.min(16, buffer.byteLength));
  const n = buffer.byteLength >= 16 ? head.getUint32(12, true) : 0;
  const posBuffer = pool.take(12 * n), tgtBuffer = pool.take(n);
  const out = { positions: new Float32Array(posBuffer, 0, posBuffer.byteLength >> 2) };
  let f;
  try {
    f = decodeFrame(buffer, out);
  } catch (e) {
    pool.give(posBuffer);
    pool.give(tgtBuffer);
    throw e;
  }
  const targets = new Uint8Array(tgtBuffer, 0, n);
  targets.set(f.targets);
  const p = f.positions;
  let cx = 0, cy = 0, cz = 0;
  for (let i = 0; i < 3 * n; i += 3) cx += p[i], cy += p[i + 1], cz += p[i + 2];
  const k = 1 / Math.max(1, n);
  const frame = { frame: f.frame, count: n, time: f.time, stepMs: f.stepMs, errorRate: f.errorRate, simFps: f.simFps,
                  controlled: f.controlled, centroid: [cx * k, cy * k, cz * k], bytes: buffer.byteLength,
                  positions: new Float32Array(posBuffer, 0, 3 * n), targets };
  return { kind: 'frame', frame, transfer: [posBuffer, tgtBuffer] };
}
