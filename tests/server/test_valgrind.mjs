// The daemon under valgrind through a session that creates, steps, edits, forks and
// reads a run, exports it over HTTP (also to a client that leaves, and with an export
// in flight at the end), then SIGTERM: exit 0, no memory errors, nothing left
// allocated.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { startDaemon, stopDaemon, connect, scenario, exportBytes, askOnly, cleanup } from './harness.mjs';

test('valgrind: a full session ends with every block freed', { timeout: 600000 }, async () => {
  const d = await startDaemon({ wrapper: ['valgrind', '--leak-check=full', '--error-exitcode=99',
    '--errors-for-leak-kinds=definite,indirect,possible'] });
  const c = await connect(d.url);
  c.send({ type: 'create', name: 'v', scenario: scenario('wall.json', { iterations: 6 }) });
  const { run } = await c.type('created', 120000);
  c.send({ type: 'subscribe', run });
  await c.type('snapshot', 120000);
  c.send({ type: 'control', run, action: 'step', count: 3 });
  for (let i = 0; i < 3; i++) await c.type('delta', 120000);
  c.send({ type: 'edit', run, add_obstacles: [{ id: 'board', kind: 'box', min: [-1, -1, 2], max: [1, 1, 2.1] }] });
  await c.type('snapshot', 120000);
  c.send({ type: 'get', run, iteration: 1, id: 'g' });
  await c.next((m) => m.type === 'snapshot' && m.ref === 'g', 120000);
  c.send({ type: 'fork', run, iteration: 2, name: 'v2' });
  await c.type('created', 120000);
  c.send({ type: 'light', run, z: 1 });
  await c.next((m) => m.type === 'light_slice' || m.type === 'error', 120000);
  c.send('{"type":"bogus"}');
  await c.type('error', 120000);
  // HTTP, on a run large enough (the stand grown to its end, about 9,000 internodes)
  // that an export takes seconds under valgrind: an export (a regrown iteration), a
  // ready scenario file, a bad request
  c.send({ type: 'create', name: 'st', start: true, scenario: scenario('stand.json', { iterations: 20 }) });
  const st = (await c.type('created', 120000)).run;
  c.send({ type: 'subscribe', run: st });
  await c.next((m) => m.type === 'status' && m.run === st && m.status === 'finished', 300000);
  const ex = await fetch(`${d.http}/api/runs/st/export?format=ply&iteration=19&obstacles=1`);
  assert.equal(ex.status, 200);
  assert.ok(Buffer.from(await ex.arrayBuffer()).equals(exportBytes(d.db, 'st', 'ply', 19, ['--obstacles'])));
  assert.equal((await fetch(`${d.http}/api/scenarios/wall`)).status, 200);
  assert.equal((await fetch(`${d.http}/api/runs/st/export?format=obj&iteration=99`)).status, 400);
  // clients that leave while their exports are written, and exports in flight when
  // the daemon stops
  for (let i = 0; i < 3; i++)
    await askOnly(d.port, '/api/runs/st/export?format=obj&iteration=19', { leave: true });
  const deadline = Date.now() + 120000;
  while (!/export: the client left/.test(d.stderr()) && Date.now() < deadline)
    await new Promise((r) => setTimeout(r, 200));
  assert.match(d.stderr(), /\[run st\] export: the client left before it was written/);
  for (let i = 0; i < 2; i++) await askOnly(d.port, '/api/runs/st/export?format=skeleton&iteration=18');
  await new Promise((r) => setTimeout(r, 500));
  const exit = await stopDaemon(d, 'SIGTERM');
  const err = d.stderr();
  assert.equal(exit.code, 0, err.slice(-3000));
  assert.match(err, /All heap blocks were freed|definitely lost: 0 bytes/);
  assert.match(err, /ERROR SUMMARY: 0 errors/);
  cleanup(d.dir);
});
