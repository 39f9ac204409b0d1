// Opens tightex report pages in headless Chromium and checks them as a user would see them: no error,
// nothing fetched from the network, both 3D views drawn, the heat map and the tables present, every
// number on the page equal to report.json's, the table sortable and the surface toggles working.
//
//   node check_report.mjs REPORT.html REPORT.json SCREENSHOT.png [REPORT.html REPORT.json SCREENSHOT.png ...]
//
// Chromium: $CHROMIUM, else /usr/bin/chromium. Exit status 0 when every page passes, 1 otherwise (each
// failure printed as "FAIL page: what").
import { readFileSync } from 'node:fs';
import { resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

const kChromiumFlags = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
];

// The value at a dotted path of the report ("metrics.seam_length.input", "components.3.genus").
function lookup(report, path) {
  return path.split('.').reduce((v, k) => (v === undefined || v === null ? undefined : v[k]), report);
}

// Every number the page shows with its key (data-key): the shown text must be report.json's value,
// scaled as the page says (data-scale), to the digits shown.
function checkNumbers(shown, report, fail) {
  if (shown.length < 20) fail(`only ${shown.length} numbers carry their report.json key`);
  for (const required of ['metrics.surface_psnr_db', 'metrics.output.utilization', 'metrics.input.utilization', 'metrics.charts',
    'metrics.flipped', 'metrics.lost_triangles', 'metrics.seam_length.output', 'metrics.density_spread.p50',
    'metrics.angle_distortion.mean', 'wall_seconds', 'timings.0.seconds', 'components.0.triangles'])
    if (!shown.some((s) => s.key === required)) fail(`the page does not show ${required}`);
  // Each map's figures beside its picture (metrics.maps: a PSNR, or a normal map's angles).
  (lookup(report, 'metrics.maps') || []).forEach((m, i) => {
    const key = `metrics.maps.${i}.` + (typeof m.surface_psnr_db === 'number' ? 'surface_psnr_db' : 'normal_angle_median_deg');
    if (!shown.some((s) => s.key === key)) fail(`the page does not show ${key} (the ${m.slot} map)`);
  });
  for (const { key, scale, text, precision } of shown) {
    const expected = lookup(report, key);
    const value = Number(text.replace(/,/g, ''));
    const digits = (text.split('.')[1] || '').length;
    if (typeof expected !== 'number' || !Number.isFinite(value)) {
      fail(`${key}: shows "${text}", report.json has ${JSON.stringify(expected)}`);
      continue;
    }
    // Half a unit of the last digit shown (of the third significant one for data-precision="sig3").
    const magnitude = Math.abs(expected * scale);
    const unit = precision === 'sig3' && magnitude > 0 ? 10 ** (Math.floor(Math.log10(magnitude)) - 2) : 10 ** -digits;
    const tolerance = 0.5 * unit * (1 + 1e-9) + 1e-12;
    if (Math.abs(value - expected * scale) > tolerance) fail(`${key}: shows ${text}, report.json has ${expected} (x${scale})`);
  }
}

// Statistics of a canvas's pixels, read back through a 2D canvas: the luminance variance and the share
// of pixels that differ from the top-left pixel (the background).
function canvasStats(selector) {
  const source = document.querySelector(selector);
  if (!source) return null;
  const w = 240, h = Math.max(1, Math.round(240 * source.height / source.width));
  const c = document.createElement('canvas');
  c.width = w, c.height = h;
  const ctx = c.getContext('2d');
  ctx.drawImage(source, 0, 0, w, h);
  const px = ctx.getImageData(0, 0, w, h).data;
  let sum = 0, sum2 = 0, differ = 0;
  for (let i = 0; i < px.length; i += 4) {
    const y = 0.299 * px[i] + 0.587 * px[i + 1] + 0.114 * px[i + 2];
    sum += y, sum2 += y * y;
    if (Math.abs(px[i] - px[0]) + Math.abs(px[i + 1] - px[1]) + Math.abs(px[i + 2] - px[2]) > 12) ++differ;
  }
  const n = px.length / 4;
  return { variance: sum2 / n - (sum / n) ** 2, covered: differ / n, digest: Array.from(px.slice(0, px.length)).reduce((a, v, i) => (a + v * (i % 97 + 1)) % 1000000007, 0) };
}

async function checkViews(page, fail) {
  const stats = {};
  for (const id of ['#view-input', '#view-output', '#heatmap']) {
    const s = await page.evaluate(canvasStats, id);
    stats[id] = s;
    if (!s) fail(`no ${id} canvas`);
    else if (s.variance < 20 || s.covered < 0.03) fail(`${id} looks empty (luminance variance ${s.variance.toFixed(1)}, ${(100 * s.covered).toFixed(1)}% drawn)`);
  }
  // The surface toggles change what the views draw.
  for (const mode of ['checker', 'density']) {
    await page.check(`input[name="surface"][value="${mode}"]`);
    const s = await page.evaluate(canvasStats, '#view-output');
    if (!s || s.digest === stats['#view-output'].digest) fail(`the ${mode} toggle does not change the output view`);
    if (s && s.variance < 20) fail(`the ${mode} view looks empty`);
  }
  await page.check('#show-seams');
  await page.check('input[name="surface"][value="texture"]');
}

async function checkTables(page, report, fail) {
  const rows = await page.evaluate(() => ({
    summary: document.querySelectorAll('#summary-table tbody tr').length,
    components: document.querySelectorAll('#component-table tbody tr').length,
    timings: document.querySelectorAll('#timing-table tbody tr').length,
    colorbarTicks: Array.from(document.querySelectorAll('#colorbar .ticks span')).map((s) => s.textContent),
  }));
  if (rows.summary < 15) fail(`the summary table has ${rows.summary} rows`);
  if (rows.components !== report.components.length) fail(`${rows.components} component rows, report.json lists ${report.components.length}`);
  if (rows.timings !== report.timings.length) fail(`${rows.timings} timing rows, report.json has ${report.timings.length}`);
  if (rows.colorbarTicks.length < 3 || !rows.colorbarTicks.every((t) => /\d/.test(t))) fail('the colour bar has no numbers');
  // Sorting by triangles (descending on the second click) puts the largest component first.
  const header = page.locator('#component-table th', { hasText: 'Triangles' });
  await header.click();
  await header.click();
  const first = await page.evaluate(() => document.querySelector('#component-table tbody tr td:nth-child(2)').textContent);
  const largest = Math.max(...report.components.map((c) => c.triangles));
  if (Number(first.replace(/,/g, '')) !== largest) fail(`sorted by triangles, the first row shows ${first}, the largest has ${largest}`);
}

async function checkPage(browser, htmlPath, jsonPath, screenshotPath) {
  const failures = [];
  const fail = (what) => failures.push(what);
  const report = JSON.parse(readFileSync(jsonPath, 'utf8'));
  const context = await browser.newContext({ viewport: { width: 1200, height: 900 }, deviceScaleFactor: 1 });
  const page = await context.newPage();
  const requests = [];
  page.on('request', (r) => requests.push(r.url()));
  page.on('websocket', (w) => requests.push(w.url()));
  page.on('console', (m) => {
    if (m.type() === 'error') fail(`console error: ${m.text()}`);
    // three.js warns where it degrades what it was given (a texture shrunk, a deprecated call).
    if (m.type() === 'warning' && m.text().startsWith('THREE.')) fail(`three.js warning: ${m.text()}`);
  });
  page.on('pageerror', (e) => fail(`page error: ${e.message}`));
  // Anything but the page itself and data: URIs is refused, and recorded by the 'request' handler.
  await context.route((url) => !/^(file|data):/.test(url.href), (route) => route.abort());
  await page.goto(pathToFileURL(resolve(htmlPath)).href, { waitUntil: 'load' });
  try {
    await page.waitForFunction(() => window.tightexPage && (window.tightexPage.ready || window.tightexPage.errors.length > 0), null,
      { timeout: 30000 });
  } catch (e) {
    fail('the viewer did not become ready within 30 s');
  }
  const pageErrors = await page.evaluate(() => (window.tightexPage ? window.tightexPage.errors : ['no tightexPage']));
  pageErrors.forEach((e) => fail(`the page reports: ${e}`));
  const resources = await page.evaluate(() => performance.getEntriesByType('resource').map((r) => r.name));
  for (const url of new Set([...requests, ...resources])) if (!/^(file|data):/.test(url)) fail(`requested from the network: ${url}`);
  if (failures.length === 0) {
    checkNumbers(await page.evaluate(() => Array.from(document.querySelectorAll('[data-key]')).map((e) =>
      ({ key: e.dataset.key, scale: Number(e.dataset.scale || 1), text: e.textContent, precision: e.dataset.precision }))), report, fail);
    await checkTables(page, report, fail);
    await checkViews(page, fail);
    await page.locator('#viewer').scrollIntoViewIfNeeded();
  }
  await page.screenshot({ path: screenshotPath, fullPage: true });
  // The 3D views alone, at the page's size: what a reader looks at first.
  if (failures.length === 0) await page.locator('#viewer').screenshot({ path: screenshotPath.replace(/\.png$/, '') + '_viewer.png' });
  await context.close();
  return failures.map((f) => `FAIL ${htmlPath}: ${f}`);
}

async function main() {
  const args = process.argv.slice(2);
  if (args.length === 0 || args.length % 3 !== 0) {
    console.error('usage: node check_report.mjs REPORT.html REPORT.json SCREENSHOT.png [...]');
    process.exit(2);
  }
  const browser = await chromium.launch({ executablePath: process.env.CHROMIUM || '/usr/bin/chromium', args: kChromiumFlags,
    headless: true });
  let failed = false;
  try {
    for (let i = 0; i < args.length; i += 3) {
      const t0 = Date.now();
      const failures = await checkPage(browser, args[i], args[i + 1], args[i + 2]);
      failures.forEach((f) => console.log(f));
      console.log(`${failures.length ? 'failed' : 'ok'}: ${args[i]} (${((Date.now() - t0) / 1000).toFixed(1)} s; screenshot ${args[i + 2]})`);
      failed ||= failures.length > 0;
    }
  } finally {
    await browser.close();
  }
  process.exit(failed ? 1 : 0);
}

main().catch((e) => {
  console.error(e);
  process.exit(1);
});
