// The glTF export (`sylva export --format glb`, docs/cli.md "export") read by tools
// this project did not write: the Khronos glTF validator (npm's gltf-validator,
// pinned in package-lock.json) finds no error and no warning in the GLB of a run
// with a wall and a clearance zone; the daemon's export route gives the same bytes
// as model/gltf-binary; and three.js's GLTFLoader, in headless Chromium, loads it:
// the nodes, materials and leaf texture of gltf.h, and a picture of the scene that
// shows each species' leaf colour in the crowns and none in the empty sky. Bad
// options are refused as for the other formats.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { spawnSync } from 'node:child_process';
import { writeFileSync } from 'node:fs';
import validator from 'gltf-validator';
import { SYLVA, ROOT, startDaemon, stopDaemon, exportBytes, cleanup, tempDir } from '../server/harness.mjs';
import { launch, httpGet, countPixels } from './browser.mjs';

// Two trees of two species whose leaves differ in colour, either side of a wall;
// a clearance zone at the east edge. Twelve iterations: a few seconds.
const GREEN = '#2f9f2f';
const PURPLE = '#a02fb0';
const SITE = {
  format: 'sylva.scenario/1',
  name: 'glTF site',
  seed: 5,
  iterations: 12,
  world: { min: [-4, -3, 0], max: [4, 3, 8] },
  species: {
    plane: { preset: 'utdb:NoEast:PLAC', leaf_size: 0.2, leaf_colour: GREEN },
    maple: { preset: 'utdb:NoEast:PLAC', leaf_size: 0.15, leaf_colour: PURPLE },
  },
  plants: [
    { id: 'west', species: 'plane', roots: [[-1.5, 0, 0]] },
    { id: 'east', species: 'maple', roots: [[1.5, 0, 0]] },
  ],
  obstacles: [
    { id: 'wall', kind: 'box', min: [-0.2, -3, 0], max: [0.2, 3, 2.5] },
    { id: 'lane', kind: 'zone', min: [3, -3, 0.25], max: [4, 3, 8] },
  ],
};

function sylva(...args) {
  return spawnSync(SYLVA, args, { encoding: 'utf8', maxBuffer: 1 << 26 });
}

let browser, dir, db;
before(async () => {
  dir = tempDir();
  db = join(dir, 'runs.db');
  writeFileSync(join(dir, 'site.json'), JSON.stringify(SITE));
  const r = sylva('run', join(dir, 'site.json'), '--db', db, '--name', 'site', '--quiet-progress');
  if (r.status !== 0) throw new Error(`sylva run: ${r.stderr}`);
  browser = await launch();
});
after(async () => {
  await browser?.close();
  if (dir) cleanup(dir);
});

// The validator's report of a GLB, with every issue listed (maxIssues 0: no limit).
async function validate(bytes) {
  const report = await validator.validateBytes(new Uint8Array(bytes), { maxIssues: 0 });
  const summary = `${report.issues.numErrors} errors, ${report.issues.numWarnings} warnings, ` +
    `${report.issues.numInfos} infos, ${report.issues.numHints} hints`;
  return { report, summary, messages: JSON.stringify(report.issues.messages.slice(0, 20), null, 1) };
}

test('the Khronos glTF validator finds no error or warning, with and without the obstacles', async () => {
  for (const extra of [['--obstacles'], [], ['--sides', '3'], ['--sides', '64', '--obstacles']]) {
    const glb = exportBytes(db, 'site', 'glb', undefined, extra);
    const { report, summary, messages } = await validate(glb);
    console.log(`gltf-validator ${report.validatorVersion}, sylva export --format glb ${extra.join(' ')}: ` +
      `${glb.length} bytes, ${summary}; ${report.info.totalVertexCount} vertices, ` +
      `${report.info.totalTriangleCount} triangles, ${report.info.drawCallCount} draw calls`);
    assert.equal(report.issues.numErrors, 0, messages);
    assert.equal(report.issues.numWarnings, 0, messages);
    assert.equal(report.info.hasTextures, true);
    // bark, two leaf materials, and with obstacles the wall's and the zone's
    assert.equal(report.info.materialCount, extra.includes('--obstacles') ? 5 : 3);
  }
  // an earlier iteration too
  const early = await validate(exportBytes(db, 'site', 'glb', 3, ['--obstacles']));
  assert.equal(early.report.issues.numErrors, 0, early.messages);
});

test('bad options are refused and write nothing', () => {
  const out = join(dir, 'bad.glb');
  for (const [args, message] of [
    [['--sides', '2'], "--sides: expected an integer from 3 to 64, got '2'"],
    [['--sides', '65'], "--sides: expected an integer from 3 to 64, got '65'"],
    [['--sides', 'x'], "--sides: expected an integer from 3 to 64, got 'x'"],
  ]) {
    const r = sylva('export', '--db', db, '--name', 'site', '--format', 'glb', '-o', out, ...args);
    assert.equal(r.status, 2, r.stderr);
    assert.ok(r.stderr.includes(message), r.stderr);
    assert.equal(spawnSync('test', ['-e', out]).status, 1, 'no file written');
  }
  const r = sylva('export', '--db', db, '--name', 'site', '--format', 'gltf', '-o', out);
  assert.equal(r.status, 2);
  assert.match(r.stderr, /--format: 'gltf' is not skeleton, obj, ply, csv or glb/);
});

test('the daemon\'s export route and three.js\'s GLTFLoader in Chromium: nodes, materials, leaves in the crowns', async () => {
  const d = await startDaemon({ dir, args: ['--web', join(ROOT, 'web')] });
  try {
    const cli = exportBytes(db, 'site', 'glb');
    const got = await httpGet(`${d.http}/api/runs/site/export?format=glb`);
    assert.equal(got.status, 200, String(got.body));
    assert.equal(got.headers['content-type'], 'model/gltf-binary');
    assert.equal(got.headers['content-disposition'], 'attachment; filename="site-i12.glb"');
    assert.ok(got.body.equals(cli), 'the route gives the CLI\'s bytes');
    const withBoxes = await httpGet(`${d.http}/api/runs/site/export?format=glb&obstacles=1`);
    assert.ok(withBoxes.body.equals(exportBytes(db, 'site', 'glb', undefined, ['--obstacles'])));

    // a page of the daemon's origin, so the import map reaches web/node_modules
    const page = await browser.newPage({ viewport: { width: 800, height: 600 } });
    const errors = [];
    page.on('pageerror', (e) => errors.push(`page: ${e.message}`));
    page.on('console', (m) => { if (m.type() === 'error') errors.push(`console: ${m.text()}`); });
    await page.route(`${d.http}/gltf-test.html`, (route) => route.fulfill({
      contentType: 'text/html',
      body: `<!doctype html><html><head><script type="importmap">{ "imports": {
        "three": "./node_modules/three/build/three.module.js",
        "three/addons/": "./node_modules/three/examples/jsm/" } }</script></head>
        <body style="margin:0"></body></html>`,
    }));
    await page.goto(`${d.http}/gltf-test.html`);
    const seen = await page.evaluate(async () => {
      const THREE = await import('three');
      const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
      const gltf = await new GLTFLoader().loadAsync('api/runs/site/export?format=glb');
      const names = [];
      // three.js makes names fit for animation paths ("west0"); userData keeps glTF's
      gltf.scene.traverse((o) => { if (o.userData.name) names.push(o.userData.name); });
      const materials = new Map();
      const leaves = [];
      gltf.scene.traverse((o) => {
        if (!o.isMesh) return;
        materials.set(o.material.name, {
          alphaTest: o.material.alphaTest, side: o.material.side, map: !!o.material.map,
          mapSize: o.material.map ? [o.material.map.image.width, o.material.map.image.height] : null,
        });
        if (o.material.name.startsWith('leaves')) leaves.push(o);
      });
      // the leaves' box on the screen of a camera in front (glTF +z is the world's -y)
      const box = new THREE.Box3();
      for (const o of leaves) box.expandByObject(o);
      const size = box.getSize(new THREE.Vector3()), centre = box.getCenter(new THREE.Vector3());
      const camera = new THREE.PerspectiveCamera(40, 800 / 600, 0.1, 200);
      const dist = 1.3 * Math.max(size.x / camera.aspect, size.y) / (2 * Math.tan(Math.PI * 20 / 180));
      camera.position.set(centre.x, centre.y, centre.z + size.z / 2 + dist);
      camera.lookAt(centre);
      camera.updateMatrixWorld();
      const scene = new THREE.Scene();
      scene.background = new THREE.Color(0x9cc4f0);
      scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 2.0));
      const sun = new THREE.DirectionalLight(0xffffff, 2.0);
      sun.position.set(3, 10, 8);
      scene.add(sun);
      scene.add(gltf.scene);
      const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
      renderer.setPixelRatio(1);
      renderer.setSize(800, 600);
      document.body.appendChild(renderer.domElement);
      renderer.render(scene, camera);
      let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
      for (const cx of [box.min.x, box.max.x]) for (const cy of [box.min.y, box.max.y]) for (const cz of [box.min.z, box.max.z]) {
        const p = new THREE.Vector3(cx, cy, cz).project(camera);
        const px = (p.x + 1) / 2 * 800, py = (1 - p.y) / 2 * 600;
        x0 = Math.min(x0, px); x1 = Math.max(x1, px); y0 = Math.min(y0, py); y1 = Math.max(y1, py);
      }
      let root;
      gltf.scene.traverse((o) => { if (o.userData.name === 'sylva') root = o; });
      return { names, materials: Object.fromEntries(materials), rect: [x0, y0, x1, y1],
        iteration: root?.userData?.iteration, leafMeshes: leaves.length };
    });
    assert.deepEqual(errors, []);
    for (const name of ['sylva', 'west/0', 'east/0']) assert.ok(seen.names.includes(name), `${name} in ${seen.names}`);
    assert.equal(seen.iteration, 12);
    assert.equal(seen.leafMeshes, 2);
    assert.deepEqual(Object.keys(seen.materials).sort(), ['bark', 'leaves-maple', 'leaves-plane']);
    for (const m of ['leaves-maple', 'leaves-plane']) {
      assert.equal(seen.materials[m].alphaTest, 0.5, m);
      assert.equal(seen.materials[m].side, 2, `${m} double-sided`);
      assert.deepEqual(seen.materials[m].mapSize, [64, 64], `${m} textured`);
    }
    assert.equal(seen.materials.bark.map, false);

    const png = await page.locator('canvas').screenshot();
    writeFileSync(join(dir, 'gltf.png'), png);
    const [x0, y0, x1, y1] = seen.rect;
    assert.ok(y0 > 40 && x0 >= 0 && x1 <= 800 && y1 <= 600, `the crowns framed: ${seen.rect}`);
    // leaf pixels: the green species' as countPixels's 'tree', the purple one's
    const count = async (rect) => ({
      green: await countPixels(page, png, rect, 'tree'),
      purple: await countPixels(page, png, rect, 'purple'),
      pixels: Math.round(rect[2] - rect[0]) * Math.round(rect[3] - rect[1]),
    });
    const crowns = await count([Math.max(0, x0), y0, Math.min(800, x1), y1]);
    const sky = await count([0, 0, 800, Math.floor(y0) - 4]);
    console.log(`crowns ${JSON.stringify(crowns)}, sky above them ${JSON.stringify(sky)}`);
    assert.ok(crowns.green > 0.01 * crowns.pixels, `green leaves in the crowns: ${JSON.stringify(crowns)}`);
    assert.ok(crowns.purple > 0.01 * crowns.pixels, `purple leaves in the crowns: ${JSON.stringify(crowns)}`);
    assert.equal(sky.green + sky.purple, 0, `no leaf colour in the sky: ${JSON.stringify(sky)}`);
    await page.close();
  } finally {
    await stopDaemon(d);
  }
});
