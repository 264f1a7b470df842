// The live viewer end to end: `fluidform serve --max-fps 10` on the default scene (the simulation slower than the
// display on purpose), the page in Debian's chromium (headless, off the network) through playwright-core. Checks (each
// exits non-zero with a reason):
//   - the frame clock (web/src/interpolate.js) on its own, in node: the pair, alpha, and what breaks the pair
//   - at least 120 frames arrive, and a screenshot shows particles (pixels of the particle colours, not a blank canvas)
//   - the HUD shows FPS and step time (read and printed)
//   - the look is chosen by measured frame time: liquid if it holds the display rate, else spheres (the fall back)
//   - the viewer draws at least 1.5× as many frames as it receives (one that draws on receipt draws 1×), and sampled
//     particles are drawn (read back from the GPU) between the two frames they interpolate, never more than one frame
//     behind
//   - frames stay ~7 bytes per particle on the WebSocket
//   - the main thread's time per drawn frame with the frame Worker, printed next to the old path's (?decode=main)
//   - liquid, spheres and mesh on one held frame (PNGs in --out): the liquid is one smooth surface (smoothness and
//     coverage against the spheres) with the background visible through it (the background changed, the liquid
//     changes with it; the spheres do not)
//   - dragging the target: the box is drawn where the pointer put it in the next display frame, the server reports
//     the new transform, the error rate (measured against the moved target) jumps, and is back under 4 % within 3
//     simulated seconds (the time to 1 % is printed: the issue asks 1 % within 0.5 s)
//   - /../../etc/passwd and encoded variants get 403/404 from the real server; garbage, binary and oversized
//     WebSocket messages leave it serving
//   - the controller switch reaches the server
//   - WebXR on an emulated headset (IWER, stereo): the highest frame rate is requested, both eyes draw the liquid,
//     the controller drag moves the target; AR places the content at table-top scale
//   - Ctrl-C (SIGINT) stops the server with exit code 0 and frees its port
//   - live frames keep the particles' order (sent in particle-id order): at most 0.5 % of sampled particles jump more
//     than a tenth of the fluid's size between the two frames of a pair; a seek in live mode gets an error
//   - playback of a finished run (--playback OUT): frames, interpolated, and the mesh animation (animation.glb) play,
//     and the panel links the run's report page (report.html, served from the run's folder);
//     the seek slider (max: the hello's frame count − 1) follows the frame played, and seeking from it (back, then far
//     forward) brings that frame and the ones after it, drawn as they are (not interpolated across the jump), with
//     the mesh animation at the frame's time
// and prints the speed numbers: simulation steps per second of wall time, frames received per second, render FPS.
// Usage: node web/test/viewer.test.mjs --binary BIN --scene SCENE.json [--cache DIR] [--mesh EXTRA.obj] [--playback OUT]
//        [--chromium PATH] [--out DIR]
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import net from 'node:net';
import path from 'node:path';
import { chromium } from 'playwright-core';
import { FrameClock } from '../src/interpolate.js';

const args = {};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
const exe = args.binary, sceneFile = args.scene;
const browserPath = args.chromium ?? '/usr/bin/chromium';
const outDir = args.out ?? fs.mkdtempSync('/tmp/fluidform-viewer-');
if (!exe || !sceneFile) {
  console.error('usage: node web/test/viewer.test.mjs --binary BIN --scene SCENE.json [--cache DIR] [--playback OUT]');
  process.exit(2);
}

// The flags that keep chromium off the network (issue 7), plus software WebGL: --disable-gpu leaves WebGL to
// SwiftShader, which recent chromium only enables when asked.
const CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--no-first-run', '--disable-background-networking',
                       '--disable-component-update', '--disable-sync', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'];

const failures = [];
const check = (ok, what) => {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures.push(what);
  return ok;
};
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const t0 = Date.now();
const elapsed = () => ((Date.now() - t0) / 1000).toFixed(1);

// Starts `fluidform serve` on a free port; resolves with {proc, url, port, log()} once it prints its address.
function startServer(input, extra = []) {
  // Passive OpenMP waiting: the simulation shares two cores with chromium's software renderer (as in scripts/test).
  const env = { OMP_WAIT_POLICY: 'PASSIVE', ...process.env };
  // --exit-after: a test killed half-way leaves no server behind for long (the test itself ends it with Ctrl-C).
  const proc = spawn(exe, ['serve', input, '--port', '0', '--exit-after', '900', ...extra], { stdio: ['ignore', 'pipe', 'pipe'], env });
  let log = '';
  proc.stderr.on('data', (d) => (log += d));
  return new Promise((resolve, reject) => {
    let out = '';
    const timer = setTimeout(() => reject(new Error(`serve did not start in 180 s:\n${log}`)), 180_000);
    proc.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/serving (http:\/\/[^\s]+)/);
      if (m) {
        clearTimeout(timer);
        resolve({ proc, url: m[1], port: Number(new URL(m[1]).port), log: () => log });
      }
    });
    proc.on('exit', (code) => {
      clearTimeout(timer);
      reject(new Error(`serve exited with ${code} before listening:\n${log}`));
    });
  });
}

// SIGINT, then the exit code (null after 15 s).
function interrupt(server) {
  return new Promise((resolve) => {
    if (server.proc.exitCode !== null) return resolve(server.proc.exitCode);
    const timer = setTimeout(() => {
      server.proc.kill('SIGKILL');
      resolve(null);
    }, 15_000);
    server.proc.on('exit', (code) => {
      clearTimeout(timer);
      resolve(code);
    });
    server.proc.kill('SIGINT');
  });
}

// A raw GET with the target sent as it is (fetch and browsers normalise "/../" away); resolves with the status.
function rawGet(port, target) {
  return new Promise((resolve) => {
    const s = net.connect(port, '127.0.0.1', () => s.write(`GET ${target} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n`));
    let data = '';
    s.on('data', (d) => (data += d));
    s.on('end', () => resolve({ status: Number(data.slice(9, 12)), body: data }));
    s.on('error', () => resolve({ status: -1, body: '' }));
    s.setTimeout(10_000, () => s.destroy());
  });
}

function portIsFree(port) {
  return new Promise((resolve) => {
    const srv = net.createServer();
    srv.once('error', () => resolve(false));
    srv.listen(port, '127.0.0.1', () => srv.close(() => resolve(true)));
  });
}

// Counts screenshot pixels that are neither the background nor near-grey: particles (coloured) on a dark page.
async function colouredPixels(page, png) {
  return page.evaluate(async (b64) => {
    const img = new Image();
    img.src = `data:image/png;base64,${b64}`;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width;
    c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) {
      const r = d[i], gg = d[i + 1], b = d[i + 2];
      if (Math.max(r, gg, b) - Math.min(r, gg, b) > 40 && Math.max(r, gg, b) > 60) n += 1;
    }
    return { coloured: n, total: c.width * c.height };
  }, png.toString('base64'));
}

const waitFor = async (page, fn, arg, timeoutMs, what) => {
  try {
    await page.waitForFunction(fn, arg, { timeout: timeoutMs, polling: 100 });
    return true;
  } catch {
    check(false, `${what} (timed out after ${timeoutMs / 1000} s)`);
    return false;
  }
};

// After an edit at simulated time t: waits until E < 4 % (from 0.1 s after the edit on) or 3 simulated seconds have
// passed; {ok: the wait did not time out, f: the newest frame}. The caller checks f against the issue's 4 %.
const reforms = async (page, t, what) => {
  const ok = await waitFor(page, (t0) => window.__ff.frame.time > t0 + 0.1 && window.__ff.frame.errorRate < 4 ||
                           window.__ff.frame.time > t0 + 3, t, 180_000, what);
  return { ok, f: await page.evaluate(() => window.__ff.frame) };
};

// The frame clock on its own (no browser): interpolation within the pair, clamping, and the frames shown as they are.
{
  const c = new FrameClock();
  c.push({ frame: 0, time: 0, count: 10 }, 0);
  const first = c.update(50);
  c.push({ frame: 1, time: 0.1, count: 10 }, 100);
  const atArrival = c.update(100), half = c.update(150), halfTime = c.time, late = c.update(400);
  const ok1 = first === 1 && atArrival === 0 && Math.abs(half - 0.5) < 1e-9 && Math.abs(halfTime - 0.05) < 1e-9 && late === 1;
  const more = c.push({ frame: 2, time: 0.2, count: 12 }, 200);   // another particle count: shown as it is
  const fresh = c.update(210);
  c.push({ frame: 3, time: 0.3, count: 12 }, 300);
  const back = c.push({ frame: 0, time: 0, count: 12 }, 400);     // a restart or a playback loop
  c.push({ frame: 1, time: 0.0166, count: 12 }, 500);
  const jump = c.push({ frame: 500, time: 8.3, count: 12 }, 600); // a seek
  c.push({ frame: 501, time: 8.3166, count: 12 }, 700);
  const near = c.push({ frame: 503, time: 8.35, count: 12 }, 800, true);  // a seek two frames on: the caller's cut
  const nearAlpha = c.update(850);
  check(ok1 && !more && fresh === 1 && !back && !jump && !near && nearAlpha === 1 && c.discontinuities === 4,
        `frame clock: alpha 0 at the newest frame's arrival, ${half} half way, 1 when late; a changed count, time going ` +
        `back, a jump and a cut (a near seek) are shown as they are (${c.discontinuities} discontinuities)`);
}

// Screenshot metrics for the looks on one held frame. Masks: pixels that differ from the shot without any fluid.
// Roughness: mean |Laplacian| of the luminance inside the fluid (pixels 2 px in from the edge of both masks), which
// sphere shading and the gaps between spheres raise and one smooth surface does not. Holes: uncovered pixels that
// cannot be reached from the image border (gaps inside the silhouette). See-through: how much of a change of the
// background shows inside the fluid (0: opaque).
async function lookMetrics(page, shots) {
  const b64 = Object.fromEntries(Object.entries(shots).map(([k, v]) => [k, v.toString('base64')]));
  return page.evaluate(async (b64s) => {
    const im = {};
    let W = 0, H = 0;
    for (const [k, v] of Object.entries(b64s)) {
      const img = new Image();
      img.src = `data:image/png;base64,${v}`;
      await img.decode();
      const c = document.createElement('canvas');
      W = c.width = img.width;
      H = c.height = img.height;
      const g = c.getContext('2d');
      g.drawImage(img, 0, 0);
      im[k] = g.getImageData(0, 0, W, H).data;
    }
    const N = W * H;
    const lum = (a, i) => 0.299 * a[4 * i] + 0.587 * a[4 * i + 1] + 0.114 * a[4 * i + 2];
    const mask = (a) => {
      const m = new Uint8Array(N);
      for (let i = 0; i < N; ++i) {
        const d = Math.abs(a[4 * i] - im.bg[4 * i]) + Math.abs(a[4 * i + 1] - im.bg[4 * i + 1]) + Math.abs(a[4 * i + 2] - im.bg[4 * i + 2]);
        m[i] = d > 30 ? 1 : 0;
      }
      return m;
    };
    const count = (m) => m.reduce((s, v) => s + v, 0);
    const holes = (m) => {
      const seen = new Uint8Array(N), stack = [];
      for (let x = 0; x < W; ++x) stack.push(x, (H - 1) * W + x);
      for (let y = 0; y < H; ++y) stack.push(y * W, y * W + W - 1);
      let reached = 0;
      while (stack.length) {
        const i = stack.pop();
        if (seen[i] || m[i]) continue;
        seen[i] = 1;
        reached += 1;
        const x = i % W, y = (i / W) | 0;
        if (x > 0) stack.push(i - 1);
        if (x < W - 1) stack.push(i + 1);
        if (y > 0) stack.push(i - W);
        if (y < H - 1) stack.push(i + W);
      }
      return N - count(m) - reached;
    };
    const ms = mask(im.spheres), ml = mask(im.liquid);
    const interior = new Uint8Array(N);
    for (let y = 2; y < H - 2; ++y) for (let x = 2; x < W - 2; ++x) {
      let all = 1;
      for (let dy = -2; dy <= 2 && all; ++dy) for (let dx = -2; dx <= 2; ++dx) {
        const j = (y + dy) * W + x + dx;
        if (!(ms[j] && ml[j])) { all = 0; break; }
      }
      interior[y * W + x] = all;
    }
    const rough = (a) => {
      let s = 0, n = 0;
      for (let i = 0; i < N; ++i) if (interior[i]) {
        s += Math.abs(4 * lum(a, i) - lum(a, i - 1) - lum(a, i + 1) - lum(a, i - W) - lum(a, i + W));
        n += 1;
      }
      return n ? s / n : NaN;
    };
    // The background's own change, where neither look covers anything.
    let bgShift = 0, nb = 0;
    for (let i = 0; i < N; ++i) if (!ms[i] && !ml[i]) bgShift += lum(im.bgBright, i) - lum(im.bg, i), nb += 1;
    bgShift /= Math.max(1, nb);
    const through = (dark, bright) => {
      let s = 0, n = 0;
      for (let i = 0; i < N; ++i) if (interior[i]) s += lum(bright, i) - lum(dark, i), n += 1;
      return n ? s / n / bgShift : NaN;
    };
    return { width: W, height: H, interior: count(interior), bgShift,
             spheres: { coverage: count(ms), holes: holes(ms), roughness: rough(im.spheres), seeThrough: through(im.spheres, im.spheresBright) },
             liquid: { coverage: count(ml), holes: holes(ml), roughness: rough(im.liquid), seeThrough: through(im.liquid, im.liquidBright) } };
  }, b64);
}

// Sampled particles, drawn between the frames they interpolate: `rounds` samples at random moments, 32 particles each.
async function sampleInterpolation(page, rounds, gapMs) {
  const samples = [];
  for (let k = 0; k < rounds; ++k) {
    await sleep(gapMs * (0.5 + Math.random()));
    const s = await page.evaluate(() => {
      const n = window.__ff.frame?.count ?? 0;
      const ids = Array.from({ length: 32 }, (_, j) => Math.floor(((j + Math.random()) * n) / 32));
      return window.__ff.sampleInterpolation(ids);
    });
    if (s) samples.push(s);
  }
  let between = 0, total = 0, inner = 0, behind = 0, far = 0, pairs = 0, worst = 0, extent = 0;
  for (const s of samples) {
    if (s.alpha > 0.02 && s.alpha < 0.98 && !s.single) inner += 1;
    // At most one frame behind: the pair is (the frame received before the newest, the newest).
    if (s.b.frame !== s.newest || (!s.single && s.a.frame !== s.previous)) behind += 1;
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (const p of s.samples) for (let a = 0; a < 3; ++a) lo[a] = Math.min(lo[a], p.newer[a]), hi[a] = Math.max(hi[a], p.newer[a]);
    const ext = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    extent = Math.max(extent, ext);
    for (const p of s.samples) {
      total += 1;
      let ok = true;
      for (let a = 0; a < 3; ++a) {
        const l = Math.min(p.older[a], p.newer[a]), h = Math.max(p.older[a], p.newer[a]), tol = 1e-6 * (1 + Math.abs(h));
        const want = p.older[a] + s.alpha * (p.newer[a] - p.older[a]);
        worst = Math.max(worst, Math.abs(p.drawn[a] - want));
        if (!(p.drawn[a] >= l - tol && p.drawn[a] <= h + tol) || Math.abs(p.drawn[a] - want) > 1e-5 * (1 + Math.abs(want))) ok = false;
      }
      if (ok) between += 1;
      if (!s.single) {
        pairs += 1;
        // A particle that moves more than a tenth of the fluid's extent in one frame: the two frames' orders differ.
        if (Math.hypot(p.newer[0] - p.older[0], p.newer[1] - p.older[1], p.newer[2] - p.older[2]) > 0.1 * ext) far += 1;
      }
    }
  }
  return { rounds: samples.length, total, between, inner, behind, worst, far, pairs, farFraction: pairs ? far / pairs : NaN,
           alphas: samples.map((s) => Number(s.alpha.toFixed(2))) };
}

// Main-thread time over `ms` of wall time: chromium's own task time for the page's main thread (CDP Performance
// metrics) and the viewer's counters, per drawn and per received frame.
async function mainThreadTime(page, cdp, ms) {
  const read = async () => {
    const { metrics } = await cdp.send('Performance.getMetrics');
    const m = Object.fromEntries(metrics.map((x) => [x.name, x.value]));
    const s = await page.evaluate(() => ({ drawn: window.__ff.renderedFrames, recv: window.__ff.framesReceived, ...window.__ff.main }));
    return { ...s, task: m.TaskDuration * 1000, script: m.ScriptDuration * 1000 };
  };
  const a = await read();
  await sleep(ms);
  const b = await read();
  const drawn = Math.max(1, b.drawn - a.drawn), recv = Math.max(1, b.recv - a.recv);
  return { drawn, recv, taskMsPerDraw: (b.task - a.task) / drawn, scriptMsPerDraw: (b.script - a.script) / drawn,
           frameHandlingMsPerFrame: (b.ingestMs - a.ingestMs + b.decodeMs - a.decodeMs) / recv,
           mainDecodeMsPerFrame: (b.decodeMs - a.decodeMs) / recv, workerDecodeMsPerFrame: (b.workerDecodeMs - a.workerDecodeMs) / recv,
           renderLoopMsPerDraw: (b.renderMs - a.renderMs) / drawn };
}

// Hides the HUD, the panel and the XR buttons (the looks' screenshots compare the canvas alone), or shows them again.
const chrome = (page, visible) => page.evaluate((v) => {
  for (const id of ['hud', 'panel', 'xr-buttons']) document.getElementById(id).style.visibility = v ? '' : 'hidden';
}, visible);
// Waits until the page has drawn `n` more frames.
// (A held page draws only when something changed: each round asks for one.)
const drawn = async (page, n = 2) => {
  for (let k = 0; k < n; ++k) {
    const f0 = await page.evaluate(() => (window.__ff.redraw(), window.__ff.renderedFrames));
    await page.waitForFunction((f) => window.__ff.renderedFrames > f, f0, { timeout: 60_000, polling: 50 });
  }
  await sleep(100);
};

// Playback: the seek slider. It shows the hello's frame count and follows the frame played; then two seeks from it
// (set and let go, as a drag ends), back to frame 2 and far forward to frame 32. After each: the frames received
// after the seek are at most a few still on their way, then that frame and the ones after it in order; that frame
// broke the interpolation (its pair is itself: drawn positions read back from the GPU equal its own, not a mix with
// the frame before the jump); the mesh animation is at its time (the clip's time, and the mesh shown there).
async function playbackSeeks(page) {
  const N = await page.evaluate(() => window.__ff.hello.frames);
  const ui = await page.evaluate(() => {
    const el = document.getElementById('rng-seek');
    return { hidden: document.getElementById('seek').hidden, max: Number(el.max), value: Number(el.value),
             frame: window.__ff.frame.frame };
  });
  check(!ui.hidden && ui.max === N - 1 && Math.abs(ui.value - ui.frame) <= 1,
        `playback: the seek slider shows frames 0 to ${ui.max} (the hello's ${N} frames) and follows the frame played ` +
        `(at ${ui.value}, frame ${ui.frame})`);
  // Out of the first frames, so that the seek back to 2 is a jump.
  await waitFor(page, (n) => window.__ff.frame.frame >= 8 && window.__ff.frame.frame <= n - 6, N, 15_000, 'playback: mid-run');
  const result = {};
  const shown = {};
  for (const k of [2, 32]) {
    const r = await page.evaluate(async (k) => {
      const s = window.__ff, from = s.frame.frame, r0 = s.framesReceived, cuts0 = s.seek.cuts;
      const fromCentroid = s.frame.centroid;
      const el = document.getElementById('rng-seek');
      el.value = String(k);
      el.dispatchEvent(new Event('input'));
      el.dispatchEvent(new Event('change'));
      const tick = () => new Promise((res) => setTimeout(res, 0));
      const t0 = performance.now();
      while (s.frame.frame !== k && performance.now() - t0 < 10_000) await tick();
      if (s.frame.frame !== k) return { from, k, arrived: false };
      // At once, in the task after the one that took frame k in: what the GPU draws for 32 sampled particles.
      const n = s.frame.count;
      const sample = s.sampleInterpolation(Array.from({ length: 32 }, (_, j) => Math.floor(((j + 0.5) * n) / 32)));
      const centroid = s.frame.centroid;
      // The next display frame drawn (the mesh animation is set there).
      const d0 = s.renderedFrames;
      while (s.renderedFrames === d0 && performance.now() - t0 < 15_000) await new Promise((res) => requestAnimationFrame(res));
      const anim = { clipTime: s.animation.clipTime, time: s.animation.time, drawnTime: s.interp.time,
                     newest: s.frame.frame, duration: s.animation.duration, shown: s.animationShown() };
      // Five more frames.
      while (s.framesReceived < r0 + 8 && performance.now() - t0 < 15_000) await new Promise((res) => setTimeout(res, 20));
      const frames = s.history.filter((h) => h.received > r0).map((h) => ({ frame: h.frame, continues: h.continues }));
      const slider = Number(el.value);
      return { from, k, arrived: true, sample, anim, frames, slider, newest: s.frame.frame, cuts: s.seek.cuts - cuts0,
               jump: Math.hypot(...centroid.map((v, a) => v - fromCentroid[a])) };
    }, k);
    if (!check(r.arrived, `playback: seek from frame ${r.from} to ${k}: frame ${k} arrives`)) continue;
    const fps = await page.evaluate(() => window.__ff.hello.fps);
    // The frames after the seek: a few still on their way (going on from where it was), then k and the ones after it,
    // in order (a slow client may skip one: the server keeps only the newest frame per client; a loop wraps to 0).
    const at = r.frames.findIndex((f) => f.frame === k);
    const stale = r.frames.slice(0, at), after = r.frames.slice(at);
    const onward = (f, prev) => f.frame > prev || (f.frame < prev && prev >= N - 3 && f.frame <= 2);
    const staleOk = stale.length <= 3 && stale.every((f, i) => onward(f, i ? stale[i - 1].frame : r.from) && f.frame !== k);
    const inOrder = after.length >= 4 && after.every((f, i) => i === 0 || onward(f, after[i - 1].frame));
    check(at >= 0 && staleOk && inOrder,
          `playback: after the seek from ${r.from} to ${k} the frames received are ${r.frames.map((f) => f.frame).join(' ')} ` +
          `(${stale.length} still on their way, then ${k} and the ones after it in order)`);
    // Not interpolated across the jump: the seek's frame breaks the pair, the GPU draws its positions as they are.
    const sm = r.sample;
    let same = 0, exact = 0;
    for (const p of sm?.samples ?? []) {
      if ([0, 1, 2].every((a) => p.older[a] === p.newer[a])) same += 1;
      if ([0, 1, 2].every((a) => Math.abs(p.drawn[a] - p.newer[a]) <= 1e-6 * (1 + Math.abs(p.newer[a])))) exact += 1;
    }
    const n = sm?.samples.length ?? 0;
    check(after[0]?.continues === false && sm && sm.b.frame === k && sm.single && n > 0 && same === n && exact === n &&
          after.slice(1).every((f, i) => f.continues || f.frame < after[i].frame),
          `playback: the seek's frame ${k} is drawn as it is, not interpolated across the jump (its pair is itself: ` +
          `${same} of ${n} sampled particles in both slots, ${exact} drawn at its positions; the fluid's centroid jumped ` +
          `${r.jump.toFixed(3)} m), and the frames after it interpolate again`);
    // The mesh animation follows: drawn at frame k's time (or just after it), the clip at that time.
    const a = r.anim, tk = k / fps;
    const clipWant = a.drawnTime % a.duration;
    const animOk = a.drawnTime >= tk - 1e-9 && a.drawnTime <= tk + 1.5 / fps && a.time === a.drawnTime &&
                   Math.abs(a.clipTime - clipWant) < 1e-4 && a.shown >= 0;
    shown[k] = a.shown;
    check(animOk, `playback: the mesh animation follows the seek to ${k} (drawn at t = ${a.drawnTime.toFixed(4)} s, frame ` +
                  `${k} is at ${tk.toFixed(4)} s; the clip at ${a.clipTime.toFixed(4)} s; mesh ${a.shown} of the run's shown)`);
    check(r.slider === r.newest || Math.abs(r.slider - r.newest) <= 1,
          `playback: after the seek the slider follows the frames again (at ${r.slider}, frame ${r.newest})`);
    result[k] = { from: r.from, frames: r.frames.map((f) => f.frame), stale: stale.length, same, exact, samples: n,
                  centroid_jump_m: r.jump, anim: a };
  }
  if (2 in shown && 32 in shown)
    check(shown[2] !== shown[32], `playback: the mesh shown changes with the seek (mesh ${shown[2]} at frame 2, ${shown[32]} at frame 32)`);
  return result;
}

const summary = {};
const browser = await chromium.launch({ executablePath: browserPath, headless: true, args: CHROMIUM_ARGS });
try {
  // ---- live ---------------------------------------------------------------------------------------------------
  // --max-fps 10: the simulation slower than the display on purpose (the viewer must not wait for it).
  const extra = [...(args.cache ? ['--cache', args.cache] : []), ...(args.mesh ? ['--mesh', args.mesh] : []), '--max-fps', '10'];
  const server = await startServer(sceneFile, extra);
  console.log(`[${elapsed()} s] serving ${server.url}`);
  try {
    // Path traversal on the real port.
    for (const target of ['/../../etc/passwd', '/%2e%2e/%2e%2e/etc/passwd', '/%2E%2E%2F%2E%2E%2Fetc%2Fpasswd',
                          '/..%2f..%2f..%2fetc%2fpasswd', '/vendor/three/../../../../etc/passwd',
                          '/vendor/three/%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd', '/%252e%252e/etc/passwd', '/..\\..\\etc\\passwd']) {
      const r = await rawGet(server.port, target);
      check((r.status === 403 || r.status === 404 || r.status === 400) && !r.body.includes('root:'), `GET ${target} -> ${r.status}`);
    }
    check((await rawGet(server.port, '/')).status === 200, 'GET / -> 200');

    const page = await browser.newPage({ viewport: { width: 640, height: 400 } });
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(String(e)));
    page.on('console', (m) => m.type() === 'error' && pageErrors.push(m.text()));
    await page.goto(server.url);
    // Frames: at least 120.
    if (await waitFor(page, () => window.__ff?.framesReceived >= 120, null, 150_000, 'received 120 frames')) {
      check(true, `received ${await page.evaluate(() => window.__ff.framesReceived)} frames [${elapsed()} s]`);
    }
    // Speed over the frames received so far (from the 20th on): frames the simulation stepped, frames that arrived,
    // frames the page rendered, per second of wall time.
    const speed = await page.evaluate(() => {
      const h = window.__ff.history, a = h.find((e) => e.received >= 20), b = h[h.length - 1];
      const secs = (b.wall - a.wall) / 1000;
      return { sim: (b.frame - a.frame) / secs, recv: (b.received - a.received) / secs,
               render: window.__ff.hud?.fps ?? NaN };
    });
    summary.while_forming = { sim_steps_per_s: speed.sim, frames_received_per_s: speed.recv, render_fps: speed.render };
    const hudFps = await page.textContent('#hud-fps'), hudStep = await page.textContent('#hud-step');
    const hudSim = await page.textContent('#hud-simfps'), hudErr = await page.textContent('#hud-error');
    summary.hud = { fps: hudFps, step_ms: hudStep, sim_fps: hudSim, error_rate: hudErr,
                    particles: await page.textContent('#hud-count') };
    console.log(`HUD: render ${hudFps} fps, step ${hudStep} ms, simulation ${hudSim} frames/s, error rate ${hudErr} %`);
    console.log(`speed while pouring and forming (10k bunny; 60 steps/s is real time): simulation ${speed.sim.toFixed(1)} steps/s, ` +
                `received ${speed.recv.toFixed(1)} frames/s, render ${speed.render.toFixed(1)} fps`);
    check(Number.isFinite(Number(hudFps)) && Number.isFinite(Number(hudStep)), 'HUD shows FPS and step time');
    // The look, chosen by measured frame time: liquid if it holds the display rate, else the fall back to spheres.
    await waitFor(page, () => Number.isFinite(window.__ff.look.liquidFrameMs) || window.__ff.look.fellBack, null, 60_000,
                  'the liquid look measured its frame time');
    const look = await page.evaluate(() => window.__ff.look);
    summary.look = look;
    const cannotHold = look.liquidFrameMs > 1.25 * look.displayMs + 2;
    console.log(`look: liquid drew a frame every ${look.liquidFrameMs?.toFixed(1)} ms (its targets at ${look.liquidScale}× ` +
                `resolution), the display's period ${look.displayMs?.toFixed(1)} ms: ${look.mode}` +
                `${look.fellBack ? ` (fell back: ${look.reason})` : ''} [${await page.evaluate(() => window.__ff.gpu)}]`);
    check(look.auto && Number.isFinite(look.liquidFrameMs) && (cannotHold ? look.mode === 'spheres' && look.fellBack : look.mode === 'liquid'),
          `the look follows the measured frame time (${look.mode})`);

    // Drawing at the display's rate, not the simulation's: frames drawn per frame received, over 5 s.
    const rates = await page.evaluate(async () => {
      const s = window.__ff, d0 = s.renderedFrames, r0 = s.framesReceived, w0 = performance.now();
      await new Promise((r) => setTimeout(r, 5000));
      const secs = (performance.now() - w0) / 1000;
      return { drawn: s.renderedFrames - d0, received: s.framesReceived - r0, secs, look: s.look.mode };
    });
    summary.render_fps_continuous = rates.drawn / rates.secs;
    summary.draws_per_frame_received = rates.drawn / Math.max(1, rates.received);
    console.log(`render: ${summary.render_fps_continuous.toFixed(1)} draws/s (${rates.look}; headless chromium, SwiftShader), ` +
                `${(rates.received / rates.secs).toFixed(1)} frames received/s (serve --max-fps 10): ` +
                `${summary.draws_per_frame_received.toFixed(2)} draws per frame received`);
    // 1.5×, not more: a viewer that draws when a frame arrives draws 1×, and SwiftShader on two cores shared with the
    // rest of CI drew 19 frames a second against 7.8 received (2.46×), where a quiet machine draws 3–6×.
    check(rates.received > 0 && rates.drawn >= 1.5 * rates.received,
          `the viewer draws at least 1.5× as many frames as it receives (${rates.drawn} drawn, ${rates.received} received in ${rates.secs.toFixed(1)} s)`);

    // Interpolation, read back from the GPU on sampled particles.
    const interp = await sampleInterpolation(page, 16, 180);
    summary.interpolation = interp;
    console.log(`interpolation: ${interp.rounds} samples × 32 particles, alphas ${interp.alphas.join(' ')}; ` +
                `largest miss of the drawn position ${interp.worst.toExponential(1)} m`);
    check(interp.rounds >= 10 && interp.between === interp.total,
          `drawn positions lie between the two frames they interpolate (${interp.between} of ${interp.total} sampled particles)`);
    check(interp.behind === 0, `never more than one frame behind: each sample's pair is (the previous frame, the newest) ` +
                               `(${interp.behind} of ${interp.rounds} otherwise)`);
    check(interp.inner >= 0.3 * interp.rounds, `drawn in between, not at the frames: ${interp.inner} of ${interp.rounds} samples ` +
                                               `with 0.02 < alpha < 0.98`);
    // The particles' order between frames: the live server sends them in particle-id order (before, in the solver's
    // cell-sorted order, 1.8–2.9 % of the sampled particles jumped across the fluid between two frames).
    check(interp.pairs > 0 && interp.farFraction <= 0.005,
          `live: particles keep their order between frames (${(100 * interp.farFraction).toFixed(2)} % of ${interp.pairs} ` +
          `sampled particles moved more than a tenth of the fluid's extent between the two frames of a pair; at most 0.5 %)`);

    // Frames as compact as before: 16-bit positions and a target byte per particle.
    const wire = await page.evaluate(() => ({ bytes: window.__ff.bytesReceived, particles: window.__ff.particlesReceived,
                                              frames: window.__ff.framesReceived }));
    summary.bytes_per_particle = wire.bytes / wire.particles;
    check(summary.bytes_per_particle > 6.9 && summary.bytes_per_particle < 7.1,
          `${summary.bytes_per_particle.toFixed(3)} bytes per particle on the WebSocket (${wire.frames} frames, ${(wire.bytes / 1e6).toFixed(1)} MB)`);

    // Main-thread time per drawn frame: this page (frames from the Worker), then the old path (WebSocket and decoding on
    // the main thread, ?decode=main) in a page of its own, in the same look, while this one stands still.
    {
      const cdp = await page.context().newCDPSession(page);
      await cdp.send('Performance.enable');
      const worker = await mainThreadTime(page, cdp, 4000);
      await page.evaluate(() => window.__ff.suspend(true));
      const oldPage = await browser.newPage({ viewport: { width: 640, height: 400 } });
      oldPage.on('pageerror', (e) => pageErrors.push(`old path: ${e}`));
      await oldPage.goto(`${server.url}?decode=main&look=${look.mode}`);
      await waitFor(oldPage, () => window.__ff?.framesReceived >= 8, null, 60_000, 'old path: frames');
      await sleep(1500);
      const ocdp = await oldPage.context().newCDPSession(oldPage);
      await ocdp.send('Performance.enable');
      const old = await mainThreadTime(oldPage, ocdp, 4000);
      const oldDecode = await oldPage.evaluate(() => window.__ff.decode);
      await oldPage.close();
      await page.evaluate(() => window.__ff.suspend(false));
      summary.main_thread = { worker, old };
      const f = (x) => x.toFixed(2);
      console.log(`main thread per drawn frame (${look.mode}): with the Worker ${f(worker.taskMsPerDraw)} ms of tasks ` +
                  `(${f(worker.scriptMsPerDraw)} ms script; render loop ${f(worker.renderLoopMsPerDraw)} ms), old path ` +
                  `${f(old.taskMsPerDraw)} ms (${f(old.scriptMsPerDraw)} ms script; render loop ${f(old.renderLoopMsPerDraw)} ms); ` +
                  `per received frame the main thread spends ${f(worker.frameHandlingMsPerFrame)} ms with the Worker ` +
                  `(which decodes in ${f(worker.workerDecodeMsPerFrame)} ms), ${f(old.frameHandlingMsPerFrame)} ms on the old path ` +
                  `(decoding ${f(old.mainDecodeMsPerFrame)} ms)`);
      // Sub-millisecond times on two loaded cores are noise-bound (the same render loop reads differently in the two
      // pages): the check is where the decoding runs; the times are printed.
      check(oldDecode === 'main' && worker.mainDecodeMsPerFrame === 0 && worker.workerDecodeMsPerFrame > 0 &&
            old.mainDecodeMsPerFrame > 0,
            `frames are decoded in the Worker (${f(worker.workerDecodeMsPerFrame)} ms a frame there, none on the main thread; ` +
            `the old path decodes on the main thread, ${f(old.mainDecodeMsPerFrame)} ms a frame)`);
      await cdp.detach();
    }

    // Without a WebXR device the VR and AR buttons say so (and nothing breaks); the XR part below emulates one.
    const xrButtons = await page.evaluate(() => [...document.querySelectorAll('#xr-buttons button')].map((b) => b.textContent));
    check(xrButtons.length === 2 && xrButtons.every((t) => /NOT SUPPORTED/.test(t)),
          `without an XR device the buttons say so: ${xrButtons.join(', ')}`);

    // Screenshot with particles.
    const shot = await page.screenshot({ path: path.join(outDir, 'live.png') });
    const px = await colouredPixels(page, shot);
    summary.screenshot_coloured_pixels = px.coloured;
    check(px.coloured > 0.005 * px.total, `screenshot shows particles (${px.coloured} coloured pixels of ${px.total})`);

    // The live surface: ticking "mesh" asks the server to reconstruct the fluid about twice a second; the mesh
    // arrives and is drawn; unticking stops it.
    check(await page.evaluate(() => !document.getElementById('chk-mesh').checked && window.__ff.hello.surface === false),
          'live: the mesh starts off (reconstruction costs simulation time)');
    await page.check('#chk-mesh');
    if (await waitFor(page, () => window.__ff.surface.received >= 2 && window.__ff.surface.triangles > 500, null, 30_000,
                      'live surface arrives')) {
      const s = await page.evaluate(() => window.__ff.surface);
      summary.live_surface = s;
      const meshShot = await page.screenshot({ path: path.join(outDir, 'live-mesh.png') });
      const mpx = await colouredPixels(page, meshShot);
      check(mpx.coloured > px.coloured, `live surface: ${s.received} meshes, the last ${s.triangles} triangles from frame ` +
                                        `${s.frame}, built in ${s.buildMs.toFixed(0)} ms; drawn (${mpx.coloured} coloured pixels)`);
    }
    await page.uncheck('#chk-mesh');
    check(await waitFor(page, () => window.__ff.hello.surface === false, null, 10_000, 'live surface off'), 'live surface off again');

    // Live mode has no seek control, and the server answers a seek with an error (the stream goes on).
    {
      const hidden = await page.evaluate(() => document.getElementById('seek').hidden);
      const r = await page.evaluate(async () => {
        const ws = new WebSocket(`ws://${location.host}/ws`);
        await new Promise((res) => (ws.onopen = res));
        let error = null;
        ws.onmessage = (e) => {
          if (typeof e.data !== 'string') return;
          const m = JSON.parse(e.data);
          if (m.type === 'error' && /seek/.test(m.message)) error = m.message;
        };
        ws.send(JSON.stringify({ type: 'seek', frame: 3 }));
        const t = performance.now();
        while (error === null && performance.now() - t < 5000) await new Promise((res) => setTimeout(res, 50));
        ws.close();
        return { error, frame: window.__ff.frame.frame };
      });
      await sleep(500);
      const later = await page.evaluate(() => window.__ff.frame.frame);
      check(hidden && r.error !== null && later > r.frame,
            `live: no seek control (hidden: ${hidden}); a seek is answered "${r.error}", the simulation goes on ` +
            `(frame ${r.frame} -> ${later})`);
    }

    // Garbage over a second WebSocket: the server logs and ignores each message (an oversized one too) and that
    // client stays connected and keeps receiving frames; the viewer's stream goes on.
    const garbage = await page.evaluate(async () => {
      const ws = new WebSocket(`ws://${location.host}/ws`);
      ws.binaryType = 'arraybuffer';
      await new Promise((r) => (ws.onopen = r));
      let closed = null, frames = 0;
      ws.onclose = (e) => (closed = e.code);
      ws.onmessage = (e) => { if (typeof e.data !== 'string') frames += 1; };
      ws.send('garbage{');
      ws.send('{"type":"pose","target":99,"translate":[0,0,0]}');
      ws.send(new Uint8Array([0, 1, 2, 3, 255]).buffer);
      ws.send('x'.repeat(100_000));
      const before = frames;
      await new Promise((r) => setTimeout(r, 2000));
      const result = { closed, framesAfter: frames - before };
      ws.close();
      return result;
    });
    const before = await page.evaluate(() => window.__ff.framesReceived);
    await sleep(1500);
    const after = await page.evaluate(() => window.__ff.framesReceived);
    check(server.proc.exitCode === null && garbage.closed === null && garbage.framesAfter > 0 && after > before,
          `garbage, binary and oversized WebSocket messages ignored: that client stays open (closed: ${garbage.closed}) ` +
          `and got ${garbage.framesAfter} frames after them; the viewer got ${after - before} frames in 1.5 s`);

    // Editing: wait until formed (E < 4 %), drag the target, then E against the moved target within 3 simulated s.
    if (await waitFor(page, () => window.__ff.frame?.errorRate < 4, null, 120_000, 'formed before the drag (E < 4 %)')) {
      const formed = await page.evaluate(() => window.__ff.frame);
      console.log(`[${elapsed()} s] formed: E = ${formed.errorRate.toFixed(2)} % at t = ${formed.time.toFixed(2)} s`);

      // The three looks on one held frame of the formed bunny, the canvas alone; the background changed for the
      // see-through check. PNGs in --out.
      {
        const shots = {};
        await chrome(page, false);
        await page.evaluate(() => window.__ff.hold(true));
        const shoot = async (lookName, key, file) => {
          await page.evaluate((l) => window.__ff.setLook(l), lookName);
          await drawn(page, 2);
          shots[key] = await page.screenshot(file ? { path: path.join(outDir, file) } : {});
        };
        await shoot('none', 'bg', 'look-background.png');
        await shoot('spheres', 'spheres', 'look-spheres.png');
        await shoot('liquid', 'liquid', 'look-liquid.png');
        await page.evaluate(() => window.__ff.setBackground(0x8a9bb0));
        await shoot('none', 'bgBright');
        await shoot('spheres', 'spheresBright');
        await shoot('liquid', 'liquidBright', 'look-liquid-light-background.png');
        await page.evaluate(() => window.__ff.setBackground(0x111418));
        const m = await lookMetrics(page, shots);
        summary.looks = m;
        const L = m.liquid, S = m.spheres;
        console.log(`looks on one frame (${m.width}×${m.height}): coverage liquid ${L.coverage} px, spheres ${S.coverage} px ` +
                    `(${(L.coverage / S.coverage).toFixed(2)}×); roughness (mean |Laplacian| of luminance inside) liquid ` +
                    `${L.roughness.toFixed(2)}, spheres ${S.roughness.toFixed(2)} (${(L.roughness / S.roughness).toFixed(2)}×); ` +
                    `holes liquid ${L.holes} px, spheres ${S.holes} px; see-through liquid ${L.seeThrough.toFixed(3)}, ` +
                    `spheres ${S.seeThrough.toFixed(3)} of the background's change`);
        check(m.interior > 2000 && L.roughness < 0.6 * S.roughness,
              `liquid: one smooth surface (roughness ${L.roughness.toFixed(2)} against the spheres' ${S.roughness.toFixed(2)})`);
        // (Holes are printed, not checked: dark, thin liquid over the dark floor can read as background.)
        check(L.coverage > 0.85 * S.coverage && L.coverage < 1.5 * S.coverage,
              `liquid: the spheres' silhouette, one body (coverage ${(L.coverage / S.coverage).toFixed(2)}× theirs)`);
        check(L.seeThrough > 0.08 && L.seeThrough > S.seeThrough + 0.05,
              `liquid: the background is visible through it (${(100 * L.seeThrough).toFixed(1)} % of its change shows, ` +
              `${(100 * S.seeThrough).toFixed(1)} % through the spheres)`);
        // The mesh look: the live surface (the server reconstructs it while the look shows it).
        const s0 = await page.evaluate(() => window.__ff.surface.received);
        const input = (id, v) => page.evaluate(([i, x]) => {  // the panel is hidden: set the control and tell the page
          const e = document.getElementById(i);
          if (e.type === 'checkbox') e.checked = x; else e.value = x;
          e.dispatchEvent(new Event('change'));
        }, [id, v]);
        await input('sel-look', 'mesh');
        if (await waitFor(page, (n) => window.__ff.surface.received > n, s0, 30_000, 'mesh look: a live surface')) {
          await drawn(page, 2);
          const meshShot = await page.screenshot({ path: path.join(outDir, 'look-mesh.png') });
          const mpx = await colouredPixels(page, meshShot);
          check(mpx.coloured > 0.5 * S.coverage, `mesh look: the live surface drawn (${mpx.coloured} coloured pixels)`);
        }
        await input('chk-mesh', false);
        await page.evaluate((l) => window.__ff.setLook(l), look.mode);
        await page.evaluate(() => window.__ff.hold(false));
        await chrome(page, true);
        console.log(`[${elapsed()} s] looks saved: ${['look-liquid.png', 'look-spheres.png', 'look-mesh.png'].map((f) => path.join(outDir, f)).join(' ')}`);
      }
      const from = await page.evaluate(() => window.__ff.targetScreen(0));
      const to = await page.evaluate(() => {
        const h = window.__ff.hello.targets[0];
        const size = h.box.max[0] - h.box.min[0];
        return window.__ff.project([h.pivot[0] + 0.35 * size, h.pivot[1], h.pivot[2] - 0.35 * size]);
      });
      const acks = await page.evaluate(() => window.__ff.poseAcks);
      await page.mouse.move(from.x, from.y);
      await page.mouse.down();
      for (let k = 1; k <= 10; ++k) {
        await page.mouse.move(from.x + ((to.x - from.x) * k) / 10, from.y + ((to.y - from.y) * k) / 10);
        await sleep(30);
      }
      await page.mouse.up();
      const dragDraw = await page.evaluate(() => window.__ff.drag);
      const lag = [...dragDraw.lagMs].sort((x, y) => x - y);
      summary.drag_draw = { moves: dragDraw.moves, checked: dragDraw.checked, drawn_next: dragDraw.drawnNext,
                            median_lag_ms: lag[lag.length >> 1] };
      check(dragDraw.checked >= 3 && dragDraw.drawnNext === dragDraw.checked,
            `the dragged box is drawn where the pointer put it in the next display frame (${dragDraw.drawnNext} of ` +
            `${dragDraw.checked} draws after ${dragDraw.moves} pointer moves; median ${lag[lag.length >> 1]?.toFixed(0)} ms from ` +
            `the event to the draw), before the server answers`);
      if (await waitFor(page, (n) => window.__ff.poseAcks > n && window.__ff.poses[0] &&
                          Math.hypot(...window.__ff.poses[0].translate) > 0.01, acks, 10_000, 'the server reports the new transform')) {
        await sleep(300);  // the last pose of the drag
        const pose = await page.evaluate(() => window.__ff.poses[0]);
        console.log(`[${elapsed()} s] server pose: translate [${pose.translate.map((v) => v.toFixed(3))}] m at t = ${pose.time.toFixed(2)} s`);
        check(true, `the server reports the new transform (moved ${Math.hypot(...pose.translate).toFixed(3)} m)`);
        const tMove = pose.time;
        // Until the shape has followed (centroid within a quarter of the move of where the target went) with E < 4 %,
        // or 3 simulated seconds have passed: checked below either way.
        await waitFor(page, ([t, c0, tr]) => {
          const f = window.__ff.frame;
          const miss = Math.hypot(...f.centroid.map((v, a) => v - c0[a] - tr[a]));
          // (at least 0.6 simulated s: the error rate at 0.5 s is the issue's figure)
          return f.time >= t + 3.0 || (f.time > t + 0.6 && f.errorRate < 4 && miss < 0.25 * Math.hypot(...tr));
        }, [tMove, formed.centroid, pose.translate], 180_000, 'the shape follows the drag');
        const hist = await page.evaluate(() => window.__ff.history);
        const afterMove = hist.filter((h) => h.time > tMove && h.time <= tMove + 3.0 + 1e-9);
        const last = afterMove.at(-1);
        const peak = Math.max(...afterMove.map((h) => h.error));
        const firstUnder = afterMove.find((h) => h.error < 4);
        // The issue's 1 % within 0.5 simulated s: the first frame under 1 %, and from when on it stays under.
        const firstUnder1 = afterMove.find((h) => h.error < 1);
        const lastOver1 = afterMove.filter((h) => h.error >= 1).at(-1);
        const settled1 = lastOver1 ? afterMove.find((h) => h.time > lastOver1.time) : afterMove[0];
        // The formed shape went where the target went: its centroid moved by the target's translation. With that,
        // an E under 4 % can only be E against the moved target (against the old place it would be ~ the move).
        const shift = last.centroid.map((v, a) => v - formed.centroid[a]);
        const miss = Math.hypot(...shift.map((v, a) => v - pose.translate[a]));
        summary.edit = { moved_m: Math.hypot(...pose.translate), centroid_shift_m: Math.hypot(...shift), centroid_miss_m: miss,
                         peak_error_pct: peak, error_when_followed_pct: last.error, followed_after_s: last.time - tMove,
                         first_under_4pct_after_s: firstUnder ? firstUnder.time - tMove : null,
                         first_under_1pct_after_s: firstUnder1 ? firstUnder1.time - tMove : null,
                         under_1pct_from_s: settled1 ? settled1.time - tMove : null,
                         error_at_0_5s_pct: afterMove.find((h) => h.time >= tMove + 0.5)?.error ?? null };
        const fs1 = (v) => (v === null || v === undefined ? 'not within the window' : `${v.toFixed(2)} s`);
        console.log(`edit: E under 1 % first at ${fs1(summary.edit.first_under_1pct_after_s)}, and stays under from ` +
                    `${fs1(summary.edit.under_1pct_from_s)} after the move; E at 0.5 s: ` +
                    `${summary.edit.error_at_0_5s_pct?.toFixed(2) ?? '–'} % (the issue asks < 1 % within 0.5 simulated s)`);
        console.log(`edit: after the move E peaked at ${peak.toFixed(2)} %, was ${last.error.toFixed(2)} % at ` +
                    `${(last.time - tMove).toFixed(2)} simulated s; the fluid's centroid moved ${Math.hypot(...shift).toFixed(3)} m ` +
                    `(${miss.toFixed(3)} m from the target's translation)`);
        check(miss < 0.25 * Math.hypot(...pose.translate), 'the formed shape followed the moved target');
        // Speed while serving the formed shape (from formed, through the drag, until it has followed): the issue's numbers.
        const win = hist.filter((h) => h.time >= formed.time);
        const w0 = win[0], w1 = win.at(-1), wsecs = (w1.wall - w0.wall) / 1000;
        summary.sim_steps_per_s = (w1.frame - w0.frame) / wsecs;
        summary.frames_received_per_s = (w1.received - w0.received) / wsecs;
        summary.render_fps = await page.evaluate(() => window.__ff.hud.fps);
        console.log(`speed serving the formed 10k bunny (60 steps/s is real time): simulation ${summary.sim_steps_per_s.toFixed(1)} ` +
                    `steps/s of wall time, received ${summary.frames_received_per_s.toFixed(1)} frames/s, render ` +
                    `${summary.render_fps.toFixed(1)} fps (headless chromium, SwiftShader, same 2 cores)`);
        check(last.error < 4, `E against the moved target under 4 % within 3 simulated seconds (at ${(last.time - tMove).toFixed(2)} s)`);
        check(summary.edit.under_1pct_from_s !== null && summary.edit.under_1pct_from_s <= 0.5 && last.time >= tMove + 0.5,
              `E against the moved target under 1 % within 0.5 simulated seconds and after (from ` +
              `${fs1(summary.edit.under_1pct_from_s)} on, through ${(last.time - tMove).toFixed(2)} s)`);
      }
    }

    // Rotating: shift-drag sideways turns the target about the vertical axis; the server reports the rotation and
    // the shape re-forms against the turned target (E < 4 % within 3 simulated s).
    {
      const from = await page.evaluate(() => window.__ff.targetScreen(0));
      const acks = await page.evaluate(() => window.__ff.poseAcks);
      const rot0 = await page.evaluate(() => window.__ff.poses[0]?.rotate?.[1] ?? 0);
      await page.keyboard.down('Shift');
      await page.mouse.move(from.x, from.y);
      await page.mouse.down();
      for (let k = 1; k <= 10; ++k) {
        await page.mouse.move(from.x + 6 * k, from.y);
        await sleep(30);
      }
      await page.mouse.up();
      await page.keyboard.up('Shift');
      if (await waitFor(page, ([n, r0]) => window.__ff.poseAcks > n && Math.abs(window.__ff.poses[0].rotate[1] - r0) > 5,
                        [acks, rot0], 10_000, 'the server reports the rotation')) {
        await sleep(300);
        const pose = await page.evaluate(() => window.__ff.poses[0]);
        check(true, `the server reports the rotation (${(pose.rotate[1] - rot0).toFixed(1)}° about y)`);
        const { ok, f } = await reforms(page, pose.time, 'the shape re-forms after the rotation');
        summary.rotate = { degrees: pose.rotate[1] - rot0, error_pct: f.errorRate, after_s: f.time - pose.time };
        check(ok && f.errorRate < 4, `E against the rotated target under 4 % within 3 simulated seconds ` +
                                     `(${f.errorRate.toFixed(2)} % at ${(f.time - pose.time).toFixed(2)} s)`);
      }
    }

    // Swapping the mesh (when the scene lists more than one, e.g. `--mesh` given): the server samples the new mesh,
    // says so in its hello, and the fluid forms the new shape (E against it < 4 % within 3 simulated s).
    const meshes = await page.evaluate(() => window.__ff.hello.meshes ?? []);
    if (args.mesh) check(meshes.length >= 2, `the mesh list has the extra mesh (${meshes.join(', ')})`);
    if (meshes.length >= 2) {
      const tSwap = await page.evaluate(() => window.__ff.frame.time);
      await page.selectOption('#sel-mesh', { index: 1 });
      if (await waitFor(page, () => window.__ff.hello.targets[0].mesh === 1, null, 120_000, 'the server swaps the mesh')) {
        check(true, `the server swapped target 0 to ${meshes[1]}`);
        const t1 = await page.evaluate(() => window.__ff.frame.time);
        const { ok, f } = await reforms(page, t1, 'the fluid forms the new mesh');
        const hist = await page.evaluate(() => window.__ff.history);
        const peak = Math.max(...hist.filter((h) => h.time > tSwap).map((h) => h.error));
        summary.swap = { error_peak_pct: peak, error_pct: f.errorRate, after_s: f.time - t1 };
        await page.screenshot({ path: path.join(outDir, 'swapped.png') });
        check(ok && f.errorRate < 4 && peak > f.errorRate,
              `E against the new mesh: ${peak.toFixed(2)} % just after the swap, ${f.errorRate.toFixed(2)} % at ` +
              `${(f.time - t1).toFixed(2)} simulated s (under 4 % within 3 s)`);
      }
    }

    // WebXR, emulated: IWER (Meta's WebXR runtime in JavaScript) stands in for a Quest 3 headset in a second page.
    // Enter VR from the VR button, see the XR loop draw, carry the target with the right controller's ray and the
    // trigger, leave VR and enter AR (table-top placement).
    {
      const xrPage = await browser.newPage({ viewport: { width: 800, height: 500 } });
      const xrErrors = [];
      xrPage.on('pageerror', (e) => xrErrors.push(String(e)));
      await xrPage.addInitScript({ path: path.join(path.dirname(new URL(import.meta.url).pathname), '..', '..',
                                                   'node_modules', 'iwer', 'build', 'iwer.min.js') });
      await xrPage.addInitScript(() => {
        // Stereo: two eyes side by side in the canvas (IWER's default is one view).
        const d = new IWER.XRDevice(IWER.metaQuest3, { stereoEnabled: true });
        d.installRuntime({ forceInstall: true });
        window.__xrDevice = d;
      });
      // The liquid in both eyes whatever this machine's frame time (?look= turns the fall back off).
      await xrPage.goto(`${server.url}?look=liquid`);
      await waitFor(xrPage, () => window.__ff?.framesReceived >= 3 && window.__ff.hello, null, 30_000, 'XR page connected');
      const labels = await xrPage.evaluate(() => [...document.querySelectorAll('#xr-buttons button')].map((b) => b.textContent));
      check(labels[0] === 'ENTER VR' && labels[1] === 'START AR', `with an (emulated) headset the buttons offer VR and AR: ${labels.join(', ')}`);
      await xrPage.click('#xr-buttons button >> nth=0');
      const inVr = await waitFor(xrPage, () => window.__ff.xr.presenting && window.__ff.xr.renderedFrames >= 20, null, 20_000,
                                 'VR session draws');
      if (inVr) {
        const xr = await xrPage.evaluate(() => window.__ff.xr);
        check(xr.mode === 'immersive-vr', `entered ${xr.mode}; the XR loop drew ${xr.renderedFrames} frames`);
        const vrShot = await xrPage.screenshot({ path: path.join(outDir, 'vr.png') });
        // The frame rate: the highest the session supports, asked for and granted.
        await waitFor(xrPage, () => window.__ff.xr.frameRate === window.__ff.xr.frameRateRequested, null, 5_000, 'XR frame rate');
        const rate = await xrPage.evaluate(() => window.__ff.xr);
        check(rate.supportedFrameRates && rate.frameRateRequested === Math.max(...rate.supportedFrameRates) &&
              rate.frameRate === rate.frameRateRequested,
              `XR: the highest frame rate requested (${rate.frameRateRequested} Hz of ${rate.supportedFrameRates?.join(', ')}; ` +
              `the session runs at ${rate.frameRate} Hz)`);
        // Both eyes draw the liquid: its smoothed depth holds liquid in each eye's viewport, and each half of the
        // canvas shows it.
        const cov = await xrPage.evaluate(() => ({ look: window.__ff.look.mode, ...window.__ff.liquidCoverage() }));
        const halves = await xrPage.evaluate(async (b64) => {
          const img = new Image();
          img.src = `data:image/png;base64,${b64}`;
          await img.decode();
          const c = document.createElement('canvas');
          c.width = img.width;
          c.height = img.height;
          const g = c.getContext('2d');
          g.drawImage(img, 0, 0);
          const d = g.getImageData(0, 0, c.width, c.height).data, n = [0, 0];
          for (let i = 0; i < d.length; i += 4) {
            const r = d[i], gg = d[i + 1], b = d[i + 2];
            if (Math.max(r, gg, b) - Math.min(r, gg, b) > 40 && Math.max(r, gg, b) > 60) n[((i / 4) % c.width) < c.width / 2 ? 0 : 1] += 1;
          }
          return n;
        }, vrShot.toString('base64'));
        summary.xr_liquid = { viewports: cov.viewports, liquid_pixels: cov.pixels, coloured_halves: halves };
        check(cov.look === 'liquid' && cov.viewports.length === 2 && cov.pixels.every((n) => n > 300) && halves.every((n) => n > 300),
              `XR: both eyes draw the liquid (viewports ${cov.viewports.map((v) => v.join('/')).join(' and ')}: ${cov.pixels.join(' and ')} ` +
              `liquid pixels; ${halves.join(' and ')} coloured pixels in the two halves of the canvas)`);
        // Aim the right controller at the target from 1.2 m away, hold the trigger, sweep sideways, release.
        const aim = (dx) => xrPage.evaluate((off) => {
          const ctl = window.__xrDevice.controllers.right, t = window.__ff.targetWorld(0);
          const pos = [t[0] + 0.3 + off, t[1] + 0.3, t[2] + 1.2];
          const dir = [t[0] + off - pos[0], t[1] - pos[1], t[2] - pos[2]];
          const n = Math.hypot(...dir);
          const b = dir.map((v) => v / n);
          // The rotation taking −z (the controller's pointing direction) to b: axis (−z) × b, w = 1 + (−z)·b.
          const ax = [b[1], -b[0], 0], w = 1 - b[2], qn = Math.hypot(ax[0], ax[1], ax[2], w);
          ctl.position.set(...pos);
          ctl.quaternion.set(ax[0] / qn, ax[1] / qn, ax[2] / qn, w / qn);
          return t;
        }, dx);
        const t0 = await aim(0);
        await sleep(300);
        const acks = await xrPage.evaluate(() => window.__ff.poseAcks);
        await xrPage.evaluate(() => window.__xrDevice.controllers.right.updateButtonValue('trigger', 1));
        await sleep(300);
        for (let k = 1; k <= 10; ++k) {
          await aim(0.02 * k);
          await sleep(80);
        }
        await xrPage.evaluate(() => window.__xrDevice.controllers.right.updateButtonValue('trigger', 0));
        const moved = await waitFor(xrPage, ([n, x0]) => window.__ff.poseAcks > n && Math.abs(window.__ff.targetWorld(0)[0] - x0) > 0.05,
                                    [acks, t0[0]], 10_000, 'XR controller drag reaches the server');
        if (moved) {
          await sleep(300);
          const pose = await xrPage.evaluate(() => window.__ff.poses[0]);
          summary.xr = { rendered_frames: xr.renderedFrames, drag_translate: pose.translate };
          check(true, `XR controller drag: the server reports translate [${pose.translate.map((v) => v.toFixed(3))}] m`);
        }
        await xrPage.evaluate(() => window.__xrDevice.activeSession?.end());
        await waitFor(xrPage, () => !window.__ff.xr.presenting, null, 10_000, 'VR session ends');
        await xrPage.click('#xr-buttons button >> nth=1');
        if (await waitFor(xrPage, () => window.__ff.xr.presenting && window.__ff.xr.mode === 'immersive-ar', null, 20_000, 'AR session')) {
          const scale = await xrPage.evaluate(() => window.__ff.worldScale());
          check(scale < 1, `entered immersive-ar, the content at table-top scale (${scale.toFixed(2)})`);
          await xrPage.screenshot({ path: path.join(outDir, 'ar.png') });
          await xrPage.evaluate(() => window.__xrDevice.activeSession?.end());
        }
      }
      check(xrErrors.length === 0, `no page errors in XR${xrErrors.length ? `: ${xrErrors.slice(0, 3).join(' | ')}` : ''}`);
      await xrPage.close();
    }

    // Controller switch.
    await page.selectOption('#sel-controller', { label: 'none' });
    check(await waitFor(page, () => window.__ff.hello?.controller === 'none', null, 10_000, 'controller switch'),
          'controller switch reaches the server');
    console.log(`[${elapsed()} s] live part done`);
    check(pageErrors.length === 0, `no page errors${pageErrors.length ? `: ${pageErrors.slice(0, 3).join(' | ')}` : ''}`);
    await page.close();
  } finally {
    const code = await interrupt(server);
    check(code === 0, `Ctrl-C: serve exited with ${code}`);
    check(await portIsFree(server.port), `port ${server.port} is free after exit`);
    if (code !== 0) console.log(server.log());
  }

  // ---- playback -----------------------------------------------------------------------------------------------
  if (args.playback) {
    const pb = await startServer(args.playback, ['--max-fps', '10']);
    console.log(`[${elapsed()} s] playback: serving ${pb.url}`);
    try {
      const page = await browser.newPage({ viewport: { width: 800, height: 500 } });
      await page.goto(pb.url);
      const ok = await waitFor(page, () => window.__ff?.animation?.loaded && window.__ff.framesReceived >= 30, null,
                               60_000, 'playback: animation.glb loaded and 30 frames');
      if (ok) {
        // The run's report page, linked from the panel and served from the run's folder.
        const link = await page.$eval('#lnk-report', (e) => ({ hidden: e.hidden, href: e.getAttribute('href') }));
        const rep = await page.evaluate(async (h) => { const r = await fetch(h); return { status: r.status, text: await r.text() }; }, link.href);
        check(!link.hidden && link.href === '/run/report.html' && rep.status === 200 && rep.text.includes('id="ff-data"'),
              `playback: the panel links the run's report page (${link.href}, HTTP ${rep.status})`);
        const a1 = await page.evaluate(() => window.__ff.animation);
        check(a1.clips >= 1 && a1.meshes >= 1 && a1.duration > 0,
              `playback: mesh animation with ${a1.clips} clip(s), ${a1.meshes} mesh(es), ${a1.duration.toFixed(2)} s`);
        // Advancing: within 5 s, at least 10 more frames arrive and the mesh animation's time moves with them (one
        // fixed sleep was flaky on the loaded 2-core machine, where a 0.5 s window could see no new frame).
        const f1 = await page.evaluate(() => window.__ff.framesReceived);
        const advanced = await waitFor(page, ([t, f]) => window.__ff.animation.time !== t && window.__ff.framesReceived >= f + 10,
                                       [a1.time, f1], 5_000, 'playback: animation advances');
        const a2 = await page.evaluate(() => ({ time: window.__ff.animation.time, frames: window.__ff.framesReceived }));
        check(advanced, `playback: the animation advances with the frames (t ${a1.time.toFixed(3)} -> ${a2.time.toFixed(3)} s, ` +
                        `${a2.frames - f1} frames)`);
        // Interpolated like the live frames; the mesh animation follows the drawn time, between the frames' times.
        // (Once the look has settled: liquid drawing in software WebGL holds the main thread up to its fall back.)
        await waitFor(page, () => Number.isFinite(window.__ff.look.liquidFrameMs) || window.__ff.look.fellBack, null, 30_000,
                      'playback: the look settled');
        console.log(`playback look: ${await page.evaluate(() => window.__ff.look.mode)}`);
        const pi = await sampleInterpolation(page, 12, 150);
        const animTimes = [];
        for (let k = 0; k < 12; ++k) {
          await sleep(60 + 60 * Math.random());
          animTimes.push(await page.evaluate(() => [window.__ff.animation.time, window.__ff.frame.time, window.__ff.interp.time]));
        }
        const fps = await page.evaluate(() => window.__ff.hello.fps);
        const inBetween = animTimes.filter(([a, , t]) => a === t && Math.abs(a * fps - Math.round(a * fps)) > 0.02).length;
        summary.playback_interpolation = { ...pi, animation_in_between: inBetween };
        check(pi.rounds >= 8 && pi.between === pi.total && pi.behind === 0 && pi.inner >= 0.3 * pi.rounds,
              `playback: drawn positions between the two frames they interpolate (${pi.between} of ${pi.total}; ` +
              `${pi.inner} of ${pi.rounds} samples in between)`);
        check(inBetween >= 3, `playback: the mesh animation is drawn at the interpolated time (${inBetween} of ` +
                              `${animTimes.length} samples between two frames' times)`);
        check(pi.pairs > 0 && pi.farFraction < 0.02,
              `playback: particles keep their order between frames (${(100 * pi.farFraction).toFixed(1)} % moved more than a ` +
              `tenth of the fluid's extent in one frame)`);
        const shot = await page.screenshot({ path: path.join(outDir, 'playback.png') });
        const px = await colouredPixels(page, shot);
        check(px.coloured > 0.005 * px.total, `playback screenshot is not blank (${px.coloured} coloured pixels)`);

        // Seeking from the slider: back to frame 2, then far forward to frame 32.
        summary.seek = await playbackSeeks(page);
        await page.screenshot({ path: path.join(outDir, 'playback-seek.png') });
        summary.playback = { clips: a1.clips, duration_s: a1.duration, frames: await page.evaluate(() => window.__ff.framesReceived) };
      }
      await page.close();
    } finally {
      check((await interrupt(pb)) === 0, 'playback: Ctrl-C exits with 0');
    }
  }
} catch (e) {
  check(false, `exception: ${e.stack ?? e}`);
} finally {
  await browser.close();
}

console.log(`viewer summary ${JSON.stringify(summary)}`);
if (failures.length) {
  console.log(`viewer test FAILED (${failures.length}): ${failures.join('; ')}  [${elapsed()} s, screenshots in ${outDir}]`);
  process.exit(1);
}
console.log(`viewer test ok [${elapsed()} s]`);
