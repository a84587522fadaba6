// Runs in the daemon over time: crashes and restarts, many viewers (some of which
// never read), edits between iterations, forks and history (`get`). Against the
// real binary, with npm's ws as the client; the references are the CLI's own
// `sylva run --export` and `sylva export`.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { createHash, randomBytes } from 'node:crypto';
import { readFileSync, writeFileSync } from 'node:fs';
import { request as httpRequest } from 'node:http';
import { connect as netConnect } from 'node:net';
import { join } from 'node:path';
import WebSocket from 'ws';
import { startDaemon, stopDaemon, connect, scenario, Model, exportSkeleton, plantsJSON,
  cleanup, tempDir, gisSite, SYLVA, SLOW } from './harness.mjs';

// ---- helpers ------------------------------------------------------------------

// The uninterrupted reference: `sylva run FILE --iterations N --export OUT`.
function referenceRun(scenarioObj, iterations, dir) {
  const file = join(dir, `ref-${iterations}-${randomBytes(4).toString('hex')}.json`);
  const out = `${file}.skeleton.json`;
  writeFileSync(file, JSON.stringify(scenarioObj));
  const r = spawnSync(SYLVA, ['run', file, '--iterations', String(iterations), '--export', out,
    '--quiet-progress'], { stdio: ['ignore', 'ignore', 'pipe'], encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`sylva run failed (${r.status}): ${r.stderr}`);
  return JSON.parse(readFileSync(out, 'utf8'));
}

// `sylva runs --db DB` as [{name, status, ended, iteration, limit, nodes}].
function storedRuns(db) {
  const r = spawnSync(SYLVA, ['runs', '--db', db], { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`sylva runs failed: ${r.stderr}`);
  return r.stdout.trim().split('\n').slice(1).map((line) => {
    const [name, status, ended, it, nodes] = line.split(/\s+/);
    const [iteration, limit] = it.split('/').map(Number);
    return { name, status, ended, iteration, limit, nodes: Number(nodes) };
  });
}

function storedRun(db, name) {
  const r = storedRuns(db).find((x) => x.name === name);
  assert.ok(r, `sylva runs lists no run "${name}"`);
  return r;
}

// GET on a fresh connection each time (a pooled keep-alive socket may meet the
// daemon's idle close while this process is busy).
function httpGet(url) {
  return new Promise((resolve, reject) => {
    const req = httpRequest(url, { agent: false, headers: { connection: 'close' } }, (res) => {
      let body = '';
      res.setEncoding('utf8');
      res.on('data', (x) => { body += x; });
      res.on('end', () => resolve({ status: res.statusCode, body }));
      res.on('error', reject);
    });
    req.on('error', reject);
    req.end();
  });
}

async function metric(d, name) {
  let text;
  try {
    text = (await httpGet(`${d.http}/metrics`)).body;
  } catch (e) {
    throw new Error(`GET /metrics: ${e.message}; daemon ${d.proc.exitCode ?? d.proc.signalCode ?? 'alive'}; log: ${d.stderr().slice(-2000)}`);
  }
  const m = text.match(new RegExp(`^${name} (\\S+)$`, 'm'));
  assert.ok(m, `/metrics has no ${name}`);
  return Number(m[1]);
}

function procStatus(pid, key) {
  const m = readFileSync(`/proc/${pid}/status`, 'utf8').match(new RegExp(`^${key}:\\s+(\\d+) kB`, 'm'));
  return m ? Number(m[1]) * 1024 : NaN;
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

async function until(what, pred, ms = 30000) {
  const end = Date.now() + ms * SLOW;
  for (;;) {
    if (await pred()) return;
    if (Date.now() > end) throw new Error(`timed out waiting for ${what}`);
    await sleep(50);
  }
}

const isFinished = (m) => m.type === 'status' && m.status === 'finished';

// Applies deltas to the model until the run says finished (a snapshot replaces
// the model; its seq must follow). Returns the model.
async function followToEnd(c, model, ms = 120000) {
  for (;;) {
    const m = await c.next((x) => x.type === 'delta' || x.type === 'snapshot' || isFinished(x), ms);
    if (m.type === 'status') return model;
    if (m.type === 'snapshot') {
      assert.equal(m.seq, model.seq + 1, 'a snapshot in the stream takes the next seq');
      model = new Model(m);
    } else {
      assert.equal(m.iteration, model.iteration + 1, `delta seq ${m.seq} skips iterations`);
      model.apply(m);
    }
  }
}

// Compares two plants JSON texts; on a difference, says where instead of
// printing megabytes.
function samePlants(actual, expected, msg = 'plants differ') {
  if (actual === expected) return;
  let i = 0;
  while (i < actual.length && actual[i] === expected[i]) i++;
  const from = Math.max(0, i - 120);
  assert.fail(`${msg}: lengths ${actual.length} and ${expected.length}, first difference at ${i}:\n` +
    `  got  ...${actual.slice(from, i + 80)}\n  want ...${expected.slice(from, i + 80)}`);
}

function differentPlants(a, b, msg) {
  if (a === b) assert.fail(`${msg}: the same (${a.length} bytes)`);
}

// Stops the daemon with SIGTERM and checks it exits 0 (under the sanitizers: no
// leak or error report).
async function stopClean(d) {
  const exit = await stopDaemon(d);
  assert.equal(exit.code, 0, `daemon exit ${JSON.stringify(exit)}: ${d.stderr().slice(-4000)}`);
}

// Kills the daemon with SIGKILL and waits for it to be gone.
function kill9(d) { return stopDaemon(d, 'SIGKILL'); }

function obstacleIds(x) { return x.obstacles.map((o) => o.id).sort(); }

// ---- 1. crashes and restarts --------------------------------------------------

test('kill -9 mid-run, twice: the run continues by itself and ends as an uninterrupted run', async (t) => {
  const dir = tempDir();
  const sc = scenario('stand.json', { iterations: 14 });
  const ref = referenceRun(sc, 14, dir);
  let d = await startDaemon({ dir });
  try {
    let c = await connect(d.url);
    c.send({ type: 'create', name: 'crash', start: true, scenario: sc });
    const run = (await c.type('created')).run;
    c.send({ type: 'subscribe', run });
    await c.type('snapshot');
    await c.next((m) => m.type === 'delta' && m.iteration >= 3, 60000);
    const kills = [];
    for (let k = 0; k < 2; k++) {
      const exit = await kill9(d);
      assert.equal(exit.signal, 'SIGKILL');
      const at = storedRun(d.db, 'crash');
      kills.push(at.iteration);
      assert.equal(at.status, 'running', `after kill ${k + 1}`);
      assert.ok(at.iteration < 14, `kill ${k + 1} came after the run ended (iteration ${at.iteration})`);
      d = await startDaemon({ dir });
      // runs load on the workers after the daemon listens
      const loaded = new RegExp(`\\[run crash\\] loaded at iteration ${at.iteration} \\(running\\)`);
      for (let w = 0; w < 3000 && !loaded.test(d.stderr()); w++) await new Promise((r) => setTimeout(r, 10));
      assert.match(d.stderr(), loaded);
      // killed again at once: a restarted run resumes by itself and would reach its
      // end while a client connected and subscribed (the second kill had come at
      // iteration 12 or 13 of 14, once at 14)
      if (k === 0) continue;
      c = await connect(d.url);
      c.send({ type: 'subscribe', run });
      const snap = await c.type('snapshot');
      assert.ok(snap.iteration >= at.iteration, `snapshot at ${snap.iteration}, stored ${at.iteration}`);
      samePlants(plantsJSON(snap), plantsJSON(exportSkeleton(d.db, 'crash', snap.iteration)),
        `the restarted run's snapshot at ${snap.iteration} is what the store holds`);
      // the last life: follow it to the end
      const model = await followToEnd(c, new Model(snap), 300000);
      assert.equal(model.iteration, 14);
      samePlants(model.plantsJSON(), plantsJSON(ref), 'subscriber model = uninterrupted run');
    }
    t.diagnostic(`killed at stored iterations ${kills.join(', ')}`);
    const fin = storedRun(d.db, 'crash');
    assert.equal(fin.status, 'finished');
    assert.equal(fin.iteration, 14);
    samePlants(plantsJSON(exportSkeleton(d.db, 'crash')), plantsJSON(ref), 'final export = uninterrupted run');
    const csv = (await httpGet(`${d.http}/api/runs/crash/stats.csv`)).body;
    assert.equal(csv.trim().split('\n').length, 1 + 14 * 5, 'one stats row per stem and iteration, no gaps or repeats');
    c.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(dir);
  }
});

test('SIGTERM mid-run: after a restart the run goes on and ends as an uninterrupted run', async () => {
  const dir = tempDir();
  const sc = scenario('stand.json', { iterations: 13 });
  const ref = referenceRun(sc, 13, dir);
  let d = await startDaemon({ dir });
  try {
    let c = await connect(d.url);
    c.send({ type: 'create', name: 'term', start: true, scenario: sc });
    const run = (await c.type('created')).run;
    c.send({ type: 'subscribe', run });
    await c.next((m) => m.type === 'delta' && m.iteration >= 4, 60000);
    const exit = await stopDaemon(d, 'SIGTERM');
    assert.equal(exit.code, 0);
    const at = storedRun(d.db, 'term');
    assert.equal(at.status, 'running');
    assert.ok(at.iteration < 13, `SIGTERM came after the run ended (${at.iteration})`);
    d = await startDaemon({ dir });
    c = await connect(d.url);
    c.send({ type: 'subscribe', run });
    const model = await followToEnd(c, new Model(await c.type('snapshot')), 300000);
    samePlants(model.plantsJSON(), plantsJSON(ref));
    samePlants(plantsJSON(exportSkeleton(d.db, 'term')), plantsJSON(ref));
    c.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(dir);
  }
});

// A client that saw seq s before the daemon restarted resubscribes with since=s:
// whatever it gets must rebuild the run (a snapshot, or deltas that follow on).
test('resubscribe with since after a restart: no deltas of another numbering', async () => {
  const dir = tempDir();
  let d = await startDaemon({ dir });
  try {
    let c = await connect(d.url);
    c.send({ type: 'create', name: 'since', start: false, scenario: scenario('stand.json', { iterations: 14 }) });
    const run = (await c.type('created')).run;
    c.send({ type: 'subscribe', run });
    let model = new Model(await c.type('snapshot'));
    c.send({ type: 'control', run, action: 'step', count: 5 });
    for (let i = 1; i <= 5; i++) model.apply(await c.type('delta', 60000));
    assert.equal(model.iteration, 5);
    await kill9(d);
    d = await startDaemon({ dir });
    c = await connect(d.url);
    // iterations 6..12: more deltas than the client had seen before the restart
    c.send({ type: 'control', run, action: 'step', count: 7 });
    await c.type('status');
    await until('iteration 12', async () => storedRun(d.db, 'since').iteration === 12, 120000);
    const again = await connect(d.url);
    again.send({ type: 'subscribe', run, since: model.seq });
    const m = await again.next((x) => x.type === 'snapshot' || x.type === 'delta');
    if (m.type === 'delta') {
      assert.equal(m.iteration, model.iteration + 1,
        `resubscribed with since=${model.seq} (iteration ${model.iteration}) and got delta seq ${m.seq} of iteration ${m.iteration}`);
      model.apply(m);
      while (model.iteration < 12) model.apply(await again.type('delta'));
    } else {
      assert.equal(m.iteration, 12);
      model = new Model(m);
    }
    samePlants(model.plantsJSON(), plantsJSON(exportSkeleton(d.db, 'since', 12)), 'the resubscriber at 12');
    again.close();
    c.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(dir);
  }
});

// ---- 2. many viewers, some never read --------------------------------------------

// A WebSocket client by hand: handshake, then it only writes.
function rawViewer(port) {
  return new Promise((resolve, reject) => {
    const sock = netConnect(port, '127.0.0.1');
    const key = randomBytes(16).toString('base64');
    let head = Buffer.alloc(0);
    sock.once('connect', () => sock.write(`GET /ws HTTP/1.1\r\nHost: 127.0.0.1:${port}\r\n` +
      `Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: ${key}\r\n` +
      'Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: sylva.v1\r\n\r\n'));
    const onData = (chunk) => {
      head = Buffer.concat([head, chunk]);
      const end = head.indexOf('\r\n\r\n');
      if (end < 0) return;
      sock.off('data', onData);
      sock.pause(); // and never read again
      const status = head.toString('latin1', 0, end);
      if (!/^HTTP\/1\.1 101/.test(status)) reject(new Error(`handshake: ${status}`));
      else resolve(sock);
    };
    sock.on('data', onData);
    sock.on('error', reject);
  });
}

function wsFrame(text) {
  const payload = Buffer.from(text);
  const mask = randomBytes(4);
  let header;
  if (payload.length < 126) header = Buffer.from([0x81, 0x80 | payload.length]);
  else {
    header = Buffer.alloc(4);
    header[0] = 0x81;
    header[1] = 0x80 | 126;
    header.writeUInt16BE(payload.length, 2);
  }
  const body = Buffer.alloc(payload.length);
  for (let i = 0; i < payload.length; i++) body[i] = payload[i] ^ mask[i % 4];
  return Buffer.concat([header, mask, body]);
}

// A light reader: checks seq and iteration from the head of each message and keeps
// a hash per seq (every reader must get the very same bytes).
function lightReader(url, run, keep = false) {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(url, 'sylva.v1', { perMessageDeflate: false });
    const r = { ws, hashes: new Map(), seq: null, iteration: null, errors: [], kept: [], closed: null };
    ws.on('message', (data) => {
      const head = data.toString('latin1', 0, Math.min(data.length, 120));
      const type = (head.match(/^\{"type":"(\w+)"/) || [])[1];
      if (type === 'welcome') { ws.send(JSON.stringify({ type: 'subscribe', run })); return; }
      if (type !== 'snapshot' && type !== 'delta') {
        if (type !== 'status') r.errors.push(`unexpected ${head}`);
        return;
      }
      const m = head.match(/^\{"type":"\w+","run":(\d+),"seq":(\d+),"iteration":(\d+),/);
      if (!m || Number(m[1]) !== run) { r.errors.push(`unexpected head ${head}`); return; }
      const seq = Number(m[2]);
      const it = Number(m[3]);
      if (type === 'delta') {
        if (seq !== r.seq + 1) r.errors.push(`gap: ${r.seq} then ${seq}`);
        if (it !== r.iteration + 1) r.errors.push(`iteration ${r.iteration} then ${it}`);
      } else if (r.seq !== null) r.errors.push(`unasked snapshot at seq ${seq}`);
      r.seq = seq;
      r.iteration = it;
      r.hashes.set(seq, createHash('sha1').update(data).digest('hex'));
      if (keep) r.kept.push(JSON.parse(data.toString()));
      r.lastAt = performance.now();
    });
    ws.on('close', (code) => { r.closed = code; });
    ws.once('open', () => resolve(r));
    ws.once('error', reject);
  });
}

test('200 viewers of a growing stand, 10 never read: readers get every delta, memory bounded', async (t) => {
  const d = await startDaemon();
  const ITER = 15;
  const sc = scenario('stand.json', { iterations: ITER });
  let t0 = performance.now();
  const ref = referenceRun(sc, ITER, d.dir);
  const cliSeconds = (performance.now() - t0) / 1000;
  const nonReaders = [];
  const timers = [];
  const MB = (x) => `${(x / 2 ** 20).toFixed(0)} MiB`;
  try {
    const ctl = await connect(d.url);
    ctl.send({ type: 'create', name: 'crowd', start: false, scenario: sc });
    const run = (await ctl.type('created')).run;
    const readers = [await lightReader(d.url, run, true)];
    while (readers.length < 190) {
      const n = Math.min(10, 190 - readers.length);
      readers.push(...await Promise.all(Array.from({ length: n }, () => lightReader(d.url, run))));
    }
    assert.equal(readers.length, 190);
    for (let i = 0; i < 10; i++) {
      const s = await rawViewer(d.port);
      s.on('error', () => {});
      s.write(wsFrame(JSON.stringify({ type: 'subscribe', run })));
      nonReaders.push(s);
    }
    await until('every reader subscribed', () => readers.every((r) => r.seq === 0));
    await until('201 clients', async () => (await metric(d, 'sylva_clients')) === 201);
    const rssBefore = procStatus(d.proc.pid, 'VmRSS');

    // phase 1: the stand grows; the non-readers' kernel buffers fill and stay full
    t0 = performance.now();
    ctl.send({ type: 'subscribe', run });
    await ctl.type('snapshot');
    ctl.send({ type: 'control', run, action: 'start' });
    await ctl.next(isFinished, 300000);
    const finishedAt = performance.now();
    await until('every reader at the last iteration', () => readers.every((r) => r.iteration === ITER), 120000);
    const lastAt = Math.max(...readers.map((r) => r.lastAt));
    const rssGrown = procStatus(d.proc.pid, 'VmRSS');
    t.diagnostic(`190 readers + 10 non-readers: ${ITER} iterations in ${((finishedAt - t0) / 1000).toFixed(2)} s (sylva run alone: ${cliSeconds.toFixed(2)} s); the last reader had the last delta ${((lastAt - finishedAt) / 1000).toFixed(2)} s after the finish status; ${readers[0].hashes.size} messages per reader; daemon RSS ${MB(rssBefore)} before, ${MB(rssGrown)} after`);
    for (const r of readers) assert.deepEqual(r.errors, []);
    const want = [...readers[0].hashes];
    assert.equal(want.length, ITER + 1, 'a snapshot and one delta per iteration');
    for (const r of readers) assert.deepEqual([...r.hashes], want, 'every reader got the same bytes');
    let model = new Model(readers[0].kept[0]);
    for (const m of readers[0].kept.slice(1)) model.apply(m);
    assert.equal(model.iteration, ITER);
    samePlants(model.plantsJSON(), plantsJSON(ref), 'the readers end at the export');
    assert.ok(readers.every((r) => r.closed === null), 'no reader was closed');
    assert.ok(lastAt - finishedAt < 10000 * SLOW, 'readers were held back');
    assert.equal(await metric(d, 'sylva_clients'), 201, 'non-readers below the cap stay');

    // phase 2: the non-readers keep asking for the full snapshot (25 a second,
    // under the rate limit) and never read: past the cap on pending output
    // (64 MiB) the daemon drops them
    for (const s of nonReaders) {
      timers.push(setInterval(() => {
        if (!s.destroyed) s.write(wsFrame(JSON.stringify({ type: 'subscribe', run })));
      }, 40));
    }
    const t2 = performance.now();
    // meanwhile, how long does another client wait for a reply?
    let waits = [];
    let probing = true;
    const probe = (async () => {
      while (probing) {
        const q = performance.now();
        ctl.send({ type: 'list' });
        await ctl.type('runs', 120000);
        waits.push(performance.now() - q);
        await sleep(200);
      }
    })();
    await until('the non-readers dropped (sylva_clients 191)',
      async () => (await metric(d, 'sylva_clients')) === 191, 60000);
    probing = false;
    await probe;
    const hwm = procStatus(d.proc.pid, 'VmHWM');
    waits = waits.sort((x, y) => x - y);
    t.diagnostic(`non-readers dropped after ${((performance.now() - t2) / 1000).toFixed(2)} s; a list meanwhile waited median ${waits[waits.length >> 1].toFixed(0)} ms, max ${waits[waits.length - 1].toFixed(0)} ms; daemon peak RSS ${MB(hwm)}, now ${MB(procStatus(d.proc.pid, 'VmRSS'))}`);
    assert.ok(hwm < 1.5 * 2 ** 30, `daemon peak RSS ${MB(hwm)}`);
    assert.ok(readers.every((r) => r.closed === null), 'no reader was closed');
    ctl.send({ type: 'list' });
    assert.equal((await ctl.type('runs')).runs[0].status, 'finished');
    const t3 = performance.now();
    for (const r of readers) r.ws.close();
    ctl.close();
    await until('every client gone', async () => (await metric(d, 'sylva_clients')) === 0, 30000);
    t.diagnostic(`readers closed in ${((performance.now() - t3) / 1000).toFixed(2)} s`);
    await stopClean(d);
  } finally {
    for (const x of timers) clearInterval(x);
    for (const s of nonReaders) s.destroy();
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// ---- 3. edits -----------------------------------------------------------------------

const WALL = { id: 'w2', kind: 'box', min: [0.3, -2, 0], max: [0.4, 2, 3] };
const SEEDLING = { id: 't9', species: 'broadleaf', roots: [[-2, 0, 0]] };

async function stepAndFollow(c, run, count, model) {
  c.send({ type: 'control', run, action: 'step', count });
  await c.next((m) => m.type === 'status' && m.run === run);
  for (let i = 0; i < count; i++) {
    const m = await c.next((x) => (x.type === 'delta' || x.type === 'snapshot') && x.run === run, 60000);
    if (m.type === 'snapshot') throw new Error(`unexpected snapshot at seq ${m.seq}`);
    model.apply(m);
  }
  return model;
}

test('edit: a wall and a seedling between iterations; subscribers get a fresh snapshot; bad edits change nothing', async (t) => {
  const dir = tempDir();
  let d = await startDaemon({ dir });
  try {
    const sc = scenario('wall.json', { iterations: 10 });
    const a = await connect(d.url);
    const b = await connect(d.url);
    a.send({ type: 'create', name: 'A', start: false, scenario: sc });
    const runA = (await a.type('created')).run;
    b.send({ type: 'create', name: 'B', start: false, scenario: sc });
    const runB = (await b.type('created')).run;
    a.send({ type: 'subscribe', run: runA });
    b.send({ type: 'subscribe', run: runB });
    let mA = new Model(await a.type('snapshot'));
    const mB = new Model(await b.type('snapshot'));
    await stepAndFollow(a, runA, 4, mA);
    await stepAndFollow(b, runB, 4, mB);
    samePlants(mA.plantsJSON(), mB.plantsJSON(), 'same scenario and seed, same growth');

    const editor = await connect(d.url);
    // bad edits: an error naming the place, nothing changes
    editor.send({ type: 'list' });
    const listBefore = (await editor.type('runs')).runs;
    const exportBefore = exportSkeleton(d.db, 'A');
    const bad = [
      [{ add_plants: [{ ...SEEDLING, species: 'conifer' }] }, /\/add_plants\/0\/species/],
      [{ add_plants: [{ ...SEEDLING, roots: [[0.9, 0, 0]] }] }, /\/add_plants\/0\/roots\/0/],
      [{ add_obstacles: [{ ...WALL, id: 'wall' }] }, /\/add_obstacles\/0/],
      [{ remove_obstacles: ['nope'] }, /\/remove_obstacles\/0/],
      // all or nothing: a good obstacle and a bad plant
      [{ add_obstacles: [WALL], add_plants: [{ ...SEEDLING, species: 'conifer' }] }, /\/add_plants\/0\/species/],
      [{ add_plants: [SEEDLING, { ...SEEDLING, id: 't10', roots: [[0.9, 0, 0]] }] }, /\/add_plants\/1\/roots\/0/],
      [{ add_plants: [{ ...SEEDLING, id: 'tree' }] }, /\/add_plants\/0\/id/],
    ];
    for (const [fields, where] of bad) {
      editor.send({ type: 'edit', run: runA, id: 'bad', ...fields });
      const e = await editor.next((m) => m.type === 'error' || m.type === 'status');
      assert.equal(e.type, 'error', `${JSON.stringify(fields)} was accepted`);
      assert.equal(e.code, 'bad_request', JSON.stringify(fields));
      assert.match(e.message, where, JSON.stringify(fields));
      assert.equal(e.ref, 'bad', JSON.stringify(e));
    }
    editor.send({ type: 'edit', run: 999, add_obstacles: [WALL] });
    assert.equal((await editor.type('error')).code, 'unknown_run');
    editor.send({ type: 'list' });
    assert.deepEqual((await editor.type('runs')).runs, listBefore, 'bad edits changed the runs');
    const exportAfterBad = exportSkeleton(d.db, 'A');
    samePlants(JSON.stringify(exportAfterBad), JSON.stringify(exportBefore), 'bad edits changed the store');
    a.send({ type: 'list' }); // a barrier on A's subscriber connection
    await a.type('runs');
    assert.deepEqual(a.messages.filter((m) => m.type === 'snapshot'), [], 'a bad edit sent a snapshot');

    // the edit
    const seqBefore = mA.seq;
    editor.send({ type: 'edit', run: runA, id: 'e1', add_obstacles: [WALL], add_plants: [SEEDLING] });
    const st = await editor.next((m) => m.ref === 'e1');
    assert.equal(st.type, 'status', JSON.stringify(st));
    assert.equal(st.run, runA);
    const fresh = await a.type('snapshot');
    assert.equal(fresh.seq, seqBefore + 1, 'the post-edit snapshot takes the next seq');
    assert.equal(fresh.iteration, 4);
    assert.deepEqual(obstacleIds(fresh), ['w2', 'wall']);
    assert.deepEqual(fresh.plants.map((p) => p.id), ['tree', 't9']);
    const original = JSON.parse(mA.plantsJSON())[0];
    samePlants(JSON.stringify(JSON.parse(plantsJSON(fresh))[0]), JSON.stringify(original), 'the edit left the grown tree as it was');
    mA = new Model(fresh);
    // a new subscriber sees it too
    const late = await connect(d.url);
    late.send({ type: 'subscribe', run: runA });
    const lateSnap = await late.type('snapshot');
    assert.deepEqual(obstacleIds(lateSnap), ['w2', 'wall']);
    samePlants(plantsJSON(lateSnap), mA.plantsJSON());
    const lateModel = new Model(lateSnap);

    await stepAndFollow(a, runA, 6, mA);
    await stepAndFollow(b, runB, 6, mB);
    for (let i = 0; i < 6; i++) lateModel.apply(await late.type('delta', 60000));
    await a.next(isFinished);
    await b.next(isFinished);
    const finalA = exportSkeleton(d.db, 'A');
    const finalB = exportSkeleton(d.db, 'B');
    assert.equal(finalA.iteration, 10);
    samePlants(mA.plantsJSON(), plantsJSON(finalA), "A's subscriber = A's export");
    samePlants(lateModel.plantsJSON(), plantsJSON(finalA));
    samePlants(mB.plantsJSON(), plantsJSON(finalB));
    assert.deepEqual(obstacleIds(finalA), ['w2', 'wall'], "the wall is in A's export");
    assert.deepEqual(obstacleIds(finalB), ['wall']);
    assert.ok(finalA.plants.some((p) => p.id === 't9' && p.stems[0].nodes.length > 3), 'the seedling grew');
    for (let i = 0; i <= 10; i++) {
      const ea = exportSkeleton(d.db, 'A', i);
      const eb = exportSkeleton(d.db, 'B', i);
      if (i < 4) samePlants(plantsJSON(ea), plantsJSON(eb), `A and B at iteration ${i}`);
      else if (i === 4) samePlants(JSON.stringify(ea.plants[0]), JSON.stringify(eb.plants[0]), 'the tree at 4');
      else {
        differentPlants(plantsJSON(ea), plantsJSON(eb), `A and B at iteration ${i}`);
        assert.deepEqual(obstacleIds(ea), ['w2', 'wall'], `A's obstacles at ${i}`);
      }
    }
    differentPlants(JSON.stringify(finalA.plants[0]), JSON.stringify(finalB.plants[0]),
      'the new wall changed how the tree grew');

    // a fork of A after the edit carries the edit, and grows as A did
    editor.send({ type: 'fork', run: runA, iteration: 7, name: 'A7', id: 'f' });
    const forked = await editor.next((m) => m.ref === 'f');
    assert.equal(forked.type, 'created', JSON.stringify(forked));
    const f = await connect(d.url);
    f.send({ type: 'subscribe', run: forked.run });
    const fSnap = await f.type('snapshot');
    assert.deepEqual(obstacleIds(fSnap), ['w2', 'wall']);
    samePlants(plantsJSON(fSnap), plantsJSON(exportSkeleton(d.db, 'A', 7)));
    const fModel = await stepAndFollow(f, forked.run, 3, new Model(fSnap));
    samePlants(fModel.plantsJSON(), plantsJSON(finalA), 'fork of A at 7, stepped 3 = A at 10');

    // the edit is logged: C gets the same edit, the daemon is killed right after
    // the reply, and again two iterations later; C ends as A
    const c = await connect(d.url);
    c.send({ type: 'create', name: 'C', start: false, scenario: sc });
    const runC = (await c.type('created')).run;
    c.send({ type: 'subscribe', run: runC });
    await stepAndFollow(c, runC, 4, new Model(await c.type('snapshot')));
    c.send({ type: 'edit', run: runC, id: 'e2', add_obstacles: [WALL], add_plants: [SEEDLING] });
    assert.equal((await c.next((m) => m.ref === 'e2')).type, 'status');
    await kill9(d);
    d = await startDaemon({ dir });
    let cc = await connect(d.url);
    cc.send({ type: 'subscribe', run: runC });
    let snap = await cc.type('snapshot');
    assert.equal(snap.iteration, 4);
    assert.deepEqual(obstacleIds(snap), ['w2', 'wall'], 'the edit survived kill -9');
    assert.deepEqual(snap.plants.map((p) => p.id), ['tree', 't9']);
    await stepAndFollow(cc, runC, 2, new Model(snap));
    await kill9(d);
    d = await startDaemon({ dir });
    cc = await connect(d.url);
    cc.send({ type: 'subscribe', run: runC });
    snap = await cc.type('snapshot');
    assert.equal(snap.iteration, 6);
    assert.deepEqual(obstacleIds(snap), ['w2', 'wall']);
    samePlants(plantsJSON(snap), plantsJSON(exportSkeleton(d.db, 'A', 6)), 'C at 6 after two kills = A at 6');
    cc.send({ type: 'control', run: runC, action: 'start' });
    const cModel = await followToEnd(cc, new Model(snap));
    samePlants(cModel.plantsJSON(), plantsJSON(finalA), 'C (killed twice) ends as A');
    samePlants(plantsJSON(exportSkeleton(d.db, 'C')), plantsJSON(finalA));
    assert.deepEqual(obstacleIds(exportSkeleton(d.db, 'C')), ['w2', 'wall']);
    // removing an obstacle works too (on a paused run)
    cc.send({ type: 'fork', run: runC, iteration: 6, name: 'C6', id: 'f2' });
    const c6 = await cc.next((m) => m.ref === 'f2');
    assert.equal(c6.type, 'created', JSON.stringify(c6));
    cc.send({ type: 'subscribe', run: c6.run });
    await cc.next((m) => m.type === 'snapshot' && m.run === c6.run);
    cc.send({ type: 'edit', run: c6.run, id: 'e3', remove_obstacles: ['w2'] });
    assert.equal((await cc.next((m) => m.ref === 'e3')).type, 'status');
    const after = await cc.next((m) => m.type === 'snapshot' && m.run === c6.run);
    assert.deepEqual(obstacleIds(after), ['wall']);
    t.diagnostic('edits, fork of an edited run and edit logging checked');
    for (const x of [a, b, editor, late, f, c, cc]) x.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(dir);
  }
});

// A scenario file needs plants (`sylva run` and `validate` refuse one without),
// but create makes an empty site, to be planted by edits.
// A prism (an L with a courtyard, at an angle) and a prism zone added by an edit:
// the snapshot gives them back as sent; the command log keeps them through kill -9;
// the run grows as the same scenario with them from the start.
const L_HOUSE = { id: 'house', kind: 'prism', polygon: [[1.2, -3], [4, -1.4], [3, 0.3], [2.1, -0.2], [1, 1.7], [0.5, 1.4]],
  holes: [[[1.6, -1.8], [2.4, -1.3], [2, -0.6]]], z: [0, 4.5] };
const LANE = { id: 'lane', kind: 'zone', polygon: [[-5, -3], [5, -1], [5, 0], [-5, -2]], z: [0.5, 10] };

test('edit: a prism and a prism zone over the wire, kept by the log through kill -9, grown as in a scenario', async () => {
  const dir = tempDir();
  let d = await startDaemon({ dir });
  try {
    const base = scenario('wall.json', { iterations: 8, obstacles: [] });
    const c = await connect(d.url);
    c.send({ type: 'create', name: 'P', start: false, scenario: base });
    const runP = (await c.type('created')).run;
    c.send({ type: 'create', name: 'Q', start: false, scenario: { ...base, obstacles: [L_HOUSE, LANE] } });
    const runQ = (await c.type('created')).run;
    c.send({ type: 'subscribe', run: runP });
    await c.next((m) => m.type === 'snapshot' && m.run === runP);
    c.send({ type: 'edit', run: runP, id: 'e1', add_obstacles: [L_HOUSE, LANE] });
    assert.equal((await c.next((m) => m.ref === 'e1')).type, 'status');
    const fresh = await c.next((m) => m.type === 'snapshot' && m.run === runP);
    assert.deepEqual(fresh.obstacles, [L_HOUSE, LANE], 'the snapshot gives the prisms back as sent');
    await kill9(d);
    d = await startDaemon({ dir });
    const cc = await connect(d.url);
    cc.send({ type: 'subscribe', run: runP });
    const snap = await cc.next((m) => m.type === 'snapshot' && m.run === runP);
    assert.deepEqual(snap.obstacles, [L_HOUSE, LANE], 'the edit survived kill -9');
    const mP = await stepAndFollow(cc, runP, 8, new Model(snap));
    cc.send({ type: 'subscribe', run: runQ });
    const mQ = await stepAndFollow(cc, runQ, 8, new Model(await cc.next((m) => m.type === 'snapshot' && m.run === runQ)));
    samePlants(mP.plantsJSON(), mQ.plantsJSON(), 'edited at 0 = the scenario with them');
    const nodes = JSON.parse(mP.plantsJSON())[0].stems[0].nodes.length;
    assert.ok(nodes > 10, `the tree grew (${nodes} nodes)`);
    const exported = exportSkeleton(d.db, 'P');
    assert.deepEqual(exported.obstacles, [L_HOUSE, LANE], "the export's obstacles");
    c.close();
    cc.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(dir);
    cleanup(d.dir);
  }
});

// What `sylva site` writes from GIS layers (the fixtures of tests/gis/data: three
// buildings at 30 degrees, one with a courtyard, a zone, trees in lon/lat) is taken
// like any scenario: its prisms and site given back, grown as the CLI grows it.
test('create: a scenario `sylva site` wrote from GIS layers, grown as the CLI grows it', async () => {
  const dir = tempDir();
  const d = await startDaemon();
  try {
    const site = { ...gisSite(dir), iterations: 3 };
    assert.ok(site.obstacles.some((o) => o.kind === 'prism' && o.holes) && site.site.crs === 'EPSG:32618',
      'the scenario has a prism with a courtyard and a site');
    const c = await connect(d.url);
    c.send({ type: 'create', name: 'site', start: false, scenario: site, id: 'c' });
    const created = await c.next((m) => m.ref === 'c');
    assert.equal(created.type, 'created', JSON.stringify(created));
    c.send({ type: 'subscribe', run: created.run });
    const snap = await c.next((m) => m.type === 'snapshot' && m.run === created.run);
    assert.deepEqual(snap.obstacles, site.obstacles, 'the prisms and the zone as written');
    assert.deepEqual(snap.plants.map((p) => p.id), site.plants.map((p) => p.id));
    const model = await stepAndFollow(c, created.run, 3, new Model(snap));
    samePlants(model.plantsJSON(), plantsJSON(referenceRun(site, 3, dir)), 'the daemon grows it as sylva run');
    c.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(dir);
    cleanup(d.dir);
  }
});

test('create: an empty site, without plants or with an empty list, planted by an edit', async () => {
  const d = await startDaemon();
  try {
    const bare = scenario('wall.json', { iterations: 10 });
    delete bare.plants;
    const c = await connect(d.url);
    for (const [name, sc] of [['bare', bare], ['empty', { ...bare, plants: [] }]]) {
      c.send({ type: 'create', name, start: false, scenario: sc, id: name });
      const created = await c.next((m) => m.ref === name);
      assert.equal(created.type, 'created', JSON.stringify(created));
      c.send({ type: 'subscribe', run: created.run });
      const snap = await c.next((m) => m.type === 'snapshot' && m.run === created.run);
      assert.deepEqual(snap.plants, [], name);
      c.send({ type: 'edit', run: created.run, id: `e-${name}`, add_plants: [SEEDLING] });
      const st = await c.next((m) => m.ref === `e-${name}`);
      assert.equal(st.type, 'status', JSON.stringify(st));
      const planted = await c.next((m) => m.type === 'snapshot' && m.run === created.run);
      assert.deepEqual(planted.plants.map((p) => p.id), ['t9'], name);
      const before = planted.plants[0].stems[0].nodes.length;
      const model = await stepAndFollow(c, created.run, 2, new Model(planted));
      assert.ok(JSON.parse(model.plantsJSON())[0].stems[0].nodes.length > before, `${name}: the seedling grew`);
    }
    c.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// An edit sent while an iteration is in flight waits for it, and lands between
// two iterations: a run given the same edit at that iteration ends the same.
test('edit of a running run: applied between iterations, as a paused run edited there', async () => {
  const d = await startDaemon();
  try {
    const sc = scenario('stand.json', { iterations: 13 });
    const edit = { add_plants: [{ id: 't9', species: 'broadleaf', roots: [[0, 3, 0]] }],
      add_obstacles: [{ id: 'fence', kind: 'box', min: [-3, -3, 0], max: [3, -2.9, 2] }] };
    const a = await connect(d.url);
    a.send({ type: 'create', name: 'live', start: true, scenario: sc });
    const runA = (await a.type('created')).run;
    a.send({ type: 'subscribe', run: runA });
    let model = new Model(await a.type('snapshot', 60000));
    for (;;) {
      const m = await a.type('delta', 60000);
      model.apply(m);
      if (m.iteration >= 9) break;
    }
    a.send({ type: 'edit', run: runA, id: 'live-edit', ...edit });
    const reply = await a.next((m) => m.ref === 'live-edit', 60000);
    assert.equal(reply.type, 'status', JSON.stringify(reply));
    // deltas up to the edit, then the snapshot with it, then deltas again
    let snap;
    for (;;) {
      const m = await a.next((x) => x.type === 'delta' || x.type === 'snapshot', 60000);
      if (m.type === 'snapshot') { snap = m; break; }
      model.apply(m);
    }
    assert.equal(snap.seq, model.seq + 1, 'the post-edit snapshot takes the next seq');
    assert.equal(snap.iteration, model.iteration, 'the edit lands between iterations');
    assert.deepEqual(obstacleIds(snap), ['fence']);
    assert.deepEqual(snap.plants.map((p) => p.id), ['t1', 't2', 't3', 't4', 't5', 't9']);
    const k = snap.iteration;
    const snapPlants = plantsJSON(snap); // (a Model shares the node arrays of its snapshot)
    model = await followToEnd(a, new Model(snap), 300000);
    assert.equal(model.iteration, 13);
    const finalA = exportSkeleton(d.db, 'live');
    samePlants(model.plantsJSON(), plantsJSON(finalA));
    // the same edit on a paused run at iteration k
    const b = await connect(d.url);
    b.send({ type: 'create', name: 'twin', start: false, scenario: sc });
    const runB = (await b.type('created')).run;
    b.send({ type: 'subscribe', run: runB });
    await stepAndFollow(b, runB, k, new Model(await b.type('snapshot')));
    b.send({ type: 'edit', run: runB, id: 'twin-edit', ...edit });
    assert.equal((await b.next((m) => m.ref === 'twin-edit')).type, 'status');
    const bSnap = await b.type('snapshot');
    assert.equal(bSnap.iteration, k);
    samePlants(plantsJSON(bSnap), snapPlants, `the edited worlds at iteration ${k}`);
    b.send({ type: 'control', run: runB, action: 'start' });
    await followToEnd(b, new Model(bSnap), 300000);
    samePlants(plantsJSON(exportSkeleton(d.db, 'twin')), plantsJSON(finalA),
      `edited while running (landed after ${k}) = edited while paused at ${k}`);
    a.close();
    b.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// ---- 4. history: get and fork -----------------------------------------------------

test('get: a stored iteration as a snapshot, not a subscription', async () => {
  const d = await startDaemon();
  try {
    const s = await connect(d.url);
    const g = await connect(d.url);
    s.send({ type: 'create', name: 'hist', start: false, scenario: scenario('stand.json', { iterations: 9 }) });
    const run = (await s.type('created')).run;
    s.send({ type: 'subscribe', run });
    const model = await stepAndFollow(s, run, 5, new Model(await s.type('snapshot')));
    for (const it of [0, 2, 5]) {
      g.send({ type: 'get', run, iteration: it, id: `g${it}` });
      const snap = await g.next((m) => m.ref === `g${it}`);
      assert.equal(snap.type, 'snapshot', JSON.stringify(snap).slice(0, 300));
      assert.equal(snap.run, run);
      assert.equal(snap.iteration, it);
      const want = exportSkeleton(d.db, 'hist', it);
      samePlants(plantsJSON(snap), plantsJSON(want), `get ${it} = export ${it}`);
      assert.deepEqual(snap.world, want.world);
      assert.deepEqual(snap.obstacles, want.obstacles);
    }
    // history of a run mid-way, then grown on: the getter gets no deltas
    s.send({ type: 'control', run, action: 'start' });
    await followToEnd(s, model);
    g.send({ type: 'list' });
    await g.type('runs');
    assert.deepEqual(g.messages.filter((m) => m.type === 'delta' || m.type === 'snapshot'), [],
      'get made a subscription');
    for (const it of [9, 7]) {
      g.send({ type: 'get', run, iteration: it, id: `h${it}` });
      const snap = await g.next((m) => m.ref === `h${it}`);
      assert.equal(snap.type, 'snapshot');
      samePlants(plantsJSON(snap), plantsJSON(exportSkeleton(d.db, 'hist', it)), `get ${it}`);
    }
    for (const it of [10, -1, 1.5]) {
      g.send({ type: 'get', run, iteration: it, id: 'bad' });
      const e = await g.next((m) => m.ref === 'bad' || m.type === 'error');
      assert.equal(e.type, 'error', `get iteration ${it}`);
      assert.equal(e.code, 'bad_request', `get iteration ${it}`);
      assert.match(e.message, /\/iteration/);
    }
    g.send({ type: 'get', run: 77, iteration: 0 });
    assert.equal((await g.type('error')).code, 'unknown_run');
    s.close();
    g.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('fork: a new paused run at a stored iteration; stepped, it grows as the original did', async () => {
  const dir = tempDir();
  let d = await startDaemon({ dir });
  try {
    const c = await connect(d.url);
    c.send({ type: 'create', name: 'orig', start: true, scenario: scenario('stand.json', { iterations: 10 }) });
    const run = (await c.type('created')).run;
    c.send({ type: 'subscribe', run });
    await c.next(isFinished, 120000);
    c.send({ type: 'fork', run, iteration: 4, name: 'branch', id: 'f1' });
    const created = await c.next((m) => m.ref === 'f1');
    assert.equal(created.type, 'created', JSON.stringify(created));
    assert.equal(created.name, 'branch');
    assert.notEqual(created.run, run);
    c.send({ type: 'list' });
    const listed = (await c.type('runs')).runs.find((r) => r.run === created.run);
    assert.ok(listed, 'list shows the fork');
    assert.equal(listed.name, 'branch');
    assert.equal(listed.status, 'paused');
    assert.equal(listed.iteration, 4);
    const stored = storedRun(d.db, 'branch');
    assert.equal(stored.status, 'paused');
    assert.equal(stored.iteration, 4);
    const v = await connect(d.url);
    v.send({ type: 'subscribe', run: created.run });
    const snap = await v.type('snapshot');
    assert.equal(snap.iteration, 4);
    samePlants(plantsJSON(snap), plantsJSON(exportSkeleton(d.db, 'orig', 4)), 'fork at 4 = orig at 4');
    const model = await stepAndFollow(v, created.run, 3, new Model(snap));
    assert.equal(model.iteration, 7);
    samePlants(model.plantsJSON(), plantsJSON(exportSkeleton(d.db, 'orig', 7)), 'fork stepped 3 = orig at 7');
    samePlants(plantsJSON(exportSkeleton(d.db, 'branch', 7)), plantsJSON(exportSkeleton(d.db, 'orig', 7)));
    // the original is untouched
    assert.equal(storedRun(d.db, 'orig').iteration, 10);
    // bad forks
    for (const [msg, code, where] of [
      [{ type: 'fork', run, iteration: 4, name: 'branch' }, 'bad_request', /name|exists/],
      [{ type: 'fork', run, iteration: 11, name: 'x1' }, 'bad_request', /\/iteration/],
      [{ type: 'fork', run, iteration: -1, name: 'x2' }, 'bad_request', /\/iteration/],
      [{ type: 'fork', run: 99, iteration: 1, name: 'x3' }, 'unknown_run', /\/run/],
    ]) {
      c.send({ ...msg, id: 'bad' });
      const e = await c.next((m) => m.ref === 'bad' || m.type === 'error');
      assert.equal(e.type, 'error', JSON.stringify(msg));
      assert.equal(e.code, code, JSON.stringify(msg));
      assert.match(e.message, where, JSON.stringify(msg));
    }
    assert.deepEqual(storedRuns(d.db).map((r) => r.name), ['orig', 'branch']);
    // a fork survives a crash, and finishes as the original
    await kill9(d);
    d = await startDaemon({ dir });
    const w = await connect(d.url);
    w.send({ type: 'subscribe', run: created.run });
    const s2 = await w.type('snapshot');
    assert.equal(s2.iteration, 7);
    w.send({ type: 'control', run: created.run, action: 'start' });
    const end = await followToEnd(w, new Model(s2));
    assert.equal(end.iteration, 10);
    samePlants(end.plantsJSON(), plantsJSON(exportSkeleton(d.db, 'orig')), 'fork ends as the original');
    w.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(dir);
  }
});

// The parser's own checks (here: a plant id twice in one edit) answer with the
// message's id as ref too.
test('errors found while parsing a message still echo its id as ref', async () => {
  const d = await startDaemon();
  try {
    const c = await connect(d.url);
    c.send({ type: 'create', name: 'p', start: false, scenario: scenario('wall.json', { iterations: 3 }) });
    const run = (await c.type('created')).run;
    c.send({ type: 'edit', run, id: 'dup', add_plants: [SEEDLING, { ...SEEDLING, roots: [[2, 2, 0]] }] });
    const e = await c.type('error');
    assert.match(e.message, /\/add_plants\/1\/id/);
    assert.equal(e.ref, 'dup', JSON.stringify(e));
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('snapshots: the daemon adds each due snapshot after the delta, every fifth and the last iteration', async () => {
  const dir = tempDir();
  const d = await startDaemon({ dir });
  try {
    const c = await connect(d.url);
    c.send({ type: 'create', name: 'snaps', start: false, scenario: scenario('stand.json', { iterations: 11 }) });
    const run = (await c.type('created')).run;
    c.send({ type: 'subscribe', run });
    await c.type('snapshot');
    c.send({ type: 'control', run, action: 'start' });
    await c.next((m) => m.type === 'status' && m.status === 'finished', 120000);
    c.close();
    await stopClean(d);
    const q = spawnSync('sqlite3', [d.db, `SELECT iteration FROM iterations WHERE run = ${run} AND snapshot IS NOT NULL ORDER BY iteration`],
      { encoding: 'utf8' });
    assert.equal(q.status, 0, q.stderr);
    assert.deepEqual(q.stdout.trim().split('\n').map(Number), [0, 5, 10, 11]);
    const rows = spawnSync('sqlite3', [d.db, `SELECT count(*) FROM iterations WHERE run = ${run}`], { encoding: 'utf8' });
    assert.equal(rows.stdout.trim(), '12');
  } finally {
    await stopDaemon(d);
    cleanup(dir);
  }
});

test('--trace-iterations: a line per grown iteration, on the clock its viewers read', async () => {
  const dir = tempDir();
  const trace = join(dir, 'iterations.trace');
  const d = await startDaemon({ dir, args: ['--trace-iterations', trace] });
  try {
    const c = await connect(d.url);
    const received = new Map(); // iteration -> CLOCK_MONOTONIC seconds at receipt
    c.ws.on('message', (data) => {
      const m = /^\{"type":"delta","run":\d+,"seq":\d+,"iteration":(\d+)/.exec(data.toString('latin1', 0, 80));
      if (m) received.set(Number(m[1]), Number(process.hrtime.bigint()) / 1e9);
    });
    c.send({ type: 'create', name: 'traced', start: false, scenario: scenario('stand.json', { iterations: 4 }) });
    const run = (await c.type('created')).run;
    c.send({ type: 'subscribe', run });
    await c.type('snapshot');
    c.send({ type: 'control', run, action: 'start' });
    await c.next((m) => m.type === 'status' && m.status === 'finished');
    const lines = readFileSync(trace, 'utf8').trim().split('\n').map((l) => l.split(' ').map(Number));
    assert.deepEqual(lines.map((l) => l.slice(0, 2)), [[run, 1], [run, 2], [run, 3], [run, 4]]);
    for (const [, it, ...times] of lines) {
      times.push(received.get(it));
      assert.deepEqual(times, [...times].sort((a, b) => a - b), `iteration ${it}: in order`);
    }
    c.close();
    await stopClean(d);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});
