// The heads-up display: render FPS, simulation step time and rate, frames received, particles, live error rate.
// Plain DOM text; `values` also feeds the browser test (window.__ff.hud).

// Events per second over about the last second.
export class RateCounter {
  constructor() { this.stamps = []; }
  tick(now = performance.now()) {
    this.stamps.push(now);
    while (this.stamps.length > 2 && now - this.stamps[0] > 1000) this.stamps.shift();
  }
  rate(now = performance.now()) {
    const s = this.stamps;
    if (s.length < 2 || now - s[s.length - 1] > 2000) return 0;
    return (1000 * (s.length - 1)) / (s[s.length - 1] - s[0]);
  }
}

const fixed = (v, d) => (Number.isFinite(v) ? v.toFixed(d) : '–');

export class Hud {
  constructor(doc = document) {
    this.el = {};
    for (const k of ['fps', 'step', 'simfps', 'recv', 'count', 'error', 'time', 'status'])
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
  status(text) { this.el.status.textContent = text; }
}
