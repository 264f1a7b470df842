// Where the page's frames come from: the frame Worker (frame_worker.js; the default), or the WebSocket and decoder on
// the main thread (`?decode=main`: the old path, kept so that the browser test can print the main thread's time per
// drawn frame both ways). Both call the same handlers with the same objects, so the rest of the viewer cannot tell.
import { BufferPool, decodeMessage } from './frames.js';

/**
 * @param {{worker: boolean, url: string, onOpen(), onClose(), onText(text), onFrame(frame, decodeMs),
 *          onSurface(surface, decodeMs), onBad(bytes)}} h
 * @returns {{send(text: string): void, recycle(frame): void, kind: string}}
 */
export function createFrameSource(h) {
  return h.worker ? workerSource(h) : mainThreadSource(h);
}

function workerSource(h) {
  const worker = new Worker(new URL('./frame_worker.js', import.meta.url), { type: 'module' });
  const handed = [];  // buffers to hand back (one array, reused)
  worker.onmessage = (ev) => {
    const m = ev.data;
    switch (m.type) {
      case 'frame': h.onFrame(m.frame, m.decodeMs); break;
      case 'surface': h.onSurface(m.surface, m.decodeMs); break;
      case 'text': h.onText(m.text); break;
      case 'open': h.onOpen(); break;
      case 'close': h.onClose(); break;
      case 'bad': h.onBad(m.bytes); break;
    }
  };
  worker.onerror = (e) => h.onText(JSON.stringify({ type: 'error', message: `frame worker: ${e.message ?? e}` }));
  worker.postMessage({ type: 'connect', url: h.url });
  return {
    kind: 'worker',
    send: (text) => worker.postMessage({ type: 'send', text }),
    // Back to the Worker's pool in batches of three frames: a message per frame costs the main thread more than it
    // saves the Worker.
    recycle: (frame) => {
      handed.push(frame.positions.buffer, frame.targets.buffer);
      if (handed.length < 6) return;
      worker.postMessage({ type: 'recycle', buffers: handed }, handed);
      handed.length = 0;
    },
  };
}

function mainThreadSource(h) {
  const pool = new BufferPool(6);
  let ws = null;
  const connect = () => {
    ws = new WebSocket(h.url);
    ws.binaryType = 'arraybuffer';
    ws.onopen = () => h.onOpen();
    ws.onclose = () => {
      h.onClose();
      setTimeout(connect, 1000);
    };
    ws.onmessage = (ev) => {
      if (typeof ev.data === 'string') return h.onText(ev.data);
      const t0 = performance.now();
      let m;
      try {
        m = decodeMessage(ev.data, pool);
      } catch {
        return h.onBad(ev.data.byteLength);
      }
      const decodeMs = performance.now() - t0;
      if (m.kind === 'frame') h.onFrame(m.frame, decodeMs);
      else h.onSurface(m.surface, decodeMs);
    };
  };
  connect();
  return {
    kind: 'main',
    send: (text) => { if (ws && ws.readyState === WebSocket.OPEN) ws.send(text); },
    recycle: (frame) => {
      pool.give(frame.positions.buffer);
      pool.give(frame.targets.buffer);
    },
  };
}
