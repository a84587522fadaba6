// The viewer's pure helpers: no DOM, no network, no three.js, so that node runs
// their tests as they are (tests/web/test_helpers.mjs). Each takes values and
// returns values, and changes none of its arguments.

// A coordinate as the edits send it: metres to the centimetre.
export const round = (v) => Math.round(v * 100) / 100;

// The WebSocket address of the daemon that served the page.
export function wsAddress(protocol, host) {
  return `${protocol === 'https:' ? 'wss' : 'ws'}://${host}/ws`;
}

// The connection badge's text for a Connection state and its detail.
export function connectionLabel(state, detail) {
  if (state === 'open') return 'connected';
  if (state === 'connecting') return 'connecting…';
  return `disconnected${detail ? ' — ' + detail : ''}; retrying`;
}

// ---- runs ------------------------------------------------------------------------

// A run's summary with every field the page uses, from an entry of the `runs`
// message (or only an id and a name, before the list has it).
export function runSummary({ run, name = String(run), status = '', iteration = 0, stems = 0, nodes = 0 }) {
  return { run, name, status, iteration, stems, nodes };
}

// The cells of a run's row in the run list.
export function runCells(r) {
  const status = r.loading ? `${r.status} (loading)` : r.status;
  return [r.name, status, String(r.iteration), String(r.stems), r.nodes.toLocaleString('en')];
}

// The location hash that names a run: `#run=NAME`, NAME percent-encoded.
export function runHash(name) {
  return `#run=${encodeURIComponent(name)}`;
}

// The run name in a location hash (`#run=NAME`, possibly among other `&` parts),
// or null when it names none or cannot be decoded.
export function runFromHash(hash) {
  for (const part of hash.replace(/^#/, '').split('&')) {
    if (!part.startsWith('run=')) continue;
    try {
      const name = decodeURIComponent(part.slice(4));
      return name === '' ? null : name;
    } catch {
      return null;
    }
  }
  return null;
}

// The most recently active run of a list in creation order (as `list` and
// /api/runs give it, with no time field): the newest run that is running, else
// the newest run; null for an empty list.
export function mostRecentRun(runs) {
  for (let i = runs.length - 1; i >= 0; i--) if (runs[i].status === 'running') return runs[i];
  return runs.length ? runs[runs.length - 1] : null;
}

// The run a page opens on: the one its hash names when the list has it,
// otherwise the most recently active one.
export function initialRun(runs, hash) {
  const name = runFromHash(hash);
  return runs.find((r) => r.name === name) || mostRecentRun(runs);
}

// Which of start, pause, step and stop are disabled for a run's status (null: no
// run selected).
export function controlsDisabled(status) {
  if (status === null) return { start: true, pause: true, step: true, stop: true };
  const ended = status === 'finished' || status === 'failed';
  return { start: ended || status === 'running', pause: status !== 'running', step: ended, stop: ended };
}

// The count of a step from its field: at least 1.
export function stepCount(text) {
  return Math.max(1, Number(text) || 1);
}

// The address of the daemon's export of a run's iteration.
export function exportHref(name, format, iteration) {
  return `api/runs/${encodeURIComponent(name)}/export?format=${format}&iteration=${iteration}`;
}

// ---- edits -----------------------------------------------------------------------

// The first `${prefix}N` (N = 1, 2, ...) not in the set `taken`.
export function freeId(prefix, taken) {
  for (let i = 1; ; i++) if (!taken.has(`${prefix}${i}`)) return `${prefix}${i}`;
}

// A ground point typed as "x, y": [x, y], or null when it is not two numbers
// (an empty part is no number).
export function parsePoint(text) {
  const parts = text.split(',');
  if (parts.length !== 2 || parts.some((p) => p.trim() === '')) return null;
  const v = parts.map(Number);
  return v.every(Number.isFinite) ? v : null;
}

// An axis-aligned box from two ground corners: a wall stands on the ground up to
// its height z, a board lies at its height z; both at least `t` thick.
export function obstacleBox(kind, a, b, z, t) {
  const min = [Math.min(a[0], b[0]), Math.min(a[1], b[1])], max = [Math.max(a[0], b[0]), Math.max(a[1], b[1])];
  for (const i of [0, 1]) {
    if (max[i] - min[i] < t) {
      const c = (min[i] + max[i]) / 2;
      min[i] = c - t / 2;
      max[i] = c + t / 2;
    }
  }
  if (kind === 'wall') return { min: [...min, 0].map(round), max: [...max, z].map(round) };
  return { min: [...min, z].map(round), max: [...max, z + t].map(round) };
}

// The obstacle of the edit tools' fields (kind, the two corners, the height and
// the thickness as typed), named by the first free `${kind}N` among the ids
// `taken`: {obstacle} for `add_obstacles`, or {error} saying what is wrong.
export function obstacleFromFields({ kind, cornerA, cornerB, z, thickness }, taken) {
  const a = parsePoint(cornerA), b = parsePoint(cornerB);
  const zm = Number(z), t = Number(thickness);
  if (!a || !b) return { error: 'give both corners as "x, y" (or pick them on the ground)' };
  if (z.trim() === '' || !Number.isFinite(zm) || !Number.isFinite(t) || t <= 0) {
    return { error: 'height and thickness must be numbers' };
  }
  return { obstacle: { id: freeId(kind, taken), kind: 'box', ...obstacleBox(kind, a, b, zm, t) } };
}

// The zone of the edit tools' fields: the box over two ground corners (at
// least `thickness` wide each way) from height `base` up to height `top`, named
// by the first free `zoneN` among the ids `taken`: {obstacle} for
// `add_obstacles` (`"kind": "zone"`), or {error} saying what is wrong.
export function zoneFromFields({ cornerA, cornerB, base, top, thickness }, taken) {
  const a = parsePoint(cornerA), b = parsePoint(cornerB);
  const z0 = Number(base), z1 = Number(top), t = Number(thickness);
  if (!a || !b) return { error: 'give both corners as "x, y" (or pick them on the ground)' };
  if (base.trim() === '' || top.trim() === '' || !Number.isFinite(z0) || !Number.isFinite(z1) ||
      !Number.isFinite(t) || t <= 0) {
    return { error: 'the heights and the thickness must be numbers' };
  }
  if (!(round(z1) > round(z0))) return { error: 'a zone\'s top must be above its bottom' };
  const { min, max } = obstacleBox('board', a, b, 0, t);
  return { obstacle: { id: freeId('zone', taken), kind: 'zone', min: [min[0], min[1], round(z0)],
    max: [max[0], max[1], round(z1)] } };
}

// A new plant of `species` rooted at the ground point (x, y), named by the first
// free `treeN` among the plant ids `taken`, for `add_plants`.
export function plantAt(x, y, species, taken) {
  return { id: freeId('tree', taken), species, roots: [[round(x), round(y), 0]] };
}

// ---- creating runs ---------------------------------------------------------------

// A scenario document from pasted or uploaded text; throws an Error saying why
// when the text is not JSON or not a JSON object.
export function parseScenario(text) {
  const doc = JSON.parse(text);
  if (doc === null || typeof doc !== 'object' || Array.isArray(doc)) throw new Error('a scenario is a JSON object');
  return doc;
}

// Where a refused `create` is shown: 'name' (next to the name field) for a bad or
// taken name, 'form' (next to the scenario field it names) for any other refusal
// by the daemon, 'message' (the message line) for a failure without a reply.
export function createErrorPlace(message, fromDaemon) {
  if (/^\/name\b/.test(message) || /exists/.test(message)) return 'name';
  return fromDaemon ? 'form' : 'message';
}

// ---- plots -----------------------------------------------------------------------

// The cells of one CSV line (RFC 4180: a quoted cell may hold commas, and "" is
// a quote in it).
export function csvCells(line) {
  const cells = [];
  let i = 0;
  for (;;) {
    let cell = '';
    if (line[i] === '"') {
      for (i++; i < line.length; i++) {
        if (line[i] !== '"') cell += line[i];
        else if (line[i + 1] === '"') { cell += '"'; i++; }
        else { i++; break; }
      }
      const comma = line.indexOf(',', i);
      i = comma < 0 ? line.length : comma;
    } else {
      const comma = line.indexOf(',', i);
      cell = line.slice(i, comma < 0 ? line.length : comma);
      i = comma < 0 ? line.length : comma;
    }
    cells.push(cell);
    if (i >= line.length) return cells;
    i++;   // past the comma
  }
}

// Cells of stats.csv that hold JSON objects (zones entered, clearances).
const JSON_COLUMNS = new Set(['zones', 'clearance']);

// `sylva export --format csv` (stats.csv) text as a Map from iteration to its
// stats rows, one per stem: numbers, booleans, null for an empty cell, `plant` as
// text, `zones` and `clearance` as the objects their JSON cells hold.
export function parseStatsCsv(text) {
  const lines = text.trim().split('\n');
  const head = csvCells(lines.shift());
  const byIteration = new Map();
  for (const line of lines) {
    if (!line) continue;
    const cells = csvCells(line);
    const row = Object.fromEntries(head.map((h, i) => {
      const c = cells[i] ?? '';
      if (h === 'plant') return [h, c];
      if (c === '') return [h, null];
      if (JSON_COLUMNS.has(h)) return [h, JSON.parse(c)];
      return [h, c === 'true' ? true : c === 'false' ? false : Number(c)];
    }));
    if (!byIteration.has(row.iteration)) byIteration.set(row.iteration, []);
    byIteration.get(row.iteration).push(row);
  }
  return byIteration;
}

// ---- years -----------------------------------------------------------------------

// The calendar year of an iteration of a run whose iteration 0 is `startYear`, or
// null for a run without a start year.
export function yearOf(iteration, startYear) {
  return startYear == null ? null : startYear + iteration;
}

// How the page names an iteration: "iteration 7", or with a start year
// "2034 (iteration 7)".
export function iterationLabel(iteration, startYear) {
  return startYear == null ? `iteration ${iteration}` : `${startYear + iteration} (iteration ${iteration})`;
}

// Whether per-stem stats are a years run's: they carry a crown diameter.
export function statsInYears(stats) {
  return (stats || []).some((st) => st.crown_diameter != null);
}

// ---- light -----------------------------------------------------------------------

// What the light slice is called for a run's sky ('site', 'zenith', or null
// before the run's snapshot names it).
export function skyLabel(sky) {
  if (sky === 'site') return 'site light (sun and sky)';
  if (sky === 'zenith') return 'zenith light';
  return 'light';
}

// ---- measured trees --------------------------------------------------------------

// The pipe model's exponent a measured tree's past is drawn with (docs/model.md:
// `pipe_exponent`'s default v; a snapshot does not carry the species' own).
export const PIPE_EXPONENT = 2.5;

// A measured tree's stage at an iteration T before iteration 0 (docs/model.md,
// "Measured trees"), from the nodes at iteration 0 held in slots, each parent
// before its children: `parent` (a slot, -1 for a root), `birth`, `radius`, and
// optionally `dead` (slots to leave out, with their subtrees), over slots 0 to
// count - 1. Returns {slots, radius}: the slots shown at T in slot order (born by
// T, with their parent shown: births never decrease from parent to child, so
// that is the nodes born by T), and each one's radius by the pipe model of that
// stage: its radius at 0 times (tips of its subtree shown at T / tips of its
// subtree at 0)^(1 / exponent).
export function pastStage({ parent, birth, radius, dead = null, count }, T, exponent = PIPE_EXPONENT) {
  const shown = new Uint8Array(count);
  let n = 0;
  for (let k = 0; k < count; k++) {
    if (dead && dead[k]) continue;
    const p = parent[k];
    if (birth[k] <= T && (p < 0 || shown[p])) {
      shown[k] = 1;
      n++;
    }
  }
  // tips from the leaves down: a slot without children is a tip of its own subtree
  const tips0 = new Float64Array(count), tipsT = new Float64Array(count);
  for (let k = count - 1; k >= 0; k--) {
    if (dead && dead[k]) continue;
    const p = parent[k];
    if (tips0[k] === 0) tips0[k] = 1;
    if (p >= 0) tips0[p] += tips0[k];
    if (!shown[k]) continue;
    if (tipsT[k] === 0) tipsT[k] = 1;
    if (p >= 0) tipsT[p] += tipsT[k];
  }
  const slots = new Int32Array(n), r = new Float32Array(n);
  for (let k = 0, i = 0; k < count; k++) {
    if (!shown[k]) continue;
    slots[i] = k;
    r[i++] = tipsT[k] === tips0[k] ? radius[k] : radius[k] * Math.pow(tipsT[k] / tips0[k], 1 / exponent);
  }
  return { slots, radius: r };
}
