// Prisms and the compass in headless Chromium against a real daemon: a building
// (an L with a courtyard, turned 30 degrees) and a clearance zone drawn as prisms
// (their meshes' bounds, triangles and volume, a ray down through the courtyard),
// the internodes inside the zone's footprint highlighted as the daemon counts them,
// the shade layer on the building's walls, and the compass turning with the camera.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { ROOT, SLOW, startDaemon, stopDaemon, serverSnapshot, cleanup, tempDir, gisSite } from '../server/harness.mjs';
import { launch, openViewer, until, createAndWatch } from './browser.mjs';
import { insideFootprint } from '../../web/zones.mjs';

const WEB = ['--web', join(ROOT, 'web')];
let browser;
before(async () => { browser = await launch(); });
after(async () => { await browser?.close(); });

// A point of the L's own frame turned 30 degrees about its corner, then moved to
// (-1.5, -5); 4 decimals, as the daemon writes them back.
const COS = Math.cos(Math.PI / 6), SIN = Math.sin(Math.PI / 6);
const place = ([x, y]) => [x * COS - y * SIN - 1.5, x * SIN + y * COS - 5].map((v) => Math.round(v * 1e4) / 1e4);
// The L: arms 3 m wide and 8 m long; the courtyard a 1 m square in its corner.
const L = [[0, 0], [8, 0], [8, 3], [3, 3], [3, 8], [0, 8]];
const COURT = [[1, 1], [2, 1], [2, 2], [1, 2]];
const HOUSE = { id: 'house', kind: 'prism', polygon: L.map(place), holes: [COURT.map(place)], z: [0, 6] };
// The tree east of the house; the zone a slanted quad over its east side, 1 to 6 m up.
const TREE = [3.5, -4];
const LANE = { id: 'lane', kind: 'zone', polygon: [[3.8, -7], [6.5, -7], [6.5, -1], [3.8, -3]], z: [1, 6] };
const SITE = {
  format: 'sylva.scenario/1',
  name: 'prisms',
  seed: 3,
  iterations: 40,
  world: { min: [-6, -8, 0], max: [8, 6, 8] },
  species: { oak: { preset: 'igm-fig11' } },
  plants: [{ id: 'tree', species: 'oak', roots: [[...TREE, 0]] }],
  obstacles: [HOUSE, LANE],
};

// A ring's area (shoelace), m².
const area = (ring) => Math.abs(ring.reduce((a, [x, y], i) => {
  const [u, v] = ring[(i + 1) % ring.length];
  return a + x * v - u * y;
}, 0)) / 2;
const bounds = (ring) => [0, 1].map((a) => [Math.min(...ring.map((p) => p[a])), Math.max(...ring.map((p) => p[a]))]);
const near = (a, b, tol = 1e-4) => a.length === b.length && a.every((v, i) => Math.abs(v - b[i]) < tol);
// Degrees in [0, 360).
const deg = (a) => ((a % 360) + 360) % 360;
const turned = (a, b) => Math.min(deg(a - b), 360 - deg(a - b));

test('prisms drawn: an L with a courtyard at 30 degrees and a zone, their meshes, the courtyard open, the zone\'s internodes', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    const run = await createAndWatch(d, page, SITE, 'prisms');
    const s = await until(page, (x) => x.run === run && x.drawnObstacles.length === 1, 'the obstacles drawn');
    assert.deepEqual(s.drawnObstacles, ['house']);
    assert.deepEqual(s.zones, ['lane']);

    // the house: a prism whose mesh spans its footprint's bounds and its height,
    // an extruded L with a hole (10 points: 10 triangles on each cap by ear
    // clipping, 2 on each of the 10 sides), of the footprint's area times its height
    const house = await page.evaluate(() => window.sylva.obstacleMesh('house'));
    const [[x0, x1], [y0, y1]] = bounds(HOUSE.polygon);
    assert.equal(house.name, 'obstacle:house');
    assert.equal(house.shape, 'prism');
    assert.ok(near(house.min, [x0, y0, 0]) && near(house.max, [x1, y1, 6]), JSON.stringify(house));
    assert.equal(house.triangles, 40);
    const floor = area(HOUSE.polygon) - area(HOUSE.holes[0]);
    assert.ok(Math.abs(floor - 38) < 1e-3, `the footprint's area ${floor}`);
    assert.ok(Math.abs(house.volume - floor * 6) < 1e-3, `volume ${house.volume}, want ${floor * 6}`);

    // a ray straight down meets the house's roof on an arm, but not in the
    // courtyard nor in the L's open corner
    const at = (p) => page.evaluate(([x, y]) => window.sylva.obstaclesAt(x, y), p);
    const arm = await at(place([0.5, 6]));
    assert.deepEqual(arm.map((h) => h.id), ['house']);
    assert.ok(Math.abs(arm[0].z - 6) < 1e-4, JSON.stringify(arm));
    assert.deepEqual(await at(place([1.5, 1.5])), [], 'the courtyard\'s centre');
    assert.deepEqual(await at(place([6, 6])), [], 'the L\'s open corner');

    // the zone: a prism drawn as a zone
    const lane = await page.evaluate(() => window.sylva.obstacleMesh('lane'));
    assert.equal(lane.name, 'zone:lane');
    assert.equal(lane.shape, 'prism');
    assert.ok(near(lane.min, [3.8, -7, 1]) && near(lane.max, [6.5, -1, 6]), JSON.stringify(lane));
    assert.ok(Math.abs(lane.volume - area(LANE.polygon) * 5) < 1e-3, `volume ${lane.volume}`);
    assert.deepEqual(s.drawnZones.map((z) => [z.id, z.shape]), [['lane', 'prism']]);
    const hit = await at([6, -6]);
    assert.deepEqual(hit.map((h) => h.id), ['lane']);
    assert.ok(Math.abs(hit[0].z - 6) < 1e-4);
    assert.deepEqual(await at([4, -2]), [], 'inside the zone\'s bounds, outside its footprint');

    // the crown grows into the zone: the page highlights the nodes inside its
    // footprint, as many as the daemon's stats count
    await page.fill('#step-count', '8');
    await page.click('#step');
    await until(page, (x) => x.iteration === 8, 'eight iterations', 120000 * SLOW);
    const snap = await serverSnapshot(d, run);
    const nodes = snap.plants.flatMap((p) => p.stems.flatMap((st) => st.nodes)).length;
    const inside = snap.stats[0].zones?.lane?.nodes ?? 0;
    assert.ok(inside > 0, `the tree grew into the zone: ${JSON.stringify(snap.stats[0].zones)}`);
    const t = await until(page, (x) => x.nodes === nodes, 'the page at the daemon\'s nodes');
    assert.deepEqual(t.inZones, { lane: inside });
    assert.equal(t.highlighted, inside);
    await page.waitForFunction(() => document.querySelectorAll('#conflicts tbody tr[data-zone="lane"]').length === 1);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('the shade layer on a prism: a quad on each wall of the L and its courtyard, off the wall, as long as it', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    await createAndWatch(d, page, { ...SITE, light: { sky: 'site', latitude: 48.1, samples: 16 } }, 'prisms');
    await page.click('#shade-toggle');
    const s = await until(page, (x) => x.shade.iteration === 0 && !x.shade.busy, 'the shade layer', 60000 * SLOW);
    // the walls by the daemon's names: the L's six edges in ring order, then the courtyard's four
    const walls = [...HOUSE.polygon.map((p, i, r) => [p, r[(i + 1) % r.length]]),
      ...HOUSE.holes[0].map((p, i, r) => [p, r[(i + 1) % r.length]])];
    const names = walls.map((_, i) => `shade:house:e${i}`);
    assert.deepEqual(s.shade.meshes.filter((m) => m.startsWith('shade:house:')), names);
    const quads = new Map((await page.evaluate(() => window.sylva.shadeQuads())).map((q) => [q.name, q]));
    walls.forEach(([[ax, ay], [bx, by]], i) => {
      const q = quads.get(names[i]), len = Math.hypot(bx - ax, by - ay);
      const [ux, uy] = [(bx - ax) / len, (by - ay) / len], [cx, cy, cz] = q.centre;
      const what = `${names[i]}: ${JSON.stringify(q)}`;
      // upright, along its edge, its middle 1 cm off the edge's middle, outside the
      // footprint (into the courtyard for its walls), as long and as high as the wall
      assert.ok(Math.abs(q.normal[2]) < 1e-6 && Math.abs(q.normal[0] * ux + q.normal[1] * uy) < 1e-5, what);
      assert.ok(Math.abs((cx - ax) * ux + (cy - ay) * uy - len / 2) < 0.03, what);
      assert.ok(Math.abs(Math.abs((cx - ax) * uy - (cy - ay) * ux) - 0.01) < 1e-4, what);
      assert.ok(!insideFootprint(HOUSE, cx, cy), what);
      assert.ok(Math.abs(q.width - len) < 0.05 && Math.abs(q.height - 6) < 1e-6 && Math.abs(cz - 3) < 1e-6, what);
    });
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

test('the compass points to +y and turns with the camera', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    await createAndWatch(d, page, SITE, 'prisms');
    assert.ok(await page.isVisible('#view svg.compass'));
    const compass = async () => {
      await page.evaluate(() => window.sylva.render());
      const [angle, transform] = await page.evaluate(() => [window.sylva.state().compass,
        document.querySelector('#view svg.compass > g').getAttribute('transform')]);
      assert.equal(transform, `rotate(${angle})`, 'the needle is drawn at the angle');
      return angle;
    };
    // north's direction on screen, degrees clockwise from up: the world's +y from
    // the view's target
    const screenNorth = () => page.evaluate(() => {
      const [ax, ay] = window.sylva.project(1, -1, 0), [bx, by] = window.sylva.project(1, 0, 0);
      return Math.atan2(bx - ax, -(by - ay)) * 180 / Math.PI;
    });

    // the 3D view (from the south-east): orbiting by 30 degrees anticlockwise
    // turns the needle 30 degrees clockwise, and back
    await page.evaluate(() => window.sylva.setView('persp'));
    const a0 = await compass();
    assert.ok(a0 > 0 && a0 < 90, `from the south-east, north lies up and to the right: ${a0}`);
    await page.evaluate(() => window.sylva.orbit(Math.PI / 6));
    assert.ok(turned(await compass(), a0 + 30) < 0.05);
    await page.evaluate(() => window.sylva.orbit(-Math.PI / 2));
    assert.ok(turned(await compass(), a0 - 60) < 0.05);

    // from the top the needle lies along the world's +y on screen, also turned
    await page.evaluate(() => window.sylva.setView('top'));
    assert.ok(turned(await compass(), 0) < 0.05);
    assert.ok(turned(await screenNorth(), 0) < 0.5);
    await page.evaluate(() => window.sylva.orbit(Math.PI / 6));
    const a1 = await compass();
    assert.ok(turned(a1, 30) < 0.05, `${a1}`);
    assert.ok(turned(await screenNorth(), a1) < 0.5, `north on screen ${await screenNorth()}, the needle ${a1}`);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// What `sylva site` writes from the GIS fixtures of tests/gis/data opens as it is: its
// buildings drawn as prisms, its zone, its five trees at their roots, the compass.
test('a scenario sylva site wrote from GIS layers: its buildings, zone and trees drawn, the compass', async () => {
  const dir = tempDir();
  const d = await startDaemon({ args: WEB });
  try {
    const site = gisSite(dir);
    const { page, errors } = await openViewer(browser, d.http);
    const run = await createAndWatch(d, page, site, 'gis-site');
    const s = await until(page, (x) => x.run === run && x.drawnObstacles.length === 4, 'the buildings drawn');
    assert.deepEqual(s.drawnObstacles.sort(), ['B1', 'B2', 'B3', 'B3/2']);
    assert.deepEqual(s.zones, ['zone-1']);
    assert.deepEqual(s.plants, site.plants.map((p) => p.id));
    assert.equal(s.year, 2027);
    // each tree stands at its root: its first node where the scenario puts it
    const nodes = await page.evaluate(() => window.sylva.skeleton().plants.map((p) =>
      [p.id, p.stems[0].nodes.find((n) => n[1] === -1)]));
    assert.equal(nodes.length, 5);
    for (const [id, n] of nodes) {
      const want = site.plants.find((p) => p.id === id).roots[0];
      assert.ok(Math.hypot(n[2] - want[0], n[3] - want[1]) < 1e-3, `${id}: ${n} against ${want}`);
    }
    assert.ok(await page.isVisible('#view svg.compass'));
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
    cleanup(dir);
  }
});
