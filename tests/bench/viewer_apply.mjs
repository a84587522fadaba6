// Benchmark (not a test): how long the viewer takes to apply each delta of the
// 100-tree stand in headless Chromium, against a real daemon.
//
//   node tests/bench/viewer_apply.mjs [--exe build/server/sylva] [--iterations 24] [--no-draw]
//        [--frames 20] [--no-leaves]
//
// For every delta the page reports its size, the time the socket worker took to
// parse it and turn it into typed arrays, and the time to apply it in the page:
// the skeleton's typed arrays changed in place plus the GPU attributes marked for
// upload (web/watch.mjs, Watch.delta). Then the separate task after it that
// squeezes shed slots out and grows the arrays ahead of need. The leaves' part of
// applying (their cards placed and marked for upload, web/leaves.mjs) is reported
// on its own. At the end, the frame time with leaves on and off: --frames frames
// drawn one after the other (each in its own animation frame, the camera turning),
// the time between them. Chromium draws with SwiftShader here (WebGL on the CPU),
// so frame times say little about a real GPU. Use a release build.
import { spawn } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { createRequire } from 'node:module';
import { stand100 } from './stand100.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const require = createRequire(join(root, 'tests/web/package.json'));
const { chromium } = require('playwright-core');
const WebSocket = require('ws');
const arg = (name, def) => {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 ? process.argv[i + 1] : def;
};
const exe = resolve(arg('exe', join(root, 'build/server/sylva')));
const iterations = Number(arg('iterations', '24'));
// --no-draw: stop the page drawing (SwiftShader renders on this VM's CPU cores,
// which a real GPU would not take from the page)
const noDraw = process.argv.includes('--no-draw');
const frames = Number(arg('frames', '20'));
// --no-leaves: the bare skeleton throughout (the viewer's leaves toggle off)
const noLeaves = process.argv.includes('--no-leaves');
const port = 18000 + Math.floor(Math.random() * 2000);
const dir = mkdtempSync(join(tmpdir(), 'sylva-bench-'));

const daemon = spawn(exe, ['serve', '--db', join(dir, 'b.db'), '--listen', `127.0.0.1:${port}`,
  '--web', join(root, 'web')], { stdio: ['ignore', 'ignore', 'pipe'] });
await new Promise((ok) => daemon.stderr.on('data', (d) => { if (String(d).includes('listening')) ok(); }));

const browser = await chromium.launch({ executablePath: '/usr/bin/chromium', args: ['--headless',
  '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--enable-unsafe-swiftshader'] });
const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
page.on('pageerror', (e) => console.error('page error:', e.message));
await page.goto(`http://127.0.0.1:${port}/`);
await page.waitForFunction(() => window.sylva?.state().connection === 'open');

const ws = new WebSocket(`ws://127.0.0.1:${port}/ws`, 'sylva.v1');
await new Promise((ok) => ws.on('open', ok));
ws.send(JSON.stringify({ type: 'create', id: 'c', scenario: { ...stand100(), iterations }, name: 'stand100', start: false }));
const run = await new Promise((ok) => ws.on('message', (m) => {
  const msg = JSON.parse(m);
  if (msg.type === 'created') ok(msg.run);
}));
await page.click(`#runs tr[data-run="${run}"]`, { timeout: 10000 });
await page.waitForFunction((r) => window.sylva.state().run === r && window.sylva.state().seq >= 0, run);
if (noLeaves) await page.evaluate(() => window.sylva.setLeaves(false));
const raf = await page.evaluateHandle(() => window.requestAnimationFrame.bind(window));
if (noDraw) await page.evaluate(() => { window.requestAnimationFrame = () => 0; });
// One iteration at a time: the daemon and the browser share this VM's two cores,
// and a growing daemon would steal the page's core while it applies a delta (a
// viewer watches from another machine).
const t0 = Date.now();
for (let k = 1; k <= iterations; k++) {
  ws.send(JSON.stringify({ type: 'control', run, action: 'step', count: 1 }));
  // (a run whose every stem has finished ends before its iteration limit)
  await page.waitForFunction((n) => {
    const st = window.sylva.state(), tidied = window.sylva.timings().tidyMs.length;
    return (st.iteration === n || st.status === 'finished') && tidied >= st.iteration;
  }, k, { timeout: 10 * 60000, polling: 50 });
  if ((await page.evaluate(() => window.sylva.state().iteration)) < k) break;
  process.stderr.write(`\riteration ${k}`);
}
const s = await page.evaluate(() => window.sylva.state());
const t = await page.evaluate(() => window.sylva.timings());
console.log(`100-tree stand, ${s.iteration} iterations stepped one by one in ${((Date.now() - t0) / 1e3).toFixed(1)} s; ` +
  `the page holds ${s.nodes.toLocaleString('en')} internodes (${(await page.evaluate(() => window.sylva.memory().skeletonBytes) / 1e6).toFixed(0)} MB of arrays)`);
console.log(`leaves: ${s.leaves ? 'on' : 'off'}, ${s.leafTotal.toLocaleString('en')} held, ` +
  `${s.drawnLeaves.toLocaleString('en')} cards drawn (stride ${s.leafStride}, budget ${s.leafBudget.toLocaleString('en')})`);
console.log('delta  bytes        parse ms  apply ms  (leaves)  tidy ms');
t.applyMs.forEach((a, i) => console.log(`${String(i + 1).padStart(5)}  ${String(t.bytes[i]).padStart(11)}  ` +
  `${t.parseMs[i].toFixed(1).padStart(8)}  ${a.toFixed(1).padStart(8)}  ${(t.leafMs[i] ?? NaN).toFixed(1).padStart(8)}  ` +
  `${(t.tidyMs[i] ?? NaN).toFixed(1).padStart(7)}`));
const sorted = t.applyMs.slice().sort((a, b) => a - b);
console.log(`apply: median ${sorted[sorted.length >> 1].toFixed(1)} ms, max ${sorted[sorted.length - 1].toFixed(1)} ms; ` +
  `tidy max ${Math.max(...t.tidyMs).toFixed(1)} ms; parse max ${Math.max(...t.parseMs).toFixed(1)} ms; frames drawn ${s.frames}, ` +
  `frame median ${(t.renderMs.slice().sort((a, b) => a - b)[t.renderMs.length >> 1] || 0).toFixed(0)} ms (SwiftShader)`);

// Frames drawn one after the other, the camera turning a little each time: the time
// between animation frames, with the leaves on and then off.
async function frameTimes(leaves) {
  await page.evaluate((on) => window.sylva.setLeaves(on), leaves);
  return page.evaluate(([n, raf]) => new Promise((done) => {
    const times = [];
    let k = 0;
    const step = (now) => {
      times.push(now);
      if (k++ === n) {
        done(times.slice(1).map((x, i) => x - times[i]));
        return;
      }
      window.sylva.orbit(0.02);
      window.sylva.render();
      raf(step);
    };
    raf(step);
  }), [frames, raf]);
}
if (!noDraw && frames > 0) {
  const median = (a) => a.slice().sort((x, y) => x - y)[a.length >> 1];
  for (const on of [true, false]) {
    const f = await frameTimes(on);
    const st = await page.evaluate(() => window.sylva.state());
    console.log(`frames with leaves ${on ? 'on ' : 'off'}: median ${median(f).toFixed(0)} ms, max ${Math.max(...f).toFixed(0)} ms ` +
      `over ${f.length} frames (${st.drawnLeaves.toLocaleString('en')} cards, ${s.nodes.toLocaleString('en')} internodes)`);
  }
}
ws.close();
await browser.close();
daemon.kill('SIGTERM');
await new Promise((ok) => daemon.on('exit', ok));
rmSync(dir, { recursive: true, force: true });
