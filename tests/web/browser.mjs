// Headless Chromium (Debian's /usr/bin/chromium) driven by playwright-core, for
// the viewer's tests. Every console error and page error is collected.
import http from 'node:http';
import { chromium } from 'playwright-core';

const CHROMIUM = process.env.SYLVA_CHROMIUM || '/usr/bin/chromium';

export async function launch() {
  return chromium.launch({
    executablePath: CHROMIUM,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--enable-unsafe-swiftshader'],
  });
}

// Opens the viewer of a daemon (at a location hash such as `#run=NAME`, when
// given); resolves when it is connected.
export async function openViewer(browser, http, { width = 1280, height = 860, hash = '' } = {}) {
  const page = await browser.newPage({ viewport: { width, height } });
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(`console: ${m.text()}`); });
  page.on('pageerror', (e) => errors.push(`page: ${e.message}`));
  page.on('requestfailed', (r) => errors.push(`request failed: ${r.url()} ${r.failure()?.errorText}`));
  await page.goto(`${http}/${hash}`);
  await page.waitForFunction(() => window.sylva?.state().connection === 'open');
  return { page, errors };
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
// the whole picture) of a PNG screenshot, decoding it in the page. Kinds: 'tree'
// (plant 0's green, lit or shaded) and 'highlight' (the zone highlight's red,
// #e8112d).
export async function countPixels(page, png, rect, kind) {
  return page.evaluate(async ([src, rect, kind]) => {
    const img = new Image();
    img.src = `data:image/png;base64,${src}`;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width;
    c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const [x0, y0, x1, y1] = rect ?? [0, 0, img.width, img.height];
    const w = Math.max(1, Math.round(x1 - x0)), h = Math.max(1, Math.round(y1 - y0));
    const d = g.getImageData(Math.round(x0), Math.round(y0), w, h).data;
    const is = kind === 'tree'
      ? (r, gr, b) => gr > r + 25 && gr > b + 15
      : (r, gr, b) => r > 150 && gr < 70 && b < 90;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) if (is(d[i], d[i + 1], d[i + 2])) n++;
    return n;
  }, [png.toString('base64'), rect, kind]);
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
