// A sweep's report over HTTP (docs/protocol.md, "HTTP routes"):
// /api/sweeps/NAME/report.(csv|html|pdf)[?years=LIST], against a real daemon on
// 127.0.0.1 over a store made by the real `sylva sweep` (the street scenario, two
// species, ten iterations). The CSV is byte for byte that of `sylva report` with
// the same years; the HTML is a page with the summary table, the PDF a PDF; an
// unknown sweep is 404 and bad years 400; the token guards it as every /api route.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { spawnSync } from 'node:child_process';
import { SYLVA, ROOT, startDaemon, stopDaemon, withDaemon, askOnly, tempDir, cleanup } from './harness.mjs';

const SWEEP = 'street species';
const SPECIES = ['utdb:NoEast:PLAC', 'utdb:NoEast:GIBI'];
const ITERATIONS = 10;
const plan = (name) => ({
  format: 'sylva.sweep/1',
  name,
  scenario: join(ROOT, 'scenarios', 'street.json'),
  axes: { species: { 'street-tree': SPECIES }, seed: [1] },
});

function sylva(...args) {
  const r = spawnSync(SYLVA, args, { encoding: 'utf8', maxBuffer: 1 << 26 });
  if (r.status !== 0) throw new Error(`sylva ${args.join(' ')}: ${r.stderr}`);
  return r;
}

// A fresh directory whose runs.db holds the sweeps of these names, each grown by
// `sylva sweep`.
function swept(names = [SWEEP]) {
  const dir = tempDir();
  names.forEach((name, i) => {
    const file = join(dir, `plan${i}.json`);
    writeFileSync(file, JSON.stringify(plan(name)));
    sylva('sweep', file, '--db', join(dir, 'runs.db'), '--iterations', String(ITERATIONS), '--jobs', '2',
      '--quiet-progress');
  });
  return dir;
}

// The bytes `sylva report --db DB --sweep NAME [--years YEARS] -o OUT.csv` writes.
function cliCsv(db, sweep, years) {
  const out = `${db}.${Math.random().toString(36).slice(2)}.csv`;
  sylva('report', '--db', db, '--sweep', sweep, ...(years ? ['--years', years] : []), '-o', out);
  return readFileSync(out);
}

async function get(d, path, headers = {}) {
  const r = await fetch(`${d.http}${path}`, { headers });
  return { status: r.status, headers: r.headers, body: Buffer.from(await r.arrayBuffer()) };
}

const route = (sweep, ext, query = '') => `/api/sweeps/${encodeURIComponent(sweep)}/report.${ext}${query}`;

test('report: the CSV is byte for byte `sylva report`\'s; HTML and PDF are attachments too', async () => {
  await withDaemon({ dir: swept() }, async (d) => {
    for (const years of ['5,10', '10,3', undefined]) {
      const r = await get(d, route(SWEEP, 'csv', years ? `?years=${years}` : ''));
      assert.equal(r.status, 200, `${years}: ${r.body}`);
      assert.match(r.headers.get('content-type'), /^text\/csv/);
      assert.equal(r.headers.get('content-disposition'), 'attachment; filename="street_species-report.csv"');
      assert.equal(Number(r.headers.get('content-length')), r.body.length);
      const cli = cliCsv(d.db, SWEEP, years);
      assert.ok(r.body.equals(cli), `years ${years}: the route's CSV\n${r.body}\nthe CLI's\n${cli}`);
      // every reached year has rows of both species (the default 10,20,40: only 10)
      const lines = r.body.toString().trim().split('\n');
      assert.match(lines[0], /^run,species\/street-tree,seed,plant,species,age,year,height,/);
      for (const sp of SPECIES) assert.ok(lines.some((l) => l.includes(`,${sp},`)), `${years}: rows of ${sp}`);
    }
    // a year no run reached is no error: the header alone
    const empty = await get(d, route(SWEEP, 'csv', '?years=50'));
    assert.equal(empty.status, 200);
    assert.ok(empty.body.equals(cliCsv(d.db, SWEEP, '50')));
    assert.equal(empty.body.toString().trim().split('\n').length, 1);

    const html = await get(d, route(SWEEP, 'html', '?years=5,10'));
    assert.equal(html.status, 200, html.body.toString());
    assert.equal(html.headers.get('content-type'), 'text/html; charset=utf-8');
    assert.equal(html.headers.get('content-disposition'), 'attachment; filename="street_species-report.html"');
    assert.equal(Number(html.headers.get('content-length')), html.body.length);
    const page = html.body.toString();
    assert.match(page, /^(<!DOCTYPE html>|<html)/i);
    assert.ok(page.includes(`<title>sylva report: ${SWEEP}</title>`), page.slice(0, 400));
    assert.ok(page.includes('<table class="summary">'), 'the summary table');
    for (const sp of SPECIES) assert.ok(page.includes(sp), sp);
    assert.ok(page.includes('data:image/png;base64,'), 'the pictures, inlined');
    assert.ok(page.trimEnd().endsWith('</html>'));

    const pdf = await get(d, route(SWEEP, 'pdf'));
    assert.equal(pdf.status, 200, pdf.body.toString());
    assert.equal(pdf.headers.get('content-type'), 'application/pdf');
    assert.equal(pdf.headers.get('content-disposition'), 'attachment; filename="street_species-report.pdf"');
    assert.equal(Number(pdf.headers.get('content-length')), pdf.body.length);
    assert.equal(pdf.body.subarray(0, 5).toString(), '%PDF-');
    assert.match(pdf.body.subarray(-16).toString('latin1'), /%%EOF\s*$/);
    assert.doesNotMatch(d.stderr(), /report of sweep/);
  });
});

test('report: an unknown sweep is 404, bad years and parameters 400, other paths 404', async () => {
  await withDaemon({ dir: swept() }, async (d) => {
    const runName = `${SWEEP}: street-tree=${SPECIES[0]}, seed=1`;
    const cases = [
      [route('nope', 'html'), 404, 'no sweep "nope"'],
      [route('nope', 'csv', '?years=5'), 404, 'no sweep "nope"'],
      [route(runName, 'pdf'), 404, `no sweep "${runName}"`],   // a run, not a sweep
      [route('Street Species', 'csv'), 404, 'no sweep "Street Species"'],
      [route(SWEEP, 'html', '?years=0'), 400, 'years: year \'0\' is not from 1 to 100000'],
      [route(SWEEP, 'csv', '?years=abc'), 400, 'years: \'abc\' is not a whole number of years from 1 to 100000'],
      [route(SWEEP, 'csv', '?years=10,,20'), 400, 'years: an empty year in \'10,,20\''],
      [route(SWEEP, 'csv', '?years='), 400, 'years: expected years like 10,20,40, got an empty list'],
      [route(SWEEP, 'pdf', '?years=5&years=6'), 400, 'years: given more than once'],
      [route(SWEEP, 'pdf', '?format=pdf'), 400, 'format: unknown parameter (known: years)'],
      [route('nope', 'html', '?years=x'), 400, 'years: \'x\' is not a whole number of years from 1 to 100000'],
      [route(SWEEP, 'txt'), 404, 'not found'],
      [`/api/sweeps/${encodeURIComponent(SWEEP)}`, 404, 'not found'],
      [`/api/sweeps/${encodeURIComponent(SWEEP)}/report`, 404, 'not found'],
      ['/api/sweeps/report.csv', 404, 'not found'],
      ['/api/sweeps', 404, 'not found'],
    ];
    for (const [path, status, line] of cases) {
      const r = await get(d, path);
      assert.equal(r.status, status, `${path}: ${r.body}`);
      assert.match(r.headers.get('content-type'), /^text\/plain/, path);
      assert.equal(r.headers.get('content-disposition'), null, path);
      assert.equal(r.body.toString(), `${line}\n`, path);
    }
    // a 404 is the client's mistake: not logged as a failure
    assert.doesNotMatch(d.stderr(), /report of sweep .* failed/);
    // and the right one still works
    assert.equal((await get(d, route(SWEEP, 'csv'))).status, 200);
  });
});

test('report: any sweep name is found, each sweep of the store its own, its file name sanitized', async () => {
  const odd = 'st/reet "ä" 10% ';
  await withDaemon({ dir: swept([SWEEP, odd]) }, async (d) => {
    for (const [sweep, file] of [[SWEEP, 'street_species'], [odd, 'st_reet______10__']]) {
      const r = await get(d, route(sweep, 'csv', '?years=10'));
      assert.equal(r.status, 200, `${sweep}: ${r.body}`);
      assert.equal(r.headers.get('content-disposition'), `attachment; filename="${file}-report.csv"`);
      assert.ok(r.body.equals(cliCsv(d.db, sweep, '10')), sweep);
      // its own runs (the CSV quotes the run's name, and doubles its quotes)
      const rows = r.body.toString().trim().split('\n').slice(1);
      assert.equal(rows.length, 2 * 5, `${sweep}: two runs of five trees`);
      for (const row of rows)
        assert.ok(row.startsWith(`"${sweep.replaceAll('"', '""')}: street-tree=`), `${sweep}: ${row}`);
    }
    const html = await get(d, route(odd, 'html', '?years=10'));
    assert.equal(html.status, 200);
    assert.equal(html.headers.get('content-disposition'), 'attachment; filename="st_reet______10__-report.html"');
  });
});

test('report: the token guards it as every /api route; --public-read opens it', async () => {
  const dir = swept();
  let d;
  try {
    d = await startDaemon({ dir, args: ['--token', 's3cret'] });
    const path = route(SWEEP, 'csv', '?years=5,10');
    for (const headers of [{}, { Authorization: 'Bearer wrong' }]) {
      const r = await get(d, path, headers);
      assert.equal(r.status, 401, JSON.stringify(headers));
      assert.equal(r.headers.get('www-authenticate'), 'Bearer');
    }
    const r = await get(d, path, { Authorization: 'Bearer s3cret' });
    assert.equal(r.status, 200);
    assert.ok(r.body.equals(cliCsv(d.db, SWEEP, '5,10')));
    // an unknown sweep is not told apart from a known one without the token
    assert.equal((await get(d, route('nope', 'csv'))).status, 401);
    assert.equal((await stopDaemon(d)).code, 0);
    d = await startDaemon({ dir, args: ['--token', 's3cret', '--public-read'] });
    const open = await get(d, path);
    assert.equal(open.status, 200);
    assert.ok(open.body.equals(r.body));
    assert.equal((await stopDaemon(d)).code, 0);
    d = null;
  } finally {
    if (d) await stopDaemon(d);
    cleanup(dir);
  }
});

test('report: clients that leave right after asking do not hurt the daemon', async () => {
  await withDaemon({ dir: swept(), args: ['--max-jobs', '30'] }, async (d) => {
    for (let i = 0; i < 12; i++)
      await askOnly(d.port, route(SWEEP, ['pdf', 'html', 'csv'][i % 3]), { leave: true });
    // it goes on serving reports (the jobs of the clients that left finish, or
    // are cancelled, and their results are freed: the sanitizer build checks)
    const r = await get(d, route(SWEEP, 'csv', '?years=5,10'));
    assert.equal(r.status, 200);
    assert.ok(r.body.equals(cliCsv(d.db, SWEEP, '5,10')));
    const pdf = await get(d, route(SWEEP, 'pdf'));
    assert.equal(pdf.status, 200);
    assert.equal(pdf.body.subarray(0, 5).toString(), '%PDF-');
    assert.doesNotMatch(d.stderr(), /report of sweep .* failed/);
  });
});
