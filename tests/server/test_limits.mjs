// The daemon's limits and its pool (docs/protocol.md, "Limits"), each shown
// exactly with a small setting against the real daemon and npm's ws client:
// refused with the right code and message, and nothing changed.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { readdirSync, readFileSync } from 'node:fs';
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

test('--memory-budget: a world whose estimate does not fit is refused busy; idle runs go back to the store', () => withDaemon({ args: ['--memory-budget', '40'] }, async (d) => {
  const c = await connect(d.url);
  // one tree: 17 MiB by estimate; runs with a subscriber stay in memory
  const one = await create(c, 'one', scenario('wall.json'));
  assert.equal(one.type, 'created');
  c.send({ type: 'subscribe', run: one.run, id: 's1' });
  assert.equal((await c.next((m) => m.ref === 's1')).type, 'snapshot');
  const two = await create(c, 'two', scenario('wall.json'));
  assert.equal(two.type, 'created');
  c.send({ type: 'subscribe', run: two.run, id: 's2' });
  const snap2 = await c.next((m) => m.ref === 's2');
  const three = await create(c, 'three', scenario('wall.json'));
  assert.equal(three.code, 'busy');
  assert.match(three.message, /the run would need about 17 MiB; 34 of the 40 MiB budget are taken \(--memory-budget\)/);
  // without a subscriber, two is idle: the next create unloads it
  c.send({ type: 'unsubscribe', run: two.run });
  const again = await create(c, 'three', scenario('wall.json'));
  assert.equal(again.type, 'created');
  // two is still listed, and loads again for a subscriber once three is idle
  c.send({ type: 'list', id: 'l' });
  assert.deepEqual((await c.next((m) => m.ref === 'l')).runs.map((r) => [r.name, r.stems]),
    [['one', 1], ['two', 1], ['three', 1]]);
  c.send({ type: 'subscribe', run: two.run, id: 's2b' });
  const back = await c.next((m) => m.ref === 's2b');
  assert.equal(back.type, 'snapshot');
  assert.deepEqual(back.nodes, snap2.nodes, 'the reloaded world is the one unloaded');
  // with one and two held by subscribers, three cannot load
  c.send({ type: 'subscribe', run: again.run, id: 's3' });
  const refused = await c.next((m) => m.ref === 's3');
  assert.equal(refused.code, 'busy');
  assert.match(refused.message, /^\/run: loading the run would need about 17 MiB; 34 of the 40 MiB budget are taken by runs in use \(--memory-budget\)$/);
  c.send({ type: 'light', run: again.run, z: 1, id: 'l3' });
  assert.equal((await c.next((m) => m.ref === 'l3')).code, 'busy');
  c.close();
}));

test('a large message is parsed off the loop: the client\'s next messages are answered after it, in order', () => withDaemon({}, async (d) => {
  const c = await connect(d.url);
  const stand = scenario('stand.json');
  // 70 plants of 1,000 stems (755 KB): parsed on a libuv thread, refused by --max-stems
  const plants = Array.from({ length: 70 }, (_, p) => ({ id: `b${p}`, species: 'broadleaf',
    roots: Array.from({ length: 1000 }, (_, k) => [p, k, 0]) }));
  const big = JSON.stringify({ type: 'create', id: 'big', name: 'big', scenario: { ...stand, plants } });
  assert.ok(big.length > 65536);
  const ok = JSON.stringify({ type: 'create', id: 'ok', name: 'ok', scenario: { ...stand, plants: [{ ...plants[0], roots: plants[0].roots.slice(0, 3) }] } });
  for (let i = 0; i < 3; i++) {
    c.send(big.replace('"id":"big"', `"id":"big${i}"`));
    c.send({ type: 'list', id: `l${i}` });
  }
  c.send(ok + ' '.repeat(70000)); // large too, and valid
  const refs = [];
  for (let i = 0; i < 7; i++) refs.push(await c.next((m) => m.ref !== undefined));
  assert.deepEqual(refs.map((m) => m.ref), ['big0', 'l0', 'big1', 'l1', 'big2', 'l2', 'ok']);
  for (const m of refs.filter((x) => x.ref.startsWith('big'))) {
    assert.equal(m.code, 'too_large');
    assert.match(m.message, /^\/scenario\/plants: 70000 stems; at most 2000 in one world \(--max-stems\)$/);
  }
  assert.equal(refs[6].type, 'created');
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
  // a refused client is read no more and dropped 250 ms after its close frame
  // (docs/protocol.md, "Limits"), not when it answers
  const t1 = Date.now();
  let h;
  do {
    await new Promise((r) => setTimeout(r, 50));
    h = await fetch(`${d.http}/healthz`).then((r) => r.json());
  } while (h.clients !== 0 && Date.now() - t1 < 1000);
  assert.equal(h.clients, 0, 'the refused clients are gone within a second');
}));

test('a client refused for what it sends is read no more and dropped soon after its close frame, without its answer', () => withDaemon({ args: ['--max-message', '4096'] }, async (d) => {
  // a frame announcing 1 MiB, of which 64 KiB come: past --max-message at once;
  // the client then neither answers the close frame nor closes (docs/protocol.md,
  // "Limits": dropped 250 ms after its close frame; lws alone waits 5 s for the
  // answer)
  const r = await rawCloseCode(d.port, (s) => {
    const head = Buffer.alloc(14);
    head[0] = 0x01;
    head[1] = 0x80 | 127;
    head.writeBigUInt64BE(BigInt(1 << 20), 2);
    head.writeUInt32BE(0x01020304, 10);
    s.write(head);
    s.write(Buffer.alloc(65536, 0x21));
  }, 15000, { untilDropped: true });
  assert.equal(r.code, 1009);
  assert.ok(r.droppedMs !== null && r.droppedMs < 2000, `dropped ${r.droppedMs} ms after its close frame`);
  const h = await fetch(`${d.http}/healthz`).then((x) => x.json());
  assert.equal(h.clients, 0);
}));

// Six stored stands (81 MiB each by estimate) against a budget of 200 MiB.
function storedStands(db, n) {
  for (let i = 0; i < n; i++) {
    const r = spawnSync(SYLVA, ['run', join(ROOT, 'scenarios', 'stand.json'), '--db', db, '--name', `s${i}`,
      '--iterations', '12', '--snapshot-every', '100', '--quiet-progress'], { encoding: 'utf8' });
    assert.equal(r.status, 0, r.stderr);
  }
}

function sql(db, statement) {
  const r = spawnSync('python3', ['-c', 'import sqlite3,sys; c=sqlite3.connect(sys.argv[1]); c.execute(sys.argv[2]); c.commit()',
    db, statement], { encoding: 'utf8' });
  assert.equal(r.status, 0, r.stderr);
}

async function listed(c) {
  c.send({ type: 'list', id: 'list' });
  return (await c.next((m) => m.ref === 'list')).runs;
}

async function untilFinished(c, names) {
  for (let w = 0; w < 1200; w++) {
    const runs = await listed(c);
    if (runs.filter((r) => names.includes(r.name)).every((r) => r.status === 'finished')) return runs;
    await new Promise((r) => setTimeout(r, 100));
  }
  throw new Error(`${names} did not finish`);
}

test('runs load after the daemon listens, growing runs as far as the budget holds, the others on demand', async () => {
  const dir = tempDir();
  try {
    const db = join(dir, 'runs.db');
    storedStands(db, 8);
    // as a daemon stopped mid-run leaves them: s0 to s5 were growing towards 14
    sql(db, "UPDATE runs SET status = 'running', iterations = 14 WHERE name IN ('s0', 's1', 's2', 's3', 's4', 's5')");
    let d = await startDaemon({ dir, args: ['--workers', '1', '--memory-budget', '500'] });
    try {
      const t0 = Date.now();
      const h = await fetch(`${d.http}/healthz`).then((r) => r.json());
      assert.ok(Date.now() - t0 < 1000);
      assert.equal(h.runs, 8);
      assert.ok(h.loading >= 1, `loading ${h.loading}`);
      const c = await connect(d.url);
      const first = await listed(c);
      assert.deepEqual(first.map((r) => [r.name, r.stems]), [0, 1, 2, 3, 4, 5, 6, 7].map((i) => [`s${i}`, 5]),
        'stems from the store');
      assert.ok(first.some((r) => r.loading === true));
      assert.ok(first.slice(6).every((r) => !r.loading), 'runs that do not grow stay in the store');
      // a subscriber of a loading run gets its snapshot once it is loaded
      c.send({ type: 'subscribe', run: first[5].run, id: 's' });
      const snap = await c.next((m) => m.type === 'snapshot', 120000);
      assert.equal(snap.ref, 's');
      const later = await untilFinished(c, ['s0', 's1', 's2', 's3', 's4', 's5']);
      assert.deepEqual(later.map((r) => r.iteration), [14, 14, 14, 14, 14, 14, 12, 12]);
      c.close();
    } finally {
      assert.equal((await stopDaemon(d)).code, 0);
    }

    // nothing grows now: nothing loads until a client needs it, within 200 MiB
    d = await startDaemon({ dir, args: ['--memory-budget', '200'] });
    try {
      const h = await fetch(`${d.http}/healthz`).then((r) => r.json());
      assert.equal(h.loading, 0);
      const c = await connect(d.url);
      const runs = await listed(c);
      const ask = async (i, id) => {
        c.send({ type: 'subscribe', run: runs[i].run, id });
        return c.next((m) => m.ref === id, 120000);
      };
      const s7 = await ask(7, 'a');
      assert.equal(s7.type, 'snapshot');
      assert.equal(s7.iteration, 12);
      assert.equal((await ask(6, 'b')).type, 'snapshot');
      // s7 and s6 hold 162 of 200 MiB: s5 cannot load until one is let go
      const no = await ask(5, 'c');
      assert.equal(no.code, 'busy');
      assert.match(no.message, /^\/run: loading the run would need about 81 MiB; 162 of the 200 MiB budget are taken by runs in use \(--memory-budget\)$/);
      c.send({ type: 'unsubscribe', run: runs[7].run });
      const s5 = await ask(5, 'd');
      assert.equal(s5.type, 'snapshot');
      assert.equal(s5.iteration, 14);
      c.close();
    } finally {
      assert.equal((await stopDaemon(d)).code, 0);
    }

    // two growing runs and room for one: the second waits for the first to end
    sql(db, "UPDATE runs SET status = 'running', iterations = 14 WHERE name IN ('s6', 's7')");
    d = await startDaemon({ dir, args: ['--memory-budget', '100'] });
    try {
      const c = await connect(d.url);
      const runs = await untilFinished(c, ['s6', 's7']);
      assert.deepEqual(runs.slice(6).map((r) => r.iteration), [14, 14]);
      assert.match(d.stderr(), /\[run s7\] waits for memory to grow: loading the run would need about 81 MiB; 81 of the 100 MiB/);
      c.close();
    } finally {
      assert.equal((await stopDaemon(d)).code, 0);
    }
  } finally {
    cleanup(dir);
  }
});

test('the pool: two growing runs take turns on one worker; SIGTERM drops what has not started and exits at once', async () => {
  const d = await startDaemon({ args: ['--workers', '1'] });
  try {
    const c = await connect(d.url);
    // created paused and subscribed before they start: a stand grows its 23
    // iterations in well under a second, so a run started at its creation could
    // finish before the subscription (seen once in the sanitizer build, no delta)
    const a = await create(c, 'a', scenario('stand.json', { iterations: 40 }));
    const b = await create(c, 'b', scenario('stand.json', { iterations: 40 }));
    c.send({ type: 'subscribe', run: a.run, id: 'sa' });
    c.send({ type: 'subscribe', run: b.run, id: 'sb' });
    await c.next((m) => m.type === 'snapshot' && m.run === a.run);
    await c.next((m) => m.type === 'snapshot' && m.run === b.run);
    c.send({ type: 'control', run: a.run, action: 'start' });
    c.send({ type: 'control', run: b.run, action: 'start' });
    const seen = [];
    while (seen.length < 40) {
      const m = await c.next((x) => x.type === 'delta', 60000);
      seen.push(m.run);
    }
    // in turn: a run takes at most RUN_AHEAD (16) iterations in a row, so neither
    // gets more than sixteen deltas ahead of the other, and both grow
    let lead = 0;
    for (const r of seen) {
      lead += r === a.run ? 1 : -1;
      assert.ok(Math.abs(lead) <= 16, `deltas ${seen.join(',')}`);
    }
    assert.ok(seen.includes(a.run) && seen.includes(b.run), `deltas ${seen.join(',')}`);
    c.close();
  } finally {
    const t0 = Date.now();
    const exit = await stopDaemon(d);
    assert.equal(exit.code, 0);
    assert.ok(Date.now() - t0 < 5000, `stopped in ${Date.now() - t0} ms`);
    cleanup(d.dir);
  }
});

test('--max-backlog: a get larger than it reaches a client that reads; a client that does not read is closed with 1008 once what waits behind passes it', () => withDaemon({ args: ['--max-backlog', '100000', '--max-jobs', '64'] }, async (d) => {
  const c = await connect(d.url);
  const a = await create(c, 'a', scenario('stand.json', { iterations: 20 }), true);
  assert.equal(a.type, 'created');
  c.send({ type: 'subscribe', run: a.run, detail: 'stems', id: 's' });
  await c.next((m) => m.type === 'status' && m.run === a.run && m.status === 'finished', 60000);
  // the stand's snapshot (about 400 KB) is larger than the backlog: it goes out whole
  c.send({ type: 'get', run: a.run, iteration: 20, id: 'g' });
  const g = await c.next((m) => m.ref === 'g', 60000);
  assert.equal(g.type, 'snapshot');
  assert.ok(JSON.stringify(g).length > 100000, 'the snapshot is larger than the backlog');
  assert.equal(c.closed, null);
  // a client that stops reading and asks for 40 of them: the kernel's buffers fill, the
  // replies wait behind the one going out, and past 100,000 bytes it is closed
  const slow = await connect(d.url);
  slow.ws._socket.pause();
  for (let i = 0; i < 40; i++) slow.send({ type: 'get', run: a.run, iteration: 20, id: `g${i}` });
  let h;
  const t0 = Date.now();
  do {
    await new Promise((r) => setTimeout(r, 100));
    h = await fetch(`${d.http}/healthz`).then((r) => r.json());
  } while (h.clients !== 1 && Date.now() - t0 < 30000);
  assert.equal(h.clients, 1, 'the slow client was closed, the reader kept');
  slow.ws._socket.resume();
  const closed = await new Promise((ok) => {
    if (slow.closed) return ok(slow.closed);
    slow.ws.once('close', (code) => ok({ code }));
  });
  assert.ok([1008, 1006].includes(closed.code), `closed with ${closed.code}`);
  c.close();
}));

// The niceness of each of a process's threads, by thread id (/proc/PID/task/TID/stat:
// the 19th field, the 17th after the command's closing parenthesis).
function threadNice(pid) {
  const out = new Map();
  for (const tid of readdirSync(`/proc/${pid}/task`)) {
    try {
      const stat = readFileSync(`/proc/${pid}/task/${tid}/stat`, 'utf8');
      out.set(Number(tid), Number(stat.slice(stat.lastIndexOf(')') + 2).split(' ')[16]));
    } catch { /* the thread ended meanwhile */ }
  }
  return out;
}

test('--work-nice: bad values exit 2; the workers, a create job and the world\'s threads run N steps below the loop', async () => {
  for (const bad of ['20', 'x', '-1']) {
    const r = spawnSync(SYLVA, ['serve', '--work-nice', bad, '--db', '/nonexistent/x.db'], { encoding: 'utf8' });
    assert.equal(r.status, 2, r.stderr);
    assert.match(r.stderr, new RegExp(`--work-nice: expected an integer from 0 to 19, got '${bad}'`));
  }
  await withDaemon({ args: ['--work-nice', '7', '--workers', '1', '--threads', '2'] }, async (d) => {
    const pid = d.proc.pid;
    const loop = threadNice(pid).get(pid);
    const below = Math.min(19, loop + 7);
    const niced = () => [...threadNice(pid).values()].filter((n) => n === below).length;
    if (below !== loop) assert.equal(niced(), 2, 'before any run: the one worker and the worlds\' second thread');
    const c = await connect(d.url);
    const a = await create(c, 'a', scenario('stand.json', { iterations: 200 }), true);
    assert.equal(a.type, 'created');
    c.send({ type: 'subscribe', run: a.run, id: 's' });
    await c.next((m) => m.type === 'delta' && m.run === a.run, 60000);
    const now = threadNice(pid);
    assert.equal(now.get(pid), loop, 'the loop keeps its niceness');
    // the worker, the libuv thread that built the world, and the worlds' second thread
    if (below !== loop) assert.ok(niced() >= 3, `niceness by thread: ${JSON.stringify([...now])}`);
    c.close();
  });
});

test('every world shares the daemon\'s --threads: three growing runs keep the threads of one', async () => {
  await withDaemon({ args: ['--threads', '4'] }, async (d) => {
    const threads = () => readdirSync(`/proc/${d.proc.pid}/task`).length;
    const c = await connect(d.url);
    const grow = async (name) => {
      const r = await create(c, name, scenario('stand.json', { iterations: 200 }), true);
      assert.equal(r.type, 'created');
      c.send({ type: 'subscribe', run: r.run, id: `s-${name}` });
      await c.next((m) => m.type === 'delta' && m.run === r.run, 60000);
    };
    await grow('a');
    const one = threads(); // the loop, the workers, libuv's threads, the worlds' three
    await grow('b');
    await grow('c');
    // each world on threads of its own would add three a run: six more here
    assert.equal(threads(), one, 'the same threads for three runs as for one');
    c.close();
  });
});

// The daemon's gauges of client input (/metrics): {input, reading, waiting}.
async function inputGauges(d) {
  const text = await fetch(`${d.http}/metrics`).then((r) => r.text());
  const g = (name) => Number(text.match(new RegExp(`^${name} (\\d+)$`, 'm'))[1]);
  return { input: g('sylva_input_bytes'), reading: g('sylva_clients_reading'), waiting: g('sylva_clients_waiting') };
}

async function until(what, ok, ms = 5000) {
  const end = Date.now() + ms;
  for (;;) {
    const v = await what();
    if (ok(v)) return v;
    if (Date.now() > end) throw new Error(`still ${JSON.stringify(v)}`);
    await new Promise((r) => setTimeout(r, 50));
  }
}

test('long messages are read 64 at a time: the next waits unread, in turn, and is answered once a place frees', () => withDaemon({}, async (d) => {
  // 64 clients each start a message (a fragment that is not the last) and never end it
  const holders = [];
  for (let i = 0; i < 64; i++) {
    const h = await connect(d.url);
    h.ws.send(`{"type":"list","id":"h${i}","pad":"${'x'.repeat(1000)}`, { fin: false });
    holders.push(h);
  }
  await until(() => inputGauges(d), (g) => g.reading === 64);
  // two more, each a whole message of 40 kB: longer than one read (4 KiB), so they
  // wait in turn; shorter than DAEMON_PARSE_INLINE, so each is answered in the turn
  // it is complete (a larger one is parsed off the loop, its answer in any order)
  const late = [await connect(d.url), await connect(d.url)];
  // (the second sent once the first waits: the line is in the order the daemon reads)
  let g;
  for (const [i, c] of late.entries()) {
    c.send({ type: 'list', id: `late${i}`, pad: 'y'.repeat(40000) });
    g = await until(() => inputGauges(d), (x) => x.waiting === i + 1);
  }
  assert.equal(g.reading, 64);
  await new Promise((r) => setTimeout(r, 300));
  assert.deepEqual(late.map((c) => c.messages.filter((m) => m.ref).length), [0, 0], 'no answer while they wait');
  // one holder goes: its place goes to the first in line, read whole and answered
  // (for what it holds: an unknown key); its place then goes to the second
  const order = [];
  const answered = late.map((c, i) => c.next((m) => m.ref === `late${i}`, 5000).then((m) => { order.push(i); return m; }));
  holders[0].ws.terminate();
  for (const m of await Promise.all(answered)) {
    assert.equal(m.code, 'bad_request', JSON.stringify(m).slice(0, 300));
    assert.match(m.message, /^\/pad: unknown key/);
  }
  assert.deepEqual(order, [0, 1]);
  g = await until(() => inputGauges(d), (x) => x.waiting === 0 && x.reading === 63);
  // the other holders' unfinished messages are still held: ~1 kB each
  assert.ok(g.input > 63 * 1000 && g.input < 63 * 1100, `input ${g.input} bytes`);
  for (const h of holders) h.ws.terminate();
  for (const c of late) c.close();
  await until(() => inputGauges(d), (x) => x.input === 0 && x.reading === 0);
}));
