// The viewer's skeleton (web/skeleton.mjs, web/wire.mjs) in node: hand-made shedding cases, and
// a real daemon's snapshot and deltas applied to it equal `sylva export` at every
// iteration.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { Skeleton as Base } from '../../web/skeleton.mjs';
import { deltaArrays, snapshotArrays } from '../../web/wire.mjs';

// The skeleton fed as the page feeds it: messages converted by wire.mjs.
class Skeleton extends Base {
  loadSnapshot(msg) { super.loadSnapshot(snapshotArrays(msg)); }
  applyDelta(msg) { return super.applyDelta(deltaArrays(msg)); }
}
import { SLOW, startDaemon, stopDaemon, connect, scenario, exportSkeleton, plantsJSON, cleanup } from '../server/harness.mjs';

const f32 = (sk) => JSON.parse(plantsJSON(sk), (k, v) => (typeof v === 'number' ? Math.fround(v) : v));

// Two stems of one plant, nodes interleaved by id across stems.
function twoStems() {
  const sk = new Skeleton(4);
  sk.loadSnapshot({
    iteration: 1, seq: 1, world: { min: [0, 0, 0], max: [1, 1, 1] }, voxel: 0.05, obstacles: [], stats: [],
    plants: [{ id: 'p', stems: [
      { root: [0, 0, 0], nodes: [[0, -1, 0, 0, 0, 0.01, 0], [2, 0, 0, 0, 1, 0.01, 0], [4, 2, 1, 0, 1, 0.01, 1]] },
      { root: [5, 0, 0], nodes: [[1, -1, 5, 0, 0, 0.01, 0], [3, 1, 5, 0, 1, 0.01, 0]] }] }],
  });
  return sk;
}

const ids = (sk) => Array.from(sk.id.subarray(0, sk.count));

test('a shed subtree goes, with its descendants only, and slots stay in parent order', () => {
  const sk = twoStems();
  sk.applyDelta({ seq: 2, iteration: 2, added: [[5, 4, 0, 0, 2, 0, 2, 0.003], [6, 3, 0, 1, 5, 0, 2, 0.003],
    [7, 5, 0, 0, 3, 0, 3, 0.003]], radii: [[0, 0.02]], shed: [], stats: [] });
  assert.deepEqual(ids(sk), [0, 2, 4, 1, 3, 5, 6, 7]);
  assert.equal(sk.radius[sk.slotOf(0)], Math.fround(0.02));
  // the start of a branch is its parent's end
  const k = sk.slotOf(7), p = sk.slotOf(5);
  assert.deepEqual(Array.from(sk.start.subarray(k * 3, k * 3 + 3)), Array.from(sk.end.subarray(p * 3, p * 3 + 3)));
  sk.applyDelta({ seq: 3, iteration: 3, added: [[8, 6, 0, 1, 5, 1, 3, 0.003]], radii: [[7, 0.004]], shed: [4], stats: [] });
  // shed slots are dead (unmapped, drawn as nothing) until compact()
  for (const gone of [4, 5, 7]) assert.equal(sk.slotOf(gone), -1);
  assert.equal(sk.live, 6);
  assert.deepEqual(sk.toExport().plants[0].stems[0].nodes.map((n) => n[0]), [0, 2]);
  for (let k = 0; k < sk.count; k++) {
    if (!sk.dead[k]) continue;
    assert.equal(sk.radius[k], 0);
    assert.deepEqual(Array.from(sk.end.subarray(k * 3, k * 3 + 3)), Array.from(sk.start.subarray(k * 3, k * 3 + 3)));
  }
  assert.ok(sk.compact());
  assert.ok(!sk.compact(), 'nothing left to squeeze');
  assert.deepEqual(ids(sk), [0, 2, 1, 3, 6, 8]);
  for (const gone of [4, 5, 7]) assert.equal(sk.slotOf(gone), -1);
  for (let i = 0; i < sk.count; i++) {
    const p = sk.parent[i];
    assert.ok(p < i, 'a parent sits before its child');
    if (p >= 0) {
      const want = { 2: 0, 3: 1, 6: 3, 8: 6 }[sk.id[i]];
      assert.equal(sk.id[p], want, `parent of ${sk.id[i]}`);
    }
  }
  const ex = sk.toExport();
  assert.deepEqual(ex.plants[0].stems[1].nodes.map((n) => n[0]), [1, 3, 6, 8]);
  assert.deepEqual(ex.plants[0].stems[1].nodes[3], [8, 6, 5, 1, 3, Math.fround(0.003), 3]);
});

test('growing past the capacity keeps every node', () => {
  const sk = twoStems();
  const added = [];
  for (let i = 0; i < 5000; i++) added.push([5 + i, i === 0 ? 4 : 4 + i, 0, 0, 0, 0, i * 0.001, 0.003]);
  sk.applyDelta({ seq: 2, iteration: 2, added, radii: [], shed: [], stats: [] });
  assert.equal(sk.count, 5005);
  sk.applyDelta({ seq: 3, iteration: 3, added: [], radii: [], shed: [2], stats: [] });
  assert.equal(sk.live, 3);
  sk.compact();
  assert.deepEqual(ids(sk), [0, 1, 3]);
  assert.ok(sk.growAhead() === false && sk.capacity >= 5005);
  assert.throws(() => sk.applyDelta({ seq: 4, iteration: 4, added: [[9000, 8999, 0, 0, 0, 0, 0, 0.003]],
    radii: [], shed: [], stats: [] }), /parent 8999 is not held/);
});

test('a measured tree\'s past: the earliest birth, and the stage at an iteration before 0', () => {
  // two stems: a measured one born from -4 (a fork at node 2), a young one from 0
  const sk = new Skeleton(4);
  sk.loadSnapshot({
    iteration: 0, seq: 0, world: { min: [0, 0, 0], max: [6, 1, 3] }, voxel: 0.05, obstacles: [], stats: [{}, {}],
    start_year: 2027, sky: 'zenith', species: ['plane'],
    plants: [{ id: 'p', stems: [
      { root: [0, 0, 0], nodes: [[0, -1, 0, 0, 0, 0.04, -4], [2, 0, 0, 0, 1, 0.03, -4], [4, 2, 0, 0, 2, 0.01, -1],
        [5, 2, 1, 0, 2, 0.01, 0]] },
      { root: [5, 0, 0], nodes: [[1, -1, 5, 0, 0, 0.01, 0], [3, 1, 5, 0, 1, 0.01, 0]] }] }],
  });
  assert.equal(sk.earliest, -4);
  // a delta's nodes are born at its iteration: the earliest birth stays
  sk.applyDelta({ seq: 1, iteration: 1, added: [[6, 5, 0, 0, 1, 0, 3, 0.003]], radii: [], shed: [], stats: [] });
  assert.equal(sk.earliest, -4);
  const zero = twoStems();
  assert.equal(zero.earliest, 0, 'a tree without a past');
  const base = new Skeleton(4);
  base.loadSnapshot({ ...sk.toExport(), iteration: 0, seq: 0, stats: [], start_year: 2027 });
  const at = base.stageAt(-2);
  assert.equal(at.iteration, -2);
  assert.equal(at.startYear, 2027);
  assert.deepEqual(at.stats, []);
  assert.equal(at.live, 2);
  const ex = at.toExport();
  // the stem of two nodes: one tip above each, of the two at 0 (nodes 4 and 6)
  assert.deepEqual(ex.plants[0].stems[0].nodes, [
    [0, -1, 0, 0, 0, Math.fround(Math.fround(0.04) * (1 / 2) ** 0.4), -4],
    [2, 0, 0, 0, 1, Math.fround(Math.fround(0.03) * (1 / 2) ** 0.4), -4]]);
  assert.deepEqual(ex.plants[0].stems[1].nodes, []);
  assert.equal(at.start[3 * 1 + 2], 0, 'a branch starts at its parent');
  assert.equal(base.live, 7, 'the skeleton it was made from is unchanged');
});

test('snapshot plus deltas from a real daemon equal the export at every iteration', async () => {
  const d = await startDaemon({});
  try {
    const c = await connect(d.url);
    c.send({ type: 'create', scenario: scenario('wall.json', { iterations: 14 }), name: 'w', start: false, id: 'c' });
    const { run } = await c.type('created');
    c.send({ type: 'subscribe', run });
    const sk = new Skeleton();
    sk.loadSnapshot(await c.type('snapshot'));
    c.send({ type: 'control', run, action: 'start' });
    let shed = 0;
    for (let it = 1; it <= 14; it++) {
      const delta = await c.next((m) => m.type === 'delta', 60000);
      shed += delta.shed.length;
      sk.applyDelta(delta);
      if (it % 3 === 0) sk.compact(); // the page compacts when it has a moment; either way
      assert.equal(sk.iteration, it);
      assert.deepEqual(f32(sk.toExport()), f32(exportSkeleton(d.db, 'w', it)), `iteration ${it}`);
    }
    assert.ok(shed > 0, 'the run shed branches');
    // the leaves held are those of a fresh snapshot, and their total is kept
    const fresh = await connect(d.url);
    fresh.send({ type: 'subscribe', run });
    const snap = await fresh.type('snapshot');
    fresh.close();
    const held = [];
    let total = 0;
    for (let k = 0; k < sk.count; k++) {
      if (!sk.dead[k] && sk.leaves[k] > 0) held.push([sk.id[k], sk.leaves[k]]);
      total += sk.leaves[k];
    }
    assert.ok(snap.leaves.length > 0);
    assert.deepEqual(held.sort((a, b) => a[0] - b[0]), snap.leaves);
    assert.equal(sk.leafTotal, total);
    c.close();
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});
