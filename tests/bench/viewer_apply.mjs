// Benchmark (not a test): how long the viewer takes to apply each delta of a
// stand in headless Chromium, against a real daemon.
//
//   node tests/bench/viewer_apply.mjs [--stand stand100|planes] [--exe build/server/sylva]
//        [--iterations N] [--no-draw] [--frames 20] [--no-leaves] [--web web]
//
// --stand stand100 (the default): the 100-tree stand of igm-fig17b (stand100.mjs);
// every stem finishes at iteration 23 (the stop rule) with 169,525 internodes.
// --stand planes: 100 London planes in years (planes.mjs), 35 seasons: a million
// internodes and 600,000 leaves, the viewer's level of detail at that size.
// --web DIR: the viewer's files served (default web/), to compare another version.
//
// For every delta the page reports its size, the time the socket worker took to
// parse it and turn it into typed arrays, and the time to apply it in the page:
// the skeleton's typed arrays changed in place plus the GPU attributes marked for
// upload (web/watch.mjs, Watch.delta). Then the separate task after it that
// squeezes shed slots out and grows the arrays ahead of need. The leaves' part of
// applying (their cards placed and marked for upload, web/leaves.mjs: at most a
// slice, the rest in tasks of their own) is reported on its own, and how long
// after the tidy every card was in place. Also the leaves' level of detail as the
// page chose it after each delta (the budget its slow frames left, the stride,
// the cards drawn), the leaves' larger pieces of work (a pass over every node
// after a change of stride or a snapshot, the instance arrays squeezed or grown)
// with their time, and the page's JS heap after a garbage collection (the V8
// heap; the typed arrays' buffers are outside it). At the end, the frame time
// with leaves on and off: --frames frames drawn one after the other (each in its
// own animation frame, the camera turning), the time between them. Chromium draws
// with SwiftShader here (WebGL on the CPU), so frame times say little about a
// real GPU, and its slow frames halve the leaves' budget (--no-draw: no frames,
// the budget stays, as with a GPU that keeps up). Use a release build.
import { spawn } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { createRequire } from 'node:module';
import { stand100 } from './stand100.mjs';
import { planes100 } from './planes.mjs';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const require = createRequire(join(root, 'tests/web/package.json'));
const { chromium } = require('playwright-core');
const WebSocket = require('ws');
const arg = (name, def) => {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 ? process.argv[i + 1] : def;
};
const exe = resolve(arg('exe', join(root, 'build/server/sylva')));
const web = resolve(arg('web', join(root, 'web')));   // the viewer's files (another version, to compare)
const stands = { stand100: [stand100, 24], planes: [planes100, 35] };
const standName = arg('stand', 'stand100');
if (!stands[standName]) throw new Error(`--stand: one of ${Object.keys(stands).join(', ')}`);
const [makeStand, defaultIterations] = stands[standName];
const iterations = Number(arg('iterations', String(defaultIterations)));
// --no-draw: stop the page drawing (SwiftShader renders on this VM's CPU cores,
// which a real GPU would not take from the page)
const noDraw = process.argv.includes('--no-draw');
const frames = Number(arg('frames', '20'));
// --no-leaves: the bare skeleton throughout (the viewer's leaves toggle off)
const noLeaves = process.argv.includes('--no-leaves');
const port = 18000 + Math.floor(Math.random() * 2000);
const dir = mkdtempSync(join(tmpdir(), 'sylva-bench-'));

const daemon = spawn(exe, ['serve', '--db', join(dir, 'b.db'), '--listen', `127.0.0.1:${port}`,
  '--web', web], { stdio: ['ignore', 'ignore', 'pipe'] });
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
ws.send(JSON.stringify({ type: 'create', id: 'c', scenario: { ...makeStand(), iterations }, name: standName, start: false }));
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
const lod = [];   // after each delta: [iteration, internodes, leaves, cards, stride, budget]
const settle = [];   // ms from the delta applied and tidied to its cards all placed
for (let k = 1; k <= iterations; k++) {
  ws.send(JSON.stringify({ type: 'control', run, action: 'step', count: 1 }));
  // (a run whose every stem has finished ends before its iteration limit)
  await page.waitForFunction((n) => {
    const st = window.sylva.state(), tidied = window.sylva.timings().tidyMs.length;
    return (st.iteration === n || st.status === 'finished') && tidied >= st.iteration;
  }, k, { timeout: 10 * 60000, polling: 50 });
  // (the leaves' cards placed in slices after the delta: until every one is)
  const t1 = Date.now();
  await page.waitForFunction(() => !window.sylva.state().leafPending, null, { timeout: 10 * 60000, polling: 20 });
  settle.push(Date.now() - t1);
  const st = await page.evaluate(() => window.sylva.state());
  lod.push([st.iteration, st.nodes, st.leafTotal, st.drawnLeaves, st.leafStride, st.leafBudget]);
  if (st.iteration < k) break;
  process.stderr.write(`\riteration ${k}`);
}
process.stderr.write('\n');
const s = await page.evaluate(() => window.sylva.state());
const t = await page.evaluate(() => window.sylva.timings());
const cdp = await page.context().newCDPSession(page);
async function heap() {
  await cdp.send('HeapProfiler.collectGarbage');
  return cdp.send('Runtime.getHeapUsage');
}
const mb = (x) => (x / 1e6).toFixed(0);
console.log(`${makeStand().name}, ${s.iteration} iterations stepped one by one in ${((Date.now() - t0) / 1e3).toFixed(1)} s; ` +
  `the page holds ${s.nodes.toLocaleString('en')} internodes (${(await page.evaluate(() => window.sylva.memory().skeletonBytes) / 1e6).toFixed(0)} MB of arrays)`);
console.log(`leaves: ${s.leaves ? 'on' : 'off'}, ${s.leafTotal.toLocaleString('en')} held, ` +
  `${s.drawnLeaves.toLocaleString('en')} cards drawn (stride ${s.leafStride}, budget ${s.leafBudget.toLocaleString('en')})`);
const h = await heap();
console.log(`JS heap after a GC: ${mb(h.usedSize)} MB used of ${mb(h.totalSize)} MB` +
  (h.backingStorageSize !== undefined ? ` (array buffers outside it: ${mb(h.backingStorageSize)} MB)` : ''));
console.log('delta  bytes        parse ms  apply ms  (leaves)  tidy ms   internodes     leaves    cards  stride    budget');
t.applyMs.forEach((a, i) => console.log(`${String(i + 1).padStart(5)}  ${String(t.bytes[i]).padStart(11)}  ` +
  `${t.parseMs[i].toFixed(1).padStart(8)}  ${a.toFixed(1).padStart(8)}  ${(t.leafMs[i] ?? NaN).toFixed(1).padStart(8)}  ` +
  `${(t.tidyMs[i] ?? NaN).toFixed(1).padStart(7)}  ` + (lod[i] ?? []).slice(1).map((v, j) => String(v).padStart([11, 9, 8, 6, 9][j])).join(' ')));
const sorted = t.applyMs.slice().sort((a, b) => a - b), leafSorted = t.leafMs.slice().sort((a, b) => a - b);
const rebuilds = t.leafRebuilds;
const settleSorted = settle.slice().sort((a, b) => a - b);
console.log(`leaves' part of applying: median ${leafSorted[leafSorted.length >> 1].toFixed(1)} ms, max ${leafSorted[leafSorted.length - 1].toFixed(1)} ms; ` +
  `every card in place ${settleSorted[settleSorted.length >> 1]} ms (median), at most ${settleSorted[settleSorted.length - 1]} ms after the tidy`);
// (passes over every node: 'all' after a snapshot or the leaves shown again,
// 'stride' after a change of stride; 'squeeze' and 'grow': the instance arrays)
console.log(`the leaves' larger pieces of work: ${rebuilds.map((r) => `${r.why} ${r.ms.toFixed(0)} ms` +
  (r.wall > r.ms + 1 ? ` (over ${r.wall.toFixed(0)} ms)` : '') + ` at ${r.cards.toLocaleString('en')} cards, stride ${r.stride}`).join('; ')}`);
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
