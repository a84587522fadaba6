// The daemon's protocol against a real daemon on 127.0.0.1, with the ws client.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync, readdirSync, readFileSync, mkdtempSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { spawnSync } from 'node:child_process';
import { startDaemon, stopDaemon, connect, Client, scenario, Model, exportSkeleton, plantsJSON,
  exportBytes, cleanup, rawGet, ROOT, SYLVA, YEARS_FILE, yearsScenario } from './harness.mjs';

test('HTTP: /healthz, /metrics, /api/runs, and 404', async () => {
  const d = await startDaemon();
  try {
    const h = await (await fetch(`${d.http}/healthz`)).json();
    assert.equal(h.ok, true);
    const m = await (await fetch(`${d.http}/metrics`)).text();
    assert.match(m, /^sylva_runs 0$/m);
    assert.match(m, /^# TYPE sylva_iterations_total counter$/m);
    const runs = await (await fetch(`${d.http}/api/runs`)).json();
    assert.deepEqual(runs, []);
    assert.equal((await fetch(`${d.http}/api/nothing`)).status, 404);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// Each stem's leaf_area in a message's stats (one species, msg.foliage[0]) is the
// leaves the model holds on its nodes x pi/4 x leaf_size^2 (docs/model.md, "Foliage").
function checkLeafArea(model, msg) {
  const { leaf_size: size } = msg.foliage[0];
  for (const st of msg.stats) {
    const plant = model.plants.find((p) => p.id === st.plant);
    let leaves = 0;
    for (const id of plant.stems[st.stem].nodes.keys()) leaves += model.leaves.get(id) ?? 0;
    assert.equal(st.leaf_area, Number((leaves * Math.PI / 4 * size * size).toFixed(4)), `leaf_area of ${st.plant}/${st.stem}`);
  }
}

test('create, subscribe, step: snapshot + deltas equal the stored export', async () => {
  const d = await startDaemon();
  try {
    const c = await connect(d.url);
    c.send({ type: 'list', id: 1 });
    const list = await c.type('runs');
    assert.deepEqual(list.runs, []);
    assert.equal(list.ref, 1);
    c.send({ type: 'create', id: 'c1', name: 'stand', start: false,
      scenario: scenario('stand.json', { iterations: 12 }) });
    const created = await c.type('created');
    assert.equal(created.ref, 'c1');
    const run = created.run;
    c.send({ type: 'subscribe', run });
    const snap = await c.type('snapshot');
    assert.equal(snap.iteration, 0);
    const model = new Model(snap);
    assert.equal(model.plantsJSON(), plantsJSON(exportSkeleton(d.db, 'stand', 0)));
    // the species' foliage, and the initial trunks' leaves
    assert.deepEqual(snap.foliage, [{ species: 'broadleaf', leaf_size: 0.1, leaf_density: 6, leaf_colour: '#4a7f35' }]);
    assert.deepEqual(snap.plant_species, [0, 0, 0, 0, 0]);
    assert.ok(snap.leaves.length > 0 && snap.leaves.every(([, n]) => n === 6), 'the trunks bear leaves');
    checkLeafArea(model, snap);
    c.send({ type: 'control', run, action: 'step', count: 4, id: 2 });
    const st = await c.type('status');
    assert.equal(st.status, 'paused');
    let lost = 0;
    for (let i = 1; i <= 4; i++) {
      const delta = await c.type('delta');
      assert.equal(delta.iteration, i);
      assert.equal(delta.stats.length, 5);
      lost += delta.leaves.filter(([, n]) => n === 0).length;
      model.apply(delta);
      assert.equal(model.plantsJSON(), plantsJSON(exportSkeleton(d.db, 'stand', i)), `iteration ${i}`);
      checkLeafArea(model, { ...delta, foliage: snap.foliage });
      // the leaves held are those of the stored iteration, regrown
      c.send({ type: 'get', run, iteration: i, id: `g${i}` });
      const stored = await c.type('snapshot');
      assert.deepEqual(model.leavesList(), stored.leaves, `leaves at iteration ${i}`);
    }
    assert.ok(lost > 0, 'nodes lose their leaves');
    // a late subscriber, and a resubscriber with since, end equal too
    const late = await connect(d.url);
    late.send({ type: 'subscribe', run });
    const lateModel = new Model(await late.type('snapshot'));
    const again = await connect(d.url);
    again.send({ type: 'subscribe', run, since: 2 });
    // the resubscriber gets deltas 3 and 4 replayed: rebuild from a fresh snapshot at 2
    const base = exportSkeleton(d.db, 'stand', 2);
    const m2 = new Model({ iteration: 2, seq: 2, plants: base.plants });
    const r3 = await again.type('delta');
    assert.equal(r3.seq, 3);
    m2.apply(r3);
    m2.apply(await again.type('delta'));
    assert.equal(m2.plantsJSON(), model.plantsJSON());
    c.send({ type: 'control', run, action: 'start' });
    let last = 4;
    for (;;) {
      const msg = await c.next((m) => m.type === 'delta' || (m.type === 'status' && m.status === 'finished'), 120000);
      if (msg.type === 'status') break;
      model.apply(msg);
      lateModel.apply(await late.type('delta', 120000));
      last = msg.iteration;
    }
    assert.equal(last, 12);
    const final = plantsJSON(exportSkeleton(d.db, 'stand'));
    assert.equal(model.plantsJSON(), final);
    assert.equal(lateModel.plantsJSON(), final);
    const fresh = await connect(d.url);
    fresh.send({ type: 'subscribe', run });
    const finalSnap = await fresh.type('snapshot');
    fresh.close();
    assert.deepEqual(model.leavesList(), finalSnap.leaves);
    assert.deepEqual(lateModel.leavesList(), finalSnap.leaves);
    checkLeafArea(model, finalSnap);
    const csv = await (await fetch(`${d.http}/api/runs/stand/stats.csv`)).text();
    assert.equal(csv.trim().split('\n').length, 1 + 12 * 5);
    const m = await (await fetch(`${d.http}/metrics`)).text();
    assert.match(m, /^sylva_iterations_total 12$/m);
    for (const x of [c, late, again]) x.close();
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// The part of a delta's text from its stats on (stats, canopy_cover, stand).
const statsBytes = (text) => text.slice(text.indexOf('"stats":['));

test('detail "stems": snapshots and deltas without nodes and the same stats bytes; switching back; a bad detail changes nothing', async () => {
  const d = await startDaemon();
  try {
    const full = await connect(d.url);
    const stems = await connect(d.url);
    const raw = { full: [], stems: [] };
    full.ws.on('message', (b) => raw.full.push(b.toString()));
    stems.ws.on('message', (b) => raw.stems.push(b.toString()));
    const deltaText = (texts, seq) => texts.find((t) => t.startsWith('{"type":"delta"') && JSON.parse(t).seq === seq);
    full.send({ type: 'create', name: 'stems', start: false, scenario: scenario('stand.json', { iterations: 6 }) });
    const { run } = await full.type('created');
    full.send({ type: 'subscribe', run });
    const snap = await full.type('snapshot');
    stems.send({ type: 'subscribe', run, detail: 'stems', id: 's' });
    const ssnap = await stems.type('snapshot');
    assert.equal(ssnap.detail, 'stems');
    assert.equal(ssnap.ref, 's');
    assert.equal(snap.detail, undefined);
    assert.equal(ssnap.leaves, undefined);
    assert.deepEqual(ssnap.plants, snap.plants.map((p) => ({ id: p.id, stems: p.stems.map((s) => ({ root: s.root })) })));
    assert.deepEqual(ssnap.stats, snap.stats);
    // a bad detail: bad_request naming the field, and the subscription stays as it was
    for (const detail of ['leaves', 7]) {
      stems.send({ type: 'subscribe', run, detail, id: 'bad' });
      const e = await stems.type('error');
      assert.equal(e.code, 'bad_request');
      assert.match(e.message, /^\/detail: /);
      assert.equal(e.ref, 'bad');
    }
    full.send({ type: 'control', run, action: 'step', count: 2 });
    for (let i = 1; i <= 2; i++) {
      const delta = await full.type('delta');
      const sdelta = await stems.type('delta');
      assert.equal(sdelta.detail, 'stems');
      assert.deepEqual([sdelta.seq, sdelta.iteration], [delta.seq, delta.iteration]);
      for (const k of ['added', 'radii', 'shed', 'leaves']) assert.equal(sdelta[k], undefined, k);
      assert.ok(delta.added.length > 0);
      assert.equal(statsBytes(deltaText(raw.stems, delta.seq)), statsBytes(deltaText(raw.full, delta.seq)), `stats bytes at ${i}`);
    }
    // a stems subscriber with since gets a fresh stems snapshot, even at the current seq
    stems.send({ type: 'subscribe', run, detail: 'stems', since: 2 });
    const again = await stems.type('snapshot');
    assert.deepEqual([again.detail, again.seq, again.iteration], ['stems', 2, 2]);
    // switching to nodes: a full snapshot, then full deltas
    stems.send({ type: 'subscribe', run, detail: 'nodes', id: 'n' });
    const back = await stems.type('snapshot');
    assert.equal(back.detail, undefined);
    assert.equal(back.ref, 'n');
    const model = new Model(back);
    assert.equal(model.plantsJSON(), plantsJSON(exportSkeleton(d.db, 'stems', 2)));
    full.send({ type: 'control', run, action: 'step' });
    const next = await stems.type('delta');
    await full.type('delta');
    assert.equal(next.detail, undefined);
    model.apply(next);
    assert.equal(model.plantsJSON(), plantsJSON(exportSkeleton(d.db, 'stems', 3)));
    assert.equal(deltaText(raw.stems, next.seq), deltaText(raw.full, next.seq));
    for (const x of [full, stems]) x.close();
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('bad messages get an error and change nothing; other clients unaffected', async () => {
  const d = await startDaemon();
  try {
    const c = await connect(d.url);
    const other = await connect(d.url);
    const cases = [
      ['{"type":"list"', 'bad_request'],
      ['[1,2]', 'bad_request'],
      ['{"type":"nope"}', 'bad_request'],
      ['{"type":"subscribe","run":"x"}', 'bad_request'],
      ['{"type":"subscribe","run":1e400}', 'bad_request'],
      ['{"type":"subscribe","run":99}', 'unknown_run'],
      ['{"type":"control","run":1,"action":"fly"}', 'bad_request'],
      ['{"type":"create","scenario":{"format":"sylva.scenario/1","plants":[{"id":1}]}}', 'bad_request'],
      ['{"type":"list","extra":true}', 'bad_request'],
      ['[' .repeat(100) + ']'.repeat(100), 'bad_request'],
    ];
    for (const [text, code] of cases) {
      c.send(text);
      const e = await c.type('error');
      assert.equal(e.code, code, text);
      assert.ok(e.message.length > 0);
    }
    other.send({ type: 'list' });
    await other.type('runs');
    const h = await (await fetch(`${d.http}/healthz`)).json();
    assert.equal(h.ok, true);
    assert.equal(h.runs, 0);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

function isUtf8(buf) {
  try { new TextDecoder('utf-8', { fatal: true }).decode(buf); return true; } catch { return false; }
}

// every JSONTestSuite file (meson option jsontestsuite, SYLVA_JSONTESTSUITE): an
// error, for valid JSON that is no message too; skipped without a copy
const SUITE = process.env.SYLVA_JSONTESTSUITE ||
  join(ROOT, '..', 'shared', 'testdata', 'JSONTestSuite', 'test_parsing');
test('every JSONTestSuite file gets an error and the daemon stays up',
  { skip: existsSync(SUITE) ? false : `no JSONTestSuite copy at ${SUITE}` }, async () => {
    const d = await startDaemon();
    try {
      const c = await connect(d.url);
      let sent = 0;
      for (const f of readdirSync(SUITE)) {
        const bytes = readFileSync(join(SUITE, f));
        // text frames must be UTF-8; send invalid UTF-8 as a binary frame
        c.ws.send(bytes, { binary: !isUtf8(bytes) });
        const e = await c.type('error');
        assert.equal(e.code, 'bad_request', f);
        sent++;
        if (sent % 40 === 0) await new Promise((r) => setTimeout(r, 1000)); // under the rate limit
      }
      assert.ok(sent > 300, `${sent} files sent`);
      const h = await (await fetch(`${d.http}/healthz`)).json();
      assert.equal(h.ok, true);
    } finally {
      await stopDaemon(d);
      cleanup(d.dir);
    }
  });

test('over-size messages close with 1009, floods with 1008', async () => {
  const d = await startDaemon({ args: ['--max-message', '65536', '--rate-limit', '20'] });
  try {
    const big = await connect(d.url);
    big.send('{"type":"list","x":"' + 'a'.repeat(100000) + '"}');
    const closed = await big.whenClosed();
    assert.equal(closed.code, 1009);
    const flood = await connect(d.url);
    for (let i = 0; i < 100; i++) flood.send({ type: 'list' });
    const fc = await flood.whenClosed();
    assert.equal(fc.code, 1008);
    const ok = await connect(d.url);
    ok.send({ type: 'list' });
    await ok.type('runs');
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('token: messages need a hello with the token (test_access.mjs has the rest)', async () => {
  const d = await startDaemon({ args: ['--token', 's3cret'] });
  try {
    const c = await connect(d.url);
    c.send({ type: 'create', scenario: scenario('shrub.json') });
    assert.equal((await c.type('error')).code, 'unauthorized');
    c.send({ type: 'hello', token: 'wrong' });
    assert.equal((await c.type('error')).code, 'unauthorized');
    c.send({ type: 'list' });
    assert.equal((await c.type('error')).code, 'unauthorized'); // reading too
    c.send({ type: 'hello', token: 's3cret', id: 7 });
    const w = await c.type('welcome');
    assert.equal(w.auth, true);
    assert.equal(w.ref, 7, 'the reply to hello echoes its id');
    c.send({ type: 'create', scenario: scenario('shrub.json') });
    await c.type('created');
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('origin: a foreign Origin is refused, the own one and --allow-origin accepted', async () => {
  const d = await startDaemon({ args: ['--allow-origin', 'http://viewer.example'] });
  try {
    const evil = new Client(d.url, { origin: 'http://evil.example' });
    await assert.rejects(evil.opened());
    const own = new Client(d.url, { origin: `http://127.0.0.1:${d.port}` });
    await own.opened();
    const allowed = new Client(d.url, { origin: 'http://viewer.example' });
    await allowed.opened();
    own.close();
    allowed.close();
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('a non-loopback address without a token is refused at start-up', async () => {
  const { spawnSync } = await import('node:child_process');
  const r = spawnSync(process.env.SYLVA_EXE, ['serve', '--listen', '0.0.0.0:1', '--db', '/nonexistent/x.db'],
    { encoding: 'utf8' });
  assert.equal(r.status, 2);
  assert.match(r.stderr, /not a loopback address/);
});

test('SIGTERM: clients closed with 1001, exit 0', async () => {
  const d = await startDaemon();
  const c = await connect(d.url);
  c.send({ type: 'create', name: 'long', start: true, scenario: scenario('stand.json', { iterations: 30 }) });
  const created = await c.type('created');
  c.send({ type: 'subscribe', run: created.run });
  await c.type('snapshot');
  await c.type('delta', 60000);
  const closed = c.whenClosed(20000);
  const exit = await stopDaemon(d, 'SIGTERM');
  assert.equal((await closed).code, 1001);
  assert.equal(exit.code, 0);
  assert.match(d.stderr(), /stopped/);
  cleanup(d.dir);
});

test('static files: MIME types, index, and no path escapes', async () => {
  const { mkdirSync, writeFileSync } = await import('node:fs');
  const web = join(tempDirFor(), 'web');
  mkdirSync(web, { recursive: true });
  writeFileSync(join(web, 'index.html'), '<!doctype html><title>v</title>');
  writeFileSync(join(web, 'app.mjs'), 'export const x = 1;\n');
  writeFileSync(join(web, 'style.css'), 'body{}\n');
  const d = await startDaemon({ args: ['--web', web] });
  try {
    const root = await fetch(`${d.http}/`);
    assert.equal(root.status, 200);
    assert.match(root.headers.get('content-type'), /text\/html/);
    const mjs = await fetch(`${d.http}/app.mjs`);
    assert.equal(mjs.status, 200);
    assert.match(mjs.headers.get('content-type'), /javascript/);
    assert.match((await fetch(`${d.http}/style.css`)).headers.get('content-type'), /text\/css/);
    assert.equal((await fetch(`${d.http}/missing.js`)).status, 404);
    for (const path of ['/../../../../etc/passwd', '/%2e%2e/%2e%2e/etc/passwd', '/..%2f..%2fetc/passwd']) {
      const reply = await rawGet(d.port, path);
      assert.doesNotMatch(reply, /root:x:0:0/, path);
      assert.doesNotMatch(reply.split('\r\n')[0] || '', / 200 /, path);
    }
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

function tempDirFor() {
  return mkdtempSync(join(tmpdir(), 'sylva-web-'));
}

test('light: a slice of the light field, and too_large for a huge site', async () => {
  const d = await startDaemon();
  try {
    const c = await connect(d.url);
    c.send({ type: 'create', name: 'wall', scenario: scenario('wall.json') });
    const { run } = await c.type('created');
    c.send({ type: 'light', run, z: 1.0, id: 'l' });
    const slice = await c.type('light_slice');
    assert.equal(slice.ref, 'l');
    const bytes = Buffer.from(slice.values, 'base64');
    assert.equal(bytes.length, slice.nx * slice.ny);
    assert.ok(bytes.includes(0), 'the wall is dark');
    assert.ok(bytes.includes(255), 'open ground is lit');
    // asked while an iteration is in flight: answered when it is done
    c.send({ type: 'create', name: 'growing', scenario: scenario('stand.json'), start: true, id: 'g' });
    const growing = (await c.type('created')).run;
    c.send({ type: 'light', run: growing, z: 0.5, id: 'busy' });
    const late = await c.next((m) => m.ref === 'busy', 60000);
    assert.equal(late.type, 'light_slice', JSON.stringify(late).slice(0, 200));
    assert.ok(late.iteration >= 1, 'the slice of the world after the iteration in flight');
    const huge = scenario('wall.json', { world: { min: [-500, -500, 0], max: [500, 500, 12], voxel: 0.06 } });
    c.send({ type: 'create', name: 'huge', scenario: huge });
    const big = (await c.type('created')).run;
    c.send({ type: 'light', run: big, z: 1.0 });
    assert.equal((await c.type('error')).code, 'too_large');
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// A street whose keep-clear strips reach 5 cm from the trunks, pruned every 3
// iterations from 3 (scenarios/street-pruned.json, made to conflict early).
function nearStreet() {
  const s = scenario('street-pruned.json', { iterations: 12 });
  for (const o of s.obstacles) {
    if (o.id === 'keep-clear-north') o.min[1] = 5.05;
    if (o.id === 'keep-clear-south') o.max[1] = -5.05;
  }
  s.management = s.management.map((m) => ({ ...m, from: 3 }));
  return s;
}

// Nodes inside the box by the streamed positions. The protocol gives positions to 4
// decimals (docs/protocol.md), so a node within 0.00005 m of a face may be on
// either side of it on the server: such a node counts as outside.
function nodesInside(model, box) {
  const e = 0.00005;
  let n = 0;
  for (const p of model.plants) {
    for (const s of p.stems) {
      for (const [, parent, x, y, z] of s.nodes.values()) {
        if (parent >= 0 && x >= box.min[0] + e && x <= box.max[0] - e && y >= box.min[1] + e &&
            y <= box.max[1] - e && z >= box.min[2] + e && z <= box.max[2] - e) {
          n++;
        }
      }
    }
  }
  return n;
}

// The stand's CSV columns (docs/cli.md, "export"), after canopy_cover in a run with stands.
const STAND_COLUMNS = 'alive,died,vigour,stems_per_ha,basal_area,qmd,dominant_height,sdi,' +
  'cv_height,cv_dbh,stand_died';

// A stats.csv row's stand cells equal a delta's stem stats and stand (startYear: 0, or
// the year the lines' died counts from, as the CSV's does).
function checkStandCells(row, st, stand, startYear) {
  const cells = row.split(',').slice(-11);
  const num = (v) => (v === '' ? null : Number(v));
  assert.equal(cells[0], String(st.alive), row);
  assert.equal(num(cells[1]), st.died, row);
  assert.equal(num(cells[2]), st.vigour, row);
  const keys = STAND_COLUMNS.split(',').slice(3, 10);
  assert.deepEqual(cells.slice(3, 10).map(num), keys.map((key) => stand[key]), row);
  assert.equal(num(cells[10]), stand.died, row);
  assert.ok(startYear === 0 || st.died === null || st.died > startYear, row);
}

test('zones and pruning: stats carry pruned, zones and clearance as stored; prune now by edit', async () => {
  const d = await startDaemon();
  try {
    const c = await connect(d.url);
    const s = nearStreet();
    c.send({ type: 'create', id: 'c', name: 'street "a"', start: false, scenario: s });
    const run = (await c.type('created')).run;
    c.send({ type: 'subscribe', run });
    const snap = await c.type('snapshot');
    assert.deepEqual(snap.obstacles.filter((o) => o.kind === 'zone').map((o) => o.id),
      ['road', 'keep-clear-south', 'keep-clear-north']);
    const model = new Model(snap);
    c.send({ type: 'control', run, action: 'step', count: 9 });
    const deltas = [];
    for (let i = 1; i <= 9; i++) {
      const delta = await c.type('delta', 60000);
      model.apply(delta);
      deltas.push(delta);
      // after a prune of its zones no node is inside any of them
      if (i >= 3 && (i - 3) % 3 === 0) {
        for (const z of s.obstacles.filter((o) => o.kind === 'zone')) {
          assert.equal(nodesInside(model, z), 0, `iteration ${i}: nodes left in ${z.id}`);
        }
      }
    }
    assert.ok(deltas.some((x) => x.stats.some((st) => st.pruned > 0)), 'a schedule pruned nodes');
    const last = deltas.at(-1).stats;
    assert.ok(last.some((st) => Object.keys(st.zones).length > 0), 'a stem entered a zone');
    // the stored stats (CSV) equal the streamed ones
    const csv = (await (await fetch(`${d.http}/api/runs/${encodeURIComponent('street "a"')}/stats.csv`)).text())
      .trim().split('\n');
    // the leaf area follows the conflicts, and street.json's planes grow in years:
    // their four columns come next, then the eight of what the trees give, then (a
    // species in years: a stand) the eleven of the stand
    const years = /,age,year,crown_diameter,crown_height,crown_area,/.test(csv[0]);
    const stand = csv[0].endsWith(`,canopy_cover,${STAND_COLUMNS}`);
    assert.equal(stand, years, 'a run in years has the stand columns');
    assert.match(csv[0], years ? /,pruned,zones,clearance,leaf_area,age,year,crown_diameter,crown_height,crown_area,wood_volume,biomass,biomass_model,carbon,co2,co2_sequestered,canopy_cover,/
      : /,pruned,zones,clearance,leaf_area,crown_area,wood_volume,biomass,biomass_model,carbon,co2,co2_sequestered,canopy_cover$/);
    const tail = new RegExp(`,([^,]*)(,[^,]*){${(years ? 12 : 8) + (stand ? 11 : 0)}}$`);
    const lastRows = csv.slice(1).filter((r) => r.startsWith('9,'));
    assert.equal(lastRows.length, last.length);
    assert.ok(last.every((st) => st.leaf_area > 0), 'every stem has leaves');
    for (let k = 0; k < last.length; k++) {
      const t = tail.exec(lastRows[k]);
      assert.equal(Number(t[1]), last[k].leaf_area, `leaf_area of ${lastRows[k]}`);
      const m = /,(\d+),"?(\{.*?\})"?,"?(\{.*\})"?$/.exec(lastRows[k].slice(0, t.index));
      assert.ok(m, lastRows[k]);
      assert.equal(Number(m[1]), last[k].pruned);
      assert.deepEqual(JSON.parse(m[2].replaceAll('""', '"')), last[k].zones);
      assert.deepEqual(JSON.parse(m[3].replaceAll('""', '"')), last[k].clearance);
      if (stand) checkStandCells(lastRows[k], last[k], deltas.at(-1).stand, 0);
    }
    const metrics = await (await fetch(`${d.http}/metrics`)).text();
    const pruned = deltas.reduce((a, x) => a + x.stats.reduce((b, st) => b + st.pruned, 0), 0);
    assert.match(metrics, new RegExp(`^sylva_nodes_pruned_total ${pruned}$`, 'm'));
    const inZones = last.reduce((a, st) => a + Object.values(st.zones).reduce((b, z) => b + z.nodes, 0), 0);
    assert.match(metrics, new RegExp(`^sylva_zone_nodes\\{run="street \\\\"a\\\\""\\} ${inZones}$`, 'm'));
    // prune now: a new zone around one crown, added and pruned in one edit
    const crown = { id: 'lift', kind: 'zone', min: [-5.5, 4.5, 0.35], max: [-4.5, 5.04, 3] };
    const before = nodesInside(model, crown);
    assert.ok(before > 0, 'nodes inside the new zone before the prune');
    c.send({ type: 'edit', id: 'e1', run, add_obstacles: [crown], prune: { zone: 'lift' } });
    const after = new Model(await c.type('snapshot'));
    assert.equal((await c.next((m) => m.type === 'status' && m.ref === 'e1')).ref, 'e1');
    assert.equal(nodesInside(after, crown), 0);
    const exported = exportSkeleton(d.db, 'street "a"');
    assert.equal(plantsJSON(exported), after.plantsJSON());
    // a zone that is not there, and a solid box, are refused and change nothing
    c.send({ type: 'edit', id: 'e2', run, prune: { zone: 'nowhere' } });
    let err = await c.type('error');
    assert.equal(err.message, '/prune/zone: no zone "nowhere"');
    c.send({ type: 'edit', id: 'e3', run, prune: { zone: 'facade-north' } });
    err = await c.type('error');
    assert.equal(err.message, '/prune/zone: no zone "facade-north"');
    c.send({ type: 'edit', id: 'e4', run, prune: { min: [0, 0, 0] } });
    err = await c.type('error');
    assert.match(err.message, /^\/prune: expected \{"zone": ID\}/);
    assert.equal(plantsJSON(exportSkeleton(d.db, 'street "a"')), after.plantsJSON());
    c.close();
    // restarted, the daemon reports the run's conflicts from the store without
    // loading it: those of its last stored iteration
    assert.equal((await stopDaemon(d)).code, 0);
    const d2 = await startDaemon({ dir: d.dir });
    try {
      const m2 = await (await fetch(`${d2.http}/metrics`)).text();
      const pairs = last.reduce((a, st) => a + Object.keys(st.zones).length, 0);
      assert.match(m2, new RegExp(`^sylva_zone_nodes\\{run="street \\\\"a\\\\""\\} ${inZones}$`, 'm'));
      assert.match(m2, new RegExp(`^sylva_zone_conflicts\\{run="street \\\\"a\\\\""\\} ${pairs}$`, 'm'));
      const health = await (await fetch(`${d2.http}/healthz`)).json();
      assert.equal(health.loading, 0);
    } finally {
      await stopDaemon(d2);
    }
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// The lines of `sylva run FILE --db DB` (its stats lines parsed), the reference of
// the daemon's stats.
function cliRun(file, db) {
  const r = spawnSync(SYLVA, ['run', file, '--db', db, '--quiet-progress'], { encoding: 'utf8' });
  assert.equal(r.status, 0, r.stderr);
  return r.stdout.trim().split('\n').map((l) => JSON.parse(l)).filter((l) => l.stems);
}

const metricValue = (text, name, labels) => {
  const esc = labels.replace(/[\\"{}]/g, (c) => `\\${c}`);
  const m = text.match(new RegExp(`^${name}\\{${esc}\\} (\\S+)$`, 'm'));
  return m ? Number(m[1]) : null;
};

// Runs fn(d, restart) on a daemon; restart() stops it cleanly and resolves with a
// new daemon on the same store. Both are stopped (the second with exit 0) and the
// store removed at the end.
async function withRestart(fn) {
  const d = await startDaemon();
  let d2;
  try {
    await fn(d, async () => {
      assert.equal((await stopDaemon(d)).code, 0);
      d2 = await startDaemon({ dir: d.dir });
      return d2;
    });
  } finally {
    if (d2) assert.equal((await stopDaemon(d2)).code, 0);
    await stopDaemon(d);
    cleanup(d.dir);
  }
}

// The years scenario (12 iterations) created paused and subscribed, then grown
// `steps` iterations: {run, snap (the first snapshot), status (the step's
// reply), deltas}.
async function growYears(c, steps) {
  c.send({ type: 'create', id: 'c', name: 'years', start: false, scenario: yearsScenario({ iterations: 12 }) });
  const run = (await c.type('created')).run;
  c.send({ type: 'subscribe', run });
  const snap = await c.type('snapshot');
  c.send({ type: 'control', id: 's', run, action: 'step', count: steps });
  const status = await c.next((m) => m.type === 'status' && m.ref === 's');
  const deltas = [];
  for (let i = 1; i <= steps; i++) deltas.push(await c.type('delta', 60000));
  return { run, snap, status, deltas };
}

test('years: start year, ages and crown measures in snapshots, deltas, status, stats.csv and /metrics; as stored after a restart; aged plants by edit', () => withRestart(async (d, restart) => {
  const c = await connect(d.url);
  const { run, snap, status, deltas } = await growYears(c, 8);
  assert.equal(snap.start_year, 2027);
  assert.deepEqual(snap.stats.map((st) => [st.plant, st.age]), [['young', 0], ['old', 3], ['igm', null]]);
  // a species in years makes a stand: its figures after canopy_cover, each stem's alive
  assert.deepEqual([snap.stand.alive, snap.stand.died], [3, 0]);
  assert.ok(snap.stats.every((st) => st.alive === true && st.died === null), JSON.stringify(snap.stats));
  for (const x of deltas) assert.equal(x.stand.alive + x.stats.filter((st) => !st.alive).length, 3);
  for (const st of snap.stats) assert.equal(st.crown_diameter, st.crown_width);
  assert.equal(status.start_year, 2027);
  // the stats are the CLI's lines', iteration by iteration: ages, crowns, zones in years
  const lines = cliRun(YEARS_FILE, join(d.dir, 'cli.db'));
  assert.equal(lines.length, 8);
  deltas.forEach((delta, k) => {
    assert.equal(lines[k].year, 2027 + delta.iteration);
    assert.deepEqual(delta.stats, lines[k].stems, `iteration ${delta.iteration}`);
    assert.deepEqual(delta.stats.map((st) => st.age), [delta.iteration, 3 + delta.iteration, null]);
  });
  const last = deltas.at(-1).stats;
  assert.ok(last.some((st) => st.crown_height > 0), 'a crown has a height');
  assert.ok(last.every((st) => st.leaf_area > 0), 'every stem has a leaf area');
  const lane = last[1].zones.lane;
  assert.ok(lane && lane.first > 2027 && lane.first <= 2035, `the old tree entered the lane: ${JSON.stringify(last[1].zones)}`);
  // stats.csv: the CLI's stored run exports the same bytes
  const csv = await (await fetch(`${d.http}/api/runs/years/stats.csv`)).text();
  assert.equal(csv.split('\n')[0].endsWith(',pruned,zones,clearance,leaf_area,age,year,crown_diameter,' +
    `crown_height,crown_area,wood_volume,biomass,biomass_model,carbon,co2,co2_sequestered,canopy_cover,${STAND_COLUMNS}`), true);
  const lastRows = csv.trim().split('\n').filter((r) => r.startsWith(`${deltas.at(-1).iteration},`));
  assert.equal(lastRows.length, last.length);
  for (let k = 0; k < last.length; k++) checkStandCells(lastRows[k], last[k], deltas.at(-1).stand, 2027);
  assert.equal(csv, exportBytes(join(d.dir, 'cli.db'), 'Trees in years', 'csv').toString());
  // /metrics: the run's year and each aged plant's age
  let metrics = await (await fetch(`${d.http}/metrics`)).text();
  assert.equal(metricValue(metrics, 'sylva_run_year', 'run="years"'), 2035);
  assert.equal(metricValue(metrics, 'sylva_plant_age', 'run="years",plant="young"'), 8);
  assert.equal(metricValue(metrics, 'sylva_plant_age', 'run="years",plant="old"'), 11);
  assert.equal(metricValue(metrics, 'sylva_plant_age', 'run="years",plant="igm"'), null);
  // history and forks keep the run's start year
  c.send({ type: 'get', id: 'g', run, iteration: 4 });
  const old = await c.next((m) => m.type === 'snapshot' && m.ref === 'g');
  assert.equal(old.start_year, 2027);
  assert.deepEqual(old.stats.map((st) => st.age), [4, 7, null]);
  c.send({ type: 'fork', id: 'f', run, iteration: 5, name: 'years fork' });
  const fork = (await c.next((m) => m.type === 'created' && m.ref === 'f')).run;
  c.send({ type: 'subscribe', run: fork });
  const forked = await c.next((m) => m.type === 'snapshot' && m.run === fork);
  assert.equal(forked.start_year, 2027);
  assert.equal(forked.iteration, 5);
  metrics = await (await fetch(`${d.http}/metrics`)).text();
  assert.equal(metricValue(metrics, 'sylva_run_year', 'run="years fork"'), 2032);
  c.close();
  // restarted: the metrics from the store, without loading the runs; the run's
  // snapshot still names its start year
  const d2 = await restart();
  const m2 = await (await fetch(`${d2.http}/metrics`)).text();
  assert.equal(metricValue(m2, 'sylva_run_year', 'run="years"'), 2035);
  assert.equal(metricValue(m2, 'sylva_plant_age', 'run="years",plant="old"'), 11);
  assert.equal(metricValue(m2, 'sylva_run_year', 'run="years fork"'), 2032);
  const c2 = await connect(d2.url);
  c2.send({ type: 'subscribe', run });
  const again = await c2.type('snapshot');
  assert.equal(again.start_year, 2027);
  assert.deepEqual(again.stats, last);
  // an aged plant by edit; an age for the IGM species is refused and changes nothing
  c2.send({ type: 'edit', id: 'e1', run, add_plants: [{ id: 'late', species: 'linden', roots: [[0, -2, 0]], age: 2 }] });
  const edited = await c2.type('snapshot');
  assert.equal((await c2.next((m) => m.type === 'status' && m.ref === 'e1')).start_year, 2027);
  assert.deepEqual(edited.plants.map((p) => p.id), ['young', 'old', 'igm', 'late']);
  assert.equal(edited.stats[3].age, 2);
  c2.send({ type: 'edit', id: 'e2', run, add_plants: [{ id: 'bad', species: 'oak', roots: [[0, 2, 0]], age: 2 }] });
  const err = await c2.next((m) => m.type === 'error' && m.ref === 'e2');
  assert.equal(err.code, 'bad_request');
  assert.equal(err.message, '/add_plants/0/age: species "oak" has no time scale (years)');
  c2.send({ type: 'control', run, action: 'step' });
  const after = await c2.type('delta', 60000);
  assert.deepEqual(after.stats.map((st) => st.age), [9, 12, null, 3]);
  metrics = await (await fetch(`${d2.http}/metrics`)).text();
  assert.equal(metricValue(metrics, 'sylva_run_year', 'run="years"'), 2036);
  assert.equal(metricValue(metrics, 'sylva_plant_age', 'run="years",plant="late"'), 3);
  c2.close();
}));

test('years: a run given an aged plant by edit loads again after a restart, as it grew', () => withRestart(async (d, restart) => {
  const c = await connect(d.url);
  const { run } = await growYears(c, 8);
  c.send({ type: 'edit', id: 'e1', run, add_plants: [{ id: 'late', species: 'linden', roots: [[0, -2, 0]], age: 2 }] });
  await c.next((m) => m.type === 'status' && m.ref === 'e1');
  c.send({ type: 'control', run, action: 'step' });
  const grown = await c.type('delta', 60000);
  c.close();
  const d2 = await restart();
  const c2 = await connect(d2.url);
  c2.send({ type: 'subscribe', run });
  const again = await c2.type('snapshot', 20000).catch((e) => {
    throw new Error(`${e.message}; daemon log: ${d2.stderr().slice(-1500)}`);
  });
  assert.deepEqual(again.stats, grown.stats);
  c2.close();
}));

test('years: a run without a start year or years carries none of their fields', async () => {
  const d = await startDaemon();
  try {
    const c = await connect(d.url);
    c.send({ type: 'create', id: 'c', name: 'plain', start: false, scenario: scenario('wall.json', { iterations: 2 }) });
    const run = (await c.type('created')).run;
    c.send({ type: 'subscribe', run });
    const snap = await c.type('snapshot');
    assert.equal('start_year' in snap, false);
    c.send({ type: 'control', id: 's', run, action: 'step', count: 2 });
    const status = await c.next((m) => m.type === 'status' && m.ref === 's');
    assert.equal('start_year' in status, false);
    const delta = await c.type('delta', 60000);
    for (const key of ['age', 'crown_diameter', 'crown_height', 'alive', 'died', 'vigour']) assert.equal(key in delta.stats[0], false, key);
    assert.equal('stand' in snap || 'stand' in delta, false);
    await c.type('delta', 60000);
    const csv = await (await fetch(`${d.http}/api/runs/plain/stats.csv`)).text();
    assert.match(csv.split('\n')[0], /,pruned,zones,clearance,leaf_area,crown_area,wood_volume,biomass,biomass_model,carbon,co2,co2_sequestered,canopy_cover$/);
    const metrics = await (await fetch(`${d.http}/metrics`)).text();
    assert.doesNotMatch(metrics, /^sylva_run_year\{/m);
    assert.doesNotMatch(metrics, /^sylva_plant_age\{/m);
    c.close();
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});
