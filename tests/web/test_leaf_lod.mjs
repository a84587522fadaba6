// The leaves' level of detail in headless Chromium against a real daemon
// (docs/model.md, "Foliage"): with a budget of cards set from the page, a crown of
// N leaves is drawn with stride s, the least power of two with N / s within the
// budget (a thinner crown goes back to s / 2 only when N / (s / 2) is within 0.8
// of it); a node of n leaves draws floor((n + r) / s) cards placed by the rule for
// that count, each of edge leaf_size x sqrt(s), so the drawn leaf area is the
// crown's. Checked card by card against the server's snapshot after a change of
// budget and after deltas, once the page has placed every card; no timing.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { ROOT, SLOW, startDaemon, stopDaemon, connect, cleanup, serverSnapshot } from '../server/harness.mjs';
import { launch, openViewer, until } from './browser.mjs';
import { leafStride, drawnLeaves, placeLeaf } from '../../web/foliage.mjs';

const WEB = ['--web', join(ROOT, 'web')];
const FILL = Math.PI / 4;
let browser;
before(async () => { browser = await launch(); });
after(async () => { await browser?.close(); });

// Four small trees of two species: 40 leaves of 5 cm a leaf-bearing node (more
// than any stride below) and 3 of 12 cm (fewer), about 4,000 leaf-bearing nodes
// and 90,000 leaves after 16 iterations.
function stand() {
  return {
    format: 'sylva.scenario/1', name: 'leaf lod', seed: 5, iterations: 40,
    world: { min: [-4, -4, 0], max: [4, 4, 8] },
    species: {
      dense: { preset: 'igm-fig11', leaf_density: 40, leaf_size: 0.05, leaf_colour: '#3a7a30' },
      sparse: { preset: 'igm-fig17b', leaf_density: 3, leaf_size: 0.12, leaf_colour: '#6a9a20' },
    },
    plants: [
      { id: 'a', species: 'dense', roots: [[-1.5, -1.5, 0]] },
      { id: 'b', species: 'sparse', roots: [[1.5, -1.5, 0]] },
      { id: 'c', species: 'sparse', roots: [[-1.5, 1.5, 0]] },
      { id: 'd', species: 'dense', roots: [[1.5, 1.5, 0]] },
    ],
  };
}

// The page's cards against the server's crown at this budget and stride.
async function check(page, d, run, budget, stride, what) {
  const s = await until(page, (x) => !x.leafPending && x.leafBudget === budget, `${what}: every card placed`, 60000 * SLOW);
  const snap = await serverSnapshot(d, run);
  assert.equal(s.iteration, snap.iteration, `${what}: the iteration`);
  // every node of the crown: its position, its parent's (in float32, as the page
  // holds them), its species' leaves
  const nodes = new Map(), f32 = (n) => n.slice(2, 5).map(Math.fround);
  snap.plants.forEach((pl, i) => {
    const f = snap.foliage[snap.plant_species[i]];
    for (const st of pl.stems) {
      const at = new Map(st.nodes.map((n) => [n[0], n]));
      for (const n of st.nodes) {
        const parent = at.get(n[1]);
        nodes.set(n[0], { p: parent ? f32(parent) : null, q: f32(n), f });
      }
    }
  });
  const total = snap.leaves.reduce((a, [, n]) => a + n, 0);
  assert.ok(snap.leaves.length > 1000, `${what}: leaf-bearing nodes ${snap.leaves.length}`);
  assert.equal(s.leafTotal, total, `${what}: the crown's leaves`);
  // the stride of the rule, within the budget
  assert.equal(s.leafStride, stride, `${what}: the stride for ${total} leaves, budget ${budget}`);
  assert.ok(total / stride <= budget, `${what}: N / s = ${total / stride} within ${budget}`);
  assert.ok(s.drawnLeaves <= budget, `${what}: ${s.drawnLeaves} cards within the budget ${budget}`);

  // card by card: floor((n + r) / s) of them a node, placed by the rule for that
  // count, of edge leaf_size x sqrt(s)
  const { ids, counts, cards } = await page.evaluate(() => window.sylva.leafCards());
  const drawn = new Map(ids.map((id, i) => [id, i]));
  let cardCount = 0, area = 0, crown = 0, spread = 0;
  const wrong = [];
  const start = [];
  for (let i = 0, j = 0; i < ids.length; i++) { start.push(j); j += counts[i]; }
  for (const [id, n] of snap.leaves) {
    const node = nodes.get(id), m = drawnLeaves(n, id, stride), size = node.f.leaf_size * Math.sqrt(stride);
    crown += n * node.f.leaf_size ** 2 * FILL;
    // (floor((n + r) / s) is floor(n / s) or one more, as r is below s - n mod s or not)
    const frac = (n % stride) / stride;
    spread += (stride * node.f.leaf_size ** 2 * FILL) ** 2 * frac * (1 - frac);
    const i = drawn.get(id);
    if ((i === undefined ? 0 : counts[i]) !== m) {
      wrong.push(`node ${id}: ${i === undefined ? 0 : counts[i]} cards, ${m} by the rule (n ${n}, s ${stride})`);
      continue;
    }
    if (m === 0) continue;
    drawn.delete(id);
    for (let k = 0; k < m; k++) {
      const at = (start[i] + k) * 5, want = placeLeaf(node.p, node.q, k, m, size);
      const [x, y, z, e1, e2] = cards.slice(at, at + 5);
      const off = Math.hypot(x - want.centre[0], y - want.centre[1], z - want.centre[2]);
      if (off > 1e-5 || Math.abs(e1 - size) > 1e-5 * size || Math.abs(e2 - size) > 1e-5 * size) {
        wrong.push(`node ${id} card ${k}: centre ${off} m off, edges ${e1} ${e2} for ${size}`);
      }
      area += e1 * e2 * FILL;
    }
    cardCount += m;
  }
  for (const id of drawn.keys()) wrong.push(`node ${id}: cards, but no leaves on the server`);
  assert.deepEqual(wrong.slice(0, 10), [], `${what}: ${wrong.length} cards against the rule`);
  assert.equal(s.drawnLeaves, cardCount, `${what}: the cards drawn`);
  // the drawn leaf area is the crown's (the server's leaf_area): exactly at stride
  // 1, else to within the rounding of floor((n + r) / s) over the nodes, r spread
  // evenly by the hash of the id (four standard deviations of it)
  const leafArea = snap.stats.reduce((a, st) => a + st.leaf_area, 0);
  assert.ok(Math.abs(crown - leafArea) <= 1e-3 * leafArea, `${what}: the crown's area ${crown} against the server's ${leafArea}`);
  const tolerance = 4 * Math.sqrt(spread) + 1e-4 * leafArea;
  assert.ok(Math.abs(area - leafArea) <= tolerance, `${what}: drawn leaf area ${area.toFixed(3)} m², the crown's ` +
    `${leafArea.toFixed(3)} m² (to within ${tolerance.toFixed(3)})`);
  return { total, cards: cardCount, area, leafArea };
}

test('leaves level of detail: budget, stride, cards and area by the rule', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    // no frames drawn: what is checked is what the page holds, and SwiftShader
    // would draw each frame on the CPU that the page's tasks share
    await page.evaluate(() => { window.requestAnimationFrame = () => 0; });
    const c = await connect(d.url);
    c.send({ type: 'create', scenario: stand(), name: 'lod', start: false, id: 'c' });
    const { run } = await c.type('created');
    await page.waitForSelector(`#runs tr[data-run="${run}"]`, { timeout: 10000 * SLOW });
    await page.click(`#runs tr[data-run="${run}"]`);
    await until(page, (s) => s.run === run && s.seq >= 0, 'the run');
    const step = async (count, to) => {
      c.send({ type: 'control', run, action: 'step', count, id: `s${to}` });
      await until(page, (x) => x.iteration === to, `iteration ${to}`, 60000 * SLOW);
    };
    const budget = async (b) => { await page.evaluate((n) => window.sylva.setLeafBudget(n), b); };

    // every leaf drawn under a budget above the crown
    await step(14, 14);
    let s = await until(page, (x) => !x.leafPending, 'the leaves');
    const n14 = s.leafTotal;
    await budget(n14);
    await check(page, d, run, n14, 1, 'stride 1');

    // a fifth of the crown: stride 8 (N / 4 is over it)
    const b1 = Math.floor(n14 / 5);
    await budget(b1);
    let r = await check(page, d, run, b1, leafStride(n14, b1), 'a fifth');
    assert.equal(leafStride(n14, b1), 8);
    assert.ok(r.cards < n14 / 6, `${r.cards} cards for ${n14} leaves at stride 8`);

    // the crown grows under the same budget: deltas, and a change of stride
    await step(1, 15);
    s = await until(page, (x) => !x.leafPending, 'the leaves at 15');
    await check(page, d, run, b1, leafStride(s.leafTotal, b1), 'iteration 15');
    await step(1, 16);
    s = await until(page, (x) => !x.leafPending, 'the leaves at 16');
    const n16 = s.leafTotal, s16 = leafStride(n16, b1);
    assert.ok(s16 >= 16, `stride ${s16} for ${n16} leaves`);
    r = await check(page, d, run, b1, s16, 'iteration 16');

    // a budget N / s would fit at s / 2, but not within 0.8 of it: the stride stays
    const near = Math.ceil(n16 / (s16 / 2) / 0.9);
    assert.equal(leafStride(n16, near), s16 / 2);
    await budget(near);
    await check(page, d, run, near, s16, 'just above');
    // well above: the least stride again
    const wide = Math.ceil(n16 / 3);
    await budget(wide);
    await check(page, d, run, wide, 4, 'a third');

    // a budget under the crown's nodes: nodes of 3 leaves draw one or none
    const low = Math.floor(n16 / 100);
    await budget(low);
    r = await check(page, d, run, low, leafStride(n16, low), 'a hundredth');
    assert.equal(leafStride(n16, low), 128);
    c.close();
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});
