// A stand in headless Chromium against a real daemon (docs/model.md, "Stands"):
// six lindens with a background death rate of 20 % a year and snags that stand
// one year. A stem whose stats say it died is drawn grey (every internode it has
// left, in grey pixels where it stood in its plant's colour) with no leaf cards;
// when its snag falls its internodes, grey or not, and its cards are gone. The
// self-thinning plot has one point per iteration, the last one the last delta's
// stand, and the panel lists the stand's figures. A run of IGM presets (no
// `stand`, no `alive`) shows neither, and nothing grey.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { ROOT, SLOW, startDaemon, stopDaemon, connect, cleanup, serverSnapshot } from '../server/harness.mjs';
import { launch, openViewer, until, createAndWatch } from './browser.mjs';

const WEB = ['--web', join(ROOT, 'web')];
let browser;
before(async () => { browser = await launch(); });
after(async () => { await browser?.close(); });

const ROOTS = [[-6, -3], [0, -3], [6, -3], [-6, 3], [0, 3], [6, 3]];
const STAND = {
  format: 'sylva.scenario/1',
  name: 'dying stand',
  seed: 2,
  iterations: 12,
  world: { min: [-15, -15, 0], max: [15, 15, 20] },
  species: { lime: { preset: 'utdb:NoEast:TICO', mortality: 0.2, snag_years: 1 } },
  plants: ROOTS.map(([x, y], i) => ({ id: `t${i + 1}`, species: 'lime', roots: [[x, y, 0]] })),
};
const IGM = {
  format: 'sylva.scenario/1',
  name: 'igm',
  seed: 1,
  iterations: 12,
  world: { min: [-3, -3, 0], max: [3, 3, 6] },
  species: { oak: { preset: 'igm-fig13' } },
  plants: [{ id: 'a', species: 'oak', roots: [[-1, 0, 0]] }, { id: 'b', species: 'oak', roots: [[1, 0, 0]] }],
};

// A plant's nodes as the page holds them ([id, parent, x, y, z, r, birth]).
const nodesOf = (page, id) => page.evaluate((p) =>
  window.sylva.skeleton().plants.find((q) => q.id === p).stems.flatMap((s) => s.nodes), id);
// Those of the node ids that have leaf cards in the page, with leaves shown
// (then hidden again, for the pixels).
async function carded(page, ids) {
  await page.evaluate(() => window.sylva.setLeaves(true));
  await page.waitForFunction(() => !window.sylva.state().leafPending);
  const cards = await page.evaluate(() => window.sylva.leafCards().ids);
  assert.ok(cards.length > 0, 'the living trees\' leaf cards');
  await page.evaluate(() => window.sylva.setLeaves(false));
  return cards.filter((n) => ids.includes(n));
}

// The camera straight above the tree at (x, y); the rectangle of the canvas
// its crown (a 3 m disc about it, at 2 m up) projects to.
async function above(page, [x, y]) {
  await page.evaluate(([x, y]) => window.sylva.lookAt([x, y - 0.01, 14], [x, y, 0]), [x, y]);
  const corners = await Promise.all([[-3, -3], [3, 3], [-3, 3], [3, -3]].map(([dx, dy]) =>
    page.evaluate(([px, py]) => window.sylva.project(px, py, 2), [x + dx, y + dy])));
  const xs = corners.map((c) => c[0]), ys = corners.map((c) => c[1]);
  return [Math.min(...xs), Math.min(...ys), Math.max(...xs), Math.max(...ys)];
}

// The pixels of the view of the tree at (x, y) from above, leaves off, that are
// the dead grey (a neutral mid tone, lit or shaded) and any plant's colour (well
// saturated). They are read from the canvas in the page, in the task that draws
// it (a screenshot decoded in the page took seconds).
async function looks(page, at) {
  const rect = await above(page, at);
  return page.evaluate(([x0, y0, x1, y1]) => {
    window.sylva.render();
    const view = document.querySelector('#view canvas');
    const sx = view.width / view.clientWidth, sy = view.height / view.clientHeight;
    const left = Math.max(0, Math.floor(x0 * sx)), top = Math.max(0, Math.floor(y0 * sy));
    const w = Math.min(view.width, Math.ceil(x1 * sx)) - left, h = Math.min(view.height, Math.ceil(y1 * sy)) - top;
    const c = document.createElement('canvas');
    c.width = w;
    c.height = h;
    const g = c.getContext('2d');
    g.drawImage(view, left, top, w, h, 0, 0, w, h);
    const d = g.getImageData(0, 0, w, h).data;
    let grey = 0, coloured = 0;
    for (let i = 0; i < d.length; i += 4) {
      const spread = Math.max(d[i], d[i + 1], d[i + 2]) - Math.min(d[i], d[i + 1], d[i + 2]);
      if (spread < 16 && d[i] > 40 && d[i] < 215) grey++;
      else if (spread > 45) coloured++;
    }
    return { grey, coloured };
  }, rect);
}

test('a stand: dead stems grey without leaves, gone when their snags fall; the self-thinning plot and the stand figures', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    const run = await createAndWatch(d, page, STAND, 'dying stand');
    // (the test's own subscription: the stats and stand of each delta)
    const c = await connect(d.url);
    c.send({ type: 'subscribe', run, id: 's' });
    await c.type('snapshot');

    // one iteration at a time, until a stem died and its snag fell
    const stands = [];
    let dead = null;   // {plant, at, died, nodes (ids), looks}
    for (let it = 1; it <= STAND.iterations; it++) {
      c.send({ type: 'control', run, action: 'step', count: 1, id: `step${it}` });
      const delta = await c.next((m) => m.type === 'delta' && m.iteration === it, 60000);
      stands.push(delta.stand);
      const s = await until(page, (x) => x.liveIteration === it && x.iteration === it, `iteration ${it}`, 60000 * SLOW);
      assert.deepEqual(s.stand, delta.stand, 'the page holds the delta\'s stand');
      await page.evaluate(() => window.sylva.setLeaves(false));
      const died = delta.stats.filter((st) => st.alive === false);
      if (!dead && died.length) {
        const st = died[0], i = STAND.plants.findIndex((p) => p.id === st.plant);
        assert.equal(st.died, it);
        const nodes = await nodesOf(page, st.plant);
        assert.ok(nodes.length > 0, 'a snag stands the year it dies');
        dead = { plant: st.plant, at: ROOTS[i], died: it, nodes: nodes.map((n) => n[0]) };
        // every internode it has left is drawn grey, and no other stem's but the dead ones'
        const greyed = (await until(page, (x) => x.greyed[st.plant] === nodes.length, 'the dead stem grey')).greyed;
        for (const id of Object.keys(greyed)) assert.ok(died.some((x) => x.plant === id), `${id} is grey but alive`);
        assert.deepEqual(await carded(page, dead.nodes), [], 'leaf cards on the dead stem');
        // grey pixels, where a living tree seen the same way shows its plant's colour
        dead.looks = await looks(page, dead.at);
        assert.ok(dead.looks.grey > 100 && dead.looks.grey > 4 * dead.looks.coloured,
          `the dead tree in grey: ${JSON.stringify(dead.looks)}`);
        const living = delta.stats.findIndex((x) => x.alive);
        const green = await looks(page, ROOTS[living]);
        assert.ok(green.coloured > 100 && green.coloured > 4 * green.grey, `a living tree: ${JSON.stringify(green)}`);
      } else if (dead && it === dead.died + 1) {
        // its snag fell: nothing of it is held, drawn or carded
        assert.deepEqual(await nodesOf(page, dead.plant), []);
        await until(page, (x) => !(dead.plant in x.greyed), 'the fallen snag not drawn');
        assert.deepEqual(await carded(page, dead.nodes), [], 'leaf cards of the fallen snag');
        const gone = await looks(page, dead.at);
        assert.ok(gone.grey < 0.1 * dead.looks.grey && gone.coloured < 50, `the fallen snag's place: ${JSON.stringify(gone)}`);
        break;
      }
    }
    assert.ok(dead, 'a stem died');
    c.close();

    // the self-thinning plot: one point per iteration (each with stems and a QMD),
    // the last one the last stand's; the figures listed are the last stand's
    const n = stands.length;
    assert.ok(stands.every((x) => x.qmd > 0 && x.stems_per_ha > 0), JSON.stringify(stands));
    await page.waitForFunction((k) => window.sylva.plots().self_thinning?.x.length === k, n);
    const plot = (await page.evaluate(() => window.sylva.plots())).self_thinning;
    assert.deepEqual(plot.iterations, Array.from({ length: n }, (_, i) => i + 1));
    assert.equal(plot.axis, 'QMD (cm)');
    assert.deepEqual(plot.x, stands.map((x) => x.qmd));
    assert.deepEqual(plot.stems.stand, stands.map((x) => x.stems_per_ha));
    assert.ok(stands[n - 1].alive < ROOTS.length && stands[n - 1].stems_per_ha < stands[0].stems_per_ha);
    const s = await until(page, (x) => x.standFigures.length > 0, 'the stand figures');
    const figures = Object.fromEntries(s.standFigures);
    const last = stands[n - 1];
    assert.equal(figures.Stems, `${Math.round(last.stems_per_ha).toLocaleString('en')} /ha`);
    assert.equal(figures.QMD, `${last.qmd.toFixed(1)} cm`);
    assert.equal(figures['Basal area'], `${last.basal_area.toFixed(2)} m²/ha`);
    assert.equal(figures['Dominant height'], `${last.dominant_height.toFixed(2)} m`);
    assert.equal(figures.SDI, Math.round(last.sdi).toLocaleString('en'));
    assert.equal(figures.Alive, `${last.alive} stems`);
    assert.equal(figures.Died, `${last.died} this iteration`);
    assert.equal(await page.isVisible('#stand'), true);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('a run without stands (IGM presets): no stand figures, no self-thinning plot, nothing grey', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    await createAndWatch(d, page, IGM, 'igm');
    await page.fill('#step-count', '3');
    await page.click('#step');
    await until(page, (x) => x.iteration === 3, 'three iterations', 60000 * SLOW);
    await page.waitForFunction(() => window.sylva.plots().height?.iterations.length === 3);
    const plots = await page.evaluate(() => window.sylva.plots());
    assert.equal('self_thinning' in plots, false);
    const s = await page.evaluate(() => window.sylva.state());
    assert.equal(s.stand, null);
    assert.deepEqual(s.standFigures, []);
    assert.deepEqual(s.greyed, {});
    assert.equal(await page.isVisible('#stand'), false);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// A run above the stems threshold (lowered to 0 internodes by the page's address)
// is watched at stem detail: no internodes held or drawn, a trunk and a crown per
// stem from the stats, which the plots take too; the button switches to every
// internode (the skeleton as the store holds it) and back.
test('a large run at stem detail: a trunk and a crown per stem; the button switches to the internodes and back', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const c = await connect(d.url);
    c.send({ type: 'create', scenario: STAND, name: 'stems', id: 'c' });
    const { run } = await c.type('created');
    c.send({ type: 'subscribe', run, detail: 'stems' });
    await c.type('snapshot');
    c.send({ type: 'control', run, action: 'step', count: 2 });
    const d2 = await c.next((m) => m.type === 'delta' && m.iteration === 2, 60000);
    // a crown for each stem alive and higher than its crown base
    const crowned = (stats) => stats.filter((st) => st.alive !== false && st.height > (st.crown_base ?? 0)).length;
    const { page, errors } = await openViewer(browser, d.http, { query: '?stems=0', hash: '#run=stems' });
    const stems = ROOTS.length;
    let s = await until(page, (x) => x.run === run && x.liveDetail === 'stems' && x.drawnTrunks === stems,
      'the stems drawn');
    assert.equal(s.drawnCrowns, crowned(d2.stats));
    assert.ok(s.drawnCrowns > 0);
    assert.equal(s.nodes, 0);
    assert.equal(s.drawnInstances, 0);
    assert.equal(await page.getAttribute('#detail-toggle', 'aria-pressed'), 'true');
    c.send({ type: 'control', run, action: 'step', count: 1 });
    const d3 = await c.next((m) => m.type === 'delta' && m.iteration === 3, 60000);
    assert.equal(d3.detail, 'stems');
    s = await until(page, (x) => x.liveIteration === 3 && x.drawnTrunks === stems, 'a stems delta', 60000 * SLOW);
    assert.equal(s.drawnCrowns, crowned(d3.stats));
    assert.equal(s.nodes, 0);
    await page.waitForFunction(() => window.sylva.plots().height?.iterations.length === 3);
    // every internode, as a fresh subscriber of nodes gets them
    await page.click('#detail-toggle');
    s = await until(page, (x) => x.liveDetail === 'nodes' && x.nodes > 0, 'the internodes');
    assert.equal(s.drawnTrunks, 0);
    assert.equal(s.drawnCrowns, 0);
    const full = await serverSnapshot(d, run);
    assert.equal(s.nodes, full.plants.flatMap((p) => p.stems).reduce((n, st) => n + st.nodes.length, 0));
    assert.ok(s.drawnInstances > 0);
    assert.equal(await page.getAttribute('#detail-toggle', 'aria-pressed'), 'false');
    await page.click('#detail-toggle');
    await until(page, (x) => x.liveDetail === 'stems' && x.drawnTrunks === stems && x.nodes === 0, 'stems again');
    c.close();
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});
