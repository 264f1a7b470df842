// A run's report page (OUT/report.html, issue 46) as a person would look at it: opened from disk in Debian's chromium
// (headless, through playwright-core) with every network request refused. Checks (each exits non-zero with a reason):
//   - no console error, no page error, no request that leaves the file (the page is self-contained)
//   - the summary table is there, with the run's particle count, and the still pictures of target and formed shape
//   - every plot is drawn: each uPlot canvas has pixels of its curves' colours (not a blank frame)
//   - the 3D view draws the mesh (pixels of the water colour) when the run has one, and switching the target overlay
//     off changes the picture; with --no-mesh there is no view, and the page says so
//   - the forming's timeline, when the page carries one, moves the shape shown
// Screenshots of the page and the view go to --out (kept by the test as artifacts).
// Usage: node web/test/report.test.mjs --page OUT/report.html [--expect-view 1|0] [--particles N] [--chromium PATH] [--out DIR]
import fs from 'node:fs';
import path from 'node:path';
import { chromium } from 'playwright-core';

const args = {};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!args.page) {
  console.error('usage: node web/test/report.test.mjs --page OUT/report.html [--expect-view 1|0] [--particles N] [--out DIR]');
  process.exit(2);
}
const pageFile = path.resolve(args.page);
const expectView = (args['expect-view'] ?? '1') === '1';
const outDir = args.out ?? fs.mkdtempSync('/tmp/fluidform-report-');
fs.mkdirSync(outDir, { recursive: true });
const CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--no-first-run', '--disable-background-networking',
                       '--disable-component-update', '--disable-sync', '--enable-unsafe-swiftshader', '--use-angle=swiftshader'];

const failures = [];
const check = (ok, what) => {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures.push(what);
  return ok;
};

// Pixels of a PNG (decoded in the page) within `tol` of any of the given colours.
async function pixelsNear(page, png, colours, tol = 40) {
  return page.evaluate(async ([b64, cols, t]) => {
    const img = new Image();
    img.src = `data:image/png;base64,${b64}`;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width, c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4)
      if (cols.some(([r, gg, b]) => Math.abs(d[i] - r) + Math.abs(d[i + 1] - gg) + Math.abs(d[i + 2] - b) < t)) n += 1;
    return { n, total: c.width * c.height };
  }, [png.toString('base64'), colours, tol]);
}

const browser = await chromium.launch({ executablePath: args.chromium ?? '/usr/bin/chromium', headless: true, args: CHROMIUM_ARGS });
try {
  const context = await browser.newContext({ viewport: { width: 1280, height: 1000 } });
  const outside = [];
  await context.route('**/*', (route) => {
    const url = route.request().url();
    if (url.startsWith('file://') && url.endsWith(path.basename(pageFile))) return route.continue();
    outside.push(url);
    return route.abort();
  });
  const page = await context.newPage();
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(`file://${pageFile}`);
  await page.waitForFunction(() => document.body.dataset.ready === '1', null, { timeout: 30000 });
  await page.waitForTimeout(500);

  check(outside.length === 0, `no request leaves the file (${outside.length}${outside.length ? ': ' + outside.slice(0, 3).join(', ') : ''})`);
  const summary = await page.$eval('#summary', (e) => e.textContent);
  check(summary.includes('fluid particles') && summary.includes('error rate'), 'the summary table is there');
  if (args.particles) check(summary.replace(/,/g, '').includes(args.particles), `the summary names the run's ${args.particles} particles`);

  // Still pictures (drawn by fluidform): target and formed shape, or the target alone without a mesh.
  const stills = await page.$$eval('#stills img', (imgs) => imgs.map((i) => ({ alt: i.alt, w: i.naturalWidth, h: i.naturalHeight })));
  check(stills.length === (expectView ? 2 : 1) && stills.every((i) => i.w > 0 && i.h > 0),
        `still pictures: ${stills.map((i) => `${i.alt} ${i.w}x${i.h}`).join(', ')}`);

  // Plots: four uPlot charts, each canvas with pixels of its series' colours (web/report/report.js COLOURS).
  const charts = await page.$$('#plots .uplot canvas');
  check(charts.length === 4, `four plots (${charts.length})`);
  const curve = [[0x2a, 0x7a, 0xb0], [0xd0, 0x63, 0x2b]];
  for (const [k, c] of charts.entries()) {
    const shot = await c.screenshot();
    const px = await pixelsNear(page, shot, curve);
    check(px.n > 100, `plot ${k + 1} draws its curve (${px.n} pixels of the curve colours)`);
  }

  const canvas = await page.$('#view canvas');
  if (expectView) {
    check(!!canvas, 'the 3D view has a canvas');
    if (canvas) {
      const water = [[0x2f, 0x8f, 0xd8], [0x1b, 0x5e, 0x9a], [0x5a, 0xa8, 0xe8]];
      const shot = await canvas.screenshot({ path: path.join(outDir, 'view.png') });
      const px = await pixelsNear(page, shot, water, 120);
      check(px.n > 0.01 * px.total, `the view shows the formed mesh (${px.n} of ${px.total} pixels water-coloured)`);
      await page.click('#chk-target');
      await page.waitForTimeout(200);
      const off = await canvas.screenshot({ path: path.join(outDir, 'view-no-target.png') });
      check(!off.equals(shot), 'switching the target overlay off changes the picture');
      if (await page.$eval('#timeline', (e) => !e.hidden)) {
        await page.$eval('#rng-time', (e) => { e.value = '100'; e.dispatchEvent(new Event('input')); });
        await page.waitForTimeout(200);
        const early = await canvas.screenshot({ path: path.join(outDir, 'view-early.png') });
        check(!early.equals(off), 'the timeline shows an earlier frame of the forming');
      } else {
        console.log('     (no timeline: the page carries no animation.glb)');
      }
    }
  } else {
    check(!canvas, 'no 3D view for a run without a mesh');
    const text = await page.$eval('#view', (e) => e.textContent);
    check(text.includes('--no-mesh'), 'the page says why there is no 3D view');
  }
  await page.screenshot({ path: path.join(outDir, 'report.png'), fullPage: true });
  check(errors.length === 0, `no console errors (${errors.length}${errors.length ? ': ' + errors.slice(0, 3).join(' | ') : ''})`);
  console.log(`screenshots in ${outDir}`);
} finally {
  await browser.close();
}
if (failures.length) {
  console.error(`${failures.length} check(s) failed`);
  process.exit(1);
}
