// When to draw what: the render loop draws every display frame, the frames arrive at the simulation's (or the
// playback's) rate. The clock keeps the last two frames received, A (older) and B (newest), and places the drawing
// between them by their simulation times: at B's arrival the drawing shows A, and it reaches B when the next frame is
// due (the frames' wall-clock spacing, smoothed), so it is never more than one frame behind the newest and never
// ahead of it. A frame that cannot continue the pair (another particle count, time going back on a restart or a
// playback loop, a jump far beyond the usual step, or one the caller marks as a cut: the frame a seek asked for) is
// shown as it is: both ends of the pair become that frame.
// Plain ES module without DOM access (node's tests import it).

export class FrameClock {
  constructor() {
    this.reset();
  }
  reset() {
    this.a = null;          // {frame, time, count}: the older end of the pair (null before two frames)
    this.b = null;          // the newest frame
    this.arrival = 0;       // wall ms when b arrived
    this.interval = 0;      // smoothed wall ms between frames (0: unknown)
    this.simStep = 0;       // smoothed simulated s between frames
    this.alpha = 1;         // where the drawing is between a (0) and b (1)
    this.time = NaN;        // the simulated time drawn
    this.single = true;     // the pair is one frame (a discontinuity, or the first frame)
    this.seq = 0;           // bumped by every push
    this.discontinuities = 0;
  }

  /**
   * A new frame at wall time `now` (ms). Returns true when it continues the pair (interpolate from the previous
   * newest), false when it is shown as it is. `cut`: the caller knows there is nothing in between (a seek's frame,
   * however near the previous one).
   */
  push(frame, now, cut = false) {
    const prev = this.b;
    this.seq += 1;
    let continues = !cut && prev !== null && frame.count === prev.count && frame.time > prev.time;
    if (continues) {
      const dt = frame.time - prev.time;
      // A jump far beyond the usual step (a seek, frames dropped on a stall): no in-between to show.
      if (this.simStep > 0 && dt > 8 * this.simStep) continues = false;
      else this.simStep = this.simStep > 0 ? 0.8 * this.simStep + 0.2 * dt : dt;
      const gap = now - this.arrival;
      // Smoothed arrival spacing; a long gap (pause, a stalled tab) is not the frame rate: grows the estimate only
      // slowly, so that frames that really come slower are followed within a few frames.
      if (this.interval <= 0) this.interval = Math.min(gap, 1000);
      else if (gap < 3 * this.interval) this.interval = 0.85 * this.interval + 0.15 * gap;
      else this.interval = Math.min(1000, 1.5 * this.interval);
    }
    if (!continues) {
      this.discontinuities += prev !== null ? 1 : 0;
      if (prev === null || frame.count !== prev.count || frame.time <= prev.time) this.simStep = 0;
    }
    this.a = continues ? prev : frame;
    this.b = frame;
    this.single = !continues;
    this.arrival = now;
    this.update(now);
    return continues;
  }

  /** Sets alpha and time for a draw at wall time `now` (ms); returns alpha. */
  update(now) {
    if (!this.b) return (this.alpha = 1);
    if (this.single || this.interval <= 0) {
      this.alpha = 1;
      this.time = this.b.time;
      return 1;
    }
    const x = (now - this.arrival) / this.interval;
    this.alpha = x <= 0 ? 0 : x >= 1 ? 1 : x;
    this.time = this.a.time + this.alpha * (this.b.time - this.a.time);
    return this.alpha;
  }
}
