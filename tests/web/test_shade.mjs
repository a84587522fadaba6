// The shade layer in headless Chromium against a real daemon: the street grown a
// few years, the layer switched on (its ground and facade meshes, tree shade in
// its texture near a crown, its colours on screen under the crown), following
// the year shown, and a bad day named by the daemon's message.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { ROOT, SLOW, startDaemon, stopDaemon, scenario, cleanup } from '../server/harness.mjs';
import { launch, openViewer, until, pixels, countWhere, httpGet, createAndWatch } from './browser.mjs';

const WEB = ['--web', join(ROOT, 'web')];
let browser;
before(async () => { browser = await launch(); });
after(async () => { await browser?.close(); });

// The layer's colours of some tree shade (shadeColor past a quarter of its
// scale): blue well above red.
const isShade = (r, g, b) => b > r + 40;
const shot = async (page) => {
  await page.evaluate(() => window.sylva.render());
  return pixels(page, await page.locator('#view canvas').screenshot());
};

test('the shade layer: ground and facade cells from the daemon, coloured under the crowns, following the year shown', async () => {
  const d = await startDaemon({ args: WEB });
  try {
    const { page, errors } = await openViewer(browser, d.http);
    // the species' typical planes (docs/model.md, "Stands"): the crowns whose shade the
    // layer is measured under, as the pixel counts below were set for them
    const street = scenario('street.json', { iterations: 3 });
    Object.assign(street.species['street-tree'], { vigour_spread: 0, stock_spread: 0 });
    const run = await createAndWatch(d, page, street, 'street', { start: true });
    await until(page, (x) => x.run === run && x.status === 'finished' && x.iteration === 3, 'the street grown',
      120000 * SLOW);

    // on: the ground and every face of the solid boxes, of the year shown, the default day
    await page.click('#shade-toggle');
    let s = await until(page, (x) => x.shade.iteration === 3 && !x.shade.busy, 'the shade layer', 60000 * SLOW);
    assert.deepEqual([s.shade.on, s.shade.date, s.shade.from, s.shade.to], [true, '07-21', '10:00', '16:00']);
    assert.ok(s.shade.meshes.includes('shade:ground'), s.shade.meshes);
    for (const face of ['+y', '-y', '+x', '-x'])
      assert.ok(s.shade.meshes.includes(`shade:facade-north:${face}`), face);
    assert.equal(await page.getAttribute('#shade-toggle', 'aria-pressed'), 'true');
    assert.equal(await page.isVisible('#shade-legend'), true);
    assert.equal(await page.textContent('#shade-legend-max'), `${s.shade.scale} h`);

    // the most tree shade on the sidewalks (the ground outside the zones and
    // boxes, whose tints would change its colour on screen), within a crown's
    // reach of a plane's root, and coloured in the texture
    const best = await page.evaluate(() => {
      let b = { v: 0 };
      for (let x = -13.9375; x < 14; x += 0.125)
        for (const y0 of [-5.9375, 3.5625])
          for (let y = y0; y < y0 + 2.4; y += 0.125) {
            const v = window.sylva.shadeAt(x, y);
            if (v > b.v) b = { v, x, y };
          }
      return b;
    });
    assert.ok(best.v >= 0.3 * s.shade.scale, `tree shade: ${JSON.stringify(best)} of ${s.shade.scale} h`);
    const roots = [[-9, -5], [0, -5], [9, -5], [-5, 5], [5, 5]];
    assert.ok(roots.some(([x, y]) => Math.hypot(best.x - x, best.y - y) < 3), `near a root: ${JSON.stringify(best)}`);
    const texel = await page.evaluate(([a, b]) => window.sylva.shadeTexel(a, b), [best.x, best.y]);
    assert.ok(isShade(...texel), `the texture there: ${texel}`);
    assert.deepEqual(await page.evaluate(() => window.sylva.shadeTexel(13.9, 0)), [242, 236, 214], 'no tree shade far from the trees');

    // on screen, from the top with the leaves off: the layer's colours there, none without it
    await page.evaluate(() => { window.sylva.setLeaves(false); window.sylva.setView('top'); });
    const [px, py] = await page.evaluate(([a, b]) => window.sylva.project(a, b, 0), [best.x, best.y]);
    const rect = [px - 12, py - 12, px + 12, py + 12];
    const coloured = countWhere(await shot(page), rect, isShade);
    assert.ok(coloured > 60, `shade-coloured pixels under the crown: ${coloured}`);
    await page.click('#shade-toggle');
    await until(page, (x) => !x.shade.on && x.shade.meshes.length === 0, 'the layer off');
    assert.equal(countWhere(await shot(page), rect, isShade), 0, 'no shade colours with the layer off');
    assert.equal(await page.isVisible('#shade-legend'), false);

    // on again, then an earlier year from the store: the layer follows it
    await page.click('#shade-toggle');
    await until(page, (x) => x.shade.iteration === 3 && !x.shade.busy, 'the layer again');
    await page.evaluate(() => {
      const t = document.getElementById('timeline');
      t.value = '1';
      t.dispatchEvent(new Event('input'));
    });
    s = await until(page, (x) => !x.live && x.iteration === 1 && x.shade.iteration === 1 && !x.shade.busy,
      'the layer of iteration 1', 60000 * SLOW);
    const earlier = JSON.parse((await httpGet(`${d.http}/api/runs/street/shade?iteration=1`)).body);
    assert.equal(s.shade.max, earlier.max);
    const cell = Math.floor((best.x + 14) / 0.125) + earlier.nx * Math.floor((best.y + 8) / 0.125);
    assert.equal(await page.evaluate(([a, b]) => window.sylva.shadeAt(a, b), [best.x, best.y]), earlier.ground[cell]);

    // another day: a date that does not exist gets the daemon's message, the layer stays
    await page.fill('#shade-date', '02-30');
    await page.dispatchEvent('#shade-date', 'change');
    await page.waitForFunction(() => /^shade: date: /.test(document.getElementById('message').textContent));
    assert.equal((await page.evaluate(() => window.sylva.state())).shade.date, '07-21');
    assert.deepEqual(errors.filter((e) => !e.includes('400')), []);
  } finally {
    await stopDaemon(d);
    cleanup(d.dir);
  }
});
