// The viewer's leaf placement (web/foliage.mjs) in node: known leaves worked out
// from the rule of docs/model.md ("Foliage"), the same numbers as the C's
// foliage_place (server/export/foliage.c, printed by foliage_dump), and the level
// of detail.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { placeLeaf, leafFrame, leafAt, newFrame, leafRgb, leafStride, drawnLeaves } from '../../web/foliage.mjs';

const close = (a, b, what, eps = 1e-15) => {
  assert.equal(a.length, b.length, what);
  a.forEach((v, i) => assert.ok(Math.abs(v - b[i]) <= eps, `${what}[${i}]: ${v} != ${b[i]}`));
};

test('leaves worked out by hand from the rule', () => {
  const r = Math.SQRT1_2;
  // a vertical internode: the frame is x, y; leaf 0 of 2 at a quarter of the way,
  // its blade up and along x, its width along y
  let f = placeLeaf([0, 0, 0], [0, 0, 1], 0, 2, 0.1);
  close(f.along, [r, 0, r], 'along');
  close(f.across, [0, 1, 0], 'across');
  close(f.centre, [0.05 * r, 0, 0.25 + 0.05 * r], 'centre');
  assert.equal(f.edge, 0.1);
  // a horizontal internode along x: e1 = up x d = y, e2 = d x e1 = z; leaf 1 of 3
  // is turned by the golden angle, a half of the way along
  const phi = (137.5 * Math.PI) / 180, c = Math.cos(phi), s = Math.sin(phi);
  f = placeLeaf([1, 2, 3], [3, 2, 3], 1, 3, 0.2);
  close(f.along, [r, c * r, s * r], 'along', 1e-15);
  close(f.across, [0, -s, c], 'across', 1e-15);
  close(f.centre, [2 + 0.1 * r, 2 + 0.1 * c * r, 3 + 0.1 * s * r], 'centre', 1e-15);
  // a root: a vertical internode of one leaf's length ending at it
  f = placeLeaf(null, [0.5, 0.5, 0.3], 0, 1, 0.2);
  close(f.centre, [0.5 + 0.1 * r, 0.5, 0.1 + 0.5 * 0.2 + 0.1 * r], 'root centre', 1e-15);
  // a zero-length internode is taken as vertical
  f = placeLeaf([1, 1, 1], [1, 1, 1], 0, 1, 0.1);
  close(f.along, [r, 0, r], 'along');
  close(leafRgb('#4a7f35'), [0x4a / 255, 0x7f / 255, 0x35 / 255], 'colour');
});

test('the same leaves as the C placement', () => {
  const exe = process.env.SYLVA_FOLIAGE_DUMP;
  assert.ok(exe, 'SYLVA_FOLIAGE_DUMP names foliage_dump (meson sets it)');
  // slanted, steep, nearly vertical, downward and root internodes, several k and n
  const cases = [
    [[0.1, -0.2, 0.5], [0.1731, -0.1044, 0.6287], 0, 6, 0.1],
    [[0.1, -0.2, 0.5], [0.1731, -0.1044, 0.6287], 5, 6, 0.1],
    [[1.25, 0.5, 2], [1.2501, 0.5, 2.1], 3, 4, 0.05],
    [[-3, 4, 7.5], [-3.1, 4.05, 7.45], 2, 3, 0.3],
    [[0, 0, 0], [0, 0, 0.2], 11, 12, 0.08],
    [null, [2, -1, 0], 1, 6, 0.1],
  ];
  const args = cases.flatMap(([p, q, k, n, size]) => [...(p ? p.map(String) : ['root']), ...q.map(String),
    String(k), String(n), String(size)]);
  const r = spawnSync(exe, args, { encoding: 'utf8' });
  assert.equal(r.status, 0, r.stderr);
  const lines = r.stdout.trim().split('\n');
  assert.equal(lines.length, cases.length);
  cases.forEach(([p, q, k, n, size], i) => {
    const c = lines[i].split(' ').map(Number);
    const f = placeLeaf(p, q, k, n, size);
    // the same operations in the same order on the same doubles: the same bits, but
    // for the libm's cos and sin, which node and the C library may round apart
    close(f.centre, c.slice(0, 3), `case ${i} centre`, 1e-15);
    close(f.along, c.slice(3, 6), `case ${i} along`, 1e-15);
    close(f.across, c.slice(6, 9), `case ${i} across`, 1e-15);
    assert.equal(f.edge, c[9]);
  });
});

test('level of detail: the stride keeps the drawn leaves near total / stride', () => {
  assert.equal(leafStride(1000, 400000), 1);
  assert.equal(leafStride(400000, 400000), 1);
  assert.equal(leafStride(400001, 400000), 2);
  assert.equal(leafStride(3e6, 400000), 8);
  for (let id = 0; id < 50; id++) assert.equal(drawnLeaves(6, id, 1), 6);
  for (const s of [2, 4, 8, 16]) {
    let drawn = 0;
    const nodes = 20000;
    for (let id = 0; id < nodes; id++) {
      const m = drawnLeaves(6, id, s);
      assert.ok(m >= Math.floor(6 / s) && m <= Math.ceil(6 / s), `node ${id}: ${m} leaves at stride ${s}`);
      assert.equal(drawnLeaves(6, id, s), m, 'the same node, the same leaves');
      drawn += m;
    }
    assert.ok(Math.abs(drawn - (nodes * 6) / s) < 0.02 * nodes * 6 / s, `stride ${s}: ${drawn} leaves drawn`);
  }
  // r = (id x an odd number) mod s takes every value once over s ids in a row, and
  // floor((n + r) / s) over every r adds up to n: s nodes in a row of n leaves
  // draw n cards between them, of s times a leaf's area each
  for (const s of [2, 4, 8, 32, 128]) {
    for (const n of [1, 2, 3, 6, 40, 129]) {
      for (const from of [0, 7, 1000, 123457]) {
        let sum = 0;
        for (let id = from; id < from + s; id++) sum += drawnLeaves(n, id, s);
        assert.equal(sum, n, `n ${n}, stride ${s}, ids ${from}..${from + s - 1}`);
      }
    }
  }
});

test('placeLeaf in halves: one frame a node, each leaf in it', () => {
  const out = { centre: [0, 0, 0], along: [0, 0, 0], across: [0, 0, 0], edge: 0 };
  const f = newFrame();
  for (const [p, q, size] of [[[0.1, -0.2, 0.5], [0.1731, -0.1044, 0.6287], 0.1], [null, [2, -1, 0], 0.3],
    [[1.25, 0.5, 2], [1.2501, 0.5, 2.1], 0.05]]) {
    leafFrame(p, q, size, f);
    // (the golden angles of high k first: their table fills as they are asked for)
    for (const k of [70, 3, 0, 69, 1]) {
      leafAt(f, k, 71, size, out);
      const want = placeLeaf(p, q, k, 71, size);
      for (const key of ['centre', 'along', 'across']) assert.deepEqual(out[key], want[key], `${key} of leaf ${k}`);
      assert.equal(out.edge, want.edge);
      // the angle computed afresh: the same doubles
      const phi = (137.5 * 3.14159265358979323846) / 180.0 * k;
      const outward = [0, 1, 2].map((a) => Math.cos(phi) * f.e1[a] + Math.sin(phi) * f.e2[a]);
      const across = [f.d[1] * outward[2] - f.d[2] * outward[1], f.d[2] * outward[0] - f.d[0] * outward[2],
        f.d[0] * outward[1] - f.d[1] * outward[0]];
      const l = Math.sqrt(across[0] * across[0] + across[1] * across[1] + across[2] * across[2]);
      assert.deepEqual(out.across, across.map((v) => v / l), `across of leaf ${k}`);
    }
  }
});
