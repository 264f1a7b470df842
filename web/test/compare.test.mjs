// `fluidform compare`'s page (OUT/compare.html, issue 46) as a person would look at it: opened from disk in Debian's
// chromium (headless, through playwright-core) with every network request refused. Checks (each exits non-zero with a
// reason): no console error and no request that leaves the file; one row per controller with every Table 3 column;
// the target's picture and each row's picture of its formed shape load; failures are marked; clicking a column sorts
// the rows by it (numbers as numbers), clicking again reverses them; each row links its controller's report.html,
// which exists beside the page. A screenshot goes to --out.
// Usage: node web/test/compare.test.mjs --page OUT/compare.html --rows N [--chromium PATH] [--out DIR]
import fs from 'node:fs';
import path from 'node:path';
import { chromium } from 'playwright-core';

const args = {};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!args.page || !args.rows) {
  console.error('usage: node web/test/compare.test.mjs --page OUT/compare.html --rows N [--chromium PATH] [--out DIR]');
  process.exit(2);
}
const pageFile = path.resolve(args.page), rows = Number(args.rows);
const outDir = args.out ?? fs.mkdtempSync('/tmp/fluidform-compare-');
fs.mkdirSync(outDir, { recursive: true });
const CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--no-first-run', '--disable-background-networking',
                       '--disable-component-update', '--disable-sync'];
const failures = [];
const check = (ok, what) => {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures.push(what);
  return ok;
};

const browser = await chromium.launch({ executablePath: args.chromium ?? '/usr/bin/chromium', headless: true, args: CHROMIUM_ARGS });
try {
  const context = await browser.newContext({ viewport: { width: 1400, height: 900 } });
  const outside = [];
  await context.route('**/*', (route) => {
    const url = route.request().url();
    if (url === `file://${pageFile}`) return route.continue();
    outside.push(url);
    return route.abort();
  });
  const page = await context.newPage();
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(`file://${pageFile}`);
  await page.waitForFunction(() => document.body.dataset.ready === '1', null, { timeout: 15000 });

  const heads = await page.$$eval('#table th', (t) => t.map((h) => h.textContent));
  check(['controller', 'error rate (%)', 'per-frame time (s)', 'memory (MB)', 'splash (%)', 'inside (%)', 'status', 'formed shape']
          .every((h) => heads.includes(h)), `every column: ${heads.join(' | ')}`);
  const names = async () => page.$$eval('#table tbody tr', (t) => t.map((r) => r.children[0].textContent));
  check((await names()).length === rows, `one row per controller (${(await names()).join(', ')})`);
  const imgs = await page.$$eval('img', (t) => t.map((i) => ({ alt: i.alt, w: i.naturalWidth })));
  check(imgs.some((i) => i.alt === 'target' && i.w > 0), 'the target\'s picture loads');
  check(imgs.filter((i) => i.alt.endsWith(' formed') && i.w > 0).length === rows, `a formed-shape picture per row (${imgs.length - 1})`);
  const failed = await page.$$eval('#table tbody tr.failure', (t) => t.map((r) => r.children[0].textContent));
  const statusFailed = await page.$$eval('#table tbody tr', (t) => t.filter((r) => r.lastElementChild.previousElementSibling.previousElementSibling.textContent.startsWith('failure')).length);
  check(failed.length === statusFailed, `failures are marked (${failed.length})`);

  // Sorting by the error rate: ascending numbers, then reversed.
  const col = heads.indexOf('error rate (%)');
  const values = async () => page.$$eval('#table tbody tr', (t, c) => t.map((r) => parseFloat(r.children[c].textContent)), col);
  await page.click(`#table th[data-col="${col}"]`);
  const up = (await values()).filter((v) => !Number.isNaN(v));
  check(up.every((v, k) => k === 0 || up[k - 1] <= v), `sorted by error rate, ascending (${up.join(', ')})`);
  await page.click(`#table th[data-col="${col}"]`);
  const down = (await values()).filter((v) => !Number.isNaN(v));
  check(down.every((v, k) => k === 0 || down[k - 1] >= v), `and descending (${down.join(', ')})`);
  const links = await page.$$eval('#table tbody a', (t) => t.map((a) => a.getAttribute('href')));
  check(links.length === rows && links.every((h) => fs_exists(h)), `each row links its report.html (${links.join(', ')})`);
  await page.screenshot({ path: path.join(outDir, 'compare.png'), fullPage: true });
  check(outside.length === 0, `no request leaves the file (${outside.length})`);
  check(errors.length === 0, `no console errors (${errors.length}${errors.length ? ': ' + errors.join(' | ') : ''})`);
  console.log(`screenshot in ${outDir}`);
} finally {
  await browser.close();
}
function fs_exists(href) { return fs.existsSync(path.join(path.dirname(pageFile), href)); }
if (failures.length) {
  console.error(`${failures.length} check(s) failed`);
  process.exit(1);
}
