// The heads-up display: render FPS, simulation step time and rate, frames received, particles, live error rate, the
// look. Plain DOM text; `values` also feeds the browser test (window.__ff.hud).

// Events per second over about the last second: a ring of time stamps (nothing allocated per event).
export class RateCounter {
  constructor(size = 256) {
    this.stamps = new Float64Array(size);
    this.head = 0;  // next slot
    this.n = 0;
  }
  tick(now = performance.now()) {
    this.stamps[this.head] = now;
    this.head = (this.head + 1) % this.stamps.length;
    this.n = Math.min(this.n + 1, this.stamps.length);
  }
  rate(now = performance.now()) {
    if (this.n < 2) return 0;
    const size = this.stamps.length, last = this.stamps[(this.head - 1 + size) % size];
    if (now - last > 2000) return 0;
    // The oldest stamp within a second of the newest (at least two stamps).
    let k = 1;
    while (k + 1 < this.n && last - this.stamps[(this.head - 1 - (k + 1) + 2 * size) % size] <= 1000) k += 1;
    const first = this.stamps[(this.head - 1 - k + 2 * size) % size];
    return (1000 * k) / Math.max(1e-3, last - first);
  }
}

const fixed = (v, d) => (Number.isFinite(v) ? v.toFixed(d) : '–');

export class Hud {
  constructor(doc = document) {
    this.el = {};
    for (const k of ['fps', 'step', 'simfps', 'recv', 'count', 'error', 'time', 'look', 'status'])
      this.el[k] = doc.getElementById(`hud-${k}`);
    this.values = { fps: NaN, stepMs: NaN, simFps: NaN, recvFps: NaN, count: 0, errorRate: NaN, time: NaN };
  }
  update(v) {
    Object.assign(this.values, v);
    const x = this.values;
    this.el.fps.textContent = fixed(x.fps, 0);
    this.el.step.textContent = fixed(x.stepMs, 1);
    this.el.simfps.textContent = fixed(x.simFps, 1);
    this.el.recv.textContent = fixed(x.recvFps, 1);
    this.el.count.textContent = String(x.count);
    this.el.error.textContent = fixed(x.errorRate, 2);
    this.el.time.textContent = fixed(x.time, 2);
  }
  look(text) { if (this.el.look) this.el.look.textContent = text; }
  status(text) { this.el.status.textContent = text; }
}
