// The viewer's frame Worker: the WebSocket to `fluidform serve` lives here, and binary frames are decoded here
// (frames.js), off the page's main thread, which gets each frame as transferred buffers (no copy) and hands them back
// once it has uploaded them (a small pool, so steady state allocates no new buffers). Text messages pass through as
// they are; the page's commands come in as {type: 'send', text}.
//
// page → worker: {type: 'connect', url} | {type: 'send', text} | {type: 'recycle', buffers: [ArrayBuffer…]}
// worker → page: {type: 'open'} | {type: 'close'} | {type: 'text', text} | {type: 'bad', bytes}
//                | {type: 'frame', frame, decodeMs} | {type: 'surface', surface, decodeMs}
import { BufferPool, decodeMessage } from './frames.js';

const pool = new BufferPool(8);
let ws = null, url = null;

function connect() {
  ws = new WebSocket(url);
  ws.binaryType = 'arraybuffer';
  ws.onopen = () => postMessage({ type: 'open' });
  ws.onclose = () => {
    postMessage({ type: 'close' });
    setTimeout(connect, 1000);
  };
  ws.onmessage = (ev) => {
    if (typeof ev.data === 'string') {
      postMessage({ type: 'text', text: ev.data });
      return;
    }
    const t0 = performance.now();
    let m;
    try {
      m = decodeMessage(ev.data, pool);
    } catch {
      postMessage({ type: 'bad', bytes: ev.data.byteLength });
      return;
    }
    const decodeMs = performance.now() - t0;
    if (m.kind === 'frame') postMessage({ type: 'frame', frame: m.frame, decodeMs }, m.transfer);
    else postMessage({ type: 'surface', surface: m.surface, decodeMs }, m.transfer);
  };
}

onmessage = (ev) => {
  const m = ev.data;
  if (m.type === 'connect') {
    url = m.url;
    if (!ws) connect();
  } else if (m.type === 'send') {
    if (ws && ws.readyState === WebSocket.OPEN) ws.send(m.text);
  } else if (m.type === 'recycle') {
    for (const b of m.buffers) pool.give(b);
  }
};
