// The compare view, in headless Chromium against a real daemon: a store made by
// the real `sylva sweep` (the street scenario, two species, ten iterations from
// 2027), its runs grouped in the run list under the sweep's name with their axes,
// two of them side by side. The shared slider moves both views to its year (their
// iterations and internodes, against `sylva export`), the pictures of the two
// differ and each changes with the year, orbiting one view moves the other, each
// run has its own conflicts table, a conflicts row moves the shared slider, and
// "compare species" opens the sweep's species; the sweep's row links its report
// (HTML, CSV, PDF) at the daemon's route, downloaded with the token when reading
// needs one. And, in node, the pure helpers of
// the run list's sweeps and the shared slider.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { createHash } from 'node:crypto';
import { join } from 'node:path';
import { spawnSync } from 'node:child_process';
import { readFileSync, writeFileSync } from 'node:fs';
import {
  SYLVA, ROOT, SLOW, startDaemon, stopDaemon, connect, exportSkeleton, cleanup, tempDir,
} from '../server/harness.mjs';
import { launch, openViewer, httpGet } from './browser.mjs';
import { groupRuns, axisLabel, axesOf, speciesComparison } from '../../web/sweeps.mjs';
import { sharedScale, iterationAt, scaleLabel } from '../../web/compare_scale.mjs';
import { conflictRows } from '../../web/zones.mjs';

const WEB = ['--web', join(ROOT, 'web')];
const SWEEP = 'street species';
const SPECIES = ['utdb:NoEast:PLAC', 'utdb:NoEast:GIBI'];
const START_YEAR = 2027;   // scenarios/street.json's
const ITERATIONS = 10;
const PLAN = {
  format: 'sylva.sweep/1',
  name: SWEEP,
  scenario: join(ROOT, 'scenarios', 'street.json'),
  axes: { species: { 'street-tree': SPECIES }, seed: [1], variants: { 'as built': [] } },
};

let browser;
before(async () => { browser = await launch(); });
after(async () => { await browser?.close(); });

// ---- the pure helpers --------------------------------------------------------

test('the run list groups a sweep\'s runs by position where its first run is', () => {
  const runs = [
    { run: 1, name: 'alone' },
    { run: 2, name: 's1', sweep: 's', position: 1, axes: { 'species/t': 'B', seed: '1' } },
    { run: 3, name: 'other', sweep: 'o', position: 0, axes: { seed: '5' } },
    { run: 4, name: 's0', sweep: 's', position: 0, axes: { 'species/t': 'A', seed: '1' } },
    { run: 5, name: 'late' },
  ];
  assert.deepEqual(groupRuns(runs).map((g) => [g.sweep, g.runs.map((r) => r.run)]),
    [[null, [1]], ['s', [4, 2]], ['o', [3]], [null, [5]]]);
  assert.deepEqual(groupRuns([]), []);
  assert.equal(axisLabel('species/street-tree', 'utdb:NoEast:PLAC'), 'street-tree: utdb:NoEast:PLAC');
  assert.equal(axisLabel('species/t', '{"preset":"igm-fig11"}'), 't: igm-fig11');
  assert.equal(axisLabel('species/t', '{"preset":"igm-fig11","alpha":2}'), 't: igm-fig11 (changed)');
  assert.equal(axisLabel('species/t', '{"alpha":2}'), 't: own parameters');
  assert.equal(axisLabel('seed', '7'), 'seed 7');
  assert.equal(axisLabel('variant', 'as built'), 'as built');
  assert.deepEqual(axesOf({ run: 1 }), []);
  assert.deepEqual(axesOf(runs[1]).map((a) => a.label), ['t: B', 'seed 1']);
});

test('"compare species" takes the runs that differ in species alone', () => {
  const run = (position, species, seed) => ({ run: position + 1, position, axes: { 'species/t': species, seed } });
  // species x seed, species fastest: the first seed's species
  const sweep = [run(0, 'A', '1'), run(1, 'B', '1'), run(2, 'C', '1'), run(3, 'A', '2'), run(4, 'B', '2'),
    run(5, 'C', '2')];
  assert.deepEqual(speciesComparison(sweep).map((r) => r.run), [1, 2, 3]);
  assert.deepEqual(speciesComparison(sweep, 2).map((r) => r.run), [1, 2]);
  // seeds only, or one species: nothing to compare
  assert.deepEqual(speciesComparison([{ run: 1, axes: { seed: '1' } }, { run: 2, axes: { seed: '2' } }]), []);
  assert.deepEqual(speciesComparison([run(0, 'A', '1'), run(1, 'A', '2')]), []);
});

test('the shared slider: calendar years when every run has one, else iterations', () => {
  const a = { startYear: 2027, earliest: 0, last: 10 }, b = { startYear: 2030, earliest: -5, last: 4 };
  let s = sharedScale([a, b]);
  assert.deepEqual(s, { years: true, offsets: [2027, 2030], min: 2025, max: 2037 });
  assert.equal(iterationAt(s, 0, a, 2031), 4);
  assert.equal(iterationAt(s, 1, b, 2031), 1);
  assert.equal(iterationAt(s, 1, b, 2037), 4, 'a run past its last shows its last');
  assert.equal(iterationAt(s, 0, a, 2025), 0, 'and before its first its first');
  assert.equal(iterationAt(s, 1, b, 2025), -5, 'a measured tree\'s past');
  assert.equal(scaleLabel(s, 2031), '2031');
  s = sharedScale([a, { startYear: null, earliest: 0, last: 3 }]);
  assert.deepEqual(s, { years: false, offsets: [0, 0], min: 0, max: 10 });
  assert.equal(scaleLabel(s, 3), 'iteration 3');
});

// ---- in the browser -----------------------------------------------------------

function sylva(...args) {
  const r = spawnSync(SYLVA, args, { encoding: 'utf8', maxBuffer: 1 << 26 });
  if (r.status !== 0) throw new Error(`sylva ${args.join(' ')}: ${r.stderr}`);
  return r.stdout;
}

const nodeCount = (sk) => sk.plants.reduce((n, p) => n + p.stems.reduce((m, s) => m + s.nodes.length, 0), 0);
const hash = (dataUrl) => createHash('sha256').update(dataUrl).digest('hex');
const compareState = (page) => page.evaluate(() => window.sylva.compare());
const images = async (page) => (await page.evaluate(() => window.sylva.compareImages())).map(hash);

// Waits until the compare view's state satisfies pred.
/* The test plan swept into DIR/runs.db; its path. */
function sweepInto(dir) {
  writeFileSync(join(dir, 'plan.json'), JSON.stringify(PLAN));
  const db = join(dir, 'runs.db');
  sylva('sweep', join(dir, 'plan.json'), '--db', db, '--iterations', String(ITERATIONS), '--jobs', '2',
    '--quiet-progress');
  return db;
}

async function untilCompare(page, pred, what, ms = 60000 * SLOW) {
  const end = Date.now() + ms;
  for (;;) {
    const s = await compareState(page);
    if (pred(s)) return s;
    if (Date.now() > end) throw new Error(`timed out waiting for ${what}; state ${JSON.stringify(s)}`);
    await new Promise((r) => setTimeout(r, 100));
  }
}

// Both panes show these iterations, with nothing left to fetch.
const showing = (page, its, what) => untilCompare(page,
  (s) => s.pending === 0 && s.panes.length === its.length && s.panes.every((p, i) => p.iteration === its[i]), what);

// Moves the shared slider as a user's drag leaves it.
async function slide(page, value) {
  await page.evaluate((v) => {
    const t = document.getElementById('compare-slider');
    t.value = String(v);
    t.dispatchEvent(new Event('input'));
  }, value);
}

// The rows of a stored iteration's conflicts, as the page works them out.
async function storedRows(d, run, iteration) {
  const c = await connect(d.url);
  c.send({ type: 'get', run, iteration, id: 'g' });
  const snap = await c.next((m) => m.ref === 'g', 60000);
  c.close();
  assert.equal(snap.type, 'snapshot', JSON.stringify(snap).slice(0, 300));
  return conflictRows(snap.stats);
}

test('two runs of a sweep side by side: one slider, one camera, their own conflicts', async () => {
  const dir = tempDir();
  let d;
  try {
    const db = sweepInto(dir);

    d = await startDaemon({ dir, args: WEB });
    // the run list says each run's sweep, position and axes
    // (in the order the sweep's processes created them: by position here)
    const listed = JSON.parse((await httpGet(`${d.http}/api/runs`)).body.toString())
      .sort((x, y) => x.position - y.position);
    assert.equal(listed.length, 2);
    listed.forEach((r, i) => {
      assert.equal(r.sweep, SWEEP);
      assert.equal(r.position, i);
      assert.deepEqual(r.axes, { 'species/street-tree': SPECIES[i], seed: '1', variant: 'as built' });
      assert.equal(r.status, 'finished');
      assert.equal(r.iteration, ITERATIONS);
    });
    const [a, b] = listed;
    const at = (r, it) => nodeCount(exportSkeleton(db, r.name, it));
    const nodes = { a3: at(a, 3), a10: at(a, 10), b3: at(b, 3), b10: at(b, 10) };
    // planted trees of a species in years have a past (their nursery years, born
    // below 0): the slider starts at the earliest, as the timeline does
    const births = (r) => exportSkeleton(db, r.name, 0).plants
      .flatMap((p) => p.stems.flatMap((st) => st.nodes.map((n) => n[6])));
    const first = [Math.min(0, ...births(a)), Math.min(0, ...births(b))];
    const earliest = Math.min(...first);
    console.log(`# internodes: ${JSON.stringify(nodes)}; earliest birth ${earliest}`);
    assert.notEqual(nodes.a10, nodes.b10, 'two species grow differently');

    const { page, errors } = await openViewer(browser, d.http, { width: 1400, height: 900 });

    // the run list: the sweep's row, then its runs by their axes
    await page.waitForSelector(`#runs tr.sweep[data-sweep="${SWEEP}"]`, { timeout: 10000 * SLOW });
    const list = await page.$$eval('#runs tbody tr', (trs) => trs.map((tr) => ({
      sweep: tr.dataset.sweep ?? null, run: tr.dataset.run ? Number(tr.dataset.run) : null,
      head: tr.classList.contains('sweep') ? tr.querySelector('.sweep-name').textContent : null,
      axes: [...tr.querySelectorAll('.axis')].map((c) => c.textContent),
      actions: tr.querySelector('.sweep-actions')
        ? [...tr.querySelector('.sweep-actions').children].map((c) => c.textContent) : null,
    })));
    assert.deepEqual(list, [
      { sweep: SWEEP, run: null, head: SWEEP, axes: [], actions: ['compare species', 'report HTML CSV PDF'] },
      { sweep: SWEEP, run: a.run, head: null, axes: [`street-tree: ${SPECIES[0]}`, 'seed 1', 'as built'], actions: null },
      { sweep: SWEEP, run: b.run, head: null, axes: [`street-tree: ${SPECIES[1]}`, 'seed 1', 'as built'], actions: null },
    ]);

    // the sweep's report: a link per format to the daemon's route, each served
    // (the CSV as `sylva report` writes it), and a click downloads it
    const reportLinks = await page.$$eval(`#runs tr.sweep[data-sweep="${SWEEP}"] .sweep-report a.report`,
      (as) => as.map((a) => ({ format: a.dataset.format, href: a.getAttribute('href'), url: a.href,
        download: a.hasAttribute('download') })));
    const route = (ext) => `api/sweeps/${encodeURIComponent(SWEEP)}/report.${ext}`;
    assert.deepEqual(reportLinks, ['html', 'csv', 'pdf'].map((ext) => ({ format: ext, href: route(ext),
      url: `${d.http}/${route(ext)}`, download: true })));
    assert.equal(route('html'), 'api/sweeps/street%20species/report.html');
    const reportTypes = { html: /^text\/html/, csv: /^text\/csv/, pdf: /^application\/pdf/ };
    for (const { format, url } of reportLinks) {
      const r = await httpGet(url);
      assert.equal(r.status, 200, `${format}: ${r.body}`);
      assert.match(r.headers['content-type'], reportTypes[format]);
      assert.equal(r.headers['content-disposition'], `attachment; filename="street_species-report.${format}"`);
      if (format === 'csv') {
        const out = join(dir, 'report.csv');
        sylva('report', '--db', db, '--sweep', SWEEP, '-o', out);
        assert.ok(r.body.equals(readFileSync(out)), 'the CSV of `sylva report`');
      }
    }
    const [download] = await Promise.all([page.waitForEvent('download'),
      page.click(`#runs tr.sweep[data-sweep="${SWEEP}"] a.report[data-format="pdf"]`)]);
    assert.equal(download.suggestedFilename(), 'street_species-report.pdf');
    assert.equal(download.url(), `${d.http}/${route('pdf')}`);
    assert.equal(await download.failure(), null);
    assert.ok(await page.isVisible('#view'), 'the page stays where it was');

    // tick both runs and compare them
    assert.ok(await page.isDisabled('#compare-button'));
    await page.check(`#runs tr[data-run="${a.run}"] input.pick`);
    assert.ok(await page.isDisabled('#compare-button'), 'one run is not a comparison');
    await page.check(`#runs tr[data-run="${b.run}"] input.pick`);
    await page.click('#compare-button');
    let s = await showing(page, [ITERATIONS, ITERATIONS], 'both runs at their last iteration');
    assert.ok(s.open);
    assert.ok(await page.isHidden('#view'), 'the compare view is over the single view');
    assert.deepEqual(s.panes.map((p) => p.run), [a.run, b.run]);
    assert.deepEqual({ years: s.years, min: s.min, max: s.max, value: s.value },
      { years: true, min: START_YEAR + earliest, max: START_YEAR + ITERATIONS, value: START_YEAR + ITERATIONS });
    assert.equal(await page.textContent('#compare-unit'), 'Year');
    assert.deepEqual(s.panes.map((p) => [p.year, p.nodes, p.drawn]),
      [[START_YEAR + 10, nodes.a10, nodes.a10], [START_YEAR + 10, nodes.b10, nodes.b10]]);
    assert.equal(s.panes[0].info, `${START_YEAR + 10} (iteration 10) · ${nodes.a10.toLocaleString('en')} internodes`);
    assert.deepEqual(s.panes[1].axes, b.axes);
    // the same camera, and two different pictures
    assert.deepEqual(s.panes[0].camera, s.panes[1].camera);
    const [a10, b10] = await images(page);
    assert.notEqual(a10, b10, 'two species, two pictures');

    // each run's own conflicts: its last iteration's, as the page works them out
    const rows = [await storedRows(d, a.run, 10), await storedRows(d, b.run, 10)];
    assert.ok(rows[0].length > 0 && rows[1].length > 0, 'the street\'s trees grow into its clearances');
    assert.notDeepEqual(rows[0], rows[1]);
    assert.deepEqual(s.panes.map((p) => p.conflicts), rows);
    assert.deepEqual(s.panes.map((p) => p.conflictRows), rows.map((r) => r.length));

    // the shared slider to 2030: both views at iteration 3
    await slide(page, START_YEAR + 3);
    s = await showing(page, [3, 3], 'both runs at 2030');
    assert.equal(s.label, String(START_YEAR + 3));
    assert.deepEqual(s.panes.map((p) => [p.year, p.nodes, p.drawn]),
      [[START_YEAR + 3, nodes.a3, nodes.a3], [START_YEAR + 3, nodes.b3, nodes.b3]]);
    assert.ok(nodes.a3 < nodes.a10 && nodes.b3 < nodes.b10, 'fewer internodes in 2030');
    const [a3, b3] = await images(page);
    assert.notEqual(a3, a10, 'the first view\'s picture moved with the slider');
    assert.notEqual(b3, b10, 'the second view\'s picture moved with the slider');
    assert.notEqual(a3, b3);
    // the conflicts stay those of the last iteration
    assert.deepEqual((await compareState(page)).panes.map((p) => p.conflicts), rows);
    // and the trees' past, as the timeline shows it (stages of iteration 0)
    await slide(page, START_YEAR + earliest);
    s = await showing(page, first, `both runs in ${START_YEAR + earliest}`);
    assert.ok(s.panes.every((p) => p.nodes > 0 && p.drawn === p.nodes), 'a young tree drawn in each');
    await slide(page, START_YEAR + 3);
    s = await showing(page, [3, 3], 'both runs at 2030 again');
    assert.deepEqual(await images(page), [a3, b3], 'the same pictures at the same year');

    // orbiting the first view moves the second the same way
    const box = await page.locator('#compare-grid .pane').first().locator('canvas').boundingBox();
    const before = s.panes[0].camera;
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
    await page.mouse.down();
    await page.mouse.move(box.x + box.width / 2 + 120, box.y + box.height / 2 + 30, { steps: 8 });
    await page.mouse.up();
    s = await compareState(page);
    assert.notDeepEqual(s.panes[0].camera, before, 'the dragged view orbited');
    assert.deepEqual(s.panes[1].camera, s.panes[0].camera, 'the other view with it');
    assert.deepEqual(s.panes[1].target, s.panes[0].target);
    const [a3o, b3o] = await images(page);
    assert.notEqual(a3o, a3);
    assert.notEqual(b3o, b3, 'the other view\'s picture turned too');
    // and a preset camera for both
    await page.click('[data-compare-view="front"]');
    s = await compareState(page);
    assert.deepEqual(s.panes.map((p) => p.view), ['front', 'front']);
    assert.deepEqual(s.panes[1].camera, s.panes[0].camera);

    // a conflicts row of the second run: the slider to the year it first grew
    // into that zone, both views with it
    const row = rows[1][0];
    await page.click(`#compare-grid .pane:nth-child(2) .pane-zone-conflicts tbody tr:nth-child(1)`);
    s = await showing(page, [row.first - START_YEAR, row.first - START_YEAR], `both runs at ${row.first}`);
    assert.equal(s.value, row.first);
    assert.equal(await page.getAttribute('#compare-grid .pane:nth-child(2) .pane-zone-conflicts tbody tr:nth-child(1)',
      'class'), 'selected');

    // Close: the single view again; "compare species" ticks and opens the sweep's species
    await page.click('#compare-close');
    assert.ok(await page.isVisible('#view'));
    assert.ok(await page.isHidden('#compare'));
    await page.uncheck(`#runs tr[data-run="${a.run}"] input.pick`);
    await page.click(`#runs tr.sweep[data-sweep="${SWEEP}"] .compare-species`);
    s = await showing(page, [ITERATIONS, ITERATIONS], 'the sweep\'s species at their last iteration');
    assert.deepEqual(s.panes.map((p) => p.run), [a.run, b.run]);
    assert.equal(s.value, START_YEAR + ITERATIONS);
    assert.ok(await page.isChecked(`#runs tr[data-run="${a.run}"] input.pick`));
    assert.deepEqual(s.panes.map((p) => p.view), ['persp', 'persp'], 'a new comparison starts from the 3D camera');
    assert.deepEqual(await images(page), [a10, b10], 'the same pictures as the first time');
    // a click on a run in the list watches it in the single view
    await page.click(`#runs tr[data-run="${b.run}"] td:nth-child(2)`);
    await page.waitForFunction((run) => window.sylva.state().run === run, b.run);
    assert.ok(await page.isHidden('#compare'));
    assert.ok(await page.isVisible('#view'));

    assert.deepEqual(errors, []);
    await page.close();
  } finally {
    if (d) await stopDaemon(d);
    cleanup(dir);
  }
});

test('with a token for reading, the sweep\'s report link downloads with it', async () => {
  const dir = tempDir();
  let d;
  try {
    const db = sweepInto(dir);
    d = await startDaemon({ dir, args: [...WEB, '--token', 's3cret'] });
    const url = `${d.http}/api/sweeps/${encodeURIComponent(SWEEP)}/report.csv`;
    assert.equal((await httpGet(url)).status, 401, 'a plain link would be refused');
    const { page, errors } = await openViewer(browser, d.http);
    await page.waitForSelector('#token-dialog[open]');
    await page.fill('#token-input', 's3cret');
    await page.click('#token-ok');
    const link = `#runs tr.sweep[data-sweep="${SWEEP}"] a.report[data-format="csv"]`;
    await page.waitForSelector(link, { timeout: 10000 * SLOW });
    const [download] = await Promise.all([page.waitForEvent('download'), page.click(link)]);
    assert.equal(download.suggestedFilename(), 'street_species-report.csv');
    const out = join(dir, 'report.csv');
    sylva('report', '--db', db, '--sweep', SWEEP, '-o', out);
    const csv = readFileSync(await download.path());
    assert.ok(csv.equals(readFileSync(out)), 'the CSV of `sylva report`');
    assert.ok(csv.toString().trim().split('\n').length > 1, 'with rows of year 10');
    assert.deepEqual(errors, []);
    await page.close();
  } finally {
    if (d) await stopDaemon(d);
    cleanup(dir);
  }
});
