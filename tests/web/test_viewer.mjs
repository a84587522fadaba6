// The viewer in headless Chromium against a real daemon (`sylva serve --web web`).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { spawnSync } from 'node:child_process';
import { readFileSync } from 'node:fs';
import {
  SYLVA, ROOT, SLOW, startDaemon, stopDaemon, connect, scenario, exportSkeleton, plantsJSON, cleanup, tempDir,
  serverSnapshot,
} from '../server/harness.mjs';
import { launch, openViewer, state, until, treePixels, httpGet, createAndWatch } from './browser.mjs';

const WEB = ['--web', join(ROOT, 'web')];
let browser;
before(async () => { browser = await launch(); });
after(async () => { await browser?.close(); });

// The page's skeleton rounded as its Float32Arrays hold it, against the store's.
const f32 = (sk) => JSON.parse(plantsJSON(sk), (k, v) => (typeof v === 'number' ? Math.fround(v) : v));

async function serverRun(http, name) {
  const runs = JSON.parse((await httpGet(`${http}/api/runs`)).body);
  return runs.find((r) => r.name === name);
}

async function createFromReady(page, ready, { start }) {
  await page.selectOption('#scenario-select', ready);
  await page.waitForSelector('#scenario-form [data-pointer="/name"]');
  await page.setChecked('#create-start', start);
  await page.click('#create-button');
  return until(page, (s) => s.run !== null && s.seq >= 0, 'the new run');
}

async function heapUsed(page) {
  const cdp = await page.context().newCDPSession(page);
  await cdp.send('HeapProfiler.collectGarbage');
  const { usedSize } = await cdp.send('Runtime.getHeapUsage');
  await cdp.detach();
  return usedSize;
}

test('the wall scenario grows in the page: internodes, pixels, plots, memory', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    const s0 = await createFromReady(page, 'wall', { start: false });
    assert.equal(s0.iteration, 0);
    const name = s0.name;
    // one iteration at a time: the page holds what the server holds
    for (let k = 1; k <= 4; k++) {
      await page.click('#step');
      const s = await until(page, (x) => x.iteration === k, `iteration ${k}`);
      const server = await serverRun(d.http, name);
      await until(page, () => true, 'settle', 1);
      assert.equal(s.nodes, server.nodes, `internodes at iteration ${k}`);
      const sk = await page.evaluate(() => window.sylva.skeleton());
      assert.deepEqual(f32(sk), f32(exportSkeleton(d.db, name, k)), `skeleton at iteration ${k}`);
    }
    const heapBefore = await heapUsed(page);
    await page.click('#start');
    const end = await until(page, (x) => x.status === 'finished', 'the run to finish', 240000 * SLOW);
    const server = await serverRun(d.http, name);
    assert.equal(end.iteration, server.iteration);
    assert.equal(end.nodes, server.nodes);
    assert.ok(end.nodes > 1000, `a grown tree (${end.nodes} internodes)`);
    assert.deepEqual(f32(await page.evaluate(() => window.sylva.skeleton())), f32(exportSkeleton(d.db, name)));
    assert.equal(end.drawnInstances, end.nodes);

    // plots: one point per iteration for every stem, equal to the stored stats
    const stats = (await httpGet(`${d.http}/api/runs/${encodeURIComponent(name)}/stats.csv`)).body.toString().trim().split('\n');
    const head = stats.shift().split(',');
    const rows = stats.map((l) => Object.fromEntries(l.split(',').map((c, i) => [head[i], c])));
    const its = [...Array(end.iteration).keys()].map((i) => i + 1);
    // after every delta the page held the internodes the stems had on the server
    const held = (await page.evaluate(() => window.sylva.timings())).held;
    assert.deepEqual(held.map(([it]) => it), its, 'one delta per iteration');
    for (const [it, count] of held) {
      const want = rows.filter((r) => Number(r.iteration) === it).reduce((a, r) => a + Number(r.nodes), 0);
      assert.equal(count, want, `internodes held after iteration ${it}`);
    }
    const plots = await page.evaluate(() => window.sylva.plots());
    // a run without years, a start year or carbon: the seven plots of its stems and
    // its canopy cover, against the iteration
    const keys = ['height', 'dbh', 'crown_width', 'leaf_area', 'crown_area', 'nodes', 'cap'];
    assert.deepEqual(Object.keys(plots), [...keys, 'canopy_cover']);
    assert.deepEqual(plots.canopy_cover.stems.site, rows.map((r) => 100 * Number(r.canopy_cover)));
    assert.ok(plots.leaf_area.stems['tree/0'].at(-1) > 0, 'a leaf area');
    for (const key of keys) {
      assert.equal(plots[key].axis, 'iteration', key);
      assert.deepEqual(plots[key].iterations, its, `${key}: one point per iteration`);
      const want = rows.map((r) => (r[key] === '' ? null : Number(r[key])));
      assert.deepEqual(plots[key].stems['tree/0'], want, `${key} of tree/0`);
    }

    // the page keeps the skeleton, not the deltas it was sent
    const heapAfter = await heapUsed(page);
    const t = await page.evaluate(() => window.sylva.timings());
    const received = t.bytes.reduce((a, b) => a + b, 0);
    console.log(`# heap ${(heapBefore / 1e6).toFixed(1)} -> ${(heapAfter / 1e6).toFixed(1)} MB over ` +
      `${t.bytes.length} deltas of ${(received / 1e6).toFixed(1)} MB; apply max ${Math.max(...t.applyMs).toFixed(1)} ms`);
    assert.ok(heapAfter - heapBefore < Math.max(4e6, received / 4),
      `JS heap grew ${heapAfter - heapBefore} bytes over ${received} bytes of deltas`);

    // a screenshot from the front has tree-coloured pixels where the tree is, and
    // none in the empty sky
    await page.evaluate(() => window.sylva.setView('front'));
    const png = await page.locator('#view canvas').screenshot();
    const [tx, ty] = await page.evaluate(() => window.sylva.project(0, 0, 0.6));
    const [sx, sy] = await page.evaluate(() => window.sylva.project(-4.5, 0, 9));
    const trunk = await treePixels(page, png, [tx - 20, ty - 20, tx + 20, ty + 20]);
    const sky = await treePixels(page, png, [sx - 20, sy - 20, sx + 20, sy + 20]);
    assert.ok(trunk > 100, `tree-coloured pixels at the tree: ${trunk}`);
    assert.equal(sky, 0, 'no tree colour in the empty sky');
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// Creates a run of a scenario file over the protocol and selects it in the page.
const runInPage = (d, page, file, { name, start, overrides = {} }) =>
  createAndWatch(d, page, scenario(file, overrides), name, { start });

test('controls, a wall and a tree between iterations, the timeline, light and exports', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    const run = await runInPage(d, page, 'wall.json', { name: 'site', start: false, overrides: { iterations: 40 } });

    // step 2: exactly two iterations, then paused again
    await page.fill('#step-count', '2');
    await page.click('#step');
    let s = await until(page, (x) => x.iteration === 2, 'two steps');
    await new Promise((r) => setTimeout(r, 1000 * SLOW));
    let server = await serverRun(d.http, 'site');
    assert.equal(server.iteration, 2);
    assert.equal(server.status, 'paused');
    assert.equal((await state(page)).nodes, server.nodes);

    // start, then pause at once: the run stops where it is
    // (clicked from inside the page: a run this small grows faster than the
    // page, drawing with SwiftShader, would let an outside click through)
    await page.evaluate(() => new Promise((resolve) => {
      const pause = document.getElementById('pause');
      new MutationObserver((_, o) => {
        if (pause.disabled) return;
        o.disconnect();
        pause.click();
        resolve();
      }).observe(pause, { attributes: true });
      document.getElementById('start').click();
    }));
    s = await until(page, (x) => x.status === 'paused', 'paused');
    await new Promise((r) => setTimeout(r, 1000 * SLOW));
    const paused = await serverRun(d.http, 'site');
    assert.equal(paused.status, 'paused');
    assert.ok(paused.iteration >= 2 && paused.iteration < 20, `paused at ${paused.iteration}`);
    await new Promise((r) => setTimeout(r, 1000 * SLOW));
    assert.equal((await serverRun(d.http, 'site')).iteration, paused.iteration, 'no growth while paused');
    s = await until(page, (x) => x.iteration === paused.iteration, 'the page at the paused iteration');
    assert.equal(s.nodes, paused.nodes);

    // a wall by two ground corners: the page shows it and the server has it
    await page.selectOption('#obstacle-kind', 'wall');
    await page.fill('#corner-a', '-2, -1.5');
    await page.fill('#corner-b', '-2, 1.5');
    await page.fill('#obstacle-z', '3');
    await page.click('#add-obstacle');
    s = await until(page, (x) => x.obstacles.includes('wall1'), 'the new wall in the page');
    assert.ok(s.drawnObstacles.includes('wall1'), 'the wall is drawn');
    let snap = await serverSnapshot(d, run);
    const wall = snap.obstacles.find((o) => o.id === 'wall1');
    assert.deepEqual([wall.min, wall.max], [[-2.1, -1.5, 0], [-1.9, 1.5, 3]]);

    // a tree at a clicked ground point
    await page.evaluate(() => window.sylva.setView('top'));
    const [px, py] = await page.evaluate(() => window.sylva.project(3, 2, 0));
    const box = await page.locator('#view canvas').boundingBox();
    await page.click('#add-tree');
    await page.mouse.click(box.x + px, box.y + py);
    s = await until(page, (x) => x.plants.includes('tree1'), 'the new tree in the page');
    snap = await serverSnapshot(d, run);
    const added = snap.plants.find((p) => p.id === 'tree1');
    assert.ok(added, 'the server has the tree');
    const [rx, ry, rz] = added.stems[0].root;
    assert.ok(Math.abs(rx - 3) < 0.1 && Math.abs(ry - 2) < 0.1 && rz === 0, `root at ${added.stems[0].root}`);

    // one more step grows with the wall and the tree
    await page.fill('#step-count', '1');
    await page.click('#step');
    s = await until(page, (x) => x.iteration === paused.iteration + 1, 'a step after the edits');
    await new Promise((r) => setTimeout(r, 500 * SLOW));
    server = await serverRun(d.http, 'site');
    assert.equal(server.iteration, paused.iteration + 1);
    assert.equal((await state(page)).nodes, server.nodes);
    assert.ok((await state(page)).plants.includes('tree1'));

    // the timeline shows an earlier, smaller iteration, then goes back to live
    const liveNodes = (await state(page)).nodes;
    await page.evaluate(() => {
      const t = document.getElementById('timeline');
      t.value = '2';
      t.dispatchEvent(new Event('input'));
    });
    s = await until(page, (x) => !x.live && x.iteration === 2, 'iteration 2 from the store');
    assert.ok(s.nodes < liveNodes, `fewer internodes at iteration 2 (${s.nodes} < ${liveNodes})`);
    assert.equal(s.nodes, exportSkeleton(d.db, 'site', 2).plants.flatMap((p) => p.stems).reduce((a, x) => a + x.nodes.length, 0));
    assert.equal(s.drawnInstances, s.nodes);
    // the export links name the shown iteration
    const href = await page.getAttribute('#export-skeleton', 'href');
    assert.match(href, /format=skeleton&iteration=2$/);
    for (const [link, format] of [['#export-skeleton', 'skeleton'], ['#export-obj', 'obj'], ['#export-glb', 'glb'],
      ['#export-csv', 'csv']]) {
      const got = await httpGet(`${d.http}/${await page.getAttribute(link, 'href')}`);
      const cli = spawnSync(SYLVA, ['export', '--db', d.db, '--name', 'site', '--iteration', '2', '--format', format, '-o', '-']);
      assert.equal(got.status, 200, format);
      assert.ok(got.body.length > 0 && got.body.equals(cli.stdout), `the ${format} download is the CLI export`);
    }
    await page.click('#live');
    s = await until(page, (x) => x.live && x.nodes === liveNodes, 'live again');

    // fork at a shown past iteration: the page moves to the new run, paused there
    await page.evaluate(() => {
      const t = document.getElementById('timeline');
      t.value = '3';
      t.dispatchEvent(new Event('input'));
    });
    const at3 = await until(page, (x) => !x.live && x.iteration === 3, 'iteration 3 from the store');
    await page.fill('#fork-name', 'site-3');
    await page.click('#fork');
    // (its status comes with the run list, which may follow the snapshot)
    s = await until(page, (x) => x.name === 'site-3' && x.live && x.seq >= 0 && Boolean(x.status),
      'the fork and its status');
    assert.equal(s.iteration, 3);
    assert.equal(s.nodes, at3.nodes);
    assert.equal(s.status, 'paused');
    assert.equal((await serverRun(d.http, 'site-3')).iteration, 3);

    // the light slice at 1 m
    await page.fill('#light-z', '1');
    await page.click('#light-show');
    s = await until(page, (x) => x.slice !== null, 'a light slice');
    assert.equal(s.slice.nx * s.slice.ny, 200 * 200);
    assert.ok(await page.isVisible('#legend'));

    // remove the scenario's wall from the fork with its chip
    await page.click('#obstacles button[title="remove obstacle wall"]');
    s = await until(page, (x) => !x.obstacles.includes('wall') && !x.drawnObstacles.includes('wall'), 'the wall gone');
    assert.ok(!(await serverSnapshot(d, s.run)).obstacles.some((o) => o.id === 'wall'), 'gone on the server');

    // start grows the fork on; stop ends it (clicked from inside the page as
    // soon as it has grown, before the young tree finishes by itself)
    await page.evaluate(() => new Promise((resolve) => {
      const timer = setInterval(() => {
        if (window.sylva.state().iteration < 4) return;
        clearInterval(timer);
        document.getElementById('stop').click();
        resolve();
      }, 5);
      document.getElementById('start').click();
    }));
    s = await until(page, (x) => x.status === 'finished', 'stopped');
    await new Promise((r) => setTimeout(r, 1000 * SLOW));
    server = await serverRun(d.http, 'site-3');
    assert.equal(server.status, 'finished');
    s = await until(page, (x) => x.iteration === server.iteration, 'the page at the last iteration');
    assert.equal(s.nodes, server.nodes);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('killed and restarted, the daemon is caught up with by itself', async () => {
  const d = await startDaemon({ args: WEB });
  let d2;
  try {
    const { page, errors } = await openViewer(browser, d.http);
    await runInPage(d, page, 'wall.json', { name: 'long', start: true, overrides: { iterations: 16 } });
    await until(page, (s) => s.iteration >= 3, 'a few iterations');
    d.proc.kill('SIGKILL');
    await until(page, (s) => s.connection === 'closed', 'the page to see the daemon gone', 20000);
    d2 = await startDaemon({ dir: d.dir, port: d.port, args: WEB });
    const end = await until(page, (s) => s.connection === 'open' && s.status === 'finished' && s.iteration === 16,
      'the page to catch up to the finished run', 240000 * SLOW);
    const server = await serverRun(d2.http, 'long');
    assert.equal(end.nodes, server.nodes);
    assert.equal(end.seq, server.iteration);
    assert.deepEqual(f32(await page.evaluate(() => window.sylva.skeleton())), f32(exportSkeleton(d.db, 'long')));
    // the only errors are the page's failed attempts while the daemon was down
    assert.deepEqual(errors.filter((e) => !/WebSocket|ERR_CONNECTION_REFUSED/.test(e)), []);
  } finally {
    if (d2) await stopDaemon(d2);
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('an invalid scenario shows the daemon\'s message next to the field it names', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    await page.click('#paste summary');
    await page.fill('#scenario-text', '{"format": "sylva.scenario/1",');
    await page.click('#scenario-load');
    assert.match(await page.textContent('#scenario-text-error'), /not a scenario/);
    const bad = scenario('wall.json');
    bad.plants[0].roots = [[0, 0]];
    await page.fill('#scenario-text', JSON.stringify(bad, null, 1));
    await page.click('#scenario-load');
    assert.ok(await page.isHidden('#scenario-text-error'));
    await page.click('#create-button');
    const note = page.locator('#scenario-form .field-error');
    await note.waitFor();
    const text = await note.textContent();
    assert.match(text, /^\/scenario\/plants\/0\/roots\/0: /);
    const where = await note.evaluate((el) => el.closest('[data-pointer]').dataset.pointer);
    assert.equal(where, '/plants/0/roots/0');
    // a three-number root with a word in it: named deeper in the form
    bad.plants[0].roots = [[0, 0, 0]];
    await page.fill('#scenario-text', JSON.stringify(bad));
    await page.click('#scenario-load');
    await page.fill('#scenario-form input[data-pointer="/plants/0/roots/0/1"]', 'north');
    await page.click('#create-button');
    const deeper = await page.locator('#scenario-form .field-error').textContent();
    const pointer = /^\/scenario(\S*):/.exec(deeper)[1];
    assert.ok(pointer.startsWith('/plants/0/roots/0'), deeper);
    // next to the vector it is in, and that number marked
    const row = await page.locator('#scenario-form .field-error').evaluate((el) => el.closest('[data-pointer]').dataset.pointer);
    assert.equal(row, '/plants/0/roots/0');
    if (pointer !== row) assert.ok(await page.locator(`#scenario-form input.invalid[data-pointer="${pointer}"]`).count() === 1);
    assert.equal(await page.locator('#scenario-form .field-error').count(), 1, 'one message at a time');
    // fixed in the form, the scenario creates a run
    await page.fill('#scenario-form input[data-pointer="/plants/0/roots/0/1"]', '0.5');
    await page.click('#create-button');
    const s = await until(page, (x) => x.run !== null && x.seq >= 0, 'the corrected run');
    assert.equal(await page.locator('#scenario-form .field-error').count(), 0);
    assert.equal(s.name, bad.name);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('a daemon with a token and --public-read: a changing action asks for it', async () => {
  const d = await startDaemon({ args: [...WEB, '--token', 's3cret', '--public-read'] });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    const c = await connect(d.url);
    c.send({ type: 'hello', token: 's3cret' });
    await c.type('welcome');
    c.send({ type: 'create', scenario: scenario('wall.json'), name: 'guarded', start: false, id: 'c' });
    const { run } = await c.type('created');
    c.close();
    await page.click(`#runs tr[data-run="${run}"]`);
    await until(page, (s) => s.run === run && s.seq >= 0, 'the run');
    assert.equal((await state(page)).auth, true);
    page.click('#step');
    await page.waitForSelector('#token-dialog[open]');
    await page.fill('#token-input', 'wrong');
    await page.click('#token-ok');
    await page.waitForSelector('#token-dialog[open] #token-error:not([hidden])');
    await page.fill('#token-input', 's3cret');
    await page.click('#token-ok');
    await until(page, (s) => s.iteration === 1 && s.authed, 'one step with the token');
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('a daemon with a token for reading too: the page asks for it first, then lists, plots and exports with it', async () => {
  const d = await startDaemon({ args: [...WEB, '--token', 's3cret'] });
  try {
    const c = await connect(d.url);
    c.send({ type: 'hello', token: 's3cret' });
    await c.type('welcome');
    // started once subscribed: a run that finished before the subscription would
    // send no status to it (docs/protocol.md, "subscribe")
    c.send({ type: 'create', scenario: scenario('wall.json', { iterations: 3 }), name: 'guarded', start: false, id: 'c' });
    const { run } = await c.type('created');
    c.send({ type: 'subscribe', run });
    await c.type('snapshot');
    c.send({ type: 'control', run, action: 'start' });
    await c.next((m) => m.type === 'status' && m.status === 'finished', 120000);
    c.close();
    const { page, errors } = await openViewer(browser, d.http);
    await page.waitForSelector('#token-dialog[open]');
    await page.fill('#token-input', 's3cret');
    await page.click('#token-ok');
    await page.waitForSelector(`#runs tr[data-run="${run}"]`);
    await page.click(`#runs tr[data-run="${run}"]`);
    await until(page, (s) => s.run === run && s.iteration === 3 && s.authed, 'the run, read with the token');
    // the plots' history comes from stats.csv, fetched with the token
    await page.waitForFunction(() => window.sylva.plots().height.iterations.length >= 3);
    // an export link downloads with the token too
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-csv')]);
    const path = await download.path();
    assert.match(readFileSync(path, 'utf8'), /^iteration,plant,stem,/);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// Creates runs over the protocol, in order ({scenario, name, start}); resolves
// with their ids by name.
async function createRuns(d, list) {
  const c = await connect(d.url);
  const ids = {};
  for (const { scenario: sc, name, start } of list) {
    c.send({ type: 'create', scenario: sc, name, start, id: name });
    ids[name] = (await c.type('created')).run;
  }
  c.close();
  return ids;
}

const hashOf = (page) => page.evaluate(() => location.hash);
const watching = (page, name) => until(page, (s) => s.name === name && s.seq >= 0, `the page watching ${name}`);

test('the page opens on the run its hash names, else on the most recently active run, and names it in the hash', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    // an empty site that was started stays running (it waits for plants), so
    // it is the most recently active run although a newer one was created after it
    const site = { ...scenario('wall.json'), plants: [] };
    const ids = await createRuns(d, [
      { scenario: scenario('wall.json'), name: 'first', start: false },
      { scenario: site, name: 'site', start: true },
      { scenario: scenario('wall.json'), name: 'newest & β', start: false },
    ]);
    assert.equal((await serverRun(d.http, 'site')).status, 'running');

    // #run=NAME opens that run
    const { page, errors } = await openViewer(browser, d.http, { hash: '#run=first' });
    let s = await watching(page, 'first');
    assert.equal(s.run, ids.first);
    assert.equal(await page.getAttribute(`#runs tr[data-run="${ids.first}"]`, 'class'), 'selected');
    assert.equal(await hashOf(page), '#run=first');

    // switching runs names the new one in the hash, so a reload opens it again
    await page.click(`#runs tr[data-run="${ids['newest & β']}"]`);
    await watching(page, 'newest & β');
    assert.equal(await hashOf(page), '#run=newest%20%26%20%CE%B2');
    await page.reload();
    await page.waitForFunction(() => window.sylva?.state().connection === 'open');
    s = await watching(page, 'newest & β');
    assert.equal(s.run, ids['newest & β']);
    // back in the browser's history: the run before
    await page.goBack();
    s = await watching(page, 'first');
    assert.equal(await hashOf(page), '#run=first');
    // a reload or going back aborts what the page was still fetching (the stats of
    // the run it showed): the browser's doing, not a failure of the page
    assert.deepEqual(errors.filter((e) => !e.endsWith('net::ERR_ABORTED')), []);
    await page.close();

    // without a hash, or with the name of no run: the running run
    for (const hash of ['', '#run=gone']) {
      const v = await openViewer(browser, d.http, { hash });
      s = await watching(v.page, 'site');
      assert.equal(s.run, ids.site, `opened at "${hash}"`);
      assert.equal(s.status, 'running');
      assert.equal(await hashOf(v.page), '#run=site', `the hash after opening at "${hash}"`);
      assert.deepEqual(v.errors, []);
      await v.page.close();
    }

    // nothing running: the newest run
    const c = await connect(d.url);
    c.send({ type: 'control', run: ids.site, action: 'stop', id: 's' });
    assert.equal((await c.type('status')).status, 'finished');
    c.close();
    const v = await openViewer(browser, d.http);
    s = await watching(v.page, 'newest & β');
    assert.equal(await hashOf(v.page), '#run=newest%20%26%20%CE%B2');
    assert.deepEqual(v.errors, []);
    await v.page.close();
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('the run list\'s columns are not cut off in a 1280 x 800 window', async () => {
  const d = await startDaemon({ args: [...WEB, '--run', join(ROOT, 'scenarios', 'stand.json')] });
  try {
    // long names (one without a space to wrap at) and thousands of internodes
    const stand = 'Five-tree stand, 2 m apart (IGM fig. 13)';
    await createRuns(d, [
      { scenario: scenario('wall.json'), name: 'a-run-name-without-any-space-to-wrap-at-0123456789', start: false },
      { scenario: scenario('wall.json'), name: 'Tree beside a wall (IGM fig. 11)', start: true },
    ]);
    const end = Date.now() + 120000 * SLOW;
    while ((await serverRun(d.http, stand)).status !== 'finished') {
      assert.ok(Date.now() < end, 'the stand to finish');
      await new Promise((r) => setTimeout(r, 200));
    }
    const nodes = (await serverRun(d.http, stand)).nodes;
    assert.ok(nodes >= 1000, `a count with a thousands separator (${nodes})`);

    const { page, errors } = await openViewer(browser, d.http, { width: 1280, height: 800 });
    // a scenario in the form makes the panel scroll (its scroll bar takes width)
    await page.selectOption('#scenario-select', 'stand');
    await page.waitForSelector('#scenario-form [data-pointer="/name"]');
    await page.waitForFunction((n) => [...document.querySelectorAll('#runs td')].some((td) => td.textContent === n),
      nodes.toLocaleString('en'));
    const m = await page.evaluate(() => {
      const table = document.getElementById('runs');
      const panel = document.getElementById('left');
      return {
        rows: table.tBodies[0].rows.length,
        clipped: [...table.querySelectorAll('th, td')].filter((c) => c.scrollWidth > c.clientWidth)
          .map((c) => `${c.textContent}: ${c.scrollWidth} > ${c.clientWidth}`),
        table: table.scrollWidth,
        section: table.parentElement.clientWidth,
        panel: [panel.scrollWidth, panel.clientWidth],
      };
    });
    assert.equal(m.rows, 3);
    assert.deepEqual(m.clipped, [], 'no cell is cut off');
    assert.ok(m.table <= m.section, `the table (${m.table} px) within its section (${m.section} px)`);
    assert.ok(m.panel[0] <= m.panel[1], `nothing wider than the panel (${m.panel[0]} > ${m.panel[1]} px)`);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});
