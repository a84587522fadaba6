// The daemon's HTTP routes for the viewer: /api/runs/NAME/export (the bytes of
// `sylva export`), /api/runs/NAME/shade (the tree shade of `sylva shade`),
// /api/scenarios/NAME (a ready scenario file), and the species a snapshot offers. A real daemon on 127.0.0.1; the CLI reads the same store while
// it runs (SQLite WAL allows a concurrent reader).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { mkdtempSync, readFileSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { spawnSync } from 'node:child_process';
import { withDaemon, connect, scenario, exportBytes, rawGet, askOnly, cleanup, ROOT,
  SLOW, SYLVA } from './harness.mjs';

// Creates run `name` of a scenario file, grows it to the end and returns its id.
async function grown(d, file, name, iterations) {
  const c = await connect(d.url);
  // started once subscribed: a run that finished before the subscription would send
  // no status to it (docs/protocol.md, "subscribe")
  c.send({ type: 'create', name, start: false, scenario: scenario(file, { iterations }) });
  const { run } = await c.type('created');
  c.send({ type: 'subscribe', run });
  await c.type('snapshot');
  c.send({ type: 'control', run, action: 'start' });
  await c.next((m) => m.type === 'status' && m.status === 'finished', 300000);
  c.close();
  return run;
}

async function get(d, path) {
  const r = await fetch(`${d.http}${path}`);
  return { status: r.status, headers: r.headers, body: Buffer.from(await r.arrayBuffer()) };
}

// Asks each [path under /api/runs/, status, message] and checks the reply: the
// status and one text line, the message itself or matching a RegExp.
async function expectErrors(d, cases) {
  for (const [path, status, message] of cases) {
    const r = await get(d, `/api/runs/${path}`);
    assert.equal(r.status, status, path);
    assert.match(r.headers.get('content-type'), /^text\/plain/, path);
    if (message instanceof RegExp) assert.match(r.body.toString(), message, path);
    else assert.equal(r.body.toString(), `${message}\n`, path);
  }
}

const TYPES = { skeleton: /^application\/json/, obj: /^text\/plain/, ply: /^application\/octet-stream/,
  csv: /^text\/csv/, glb: /^model\/gltf-binary$/ };
const EXTENSIONS = { skeleton: 'json', obj: 'obj', ply: 'ply', csv: 'csv', glb: 'glb' };

test('export: every format at a middle and the last iteration, byte for byte as the CLI', () => withDaemon({}, async (d) => {
  await grown(d, 'wall.json', 'wall', 12);
  // 7 lies between the snapshots of 5 and 10: regrown, as the CLI does
  for (const iteration of [7, 12]) {
    for (const format of ['skeleton', 'obj', 'ply', 'csv', 'glb']) {
      const r = await get(d, `/api/runs/wall/export?format=${format}&iteration=${iteration}`);
      assert.equal(r.status, 200, `${format} ${iteration}: ${r.body}`);
      assert.match(r.headers.get('content-type'), TYPES[format]);
      assert.equal(r.headers.get('content-disposition'),
        `attachment; filename="wall-i${iteration}.${EXTENSIONS[format]}"`);
      assert.equal(Number(r.headers.get('content-length')), r.body.length);
      assert.ok(r.body.equals(exportBytes(d.db, 'wall', format, iteration)), `${format} ${iteration}`);
    }
    for (const format of ['obj', 'ply', 'glb']) {
      const r = await get(d, `/api/runs/wall/export?iteration=${iteration}&obstacles=1&format=${format}`);
      assert.equal(r.status, 200);
      const cli = exportBytes(d.db, 'wall', format, iteration, ['--obstacles']);
      assert.ok(r.body.equals(cli), `${format} ${iteration} with obstacles`);
      assert.ok(!cli.equals(exportBytes(d.db, 'wall', format, iteration)), 'the wall is in it');
    }
  }
  // no iteration: the run's current one; obstacles=0 is the default
  const r = await get(d, '/api/runs/wall/export?format=ply&obstacles=0');
  assert.equal(r.status, 200);
  assert.equal(r.headers.get('content-disposition'), 'attachment; filename="wall-i12.ply"');
  assert.ok(r.body.equals(exportBytes(d.db, 'wall', 'ply')));
  // stats.csv is the CSV of the current iteration, shown rather than downloaded
  const csv = await get(d, '/api/runs/wall/stats.csv');
  assert.equal(csv.status, 200);
  assert.match(csv.headers.get('content-type'), /^text\/csv/);
  assert.equal(csv.headers.get('content-disposition'), null);
  assert.ok(csv.body.equals(exportBytes(d.db, 'wall', 'csv')));
}));

test('export: bad parameters get 400 and unknown runs 404, each with a line naming the problem', () => withDaemon({}, async (d) => {
  await grown(d, 'wall.json', 'wall', 12);
  const cases = [
    ['wall/export?format=obj&iteration=13', 400, 'iteration: run "wall" has iterations 0 to 12'],
    ['wall/export?format=obj&iteration=99999999999', 400,
      'iteration: expected an integer from 0 to 12, got "99999999999"'],
    ['wall/export?format=obj&iteration=abc', 400, 'iteration: expected an integer from 0 to 12, got "abc"'],
    ['wall/export?format=obj&iteration=-1', 400, 'iteration: expected an integer from 0 to 12, got "-1"'],
    ['wall/export?format=obj&iteration=2.5', 400, 'iteration: expected an integer from 0 to 12, got "2.5"'],
    ['wall/export?format=obj&iteration=', 400, 'iteration: expected an integer from 0 to 12, got ""'],
    ['wall/export?format=stl', 400, 'format: "stl" is not skeleton, obj, ply, csv or glb'],
    ['wall/export', 400, 'format: required (skeleton, obj, ply, csv or glb)'],
    ['wall/export?iteration=3', 400, 'format: required (skeleton, obj, ply, csv or glb)'],
    ['wall/export?format=obj&format=ply', 400, 'format: given more than once'],
    ['wall/export?format=obj&obstacles=yes', 400, 'obstacles: expected 1 or 0, got "yes"'],
    ['wall/export?format=obj&sides=5', 400,
      'sides: unknown parameter (known: format, iteration, obstacles)'],
    ['nope/export?format=obj', 404, 'no run "nope"'],
    ['nope/stats.csv', 404, 'no run "nope"'],
  ];
  await expectErrors(d, cases);
  // empty parts of a query are no parameters
  const r = await get(d, '/api/runs/wall/export?&format=csv&&iteration=2&');
  assert.equal(r.status, 200);
  assert.ok(r.body.equals(exportBytes(d.db, 'wall', 'csv', 2)));
  assert.equal((await get(d, '/api/runs/wall/exports?format=obj')).status, 404);
}));

test('export: any run name is found, and its file name is sanitized', () => withDaemon({}, async (d) => {
  const name = 'tree "A"/1 %41 ä';
  const c = await connect(d.url);
  c.send({ type: 'create', name, start: false, scenario: scenario('shrub.json') });
  await c.type('created');
  c.close();
  const r = await get(d, `/api/runs/${encodeURIComponent(name)}/export?format=skeleton`);
  assert.equal(r.status, 200, r.body.toString());
  assert.equal(r.headers.get('content-disposition'),
    'attachment; filename="tree__A__1__41___-i0.json"');
  assert.ok(r.body.equals(exportBytes(d.db, name, 'skeleton', 0)));
}));

test('export: clients that leave right after asking do not hurt the daemon', () => withDaemon({ args: ['--max-jobs', '30'] }, async (d) => {
  await grown(d, 'stand.json', 'stand', 15);
  // a regrown iteration (about 0.1 s each); libuv's threads take four at a time on
  // two cores, so most of these thirty are still queued (then cancelled) or being
  // written when their clients are long gone (the daemon looks every 0.5 s)
  for (let i = 0; i < 30; i++) {
    await askOnly(d.port, `/api/runs/stand/export?format=${i % 2 ? 'ply' : 'obj'}&iteration=14`,
      { leave: true });
  }
  const h = await get(d, '/healthz');
  assert.equal(h.status, 200);
  // the connections were seen to close while their exports were written
  const deadline = Date.now() + 60000 * SLOW;
  while (!/export: the client left before it was written/.test(d.stderr()) && Date.now() < deadline)
    await new Promise((r) => setTimeout(r, 200));
  assert.match(d.stderr(), /\[run stand\] export: the client left before it was written/);
  // and it goes on serving exports
  const r = await get(d, '/api/runs/stand/export?format=obj&iteration=14');
  assert.equal(r.status, 200);
  assert.ok(r.body.equals(exportBytes(d.db, 'stand', 'obj', 14)));
  assert.doesNotMatch(d.stderr(), /export failed/);
}));

test('scenarios: /api/scenarios/NAME is the ready file byte for byte; other names are 404', async () => {
  const dir = mkdtempSync(join(tmpdir(), 'sylva-scenarios-'));
  const wall = readFileSync(join(ROOT, 'scenarios', 'wall.json'));
  writeFileSync(join(dir, 'wall.json'), wall);
  writeFileSync(join(dir, '.hidden.json'), wall);
  writeFileSync(join(dir, 'big.json'), Buffer.alloc((4 << 20) + 1, 0x20));
  writeFileSync(join(dir, `${'a'.repeat(201)}.json`), wall);
  writeFileSync(join(dir, `${'a'.repeat(200)}.json`), wall);
  writeFileSync(join(dir, 'b-copy.json'), wall);
  writeFileSync(join(dir, 'notes.json'), '{"not": "a scenario"}');
  try {
    await withDaemon({ args: ['--scenarios', dir] }, async (d) => {
      const r = await get(d, '/api/scenarios/wall');
      assert.equal(r.status, 200);
      assert.match(r.headers.get('content-type'), /^application\/json/);
      assert.ok(r.body.equals(wall));
      assert.equal((await get(d, `/api/scenarios/${'a'.repeat(200)}`)).status, 200);
      for (const name of ['missing', '.hidden', 'wall.json', 'big', 'a'.repeat(201), 'wa%20ll'])
        assert.equal((await get(d, `/api/scenarios/${name}`)).status, 404, name);
      assert.match(d.stderr(), /big\.json: larger than 4194304 bytes; not served/);
      // the `scenarios` message lists exactly what can be fetched, sorted by name
      const c = await connect(d.url);
      c.send({ type: 'scenarios', id: 's' });
      const listed = await c.type('scenarios');
      c.close();
      assert.equal(listed.ref, 's');
      const title = JSON.parse(wall.toString()).name;
      assert.deepEqual(listed.scenarios, [
        { name: 'a'.repeat(200), title }, { name: 'b-copy', title }, { name: 'wall', title }]);
      // paths that climb out, sent as they are
      for (const path of ['/api/scenarios/../scenarios/../../wall', '/api/scenarios/..%2fwall',
        '/api/scenarios/%2e%2e/wall', '/api/scenarios/%2e%2e%2f%2e%2e%2fREADME.md',
        '/api/scenarios/..', '/api/scenarios/']) {
        const reply = await rawGet(d.port, path);
        assert.match(reply.split('\r\n')[0], / 404 /, path);
        assert.doesNotMatch(reply, /sylva\.scenario/, path);
      }
    });
  } finally {
    cleanup(dir);
  }
});

test('snapshot: carries the labels of the run\'s species, in the world\'s order', () => withDaemon({}, async (d) => {
  const c = await connect(d.url);
  c.send({ type: 'create', name: 'sp', start: false, scenario: scenario('species.json') });
  const { run } = await c.type('created');
  c.send({ type: 'subscribe', run });
  const snap = await c.type('snapshot');
  assert.deepEqual(snap.species, ['broadleaf', 'shrub', 'cypress']);
  c.send({ type: 'get', run, iteration: 0, id: 'g' });
  const got = await c.next((m) => m.type === 'snapshot' && m.ref === 'g');
  assert.deepEqual(got.species, snap.species);
  // the skeleton export format is unchanged
  assert.equal(JSON.parse(exportBytes(d.db, 'sp', 'skeleton', 0)).species, undefined);
  c.close();
}));

// The CLI's cells of a stored iteration's day (`sylva shade ... -o X.csv`):
// [{x, y, z, surface, open, with}].
function shadeCells(d, name, iteration, date, from, to) {
  const out = join(d.dir, 'shade.csv');
  const r = spawnSync(SYLVA, ['shade', '--db', d.db, '--name', name, '--iteration', String(iteration),
    '--date', date, '--from', from, '--to', to, '-o', out]);
  if (r.status !== 0) throw new Error(`shade failed: ${r.stderr}`);
  return readFileSync(out, 'utf8').trim().split('\n').slice(1).map((l) => {
    const [x, y, z, surface, open, withTrees] = l.split(',');
    return { x: Number(x), y: Number(y), z: Number(z), surface, open: Number(open), with: Number(withTrees) };
  });
}

// Whether the route's hours (two decimals) are the CLI's open - with (each of four
// decimals), none below 0.
const near = (got, cells) => got.length === cells.length &&
  got.every((v, i) => Math.abs(v - Math.max(0, cells[i].open - cells[i].with)) <= 0.0051);

test('shade: a stored iteration\'s tree shade on the ground and the facades, as the CLI computes it', () => withDaemon({}, async (d) => {
  await grown(d, 'street.json', 'street', 4);
  // 3 lies between stored snapshots: regrown, as the CLI does
  const r = await get(d, '/api/runs/street/shade?iteration=3&date=06-21&from=09:30&to=15:00');
  assert.equal(r.status, 200, r.body.toString());
  assert.match(r.headers.get('content-type'), /^application\/json/);
  const s = JSON.parse(r.body);
  assert.deepEqual([s.iteration, s.year, s.date, s.from, s.to, s.step], [3, 2030, '06-21', '09:30', '15:00', 10]);
  assert.deepEqual([s.voxel, s.origin, s.nx, s.ny], [0.125, [-14, -8, 0], 224, 128]);
  const cells = shadeCells(d, 'street', 3, '06-21', '09:30', '15:00');
  const ground = cells.filter((c) => c.surface === 'ground');
  assert.ok(near(s.ground, ground), 'the ground\'s tree shade');
  assert.ok(s.ground.some((v) => v > 0.5), 'the crowns shade the ground');
  // every face with cells, in the CLI's order: its grid and values
  const faces = [...new Set(cells.filter((c) => c.surface !== 'ground').map((c) => c.surface))];
  assert.deepEqual(s.faces.map((f) => `${f.obstacle}:${f.face}`), faces);
  for (const f of s.faces) {
    const mine = cells.filter((c) => c.surface === `${f.obstacle}:${f.face}`);
    assert.equal(f.nu * f.nz, mine.length, f.obstacle);
    assert.ok(f.first.every((v, i) => Math.abs(v - [mine[0].x, mine[0].y, mine[0].z][i]) <= 6e-4), f.obstacle);
    assert.ok(near(f.added, mine), `${f.obstacle}:${f.face}`);
  }
  assert.ok(s.faces.find((f) => f.obstacle === 'facade-north' && f.face === '-y').added.some((v) => v > 0),
    'the crowns shade the north facade');
  assert.equal(s.max, Math.max(...s.ground, ...s.faces.flatMap((f) => f.added)));
  // the defaults: the current iteration, 07-21 from 10:00 to 16:00
  const dflt = JSON.parse((await get(d, '/api/runs/street/shade')).body);
  assert.deepEqual([dflt.iteration, dflt.date, dflt.from, dflt.to], [4, '07-21', '10:00', '16:00']);
}));

test('shade: bad parameters get 400, a run without a site 400 and unknown runs 404, each with a line naming the problem', () => withDaemon({}, async (d) => {
  await grown(d, 'street.json', 'street', 2);
  const c = await connect(d.url);
  c.send({ type: 'create', name: 'wall', start: false, scenario: scenario('wall.json') });
  await c.type('created');
  c.close();
  const cases = [
    ['street/shade?iteration=3', 400, 'iteration: run "street" has iterations 0 to 2'],
    ['street/shade?iteration=x', 400, 'iteration: expected an integer from 0 to 2, got "x"'],
    ['street/shade?date=02-30', 400, /^date: .+\n$/],
    ['street/shade?date=', 400, /^date: .+\n$/],
    ['street/shade?from=25:00', 400, /^from: .+\n$/],
    ['street/shade?to=9', 400, /^to: .+\n$/],
    ['street/shade?from=12:00&to=12:00', 400, 'to: 12:00 is not after from (12:00)'],
    ['street/shade?from=17:00', 400, 'to: 16:00 is not after from (17:00)'],
    ['street/shade?date=07-01&date=07-02', 400, 'date: given more than once'],
    ['street/shade?step=5', 400, 'step: unknown parameter (known: iteration, date, from, to)'],
    ['wall/shade', 400, 'run: its light has no site (light.latitude, with "sky": "site"): the sun\'s hours need a latitude'],
    ['nope/shade', 404, 'no run "nope"'],
  ];
  await expectErrors(d, cases);
}));
