// The GLB files of test_gltf (the world of the export tests with and without its
// obstacles, and the prisms of prism_world.h) read by the Khronos glTF validator:
// no error and no warning in any. The validator is npm's gltf-validator as
// tests/web pins it (package-lock.json; scripts/bootstrap installs it there).
//
// Usage: node gltf_validate.mjs TEST_GLTF TESTS_WEB_DIR. Runs `TEST_GLTF OUTDIR`,
// validates every file its expected.tsv lists, prints each report's counts and
// every failure, then "N passed, N failed".
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';

const [testGltf, webDir] = process.argv.slice(2);
if (!testGltf || !webDir) {
  console.error('usage: node gltf_validate.mjs TEST_GLTF TESTS_WEB_DIR');
  process.exit(2);
}
let passed = 0;
let failed = 0;
function check(ok, what, detail = '') {
  if (ok) passed++;
  else {
    failed++;
    console.log(`FAIL ${what}${detail ? `: ${detail}` : ''}`);
  }
}

let validator;
try {
  validator = createRequire(join(resolve(webDir), 'package.json'))('gltf-validator');
} catch (e) {
  check(false, `gltf-validator not found under ${webDir}/node_modules: run scripts/bootstrap`,
    e.message);
}

const out = mkdtempSync(join(tmpdir(), 'sylva-gltf-'));
try {
  const run = spawnSync(testGltf, [out], { encoding: 'utf8' });
  check(run.status === 0, `${testGltf} ${out} exits 0`, run.stdout + run.stderr);
  const files = readFileSync(join(out, 'expected.tsv'), 'utf8').split('\n')
    .map((line) => line.split('\t')).filter((cols) => cols[0] === 'file').map((cols) => cols[1]);
  check(files.includes('prisms.glb'), 'expected.tsv lists prisms.glb', files.join(' '));
  for (const name of validator ? files : []) {
    const report = await validator.validateBytes(new Uint8Array(readFileSync(join(out, name))),
      { maxIssues: 0 });
    const issues = report.issues;
    console.log(`gltf-validator ${report.validatorVersion}, ${name}: ${issues.numErrors} errors, ` +
      `${issues.numWarnings} warnings, ${issues.numInfos} infos, ${issues.numHints} hints; ` +
      `${report.info.totalVertexCount} vertices, ${report.info.totalTriangleCount} triangles`);
    const messages = JSON.stringify(issues.messages.slice(0, 20));
    check(issues.numErrors === 0, `${name}: no error`, messages);
    check(issues.numWarnings === 0, `${name}: no warning`, messages);
  }
} finally {
  rmSync(out, { recursive: true, force: true });
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
