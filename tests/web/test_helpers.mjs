// The viewer's pure helpers (web/helpers.mjs) in node, as the page uses them.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import {
  round, wsAddress, connectionLabel, runSummary, runCells, runHash, runFromHash, mostRecentRun, initialRun,
  controlsDisabled, stepCount, exportHref, freeId, parsePoint, obstacleBox, obstacleFromFields, plantAt,
  parseScenario, createErrorPlace, parseStatsCsv, csvCells, zoneFromFields, skyLabel,
  yearOf, iterationLabel, statsInYears, pastStage, PIPE_EXPONENT,
} from '../../web/helpers.mjs';
import {
  isZone, zonesOf, solidsOf, insideBox, markInZones, countInZones, conflictRows, clearanceRows, stemLabel,
  boundsOf, insideFootprint, insideObstacle,
} from '../../web/zones.mjs';
import { STEM_KEY, deadStemKeys, sameKeys, markDeadStems, standRows, thinningPoint, standOfRows } from '../../web/stand.mjs';
import { STEMS_THRESHOLD, stemsThreshold, detailFor, stemShapes } from '../../web/stems.mjs';
import { deltaArrays, snapshotArrays } from '../../web/wire.mjs';

const run = (id, name, status) => ({ run: id, name, status, iteration: 3, stems: 1, nodes: 40 });

test('round keeps centimetres', () => {
  assert.equal(round(1.234), 1.23);
  assert.equal(round(-2.005 - 1e-9), -2.01);
  assert.equal(round(3), 3);
});

test('the WebSocket address follows the page\'s scheme', () => {
  assert.equal(wsAddress('http:', '127.0.0.1:8080'), 'ws://127.0.0.1:8080/ws');
  assert.equal(wsAddress('https:', 'trees.example'), 'wss://trees.example/ws');
});

test('the connection badge says the state and why it closed', () => {
  assert.equal(connectionLabel('open', ''), 'connected');
  assert.equal(connectionLabel('connecting', ''), 'connecting…');
  assert.equal(connectionLabel('closed', ''), 'disconnected; retrying');
  assert.equal(connectionLabel('closed', 'closed (1001)'), 'disconnected — closed (1001); retrying');
});

test('a run summary has every field, from a list entry or an id and a name', () => {
  assert.deepEqual(runSummary({ run: 4, name: 'wall', status: 'paused', iteration: 7, stems: 2, nodes: 90 }),
    { run: 4, name: 'wall', status: 'paused', iteration: 7, stems: 2, nodes: 90 });
  assert.deepEqual(runSummary({ run: 5, name: 'fork', type: 'created', ref: '3' }),
    { run: 5, name: 'fork', status: '', iteration: 0, stems: 0, nodes: 0 });
  assert.deepEqual(Object.keys(runSummary({ run: 6 })), ['run', 'name', 'status', 'iteration', 'stems', 'nodes']);
  assert.equal(runSummary({ run: 6 }).name, '6');
});

test('a run\'s row: name, status, iteration, stems, internodes with thousands separators', () => {
  assert.deepEqual(runCells({ run: 1, name: 'stand', status: 'running', iteration: 12, stems: 5, nodes: 1234567 }),
    ['stand', 'running', '12', '5', '1,234,567']);
  // a run the daemon is still restoring at start says so
  assert.equal(runCells({ run: 2, name: 'old', status: 'running', iteration: 40, stems: 0, nodes: 9, loading: true })[1],
    'running (loading)');
});

test('the location hash names a run and gives it back', () => {
  for (const name of ['wall', 'Tree beside a wall (IGM fig. 11)', 'a/b&c=d#e', 'élan 100%', '+plus+']) {
    assert.equal(runFromHash(runHash(name)), name, name);
  }
  assert.equal(runHash('a b'), '#run=a%20b');
  assert.equal(runFromHash('#run=wall'), 'wall');
  assert.equal(runFromHash('run=wall'), 'wall');
  assert.equal(runFromHash('#view=top&run=my%20run'), 'my run');
  assert.equal(runFromHash('#run=a+b'), 'a+b', 'a plus is a plus, not a space');
  assert.equal(runFromHash(''), null);
  assert.equal(runFromHash('#'), null);
  assert.equal(runFromHash('#run='), null);
  assert.equal(runFromHash('#runs=wall'), null);
  assert.equal(runFromHash('#run=%E0%A4%A'), null, 'a malformed escape names no run');
});

test('the most recently active run: the newest running one, else the newest', () => {
  assert.equal(mostRecentRun([]), null);
  const a = run(1, 'a', 'finished'), b = run(2, 'b', 'running'), c = run(3, 'c', 'running'), d = run(4, 'd', 'paused');
  assert.equal(mostRecentRun([a]), a);
  assert.equal(mostRecentRun([a, b, d]), b);
  assert.equal(mostRecentRun([a, b, c, d]), c);
  assert.equal(mostRecentRun([a, d]), d);
  assert.equal(mostRecentRun([d, run(5, 'e', 'failed')]).name, 'e');
});

test('the page opens on the run its hash names, else on the most recently active one', () => {
  const list = [run(1, 'old', 'running'), run(2, 'a b', 'finished'), run(3, 'new', 'paused')];
  assert.equal(initialRun(list, '#run=a%20b').run, 2);
  assert.equal(initialRun(list, '#run=old').run, 1);
  assert.equal(initialRun(list, '#run=gone').run, 1, 'an unknown name: the running one');
  assert.equal(initialRun(list, '').run, 1);
  assert.equal(initialRun(list.slice(1), '').run, 3, 'nothing running: the newest');
  assert.equal(initialRun([], '#run=old'), null);
});

test('which controls work for a status', () => {
  const all = { start: true, pause: true, step: true, stop: true };
  assert.deepEqual(controlsDisabled(null), all);
  assert.deepEqual(controlsDisabled('running'), { start: true, pause: false, step: false, stop: false });
  assert.deepEqual(controlsDisabled('paused'), { start: false, pause: true, step: false, stop: false });
  assert.deepEqual(controlsDisabled('finished'), all);
  assert.deepEqual(controlsDisabled('failed'), all);
  assert.deepEqual(controlsDisabled(''), { start: false, pause: true, step: false, stop: false }, 'not yet listed');
});

test('a step count is at least 1', () => {
  assert.equal(stepCount('3'), 3);
  assert.equal(stepCount(''), 1);
  assert.equal(stepCount('0'), 1);
  assert.equal(stepCount('-2'), 1);
  assert.equal(stepCount('many'), 1);
});

test('export links name the run (encoded), the format and the iteration', () => {
  assert.equal(exportHref('site', 'obj', 4), 'api/runs/site/export?format=obj&iteration=4');
  assert.equal(exportHref('a/b c', 'csv', 0), 'api/runs/a%2Fb%20c/export?format=csv&iteration=0');
});

test('a free id is the first unused number after the prefix', () => {
  assert.equal(freeId('wall', new Set()), 'wall1');
  assert.equal(freeId('wall', new Set(['wall1', 'wall2', 'wall4'])), 'wall3');
  assert.equal(freeId('tree', new Set(['wall1', 'tree'])), 'tree1');
});

test('a point is two numbers separated by a comma', () => {
  assert.deepEqual(parsePoint('-2, 1.5'), [-2, 1.5]);
  assert.deepEqual(parsePoint(' 3 ,4 '), [3, 4]);
  assert.deepEqual(parsePoint('1e1,0'), [10, 0]);
  for (const bad of ['', '3', '1, 2, 3', '1, ', ', 2', 'x, 1', '1; 2', 'Infinity, 0']) {
    assert.equal(parsePoint(bad), null, JSON.stringify(bad));
  }
});

test('an obstacle box from two corners: a wall stands on the ground, a board lies at its height', () => {
  assert.deepEqual(obstacleBox('wall', [-2, -1.5], [-2, 1.5], 3, 0.2), { min: [-2.1, -1.5, 0], max: [-1.9, 1.5, 3] });
  assert.deepEqual(obstacleBox('board', [2, 3], [-1, 0], 2.5, 0.1), { min: [-1, 0, 2.5], max: [2, 3, 2.6] });
  // corners in any order give the same box
  assert.deepEqual(obstacleBox('wall', [1, 2], [0, 0], 2, 0.2), obstacleBox('wall', [0, 0], [1, 2], 2, 0.2));
  // one point: a post as thick as the thickness both ways
  assert.deepEqual(obstacleBox('wall', [1, 1], [1, 1], 2, 0.4), { min: [0.8, 0.8, 0], max: [1.2, 1.2, 2] });
  // the corners are not changed
  const a = [0, 0], b = [0, 3];
  obstacleBox('wall', a, b, 1, 0.2);
  assert.deepEqual([a, b], [[0, 0], [0, 3]]);
});

test('an obstacle from the edit fields, or what is wrong with them', () => {
  const fields = { kind: 'wall', cornerA: '-2, -1.5', cornerB: '-2, 1.5', z: '3', thickness: '0.2' };
  assert.deepEqual(obstacleFromFields(fields, new Set(['wall1'])),
    { obstacle: { id: 'wall2', kind: 'box', min: [-2.1, -1.5, 0], max: [-1.9, 1.5, 3] } });
  assert.equal(obstacleFromFields({ ...fields, kind: 'board' }, new Set(['wall1'])).obstacle.id, 'board1');
  assert.match(obstacleFromFields({ ...fields, cornerB: '' }, new Set()).error, /both corners/);
  for (const [z, thickness] of [['', '0.2'], ['high', '0.2'], ['3', '0'], ['3', '-1'], ['3', '']]) {
    assert.equal(obstacleFromFields({ ...fields, z, thickness }, new Set()).error,
      'height and thickness must be numbers', `${z}, ${thickness}`);
  }
});

test('a new plant at a ground point takes the first free tree id', () => {
  assert.deepEqual(plantAt(3.004, -1.996, 'broadleaf', new Set(['tree', 'tree1'])),
    { id: 'tree2', species: 'broadleaf', roots: [[3, -2, 0]] });
});

test('a scenario is a JSON object', () => {
  assert.deepEqual(parseScenario('{"format": "sylva.scenario/1"}'), { format: 'sylva.scenario/1' });
  for (const bad of ['[]', 'null', '3', '"wall"']) assert.throws(() => parseScenario(bad), /a scenario is a JSON object/);
  assert.throws(() => parseScenario('{"format": '), SyntaxError);
});

test('a refused create is shown at the name, in the form or on the message line', () => {
  assert.equal(createErrorPlace('/name: longer than 255 bytes', true), 'name');
  assert.equal(createErrorPlace('runs.db: a run named "wall" exists already', true), 'name');
  assert.equal(createErrorPlace('/scenario/plants/0/roots/0: expected [x, y, z]', true), 'form');
  assert.equal(createErrorPlace('/names: unknown', true), 'form');
  assert.equal(createErrorPlace('not connected', false), 'message');
});

test('stats.csv rows by iteration, typed', () => {
  const csv = 'iteration,plant,stem,height,dbh,finished\n1,tree,0,1.5,,false\n1,bush,0,0.5,,false\n2,tree,0,2.25,0.01,true\n';
  const rows = parseStatsCsv(csv);
  assert.deepEqual([...rows.keys()], [1, 2]);
  assert.deepEqual(rows.get(1), [
    { iteration: 1, plant: 'tree', stem: 0, height: 1.5, dbh: null, finished: false },
    { iteration: 1, plant: 'bush', stem: 0, height: 0.5, dbh: null, finished: false },
  ]);
  assert.deepEqual(rows.get(2), [{ iteration: 2, plant: 'tree', stem: 0, height: 2.25, dbh: 0.01, finished: true }]);
  assert.equal(parseStatsCsv('iteration,plant\n').size, 0);
});

test('CSV cells: quoted ones may hold commas and doubled quotes', () => {
  assert.deepEqual(csvCells('1,tree,,0.5'), ['1', 'tree', '', '0.5']);
  assert.deepEqual(csvCells('"a,b",c'), ['a,b', 'c']);
  assert.deepEqual(csvCells('x,"say ""hi""",'), ['x', 'say "hi"', '']);
  assert.deepEqual(csvCells('""'), ['']);
  assert.deepEqual(csvCells(''), ['']);
});

test('stats.csv rows with zones entered, clearances and pruned counts', () => {
  const csv = 'iteration,plant,stem,nodes,shed,pruned,light,zones,clearance\n' +
    '7,tree,0,17,0,0,17.889,"{""road"":{""nodes"":2,""first"":7}}","{""wall"":2.4}"\n' +
    '7,"a, b",0,5,0,3,1.5,,\n';
  assert.deepEqual(parseStatsCsv(csv).get(7), [
    { iteration: 7, plant: 'tree', stem: 0, nodes: 17, shed: 0, pruned: 0, light: 17.889,
      zones: { road: { nodes: 2, first: 7 } }, clearance: { wall: 2.4 } },
    { iteration: 7, plant: 'a, b', stem: 0, nodes: 5, shed: 0, pruned: 3, light: 1.5, zones: null, clearance: null },
  ]);
  // the conflicts rows of the parsed stats
  assert.deepEqual(conflictRows(parseStatsCsv(csv).get(7)), [{ plant: 'tree', stem: 0, zone: 'road', first: 7, nodes: 2 }]);
});

test('years: an iteration\'s calendar year and label; stats of a run in years', () => {
  assert.equal(yearOf(8, 2027), 2035);
  assert.equal(yearOf(8, null), null);
  assert.equal(yearOf(8, undefined), null);
  assert.equal(iterationLabel(8, 2027), '2035 (iteration 8)');
  assert.equal(iterationLabel(8, null), 'iteration 8');
  // stats.csv of a run in years with a start year: ages (empty for an IGM stem),
  // the year, the crown's diameter and height (empty while it has no base)
  const csv = 'iteration,plant,stem,height,crown_width,crown_base,age,year,crown_diameter,crown_height\n' +
    '3,lime,0,2.5,1.2,0.8,5,2030,1.2,1.7\n3,oak,0,0.5,0.1,,,2030,0.1,\n';
  const rows = parseStatsCsv(csv).get(3);
  assert.deepEqual(rows, [
    { iteration: 3, plant: 'lime', stem: 0, height: 2.5, crown_width: 1.2, crown_base: 0.8, age: 5, year: 2030,
      crown_diameter: 1.2, crown_height: 1.7 },
    { iteration: 3, plant: 'oak', stem: 0, height: 0.5, crown_width: 0.1, crown_base: null, age: null, year: 2030,
      crown_diameter: 0.1, crown_height: null },
  ]);
  assert.equal(statsInYears(rows), true);
  // a run with a start year alone: its CSV has the columns, empty but the year
  assert.equal(statsInYears([{ plant: 'oak', age: null, year: 2030, crown_diameter: null }]), false);
  assert.equal(statsInYears([{ plant: 'oak', crown_width: 1 }]), false);
  assert.equal(statsInYears(undefined), false);
});

test('a zone from the edit fields: two corners, from one height up to another', () => {
  const fields = { cornerA: '0.5, -2', cornerB: '3, 2', base: '1', top: '6', thickness: '0.2' };
  assert.deepEqual(zoneFromFields(fields, new Set(['zone1', 'wall1'])),
    { obstacle: { id: 'zone2', kind: 'zone', min: [0.5, -2, 1], max: [3, 2, 6] } });
  // one line of corners: as wide as the thickness across it
  assert.deepEqual(zoneFromFields({ ...fields, cornerB: '0.5, 2' }, new Set()).obstacle,
    { id: 'zone1', kind: 'zone', min: [0.4, -2, 1], max: [0.6, 2, 6] });
  assert.match(zoneFromFields({ ...fields, cornerA: '1' }, new Set()).error, /both corners/);
  for (const [base, top, thickness] of [['', '6', '0.2'], ['1', '', '0.2'], ['low', '6', '0.2'], ['1', '6', '0']]) {
    assert.equal(zoneFromFields({ ...fields, base, top, thickness }, new Set()).error,
      'the heights and the thickness must be numbers', `${base}, ${top}, ${thickness}`);
  }
  for (const [base, top] of [['2', '2'], ['3', '1'], ['1', '1.001']]) {
    assert.equal(zoneFromFields({ ...fields, base, top }, new Set()).error, 'a zone\'s top must be above its bottom');
  }
});

test('what a light slice is called for a run\'s sky', () => {
  assert.equal(skyLabel('site'), 'site light (sun and sky)');
  assert.equal(skyLabel('zenith'), 'zenith light');
  assert.equal(skyLabel(null), 'light');
});

const road = { id: 'road', kind: 'zone', min: [0, -1, 1], max: [2, 1, 3] };
const strip = { id: 'strip', kind: 'zone', min: [-2, -1, 0], max: [-1, 1, 2] };
const wall = { id: 'wall', kind: 'box', min: [-3, -3, 0], max: [-2.8, 3, 3] };

test('zones and solid obstacles: the kind says which', () => {
  assert.equal(isZone(road), true);
  assert.equal(isZone(wall), false);
  assert.equal(isZone({ id: 'old', min: [0, 0, 0], max: [1, 1, 1] }), false, 'no kind: solid');
  assert.deepEqual(zonesOf([wall, road, strip]), [road, strip]);
  assert.deepEqual(solidsOf([wall, road, strip]), [wall]);
  assert.deepEqual(zonesOf(undefined), []);
});

test('a point is inside a box with its bounds included', () => {
  assert.ok(insideBox(road, 1, 0, 2));
  for (const p of [[0, -1, 1], [2, 1, 3], [0, 1, 3]]) assert.ok(insideBox(road, ...p), `corner ${p}`);
  for (const p of [[-0.0001, 0, 2], [1, 1.0001, 2], [1, 0, 0.9999], [1, 0, 3.0001]]) {
    assert.ok(!insideBox(road, ...p), `outside ${p}`);
  }
});

test('internodes marked by the zone that holds them, as the page holds them (float32)', () => {
  // slots: in road, on road's top bound, in strip, outside, dead in road, in both (road first)
  const pts = [[1, 0, 2], [0.3, 0.1, 3], [-1.5, 0, 1], [5, 5, 5], [1, 0, 2], [0.1, 0.1, 1.1]];
  const end = new Float32Array(pts.flat());
  const dead = new Uint8Array([0, 0, 0, 0, 1, 0]);
  const out = new Float32Array(6).fill(9);
  markInZones(end, dead, 0, 6, [road, strip], out);
  assert.deepEqual(Array.from(out), [1, 1, 2, 0, 0, 1]);
  // a node on a bound that float32 rounds down (0.7 is held as 0.69999998...) is
  // still inside: bounds included
  assert.ok(Math.fround(0.7) < 0.7);
  const onBound = { id: 'b', kind: 'zone', min: [0.7, 0.1, 1.1], max: [1, 1, 2] };
  const mark = new Float32Array(1);
  markInZones(new Float32Array([0.7, 0.1, 1.1]), null, 0, 1, [onBound], mark);
  assert.equal(mark[0], 1);
  assert.deepEqual(countInZones(new Float32Array([0.7, 0.1, 1.1]), null, 1, [onBound]), { b: 1 });
  // only the slots asked for are marked
  const part = new Float32Array(6).fill(7);
  markInZones(end, dead, 2, 4, [road, strip], part);
  assert.deepEqual(Array.from(part), [7, 7, 2, 0, 7, 7]);
  // no zones: nothing is marked
  markInZones(end, null, 0, 6, [], out);
  assert.deepEqual(Array.from(out), [0, 0, 0, 0, 0, 0]);
  // counted per zone, a node in two zones in both, dead slots and slots past count left out
  const both = { id: 'both', kind: 'zone', min: [0, 0, 1], max: [0.2, 0.2, 1.2] };
  assert.deepEqual(countInZones(end, dead, 6, [road, strip, both]), { road: 3, strip: 1, both: 1 });
  assert.deepEqual(countInZones(end, dead, 2, [road]), { road: 2 });
  assert.deepEqual(Array.from(end), pts.flat().map(Math.fround), 'the positions are not changed');
});

// A prism zone: an L (its corner square holds a courtyard), wound clockwise, its
// courtyard anticlockwise, from 1 m up to 4 m.
const yard = {
  id: 'yard', kind: 'zone', polygon: [[0, 0], [0, 4], [2, 4], [2, 2], [4, 2], [4, 0]],
  holes: [[[0.5, 0.5], [1.5, 0.5], [1.5, 1.5], [0.5, 1.5]]], z: [1, 4],
};

test('a prism: its bounds, and a point inside its footprint by even-odd, holes left out', () => {
  assert.deepEqual(boundsOf(yard), { min: [0, 0, 1], max: [4, 4, 4] });
  assert.deepEqual(boundsOf(road), { min: road.min, max: road.max });
  for (const p of [[0.25, 3], [3, 1], [1.75, 1.75], [1, 0.25]]) assert.ok(insideFootprint(yard, ...p), `inside ${p}`);
  // the courtyard, the L's missing square, beyond it
  for (const p of [[1, 1], [3, 3], [5, 1], [-0.5, 1]]) assert.ok(!insideFootprint(yard, ...p), `outside ${p}`);
  // a closed ring (its last point the first) reads the same
  const closed = { ...yard, polygon: [...yard.polygon, [0, 0]] };
  for (const p of [[0.25, 3], [1, 1], [3, 3]]) assert.equal(insideFootprint(closed, ...p), insideFootprint(yard, ...p));
  // in the z range, bounds included
  assert.ok(insideObstacle(yard, 3, 1, 1) && insideObstacle(yard, 3, 1, 4));
  assert.ok(!insideObstacle(yard, 3, 1, 0.99) && !insideObstacle(yard, 3, 1, 4.01) && !insideObstacle(yard, 1, 1, 2));
  assert.ok(insideObstacle(road, 1, 0, 2));
});

test('internodes marked and counted in a prism zone: its footprint, not its bounds', () => {
  // slots: in the L, in the courtyard, in the L's missing square, in the L below it, in the L and the box road
  const pts = [[3, 1, 2], [1, 1, 2], [3, 3, 2], [0.25, 3, 0.5], [1.75, 0.75, 2]];
  const end = new Float32Array(pts.flat());
  const out = new Float32Array(5);
  markInZones(end, null, 0, 5, [yard, road], out);
  assert.deepEqual(Array.from(out), [1, 2, 0, 0, 1]);
  assert.deepEqual(countInZones(end, null, 5, [yard, road]), { yard: 2, road: 2 });
});

test('the conflicts rows: one per stem and zone, from the stats\' zones', () => {
  const stats = [
    { plant: 'tree', stem: 0, nodes: 40, zones: { road: { nodes: 12, first: 5 }, strip: { nodes: 0, first: 3 } } },
    { plant: 'shrub', stem: 0, nodes: 8, zones: {} },
    { plant: 'shrub', stem: 1, nodes: 9, zones: { road: { nodes: 2, first: 7 } }, clearance: { wall: 0.5 } },
    { plant: 'old', stem: 0, nodes: 3 },   // a daemon from before zones
  ];
  assert.deepEqual(conflictRows(stats), [
    { plant: 'tree', stem: 0, zone: 'road', first: 5, nodes: 12 },
    { plant: 'tree', stem: 0, zone: 'strip', first: 3, nodes: 0 },
    { plant: 'shrub', stem: 1, zone: 'road', first: 7, nodes: 2 },
  ]);
  assert.deepEqual(conflictRows([]), []);
  assert.deepEqual(conflictRows(undefined), []);
  // the nearest solid of each stem that has one, and its pruned count
  assert.deepEqual(clearanceRows([
    { plant: 'tree', stem: 0, pruned: 4, clearance: { wall: 1.5, awning: 0.25, post: 0.25 } },
    { plant: 'shrub', stem: 1, clearance: { wall: 0.5 } },
    { plant: 'old', stem: 0 },
    { plant: 'far', stem: 0, pruned: 0, clearance: {} },
  ]), [
    { plant: 'tree', stem: 0, obstacle: 'awning', distance: 0.25, pruned: 4 },
    { plant: 'shrub', stem: 1, obstacle: 'wall', distance: 0.5, pruned: 0 },
  ]);
  assert.deepEqual(clearanceRows(undefined), []);
  assert.equal(stemLabel('tree', 0, 1), 'tree');
  assert.equal(stemLabel('shrub', 1, 2), 'shrub/1');
});

test('a measured tree\'s past stage: the nodes born by T, radii by the pipe model of that stage', () => {
  // slots, parents first:   0 (root, -3)
  //                         └ 1 (-3) ┬ 2 (-2) ─ 4 (0)
  //                                  └ 3 (-1) ─ 5 (0)
  //                         └ 6 (-1)
  // tips at 0: 4, 5, 6 (node 1's subtree 2 of them, the root's 3)
  const tree = {
    parent: new Int32Array([-1, 0, 1, 1, 2, 3, 0]),
    birth: new Int32Array([-3, -3, -2, -1, 0, 0, -1]),
    radius: new Float32Array([0.1, 0.08, 0.05, 0.04, 0.02, 0.02, 0.03]),
    count: 7,
  };
  const copy = structuredClone(tree);
  const at = (T, exponent) => {
    const { slots, radius } = pastStage(tree, T, exponent);
    return { slots: Array.from(slots), radius: Array.from(radius) };
  };
  // (the radii are held as Float32Array values)
  const f = (r, tips, tips0, v = 2.5) => Math.fround(Math.fround(r) * (tips / tips0) ** (1 / v));
  assert.equal(PIPE_EXPONENT, 2.5);
  // the youngest stage: a stem of two nodes, one tip for three at 0 (two for node 1)
  assert.deepEqual(at(-3), { slots: [0, 1], radius: [f(0.1, 1, 3), f(0.08, 1, 2)] });
  assert.deepEqual(at(-2), { slots: [0, 1, 2], radius: [f(0.1, 1, 3), f(0.08, 1, 2), Math.fround(0.05)] });
  // by -1 the tree has all three of its tips: the radii are those at 0
  assert.deepEqual(at(-1), { slots: [0, 1, 2, 3, 6], radius: [0.1, 0.08, 0.05, 0.04, 0.03].map(Math.fround) });
  assert.deepEqual(at(0), { slots: [0, 1, 2, 3, 4, 5, 6], radius: Array.from(tree.radius) });
  assert.deepEqual(at(5), at(0));
  // before the earliest birth: nothing
  assert.deepEqual(at(-4), { slots: [], radius: [] });
  // the exponent: the species' own when it is known
  assert.deepEqual(at(-3, 2).radius, [f(0.1, 1, 3, 2), f(0.08, 1, 2, 2)]);
  // shown only with its parent (a birth before its parent's), dead slots and their
  // subtrees left out, and tips counted over the live slots only
  const odd = { ...tree, birth: new Int32Array([-3, -3, -2, -1, -3, 0, -1]) };
  assert.deepEqual(Array.from(pastStage(odd, -3).slots), [0, 1]);
  const dead = new Uint8Array([0, 0, 0, 1, 0, 1, 0]);
  const pruned = pastStage({ ...tree, dead }, -2);
  assert.deepEqual(Array.from(pruned.slots), [0, 1, 2]);
  assert.deepEqual(Array.from(pruned.radius), [f(0.1, 1, 2), 0.08, 0.05].map(Math.fround));
  assert.deepEqual(tree, copy, 'the arguments are not changed');
});

test('a stand\'s dead stems: their keys from the stats, their slots marked', () => {
  const plantIndex = new Map([['a', 0], ['b', 1]]);
  const stats = [
    { plant: 'a', stem: 0, alive: true, died: null },
    { plant: 'b', stem: 0, alive: false, died: 3 },
    { plant: 'b', stem: 1, alive: false, died: 2 },
    { plant: 'gone', stem: 0, alive: false },   // a plant the skeleton does not hold
  ];
  const keys = deadStemKeys(stats, plantIndex);
  assert.deepEqual([...keys].sort((x, y) => x - y), [STEM_KEY, STEM_KEY + 1]);
  // stats without `alive` (an older daemon, IGM presets): none dead
  assert.equal(deadStemKeys([{ plant: 'a', stem: 0 }], plantIndex).size, 0);
  assert.equal(deadStemKeys(undefined, plantIndex).size, 0);
  assert.ok(sameKeys(keys, new Set([STEM_KEY + 1, STEM_KEY])));
  assert.ok(!sameKeys(keys, new Set([STEM_KEY])));
  assert.ok(!sameKeys(keys, new Set([STEM_KEY, 1])));
  // slots: a/0, b/0, b/1, b/0 shed, b/2
  const plant = new Uint16Array([0, 1, 1, 1, 1]), stem = new Uint16Array([0, 0, 1, 0, 2]);
  const dead = new Uint8Array([0, 0, 0, 1, 0]);
  const out = new Float32Array(5).fill(7);
  markDeadStems(plant, stem, dead, 0, 5, keys, out);
  assert.deepEqual(Array.from(out), [0, 1, 1, 0, 0]);
  // only the slots asked for; no dead stems: nothing marked
  out.fill(7);
  markDeadStems(plant, stem, null, 1, 3, keys, out);
  assert.deepEqual(Array.from(out), [7, 1, 1, 7, 7]);
  markDeadStems(plant, stem, null, 0, 5, new Set(), out);
  assert.deepEqual(Array.from(out), [0, 0, 0, 0, 0]);
});

test('a stand\'s figures as listed, and its self-thinning point', () => {
  const stand = { area: 208.3, alive: 3, died: 2, stems_per_ha: 1440.04, basal_area: 0.599, qmd: 7.28,
    dominant_height: 5.147, sdi: 19.9, cv_height: 0.0052, cv_dbh: 0.0384 };
  assert.deepEqual(standRows(stand), [
    ['Stems', '1,440 /ha'], ['Basal area', '0.60 m²/ha'], ['QMD', '7.3 cm'], ['Dominant height', '5.15 m'],
    ['SDI', '20'], ['Alive', '3 stems'], ['Died', '2 this iteration'],
  ]);
  // null figures (no stem alive) are dashes; no stand, no rows
  const none = { ...stand, alive: 0, stems_per_ha: 0, basal_area: 0, qmd: null, dominant_height: null, sdi: null };
  assert.deepEqual(standRows(none).map((r) => r[1]), ['0 /ha', '0.00 m²/ha', '–', '–', '–', '0 stems', '2 this iteration']);
  assert.deepEqual(standRows(null), []);
  assert.deepEqual(standRows(undefined), []);
  assert.deepEqual(thinningPoint(stand), [7.28, 1440.04]);
  assert.equal(thinningPoint(none), null);
  assert.equal(thinningPoint({ ...stand, stems_per_ha: 0 }), null);
  assert.equal(thinningPoint(undefined), null);
});

test('a stand\'s figures from stats.csv\'s rows of an iteration', () => {
  // (cli.md, "export": the stems' alive, died and vigour, then the stand's on each row)
  const csv = 'iteration,plant,stem,dbh,alive,died,vigour,stems_per_ha,basal_area,qmd,dominant_height,sdi,' +
    'cv_height,cv_dbh,stand_died\n' +
    '3,a,0,0.07,true,,0.59,144,0.599,7.28,5.147,19.9,0.0052,0.0384,2\n' +
    '3,b,0,0.06,false,3,,144,0.599,7.28,5.147,19.9,0.0052,0.0384,2\n' +
    '3,c,0,0.08,true,,0.61,144,0.599,7.28,5.147,19.9,0.0052,0.0384,2\n' +
    '4,a,0,,,,,,,,,,,,\n';
  const rows = parseStatsCsv(csv);
  assert.deepEqual(standOfRows(rows.get(3)), { alive: 2, died: 2, stems_per_ha: 144, basal_area: 0.599, qmd: 7.28,
    dominant_height: 5.147, sdi: 19.9, cv_height: 0.0052, cv_dbh: 0.0384 });
  // rows stored before the stand was kept: every figure null, no point
  const old = standOfRows(rows.get(4));
  assert.equal(old.alive, null);
  assert.equal(thinningPoint(old), null);
  // a run without stands: not given
  assert.equal(standOfRows(parseStatsCsv('iteration,plant,stem,height\n1,a,0,2\n').get(1)), undefined);
  assert.equal(standOfRows([]), undefined);
});

test('stem detail: the threshold, the detail of a run, the stems\' shapes; stems messages as typed arrays', () => {
  assert.equal(stemsThreshold(''), STEMS_THRESHOLD);
  assert.equal(stemsThreshold('?stems=0'), 0);
  assert.equal(stemsThreshold('?stems=-1'), STEMS_THRESHOLD);
  assert.equal(stemsThreshold('?stems=x'), STEMS_THRESHOLD);
  assert.equal(detailFor({ nodes: STEMS_THRESHOLD }), 'nodes');
  assert.equal(detailFor({ nodes: STEMS_THRESHOLD + 1 }), 'stems');
  assert.equal(detailFor({ nodes: 5 }, 0), 'stems');
  const plants = [{ id: 'a', stems: [{ root: [1, 2, 0] }] }, { id: 'b', stems: [{ root: [3, 4, 0.5] }] }];
  const index = new Map([['a', 0], ['b', 1]]);
  const shapes = stemShapes(plants, [
    { plant: 'a', stem: 0, height: 6, dbh: 0.12, crown_base: 2, crown_width: 3 },
    { plant: 'b', stem: 0, height: 0.8, dbh: null, crown_base: null, crown_width: 0.02, alive: true },
    { plant: 'b', stem: 1, height: 1, dbh: null, crown_base: 0, crown_width: 1 },   // not held: left out
  ], index);
  assert.deepEqual(shapes, [
    { plant: 0, root: [1, 2, 0], height: 6, dead: false, crownBase: 2, trunkRadius: 0.06, crownRadius: 1.5 },
    { plant: 1, root: [3, 4, 0.5], height: 0.8, dead: false, crownBase: 0, trunkRadius: 0.01, crownRadius: 0.05 },
  ]);
  const dead = stemShapes(plants, [{ plant: 'a', stem: 0, height: 6, dbh: 0.1, crown_base: 2, crown_width: 3, alive: false }], index);
  assert.equal(dead[0].dead, true);
  assert.equal(dead[0].crownRadius, 0);
  // a stems snapshot and delta hold no internodes
  const snap = snapshotArrays({ type: 'snapshot', run: 1, seq: 2, iteration: 2, detail: 'stems', plants, stats: [] });
  assert.equal(snap.nodes.n, 0);
  assert.equal(snap.leaves.n, 0);
  assert.equal(snap.detail, 'stems');
  assert.deepEqual(snap.plants, plants);
  const delta = deltaArrays({ type: 'delta', run: 1, seq: 3, iteration: 3, detail: 'stems', stats: [], canopy_cover: 0 });
  assert.deepEqual([delta.added.n, delta.radii.n, delta.shed.length, delta.leaves.n, delta.detail], [0, 0, 0, 0, 'stems']);
});
