// Headless Chromium (Debian's /usr/bin/chromium) driven by playwright-core, for
// the viewer's tests. Every console error and page error is collected.
import http from 'node:http';
import { chromium } from 'playwright-core';
import { SLOW, connect } from '../server/harness.mjs';

const CHROMIUM = process.env.SYLVA_CHROMIUM || '/usr/bin/chromium';

export async function launch() {
  return chromium.launch({
    executablePath: CHROMIUM,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--enable-unsafe-swiftshader'],
  });
}

// Opens the viewer of a daemon (at a location hash such as `#run=NAME`, and with a
// query such as `?stems=0`, when given); resolves when it is connected.
export async function openViewer(browser, http, { width = 1280, height = 860, hash = '', query = '' } = {}) {
  const page = await browser.newPage({ viewport: { width, height } });
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(`console: ${m.text()}`); });
  page.on('pageerror', (e) => errors.push(`page: ${e.message}`));
  page.on('requestfailed', (r) => errors.push(`request failed: ${r.url()} ${r.failure()?.errorText}`));
  await page.goto(`${http}/${query}${hash}`);
  await page.waitForFunction(() => window.sylva?.state().connection === 'open');
  return { page, errors };
}

// Creates a run of a scenario over the protocol, growing (start) or not, and
// selects it in the page; resolves with its id once the page holds its snapshot.
// A page that watches nothing opens the first run listed by itself (runs.mjs), and
// drawing it can keep a loaded machine's page busy past a 10 s selector wait: the
// page's state and list are polled instead, and the row clicked only when the
// page has not opened the run by itself.
export async function createAndWatch(d, page, doc, name, { start = false } = {}) {
  const c = await connect(d.url);
  c.send({ type: 'create', scenario: doc, name, start, id: 'c' });
  const { run } = await c.type('created');
  c.close();
  const row = `#runs tr[data-run="${run}"]`;
  for (const end = Date.now() + 60000 * SLOW; (await state(page)).run !== run;) {
    if (await page.evaluate((sel) => document.querySelector(sel) !== null, row)) {
      await page.click(row, { timeout: 30000 * SLOW });
      break;
    }
    if (Date.now() > end) throw new Error(`run ${run} never listed in the page`);
    await new Promise((r) => setTimeout(r, 100));
  }
  await until(page, (s) => s.run === run && s.seq >= 0, 'the selected run');
  return run;
}

export const state = (page) => page.evaluate(() => window.sylva.state());

// Waits until the page's state satisfies pred (a function of the state, run in node).
export async function until(page, pred, what, ms = 60000) {
  const end = Date.now() + ms;
  let s;
  for (;;) {
    s = await state(page);
    if (pred(s)) return s;
    if (Date.now() > end) throw new Error(`timed out waiting for ${what}; state ${JSON.stringify(s)}`);
    await new Promise((r) => setTimeout(r, 100));
  }
}

// Counts the pixels of one colour kind inside a rectangle [x0, y0, x1, y1] (null:
// the whole picture) of a PNG screenshot (decoded by pixels()). Kinds: 'tree'
// (plant 0's green, lit or shaded), 'highlight' (the zone highlight's red,
// #e8112d) and 'purple' (red and blue both well above green).
export async function countPixels(page, png, rect, kind) {
  const is = {
    tree: (r, gr, b) => gr > r + 25 && gr > b + 15,
    highlight: (r, gr, b) => r > 150 && gr < 70 && b < 90,
    purple: (r, gr, b) => r > gr + 25 && b > gr + 25,
  }[kind];
  return countWhere(await pixels(page, png), rect, is);
}

// The pixels of a PNG screenshot, decoded in the page: {w, h, d} (RGBA bytes, rows
// from the top).
export async function pixels(page, png) {
  const { w, h, data } = await page.evaluate(async (src) => {
    const img = new Image();
    img.src = `data:image/png;base64,${src}`;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width;
    c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    return { w: img.width, h: img.height, data: Array.from(g.getImageData(0, 0, img.width, img.height).data) };
  }, png.toString('base64'));
  return { w, h, d: data };
}

// Counts the decoded pixels (pixels()) for which is(r, g, b) holds inside a
// rectangle [x0, y0, x1, y1] of CSS pixels (null: the whole picture).
export function countWhere({ w, h, d }, rect, is) {
  const [x0, y0, x1, y1] = rect ?? [0, 0, w, h];
  let n = 0;
  for (let y = Math.max(0, Math.round(y0)), ye = Math.min(h, Math.round(y1)); y < ye; y++) {
    for (let x = Math.max(0, Math.round(x0)), xe = Math.min(w, Math.round(x1)); x < xe; x++) {
      const i = (y * w + x) * 4;
      if (is(d[i], d[i + 1], d[i + 2])) n++;
    }
  }
  return n;
}

export const treePixels = (page, png, rect) => countPixels(page, png, rect, 'tree');

// GET over a fresh connection (no keep-alive pool: the daemon may close idle
// connections between a test's steps). Resolves with {status, headers, body}.
export function httpGet(url) {
  return new Promise((resolve, reject) => {
    http.get(url, { agent: false }, (res) => {
      const chunks = [];
      res.on('data', (c) => chunks.push(c));
      res.on('end', () => resolve({ status: res.statusCode, headers: res.headers, body: Buffer.concat(chunks) }));
      res.on('error', reject);
    }).on('error', reject);
  });
}
