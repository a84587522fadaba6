// Urban sites in the viewer, in headless Chromium against a real daemon: clearance
// zones drawn, the internodes inside them highlighted, the conflicts table against
// the daemon's stats, a row's click moving the timeline, pruning a zone from the
// edit bar, adding a zone, the light slice named by the run's sky, and a run in
// years: its calendar years on the timeline, the plots and the conflicts table.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { ROOT, SLOW, startDaemon, stopDaemon, connect, scenario, yearsScenario, cleanup } from '../server/harness.mjs';
import { launch, openViewer, state, until, httpGet, countPixels } from './browser.mjs';
import { parseStatsCsv } from '../../web/helpers.mjs';

const WEB = ['--web', join(ROOT, 'web')];
let browser;
before(async () => { browser = await launch(); });
after(async () => { await browser?.close(); });

// A tree at the origin; a clearance zone (a road's clearance) on its east side
// from 1 m up, which the crown grows into within ten iterations (23 of its 44
// internodes at iteration 10); a solid wall to the west.
const ROAD = { id: 'road', kind: 'zone', min: [0.3, -3, 1], max: [3, 3, 6] };
const WALL = { id: 'wall', kind: 'box', min: [-2.6, -3, 0], max: [-2.4, 3, 3] };
const SITE = {
  format: 'sylva.scenario/1',
  name: 'street site',
  seed: 3,
  iterations: 40,
  world: { min: [-3, -3, 0], max: [3, 3, 6] },
  species: { oak: { preset: 'igm-fig11' } },
  plants: [{ id: 'tree', species: 'oak', roots: [[0, 0, 0]] }],
  obstacles: [ROAD, WALL],
};

const inside = (box, [x, y, z]) => x >= box.min[0] && x <= box.max[0] && y >= box.min[1] && y <= box.max[1] &&
  z >= box.min[2] && z <= box.max[2];

// The positions [x, y, z] of every node of a snapshot.
const positions = (snap) => snap.plants.flatMap((p) => p.stems.flatMap((s) => s.nodes.map((n) => n.slice(2, 5))));

// The conflicts rows the stats give: one per stem and zone it ever entered.
const statsRows = (stats) => stats.flatMap((st) => Object.entries(st.zones ?? {})
  .map(([zone, z]) => ({ plant: st.plant, stem: String(st.stem), zone, first: String(z.first), nodes: String(z.nodes) })));

// The rows of the page's conflicts table, as its cells' data say.
const pageRows = (page) => page.$$eval('#conflicts tbody tr', (trs) => trs.map((tr) => {
  const { plant, stem, zone, first, nodes } = tr.dataset;
  return { plant, stem, zone, first, nodes };
}));

// The daemon's snapshot of a run now (a subscription of its own).
async function serverSnapshot(d, run) {
  const c = await connect(d.url);
  c.send({ type: 'subscribe', run, id: 's' });
  const snap = await c.next((m) => m.type === 'snapshot' && m.ref === 's');
  c.close();
  return snap;
}

async function createRun(d, doc, name) {
  const c = await connect(d.url);
  c.send({ type: 'create', scenario: doc, name, start: false, id: 'c' });
  const { run } = await c.type('created');
  c.close();
  return run;
}

async function watchRun(page, run) {
  await page.waitForSelector(`#runs tr[data-run="${run}"]`, { timeout: 10000 * SLOW });
  await page.click(`#runs tr[data-run="${run}"]`);
  return until(page, (s) => s.run === run && s.seq >= 0, 'the selected run');
}

// Pixels of the zone highlight's red (#e8112d) in a screenshot of the view. The
// highlight is on the internodes, which the leaves may hide: it is counted on the
// bare skeleton (the view's Leaves toggle), and the leaves shown again.
async function highlightPixels(page) {
  await page.evaluate(() => { window.sylva.setLeaves(false); window.sylva.render(); });
  const png = await page.locator('#view canvas').screenshot();
  await page.evaluate(() => window.sylva.setLeaves(true));
  return countPixels(page, png, null, 'highlight');
}

const near = (a, b) => a.length === b.length && a.every((v, i) => Math.abs(v - b[i]) < 1e-6);

test('zones drawn and highlighted, the conflicts table and its rows, pruning and adding a zone', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    const run = await createRun(d, SITE, 'street');
    let s = await watchRun(page, run);

    // the zone is drawn as a zone, with its box; the wall as a solid obstacle
    assert.deepEqual(s.zones, ['road']);
    assert.deepEqual(s.drawnObstacles, ['wall']);
    assert.equal(s.drawnZones.length, 1);
    assert.equal(s.drawnZones[0].id, 'road');
    assert.ok(near(s.drawnZones[0].min, ROAD.min) && near(s.drawnZones[0].max, ROAD.max),
      `the zone's mesh spans its box: ${JSON.stringify(s.drawnZones[0])}`);
    assert.equal(s.highlighted, 0, 'the young tree is outside the zone');
    assert.equal(await page.locator('#conflicts tbody tr').count(), 0);
    assert.ok(await page.isVisible('#conflicts-empty'));
    assert.ok(await page.isVisible('#obstacles button.chip.zone[title="remove zone road"]'));

    // ten iterations: the crown grows into the zone
    await page.fill('#step-count', '10');
    await page.click('#step');
    s = await until(page, (x) => x.iteration === 10, 'ten iterations', 120000 * SLOW);
    let snap = await serverSnapshot(d, run);
    assert.equal(snap.iteration, 10);
    const inRoad = positions(snap).filter((p) => inside(ROAD, p)).length;
    assert.ok(inRoad > 0, 'the tree has grown into the zone');
    // the page highlights exactly the nodes the daemon's positions put inside
    s = await until(page, (x) => x.nodes === positions(snap).length, 'the page at the server\'s nodes');
    assert.equal(s.highlighted, inRoad, 'highlighted internodes');
    assert.deepEqual(s.inZones, { road: inRoad });
    assert.ok(await highlightPixels(page) > 20, 'the highlight colour is drawn');

    // the conflicts table is the daemon's stats: plant, zone, first, nodes now
    const want = statsRows(snap.stats);
    assert.equal(want.length, 1, `the stats have the zone: ${JSON.stringify(snap.stats)}`);
    assert.equal(want[0].nodes, String(inRoad), 'the stats count the nodes inside');
    await page.waitForFunction((n) => document.querySelectorAll('#conflicts tbody tr').length === n, want.length);
    assert.deepEqual(await pageRows(page), want);
    assert.deepEqual(await page.$$eval('#conflicts tbody td', (tds) => tds.map((td) => td.textContent)),
      ['tree', 'road', want[0].first, want[0].nodes]);
    assert.ok(await page.isHidden('#conflicts-empty'));
    // the clearances table: the tree's nearest solid (the wall) as the stats give it
    const clear = Object.entries(snap.stats[0].clearance);
    assert.deepEqual(clear.map(([o]) => o), ['wall']);
    assert.deepEqual(await page.$$eval('#clearances tbody td', (tds) => tds.map((td) => td.textContent)),
      ['tree', 'wall', clear[0][1].toFixed(2), String(snap.stats[0].pruned)]);
    // and the stored stats say the same
    const csv = parseStatsCsv((await httpGet(`${d.http}/api/runs/street/stats.csv`)).body.toString());
    assert.deepEqual(statsRows(csv.get(10)), want, 'stats.csv at iteration 10');
    const first = Number(want[0].first);
    assert.ok(first > 0 && first < 10, `first entered at ${first}`);

    // a row's click shows its first iteration from the store: a node is in the zone
    // there, and none the iteration before
    await page.click('#conflicts tbody tr[data-zone="road"]');
    s = await until(page, (x) => !x.live && x.iteration === first, `iteration ${first} from the store`);
    assert.equal(await page.inputValue('#timeline'), String(first));
    assert.ok(s.highlighted > 0, `nodes inside at iteration ${first}`);
    assert.ok(await page.locator('#conflicts tbody tr.selected[data-zone="road"]').count() === 1);
    assert.ok(await page.isDisabled('#prune'), 'pruning only from the live run');
    const c = await connect(d.url);
    c.send({ type: 'get', run, iteration: first - 1, id: 'g' });
    const before = await c.next((m) => m.ref === 'g');
    c.close();
    assert.equal(positions(before).filter((p) => inside(ROAD, p)).length, 0, `none inside at ${first - 1}`);
    await page.click('#live');
    s = await until(page, (x) => x.live && x.iteration === 10, 'live again');
    assert.equal(s.highlighted, inRoad);

    // prune now: the page and the daemon lose every node inside the zone
    const nodesBefore = s.nodes;
    await page.selectOption('#prune-zone', 'road');
    await page.click('#prune');
    s = await until(page, (x) => x.seq === snap.seq + 1, 'the snapshot after the prune');
    assert.equal(s.highlighted, 0, 'nothing highlighted after the prune');
    assert.deepEqual(s.inZones, { road: 0 });
    assert.ok(s.nodes <= nodesBefore - inRoad, `nodes ${nodesBefore} -> ${s.nodes}, ${inRoad} of them inside`);
    assert.equal(await highlightPixels(page), 0, 'no highlight colour drawn');
    snap = await serverSnapshot(d, run);
    assert.equal(positions(snap).filter((p) => inside(ROAD, p)).length, 0, 'the daemon holds none inside');
    assert.equal(positions(snap).length, s.nodes, 'the page holds what the daemon holds');
    assert.equal(typeof snap.stats[0].pruned, 'number');
    // the stem entered the zone once: its row stays, with no nodes inside now
    const after = statsRows(snap.stats);
    assert.deepEqual(after, [{ ...want[0], nodes: '0' }]);
    await page.waitForFunction(() => document.querySelector('#conflicts tbody tr')?.dataset.nodes === '0');
    assert.deepEqual(await pageRows(page), after);

    // a zone from the edit bar: two corners, from 0.5 m up to 4 m
    await page.selectOption('#obstacle-kind', 'zone');
    assert.ok(await page.isVisible('#zone-base'));
    await page.fill('#corner-a', '-2, -2');
    await page.fill('#corner-b', '-1, 2');
    await page.fill('#zone-base', '0.5');
    await page.fill('#obstacle-z', '4');
    await page.click('#add-obstacle');
    s = await until(page, (x) => x.zones.includes('zone1'), 'the new zone in the page');
    const drawn = s.drawnZones.find((z) => z.id === 'zone1');
    assert.ok(drawn && near(drawn.min, [-2, -2, 0.5]) && near(drawn.max, [-1, 2, 4]), JSON.stringify(drawn));
    assert.ok(!s.drawnObstacles.includes('zone1'));
    snap = await serverSnapshot(d, run);
    assert.deepEqual(snap.obstacles.find((o) => o.id === 'zone1'),
      { id: 'zone1', kind: 'zone', min: [-2, -2, 0.5], max: [-1, 2, 4] });
    assert.deepEqual(await page.$$eval('#prune-zone option', (os) => os.map((o) => o.value)), ['road', 'zone1']);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('the light slice is named by the run\'s sky: site light for a site\'s sky', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    // created in the page from a pasted scenario with a site's sky
    const site = { ...SITE, name: 'site sky', light: { sky: 'site', latitude: 48.1, samples: 16 } };
    await page.click('#paste summary');
    await page.fill('#scenario-text', JSON.stringify(site));
    await page.click('#scenario-load');
    await page.setChecked('#create-start', false);
    await page.click('#create-button');
    let s = await until(page, (x) => x.name === 'site sky' && x.seq >= 0, 'the site run');
    assert.equal(s.sky, 'site');
    assert.equal(await page.textContent('#light-sky'), 'site light (sun and sky)');
    await page.fill('#light-z', '2');
    await page.click('#light-show');
    s = await until(page, (x) => x.slice !== null, 'a light slice');
    assert.equal(s.slice.sky, 'site');
    assert.match(await page.textContent('#message'), /^site light \(sun and sky\) at /);
    assert.equal(await page.textContent('#legend-sky'), 'site light (sun and sky)');

    // its fork keeps the sky
    await page.fill('#fork-name', 'site sky fork');
    await page.click('#fork');
    s = await until(page, (x) => x.name === 'site sky fork' && x.seq >= 0, 'the fork');
    assert.equal(s.sky, 'site');

    // a ready scenario's run, created elsewhere under its title: the page looks the
    // scenario up, and its sky is the zenith
    const wall = scenario('wall.json');
    const run = await createRun(d, wall, wall.name);
    s = await watchRun(page, run);
    await page.waitForFunction(() => document.getElementById('light-sky').textContent === 'zenith light');
    assert.equal((await state(page)).sky, 'zenith');

    // back on the site run: known by its name for the tab's session, also after a reload
    const stats = page.waitForResponse((r) => r.url().endsWith('/api/runs/site%20sky/stats.csv'));
    await page.evaluate(() => { location.hash = '#run=site%20sky'; });
    await until(page, (x) => x.name === 'site sky' && x.sky === 'site', 'the site run again');
    await (await stats).finished();   // (a reload would cut the plots' fetch short)
    await page.reload();
    await until(page, (x) => x.connection === 'open' && x.name === 'site sky' && x.sky === 'site', 'after a reload');
    assert.equal(await page.textContent('#light-sky'), 'site light (sun and sky)');
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('a run in years: the calendar year on the timeline and the plots, crown diameter and height plotted, conflicts dated in years', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    const run = await createRun(d, yearsScenario(), 'years');
    let s = await watchRun(page, run);
    assert.equal(s.startYear, 2027);
    assert.equal(s.year, 2027);
    assert.equal(await page.textContent('#timeline-label'), '2027 (iteration 0) (live)');
    await page.fill('#step-count', '8');
    await page.click('#step');
    s = await until(page, (x) => x.iteration === 8, 'eight iterations', 120000 * SLOW);
    assert.equal(s.year, 2035);
    assert.equal(await page.textContent('#timeline-label'), '2035 (iteration 8) (live)');
    assert.match(await page.textContent('#view-info'), /^2035 \(iteration 8\) · /);

    // the plots: years on the x axis, and the crown's diameter and height; a run
    // in years has stands (docs/model.md, "Stands"): the self-thinning plot first
    await page.waitForFunction(() => window.sylva.plots().height?.iterations.length === 8);
    const { self_thinning: thinning, ...plots } = await page.evaluate(() => window.sylva.plots());
    assert.deepEqual(Object.keys(plots), ['height', 'dbh', 'crown_width', 'crown_diameter', 'crown_height',
      'leaf_area', 'crown_area', 'nodes', 'cap', 'canopy_cover']);
    const its = [1, 2, 3, 4, 5, 6, 7, 8];
    for (const key of Object.keys(plots)) {
      assert.equal(plots[key].axis, 'year', key);
      assert.deepEqual(plots[key].iterations, its, key);
      assert.deepEqual(plots[key].x, its.map((t) => 2027 + t), key);
      // the axis's labels are whole years without a thousands separator
      assert.ok(plots[key].ticks.includes('2030'), `${key}: ticks ${plots[key].ticks}`);
      assert.ok(plots[key].ticks.every((t) => /^\d{4}$/.test(t)), `${key}: ticks ${plots[key].ticks}`);
    }
    const snap = await serverSnapshot(d, run);
    assert.deepEqual(plots.crown_diameter.stems['old/0'].at(-1), snap.stats[1].crown_diameter);
    assert.deepEqual(plots.crown_height.stems['old/0'].at(-1), snap.stats[1].crown_height);
    assert.deepEqual(plots.leaf_area.stems['old/0'].at(-1), snap.stats[1].leaf_area);
    assert.equal(thinning.axis, 'QMD (cm)');
    assert.deepEqual([thinning.iterations.at(-1), thinning.x.at(-1), thinning.stems.stand.at(-1)],
      [8, snap.stand.qmd, snap.stand.stems_per_ha]);

    // the conflicts table: the year the old tree first grew into the lane; its row
    // shows that year from the store
    const first = snap.stats[1].zones.lane.first;
    assert.ok(first > 2027 && first <= 2035, `first ${first}`);
    assert.equal(await page.textContent('#conflicts-first'), 'first year');
    await page.waitForFunction(() => document.querySelectorAll('#conflicts tbody tr').length === 1);
    assert.deepEqual(await page.$$eval('#conflicts tbody td', (tds) => tds.map((td) => td.textContent)).then((c) => c.slice(0, 3)),
      ['old', 'lane', String(first)]);
    await page.click('#conflicts tbody tr[data-zone="lane"]');
    s = await until(page, (x) => !x.live && x.iteration === first - 2027, `the year ${first} from the store`);
    assert.equal(s.year, first);
    assert.equal(await page.textContent('#timeline-label'), `${first} (iteration ${first - 2027}) (stored)`);
    assert.ok(await page.locator('#conflicts tbody tr.selected[data-zone="lane"]').count() === 1);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('carbon and canopy plots: a library species beside one without carbon, gaps where a stem has none', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    const street = scenario('street.json', { iterations: 3 });
    street.species.oak = { preset: 'igm-fig11' };
    street.plants.push({ id: 'oak', species: 'oak', roots: [[-12, 0, 0]] });
    const run = await createRun(d, street, 'street');
    await watchRun(page, run);
    await page.click('#start');
    await until(page, (x) => x.status === 'finished' && x.iteration === 3, 'three iterations', 120000 * SLOW);
    await page.waitForFunction(() => window.sylva.plots().co2?.iterations.length === 3);
    const plots = await page.evaluate(() => window.sylva.plots());
    // (library species count in years: the run has stands, and the self-thinning plot)
    assert.deepEqual(Object.keys(plots), ['self_thinning', 'height', 'dbh', 'crown_width', 'crown_diameter',
      'crown_height', 'leaf_area', 'crown_area', 'co2', 'co2_sequestered', 'nodes', 'cap', 'canopy_cover']);
    const snap = await serverSnapshot(d, run);
    assert.equal(snap.iteration, 3);
    // the last point of every stem is the server's, null where the stem has none
    snap.stats.forEach((st) => {
      for (const key of ['crown_area', 'co2', 'co2_sequestered'])
        assert.deepEqual(plots[key].stems[`${st.plant}/${st.stem}`].at(-1), st[key] ?? null, `${key} of ${st.plant}`);
    });
    // a plane slower than the species' typical tree (its vigour, docs/model.md "Stands")
    // may stand still a season: its stock only grows, and in some season it does
    const sw = plots.co2_sequestered.stems['south-west/0'];
    assert.ok(plots.co2.stems['south-west/0'].every((v) => v > 0), `co2: ${plots.co2.stems['south-west/0']}`);
    assert.ok(sw.every((v) => v >= 0) && sw.some((v) => v > 0), `co2_sequestered: ${sw}`);
    for (const key of ['co2', 'co2_sequestered'])
      assert.deepEqual(plots[key].stems['oak/0'], [null, null, null], `${key} of the oak: gaps`);
    assert.ok(plots.crown_area.stems['oak/0'].every((v) => v !== null));
    assert.deepEqual(plots.canopy_cover.stems.site.at(-1), 100 * snap.canopy_cover);
    assert.ok(plots.canopy_cover.stems.site.every((v) => v > 0 && v <= 100), `${plots.canopy_cover.stems.site}`);
    assert.deepEqual(plots.canopy_cover.x, [2028, 2029, 2030]);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});
