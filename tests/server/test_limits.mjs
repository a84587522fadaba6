// The daemon's limits and its pool (docs/protocol.md, "Limits"), each shown
// exactly with a small setting against the real daemon and npm's ws client:
// refused with the right code and message, and nothing changed.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { join } from 'node:path';
import { SYLVA, ROOT, withDaemon, startDaemon, stopDaemon, connect, Client, scenario, tempDir,
  cleanup, rawCloseCode } from './harness.mjs';

async function create(c, name, sc, start = false) {
  c.send({ type: 'create', name, start, scenario: sc, id: name });
  return c.next((m) => m.ref === name);
}

test('--max-runs: the run past it is refused busy, forks count, and nothing is stored', () => withDaemon({ args: ['--max-runs', '2'] }, async (d) => {
  const c = await connect(d.url);
  const a = await create(c, 'a', scenario('shrub.json'));
  assert.equal(a.type, 'created');
  const f = { type: 'fork', run: a.run, iteration: 0, name: 'a-fork', id: 'f' };
  c.send(f);
  assert.equal((await c.next((m) => m.ref === 'f')).type, 'created');
  const e = await create(c, 'c', scenario('shrub.json'));
  assert.equal(e.type, 'error');
  assert.equal(e.code, 'busy');
  assert.match(e.message, /the daemon holds 2 runs, its limit \(--max-runs\)/);
  c.send({ ...f, name: 'a-fork2', id: 'f2' });
  assert.equal((await c.next((m) => m.ref === 'f2')).code, 'busy');
  c.send({ type: 'list', id: 'l' });
  assert.deepEqual((await c.next((m) => m.ref === 'l')).runs.map((r) => r.name), ['a', 'a-fork']);
  c.close();
}));

test('--max-stems and --max-obstacles: a create or an edit past them is too_large', () => withDaemon({ args: ['--max-stems', '3', '--max-obstacles', '2'] }, async (d) => {
  const c = await connect(d.url);
  const stand = scenario('stand.json'); // five trees
  const e = await create(c, 's', stand);
  assert.equal(e.code, 'too_large');
  assert.match(e.message, /^\/scenario\/plants: 5 stems; at most 3 in one world \(--max-stems\)/);
  const wall = scenario('wall.json');
  const w = await create(c, 'w', wall);
  assert.equal(w.type, 'created');
  const tree = (id, x) => ({ id, species: Object.keys(wall.species)[0], roots: [[x, -1.5, 0]] });
  c.send({ type: 'edit', run: w.run, id: 'e1', add_plants: [tree('n1', -1.5), tree('n2', -0.5), tree('n3', 0.5)] });
  const e1 = await c.next((m) => m.ref === 'e1');
  assert.equal(e1.code, 'too_large');
  assert.match(e1.message, /^\/add_plants: the world would have 4 stems; at most 3 \(--max-stems\)/);
  const box = (id, x) => ({ id, kind: 'box', min: [x, 2, 0], max: [x + 0.2, 2.2, 1] });
  c.send({ type: 'edit', run: w.run, id: 'e2', add_obstacles: [box('b1', -2), box('b2', -1)] });
  const e2 = await c.next((m) => m.ref === 'e2');
  assert.equal(e2.code, 'too_large');
  assert.match(e2.message, /^\/add_obstacles: the world would have 3 obstacles; at most 2 \(--max-obstacles\)/);
  // one more of each fits
  c.send({ type: 'edit', run: w.run, id: 'e3', add_obstacles: [box('b1', -2)], add_plants: [tree('n1', -1.5)] });
  assert.equal((await c.next((m) => m.ref === 'e3')).type, 'status');
  c.close();
}));

test('--memory-budget: a world whose estimate does not fit is refused busy', () => withDaemon({ args: ['--memory-budget', '40'] }, async (d) => {
  const c = await connect(d.url);
  const one = await create(c, 'one', scenario('wall.json')); // one tree: 17 MiB by estimate
  assert.equal(one.type, 'created');
  const two = await create(c, 'two', scenario('wall.json'));
  assert.equal(two.type, 'created');
  const three = await create(c, 'three', scenario('wall.json'));
  assert.equal(three.code, 'busy');
  assert.match(three.message, /the run would need about 17 MiB; 34 of the 40 MiB budget are taken \(--memory-budget\)/);
  c.close();
}));

test('--max-jobs: a get past it is busy, an export 503; the one running is answered', () => withDaemon({ args: ['--max-jobs', '1'] }, async (d) => {
  const c = await connect(d.url);
  const r = await create(c, 'stand', scenario('stand.json', { iterations: 12 }), true);
  c.send({ type: 'subscribe', run: r.run });
  await c.next((m) => m.type === 'status' && m.status === 'finished', 120000);
  // a history snapshot regrown from the snapshot of 10; a second at once is refused
  c.send({ type: 'get', run: r.run, iteration: 11, id: 'g1' });
  c.send({ type: 'get', run: r.run, iteration: 11, id: 'g2' });
  const replies = [await c.next((m) => m.ref === 'g1' || m.ref === 'g2'),
    await c.next((m) => m.ref === 'g1' || m.ref === 'g2')];
  const byRef = Object.fromEntries(replies.map((m) => [m.ref, m]));
  assert.equal(byRef.g1.type, 'snapshot');
  assert.equal(byRef.g2.code, 'busy');
  assert.match(byRef.g2.message, /--max-jobs/);
  const both = await Promise.all([fetch(`${d.http}/api/runs/stand/export?format=obj&iteration=11`),
    fetch(`${d.http}/api/runs/stand/export?format=obj&iteration=11`)]);
  const codes = both.map((x) => x.status).sort();
  assert.deepEqual(codes, [200, 503]);
  for (const x of both) await x.arrayBuffer();
  c.close();
}));

test('--max-clients: the upgrade past it gets 503; a place frees when a client leaves', () => withDaemon({ args: ['--max-clients', '3'] }, async (d) => {
  const cs = await Promise.all([0, 1, 2].map(() => connect(d.url)));
  const extra = new Client(d.url);
  await assert.rejects(extra.opened(), /HTTP 503/);
  cs[0].close();
  await new Promise((r) => setTimeout(r, 300));
  const again = await connect(d.url);
  again.close();
  for (const c of cs.slice(1)) c.close();
}));

// A raw WebSocket that sends the first fragment of a text message of `size`
// bytes (masked), and never its end; resolves with the close code it gets.
function unfinished(port, size) {
  return rawCloseCode(port, (s) => {
    const head = Buffer.alloc(14);
    head[0] = 0x01; // text, not final
    head[1] = 0x80 | 127;
    head.writeBigUInt64BE(BigInt(size), 2);
    head.writeUInt32BE(0x01020304, 10);
    s.write(head);
    s.write(Buffer.alloc(size, 0x21)); // any text: masked, it unmasks to other bytes
  });
}

test('--max-input: unfinished messages past the budget are closed with 1009; the rest in 10 s with 1008', () => withDaemon({ args: ['--max-input', '300000'] }, async (d) => {
  const t0 = Date.now();
  const codes = await Promise.all([0, 1, 2, 3].map(() => unfinished(d.port, 100000)));
  const sorted = codes.sort();
  assert.deepEqual(sorted, [1008, 1008, 1008, 1009].sort(), `close codes ${codes}`);
  assert.ok(Date.now() - t0 < 15000, 'closed within the time limit');
  const h = await fetch(`${d.http}/healthz`).then((r) => r.json());
  assert.equal(h.clients, 0);
}));

test('runs load after the daemon listens: /healthz and list answer at once, the runs marked loading', async () => {
  const dir = tempDir();
  try {
    const db = join(dir, 'runs.db');
    for (let i = 0; i < 6; i++) {
      const r = spawnSync(SYLVA, ['run', join(ROOT, 'scenarios', 'stand.json'), '--db', db, '--name', `s${i}`,
        '--iterations', '12', '--snapshot-every', '100', '--quiet-progress'], { encoding: 'utf8' });
      assert.equal(r.status, 0, r.stderr);
    }
    const d = await startDaemon({ dir, args: ['--workers', '1'] });
    try {
      const t0 = Date.now();
      const h = await fetch(`${d.http}/healthz`).then((r) => r.json());
      assert.ok(Date.now() - t0 < 1000);
      assert.equal(h.runs, 6);
      assert.ok(h.loading >= 1, `loading ${h.loading}`);
      const c = await connect(d.url);
      c.send({ type: 'list' });
      const first = (await c.type('runs')).runs;
      assert.ok(first.some((r) => r.loading === true));
      // a subscriber of a loading run gets its snapshot once it is loaded
      c.send({ type: 'subscribe', run: first[5].run, id: 's' });
      const snap = await c.next((m) => m.type === 'snapshot', 120000);
      assert.equal(snap.iteration, 12);
      assert.equal(snap.ref, 's');
      for (let w = 0; w < 600; w++) {
        const hh = await fetch(`${d.http}/healthz`).then((r) => r.json());
        if (hh.loading === 0) break;
        await new Promise((r) => setTimeout(r, 100));
      }
      c.send({ type: 'list' });
      assert.ok((await c.type('runs')).runs.every((r) => !r.loading && r.iteration === 12));
      c.close();
    } finally {
      const exit = await stopDaemon(d);
      assert.equal(exit.code, 0);
    }
  } finally {
    cleanup(dir);
  }
});

test('the pool: two growing runs take turns on one worker; SIGTERM drops what has not started and exits at once', async () => {
  const d = await startDaemon({ args: ['--workers', '1'] });
  try {
    const c = await connect(d.url);
    const a = await create(c, 'a', scenario('stand.json', { iterations: 40 }), true);
    const b = await create(c, 'b', scenario('stand.json', { iterations: 40 }), true);
    c.send({ type: 'subscribe', run: a.run });
    c.send({ type: 'subscribe', run: b.run });
    const seen = [];
    while (seen.length < 12) {
      const m = await c.next((x) => x.type === 'delta', 60000);
      seen.push(m.run);
    }
    // in turn: neither run gets more than one delta ahead of the other
    let lead = 0;
    for (const r of seen) {
      lead += r === a.run ? 1 : -1;
      assert.ok(Math.abs(lead) <= 2, `deltas ${seen.join(',')}`);
    }
    c.close();
  } finally {
    const t0 = Date.now();
    const exit = await stopDaemon(d);
    assert.equal(exit.code, 0);
    assert.ok(Date.now() - t0 < 5000, `stopped in ${Date.now() - t0} ms`);
    cleanup(d.dir);
  }
});
