// A measured tree's past on the timeline, in headless Chromium against a real
// daemon: a stored run of a scenario plant `from` an ITSMe TreeQSM file (aged 30,
// from 2027, grown 12 iterations by `sylva run`) opened in the page. The slider
// starts at the tree's earliest birth; scrubbing there shows the nodes born by
// then (fewer than the import's, drawn, and seen in a screenshot), iteration 0
// the import itself, and the last iteration more.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { spawnSync } from 'node:child_process';
import { copyFileSync, writeFileSync } from 'node:fs';
import {
  SYLVA, ROOT, SLOW, startDaemon, stopDaemon, exportSkeleton, cleanup, tempDir,
} from '../server/harness.mjs';
import { launch, openViewer, state, until, treePixels } from './browser.mjs';

const WEB = ['--web', join(ROOT, 'web')];
const QSM = join(ROOT, 'tests', 'import', 'data', 'non_buttressed_trees_single_qsm_tree_1_qsm.mat');
const START_YEAR = 2027;
let browser;
before(async () => { browser = await launch(); });
after(async () => { await browser?.close(); });

// As tests/import_tree/test_grow_on.py grows it, without the wall.
const MEASURED = {
  format: 'sylva.scenario/1',
  name: 'measured',
  seed: 3,
  iterations: 12,
  start_year: START_YEAR,
  world: { min: [-12, -12, 0], max: [12, 12, 30] },
  species: { plane: { preset: 'utdb:NoEast:PLAC' } },
  plants: [{ id: 'scanned', species: 'plane', roots: [[0, 0, 0]], from: { file: 'tree.mat', age: 30 } }],
};

function sylva(...args) {
  const r = spawnSync(SYLVA, args, { encoding: 'utf8', maxBuffer: 1 << 26 });
  if (r.status !== 0) throw new Error(`sylva ${args.join(' ')}: ${r.stderr}`);
  return r.stdout;
}

// Every node [id, parent, x, y, z, radius, birth] of a skeleton.
const nodesOf = (sk) => sk.plants.flatMap((p) => p.stems.flatMap((s) => s.nodes));

// Moves the timeline's slider to an iteration as a user's drag leaves it.
async function scrub(page, it) {
  await page.evaluate((v) => {
    const t = document.getElementById('timeline');
    t.value = String(v);
    t.dispatchEvent(new Event('input'));
  }, it);
}

test('a measured tree\'s past: the timeline starts at its earliest birth, with the nodes born by then', async () => {
  const dir = tempDir();
  let d;
  try {
    // the store: the scenario run beside its tree file, as `sylva run` stores it
    copyFileSync(QSM, join(dir, 'tree.mat'));
    writeFileSync(join(dir, 'measured.json'), JSON.stringify(MEASURED));
    const db = join(dir, 'runs.db');
    sylva('run', join(dir, 'measured.json'), '--db', db, '--quiet-progress');
    const imported = JSON.parse(sylva('import', join(dir, 'tree.mat'), '--age', '30', '-o', join(dir, 'imported.json')));
    const zero = nodesOf(exportSkeleton(db, 'measured', 0));
    assert.equal(zero.length, imported.nodes, 'iteration 0 is the import');
    const earliest = Math.min(...zero.map((n) => n[6]));
    assert.ok(earliest < 0, `a past before iteration 0 (earliest birth ${earliest})`);
    const bornBy = (T) => zero.filter((n) => n[6] <= T);
    const last = nodesOf(exportSkeleton(db, 'measured', 12)).length;

    d = await startDaemon({ dir, args: WEB });
    const { page, errors } = await openViewer(browser, d.http, { hash: '#run=measured' });
    let s = await until(page, (x) => x.name === 'measured' && x.seq >= 0 && x.iteration === 12, 'the stored run',
      60000 * SLOW);
    assert.equal(s.startYear, START_YEAR);
    assert.equal(s.nodes, last);
    const slider = () => page.$eval('#timeline', (t) => ({ min: Number(t.min), max: Number(t.max), value: Number(t.value) }));
    assert.deepEqual(await slider(), { min: earliest, max: 12, value: 12 }, 'the slider from the earliest birth to live');

    // iteration 0 from the store: the measured tree as imported
    await scrub(page, 0);
    s = await until(page, (x) => !x.live && x.iteration === 0, 'iteration 0 from the store');
    const atZero = s.nodes;
    assert.equal(atZero, imported.nodes, 'the import\'s nodes at iteration 0');
    assert.equal(s.drawnInstances, atZero);
    await page.evaluate(() => window.sylva.setView('front'));
    const pngZero = await page.locator('#view canvas').screenshot();

    // the earliest stage: the nodes born by then, fewer, drawn, in its calendar year
    await scrub(page, earliest);
    s = await until(page, (x) => !x.live && x.iteration === earliest, `the stage at ${earliest}`);
    const young = bornBy(earliest);
    console.log(`# slider min ${earliest}; drawn ${s.drawnInstances} at ${earliest}, ${atZero} at 0, ${last} at 12`);
    assert.ok(s.nodes < atZero, `fewer nodes at ${earliest} (${s.nodes} < ${atZero})`);
    assert.equal(s.nodes, young.length, `the nodes born by ${earliest}`);
    assert.equal(s.drawnInstances, s.nodes, 'each of them drawn');
    assert.equal(s.year, START_YEAR + earliest);
    assert.equal(await page.textContent('#timeline-label'),
      `${START_YEAR + earliest} (iteration ${earliest}) (stored)`);
    assert.equal((await slider()).value, earliest);
    // the same nodes where they are at 0, radii by the pipe model: none thicker,
    // the base thinner (fewer tips above it)
    const shown = nodesOf(await page.evaluate(() => window.sylva.skeleton()));
    assert.deepEqual(shown.map((n) => n[0]), young.map((n) => n[0]));
    const byId = new Map(zero.map((n) => [n[0], n]));
    for (const n of shown) {
      const z = byId.get(n[0]);
      assert.deepEqual(n.slice(1, 5).map(Math.fround), z.slice(1, 5).map(Math.fround), `node ${n[0]}'s place`);
      assert.equal(n[6], z[6]);
      assert.ok(n[5] > 0 && n[5] <= Math.fround(z[5]), `node ${n[0]}: radius ${n[5]} of ${z[5]} at 0`);
    }
    assert.ok(shown[0][5] < zero[0][5], `the base thinner (${shown[0][5]} < ${zero[0][5]})`);
    // a stage the store does not hold: no fork, no exports
    assert.ok(await page.isDisabled('#fork'));
    assert.equal(await page.getAttribute('#export-skeleton', 'href'), null);

    // a screenshot from the front: the young tree is drawn in its colour up its
    // trunk, and nothing where the measured crown is, which it has not grown yet
    await page.evaluate(() => window.sylva.setView('front'));
    const png = await page.locator('#view canvas').screenshot();
    const top = young.reduce((a, n) => (n[4] > a[4] ? n : a));
    const [bx, by] = await page.evaluate(() => window.sylva.project(0, 0, 0));
    const [tx, ty] = await page.evaluate(([x, y, z]) => window.sylva.project(x, y, z), top.slice(2, 5));
    const trunk = await treePixels(page, png, [Math.min(bx, tx) - 15, ty, Math.max(bx, tx) + 15, by]);
    const crown = zero.filter((n) => n[4] > top[4] + 3);
    assert.ok(crown.length > 0, 'the measured tree reaches higher');
    const [cx, cy] = await page.evaluate(([x, y, z]) => window.sylva.project(x, y, z), crown.at(-1).slice(2, 5));
    const rect = [cx - 10, cy - 10, cx + 10, cy + 10];
    const crownThen = await treePixels(page, png, rect), crownAtZero = await treePixels(page, pngZero, rect);
    console.log(`# tree pixels at ${earliest}: trunk ${trunk}, crown ${crownThen} (at 0: ${crownAtZero})`);
    assert.ok(trunk > 50, `tree-coloured pixels up the young trunk: ${trunk}`);
    assert.ok(crownAtZero > 0, `the crown drawn at iteration 0: ${crownAtZero}`);
    assert.equal(crownThen, 0, `no crown yet at ${earliest}`);

    // a stage between: the nodes born by then
    const mid = Math.round(earliest / 2);
    await scrub(page, mid);
    s = await until(page, (x) => !x.live && x.iteration === mid, `the stage at ${mid}`);
    assert.equal(s.nodes, bornBy(mid).length);
    assert.ok(s.nodes >= young.length && s.nodes <= atZero);

    // the last iteration: more than at 0; live again, with fork and exports
    await scrub(page, 12);
    s = await until(page, (x) => x.live && x.iteration === 12, 'live at the last iteration');
    assert.ok(s.nodes > atZero, `more nodes at 12 (${s.nodes} > ${atZero})`);
    assert.equal(s.drawnInstances, s.nodes);
    assert.ok(!(await page.isDisabled('#fork')));
    assert.match(await page.getAttribute('#export-skeleton', 'href'), /format=skeleton&iteration=12$/);
    assert.deepEqual(await slider(), { min: earliest, max: 12, value: 12 });
    assert.equal((await state(page)).nodes, last);
    assert.deepEqual(errors, []);
  } finally {
    if (d) await stopDaemon(d);
    cleanup(dir);
  }
});
