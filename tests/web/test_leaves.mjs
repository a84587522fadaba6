// The viewer's leaves in headless Chromium against a real daemon: one card per
// leaf of the server's snapshot (leaf-bearing nodes x leaf_density), leaf-coloured
// pixels in the crown, the toggle to the bare skeleton and back, the crown's
// shadow on the ground and the sky behind, kept up to date by deltas.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { ROOT, SLOW, startDaemon, stopDaemon, connect, scenario, cleanup, serverSnapshot } from '../server/harness.mjs';
import { launch, openViewer, until, treePixels, pixels, countWhere, createAndWatch } from './browser.mjs';

const WEB = ['--web', join(ROOT, 'web')];
const LEAF = '#d0208c';   // a leaf colour that no branch, ground or sky has
let browser;
before(async () => { browser = await launch(); });
after(async () => { await browser?.close(); });

// A small tree in the open: the wall scenario without its wall, leaves of LEAF.
function leafy() {
  const s = scenario('wall.json', { name: 'leafy', iterations: 30, obstacles: [] });
  s.species = { broadleaf: { preset: 'igm-fig11', leaf_colour: LEAF, leaf_size: 0.2, leaf_density: 5 } };
  return s;
}

// LEAF lit or shaded: red and blue well above green.
const isLeaf = (r, g, b) => r > 1.6 * g + 20 && b > 1.2 * g + 10;
const leafPixels = (img, rect = null) => countWhere(img, rect, isLeaf);

const shot = (page) => page.locator('#view canvas').screenshot();

test('leaves: counted, in the crown, off and on, their shadow, kept by deltas', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    const c = await connect(d.url);
    c.send({ type: 'create', scenario: leafy(), name: 'leafy', start: false, id: 'c' });
    const { run } = await c.type('created');
    await page.waitForSelector(`#runs tr[data-run="${run}"]`, { timeout: 10000 * SLOW });
    await page.click(`#runs tr[data-run="${run}"]`);
    await until(page, (s) => s.run === run && s.seq >= 0, 'the run');
    c.send({ type: 'control', run, action: 'step', count: 13, id: 's' });
    let s = await until(page, (x) => x.iteration === 13, '13 iterations', 60000 * SLOW);

    // one card per leaf of the server's snapshot
    let snap = await serverSnapshot(d, run);
    const { leaf_density: density, leaf_colour: colour } = snap.foliage[0];
    assert.equal(colour, LEAF);
    assert.equal(density, 5);
    assert.ok(snap.leaves.length > 100, `leaf-bearing nodes: ${snap.leaves.length}`);
    assert.ok(snap.leaves.every(([, n]) => n === density));
    s = await until(page, (x) => x.drawnLeaves === snap.leaves.length * density, 'the leaves drawn');
    assert.equal(s.leaves, true);
    assert.equal(s.leafStride, 1);
    assert.equal(s.leafTotal, snap.leaves.length * density);

    // from the front: leaf-coloured pixels in the crown (around the leaf-bearing
    // nodes), next to none away from it, and the sky's blue above
    await page.evaluate(() => window.sylva.setView('front'));
    const nodes = new Map(snap.plants[0].stems[0].nodes.map((n) => [n[0], n]));
    const xs = [], zs = [];
    for (const [id] of snap.leaves) {
      xs.push(nodes.get(id)[2]);
      zs.push(nodes.get(id)[4]);
    }
    const [left, top] = await page.evaluate(([x, z]) => window.sylva.project(x, 0, z), [Math.min(...xs) - 0.7, Math.max(...zs) + 0.7]);
    const [right, bottom] = await page.evaluate(([x, z]) => window.sylva.project(x, 0, z), [Math.max(...xs) + 0.7, Math.min(...zs) - 0.7]);
    let img = await pixels(page, await shot(page));
    const crown = leafPixels(img, [left, top, right, bottom]);
    const all = leafPixels(img);
    assert.ok(crown > 300, `leaf pixels in the crown: ${crown}`);
    assert.ok(all - crown <= 0.02 * all, `leaf pixels outside the crown: ${all - crown} of ${all}`);
    const i0 = (5 * img.w + 5) * 4;
    assert.ok(img.d[i0 + 2] > img.d[i0] + 20 && img.d[i0 + 2] >= img.d[i0 + 1], `sky blue at the top left: ${img.d.slice(i0, i0 + 3)}`);

    // the toggle: the bare skeleton (no leaf pixels, the branches still there)
    await page.click('#leaves-toggle');
    s = await until(page, (x) => !x.leaves && x.drawnLeaves === 0, 'leaves off');
    assert.equal(await page.getAttribute('#leaves-toggle', 'aria-pressed'), 'false');
    await page.evaluate(() => window.sylva.render());
    let png = await shot(page);
    img = await pixels(page, png);
    assert.equal(leafPixels(img), 0, 'no leaf pixels with leaves off');
    assert.ok(await treePixels(page, png) > 100, 'the branches are drawn');
    // grows on with leaves off, then L brings them back up to date
    c.send({ type: 'control', run, action: 'step', count: 2, id: 's2' });
    await until(page, (x) => x.iteration === 15, 'two more iterations', 60000 * SLOW);
    await page.locator('#view canvas').click({ position: { x: 5, y: 300 } });
    await page.keyboard.press('l');
    snap = await serverSnapshot(d, run);
    s = await until(page, (x) => x.leaves && x.drawnLeaves === snap.leaves.length * density, 'leaves on again');
    await page.evaluate(() => window.sylva.render());
    assert.ok(leafPixels(await pixels(page, await shot(page))) > 300, 'leaf pixels again');

    // deltas with leaves on: still one card per leaf of the server's
    c.send({ type: 'control', run, action: 'step', count: 3, id: 's3' });
    await until(page, (x) => x.iteration === 18, 'three more iterations', 60000 * SLOW);
    snap = await serverSnapshot(d, run);
    s = await until(page, (x) => x.drawnLeaves === snap.leaves.length * density, 'the leaves after deltas');
    const t = await page.evaluate(() => window.sylva.timings());
    assert.ok(t.leafMs.length > 0 && t.applyMs.length >= 18);

    // the crown's shadow: the ground under the leaf-bearing nodes, seen from the
    // 3D view, is darker with the leaves on than off
    await page.evaluate(() => window.sylva.setView('persp'));
    const ground = [];
    for (const [id] of snap.leaves) {
      const n = snap.plants[0].stems[0].nodes.find((e) => e[0] === id);
      if (n) ground.push(await page.evaluate(([x, y]) => window.sylva.project(x, y, 0), [n[2], n[3]]));
    }
    const brightness = async () => {
      await page.evaluate(() => window.sylva.render());
      const im = await pixels(page, await shot(page));
      const out = [];
      for (const [x, y] of ground) {
        const i = (Math.round(y) * im.w + Math.round(x)) * 4;
        const [r, g, b] = im.d.slice(i, i + 3);
        // the beige ground only (not a leaf or a branch in front of it)
        out.push(r >= g && g >= b && r - b > 8 && !isLeaf(r, g, b) ? r + g + b : null);
      }
      return out;
    };
    const lit = await brightness();
    await page.evaluate(() => window.sylva.setLeaves(false));
    const bare = await brightness();
    await page.evaluate(() => window.sylva.setLeaves(true));
    const pairs = lit.map((v, i) => [v, bare[i]]).filter(([a, b]) => a !== null && b !== null);
    assert.ok(pairs.length > 20, `ground points seen: ${pairs.length}`);
    const shaded = pairs.filter(([a, b]) => a < 0.85 * b).length;
    assert.ok(shaded > pairs.length / 3, `ground points in shade: ${shaded} of ${pairs.length}`);
    c.close();
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});

// Leaf-coloured: green well above red and blue (the street's London planes, lit or
// shaded).
const isGreen = (r, g, b) => g > r + 10 && g > b + 10;

test('leaves behind a see-through facade keep their colour: the street from the south', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    const run = await createAndWatch(d, page, scenario('street.json', { iterations: 8 }), 'street', { start: true });
    await until(page, (x) => x.run === run && x.status === 'finished' && x.drawnLeaves > 1000 && !x.leafPending,
      'the street grown, its leaves drawn', 120000 * SLOW);
    // south of the south facade (y -8 to -7, 12 m high), looking north: it stands in
    // front of every crown
    await page.evaluate(() => window.sylva.lookAt([0, -30, 5], [0, 0, 3]));
    const [[x0, y0], [x1, y1]] = await page.evaluate(() => [window.sylva.project(-14, -8, 12), window.sylva.project(14, -8, 0)]);
    const facade = [x0, y0, x1, y1];
    const green = async () => {
      await page.evaluate(() => window.sylva.render());
      return countWhere(await pixels(page, await shot(page)), facade, isGreen);
    };
    const behind = await green();
    await page.evaluate(() => window.sylva.setObstacleVisible('facade-south', false));
    const bare = await green();
    await page.evaluate(() => window.sylva.setObstacleVisible('facade-south', true));
    assert.ok(bare > 1000, `leaf pixels without the facade: ${bare}`);
    assert.ok(behind > 0.9 * bare, `leaf pixels behind the facade: ${behind}, without it: ${bare}`);
    assert.deepEqual(errors, []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});
