// The viewer: wires the connection, the skeletons, the 3D view, the plots and the
// controls. The page holds one live skeleton of the selected run (a snapshot, then
// deltas applied in place) and, while the timeline shows the past, one stored
// iteration's skeleton. window.sylva exposes its state for tests and debugging.
import { Connection } from './connection.mjs';
import { Skeleton } from './skeleton.mjs';
import { View, lightColor } from './scene.mjs';
import { Plots, parseStatsCsv } from './plots.mjs';
import { ScenarioForm } from './scenario_form.mjs';

const $ = (id) => document.getElementById(id);
const TIMINGS = 200;   // delta timings kept for the page's state

const app = {
  run: null,          // {run, name, status, iteration, stems, nodes}
  live: new Skeleton(),
  history: null,      // a stored iteration's skeleton while the timeline shows it
  runs: [],
  auth: false,        // the daemon needs a token
  authed: false,
  token: sessionStorage.getItem('sylva.token') || '',
  applyMs: [],
  parseMs: [],
  bytes: [],
  held: [],           // [iteration, internodes held] after each delta
  tidyMs: [],
  mode: null,         // 'tree' | 'corners' while waiting for ground clicks
  getSerial: 0,
};

const view = new View($('view'));
const plots = new Plots($('plots'));
const form = new ScenarioForm($('scenario-form'));

function shown() { return app.history || app.live; }

function message(text, isError = false) {
  const el = $('message');
  el.textContent = text;
  el.classList.toggle('error', isError);
}

// ---- connection ------------------------------------------------------------------

const wsUrl = `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`;
const conn = new Connection(wsUrl, {
  onState: (state, detail) => {
    const el = $('connection');
    el.dataset.state = state;
    el.textContent = state === 'open' ? 'connected' : state === 'connecting' ? 'connecting…'
      : `disconnected${detail ? ' — ' + detail : ''}; retrying`;
  },
  onOpen: async () => {
    hello().catch(() => {});
    refreshRuns();
    loadScenarios();
    if (app.run) subscribe(app.run.run, app.live.seq >= 0 ? app.live.seq : undefined);
  },
  onMessage: (msg) => handlers[msg.type]?.(msg),
});

async function hello() {
  try {
    const w = await conn.request({ type: 'hello', ...(app.token ? { token: app.token } : {}) });
    app.auth = w.auth;
    app.authed = true;
  } catch (e) {
    if (e.code !== 'unauthorized') throw e;
    app.auth = true;
    app.authed = false;
  }
}

// Asks for the token when the daemon needs one and the page has none that works.
function ensureAuth() {
  if (!app.auth || app.authed) return Promise.resolve();
  return new Promise((resolve, reject) => {
    const dlg = $('token-dialog');
    $('token-input').value = app.token;
    $('token-error').hidden = !app.token;
    $('token-error').textContent = app.token ? 'That token was refused.' : '';
    dlg.onclose = async () => {
      if (dlg.returnValue !== 'ok') { reject(new Error('a token is needed for this')); return; }
      app.token = $('token-input').value;
      sessionStorage.setItem('sylva.token', app.token);
      await hello().catch(() => {});
      if (app.authed) resolve(); else ensureAuth().then(resolve, reject);
    };
    dlg.showModal();
  });
}

// Sends a changing message (asking for the token first when needed).
async function change(msg) {
  await ensureAuth();
  try {
    return await conn.request(msg);
  } catch (e) {
    if (e.code === 'unauthorized') {
      app.authed = false;
      await ensureAuth();
      return conn.request(msg);
    }
    throw e;
  }
}

// ---- runs ------------------------------------------------------------------------

async function refreshRuns() {
  try {
    const r = await conn.request({ type: 'list' });
    app.runs = r.runs;
    renderRuns();
  } catch { /* the connection state says why */ }
}
setInterval(() => { if (conn.state === 'open') refreshRuns(); }, 2000);

function renderRuns() {
  const body = $('runs').tBodies[0];
  body.textContent = '';
  for (const r of app.runs) {
    const tr = body.insertRow();
    tr.dataset.run = r.run;
    tr.classList.toggle('selected', app.run?.run === r.run);
    for (const v of [r.name, r.status, r.iteration, r.stems, r.nodes.toLocaleString('en')]) {
      tr.insertCell().textContent = v;
    }
    tr.onclick = () => select(r.run);
    if (app.run?.run === r.run) Object.assign(app.run, r, { iteration: app.live.iteration || r.iteration });
  }
  renderStatus();
}

function select(runId) {
  if (app.run?.run === runId) return;
  if (app.run) conn.send({ type: 'unsubscribe', run: app.run.run });
  const r = app.runs.find((x) => x.run === runId) || { run: runId, name: String(runId), status: '' };
  app.run = { ...r };
  app.live = new Skeleton();
  app.history = null;
  app.held = [];
  app.statsLoaded = false;
  plots.reset();
  view.setSlice(null);
  $('legend').hidden = true;
  $('run-title').textContent = r.name;
  $('fork-name').value = `${r.name}-fork`;
  subscribe(runId);
  renderRuns();
}

function subscribe(runId, since) {
  conn.send({ type: 'subscribe', run: runId, ...(since !== undefined ? { since } : {}) });
}

// The stats of every stored iteration (the plots' history), once per run.
async function loadStats() {
  const run = app.run;
  try {
    const res = await fetch(`api/runs/${encodeURIComponent(run.name)}/stats.csv`);
    if (!res.ok || app.run !== run) return;
    const rows = parseStatsCsv(await res.text());
    for (const [it, stats] of rows) if (it <= app.live.iteration) plots.add(it, stats);
  } catch (e) {
    message(`stats could not be loaded: ${e.message}`, true);
  }
}

// ---- messages from the daemon ------------------------------------------------------

const handlers = {
  welcome(msg) {
    app.auth = msg.auth;
  },
  snapshot(msg) {
    if (msg.run !== app.run?.run) return;
    app.live.loadSnapshot(msg);
    app.run.iteration = msg.iteration;
    plots.setPlants(app.live.plants.map((p) => p.id));
    plots.truncate(msg.iteration);
    if (msg.iteration > 0) plots.add(msg.iteration, msg.stats);
    if (!app.statsLoaded) {
      app.statsLoaded = true;
      loadStats();
    }
    speciesOptions();
    if (!app.history) view.show(app.live);
    liveChanged();
  },
  delta(msg) {
    if (msg.run !== app.run?.run) return;
    if (msg.seq <= app.live.seq) return;   // already held (a replay after a snapshot)
    if (msg.seq !== app.live.seq + 1) {
      // a gap: ask for what was missed
      subscribe(msg.run, app.live.seq);
      return;
    }
    const t0 = performance.now();
    app.live.applyDelta(msg);
    if (!app.history) view.show(app.live);
    app.applyMs.push(performance.now() - t0);
    tidyLater(app.live);
    app.parseMs.push(msg.parseMs || 0);
    app.bytes.push(msg.bytes || 0);
    app.held.push([msg.iteration, app.live.live]);
    for (const a of [app.applyMs, app.parseMs, app.bytes, app.held]) if (a.length > TIMINGS) a.shift();
    app.run.iteration = msg.iteration;
    plots.add(msg.iteration, msg.stats);
    liveChanged();
  },
  status(msg) {
    const r = app.runs.find((x) => x.run === msg.run);
    if (r) Object.assign(r, { status: msg.status });
    if (msg.run === app.run?.run) app.run.status = msg.status;
    renderRuns();
  },
  error(msg) {
    message(msg.message, true);
  },
};

// Squeezing out shed slots and growing the arrays ahead of need run in a task of
// their own after a delta, so that no single task holds the page for long.
function tidyLater(sk) {
  if (sk.tidying) return;
  sk.tidying = true;
  setTimeout(() => {
    sk.tidying = false;
    const t0 = performance.now();
    const moved = sk.compact(), grew = sk.growAhead();
    if ((moved || grew) && shown() === sk) view.show(sk);
    app.tidyMs.push(performance.now() - t0);
    if (app.tidyMs.length > TIMINGS) app.tidyMs.shift();
  }, 0);
}

// After the live skeleton changed (and the view, when live, was synced): the
// timeline and the labels.
function liveChanged() {
  const tl = $('timeline');
  tl.max = String(app.live.iteration);
  if (!app.history) tl.value = String(app.live.iteration);
  renderShown();
  renderStatus();
}

function renderShown() {
  const s = shown();
  $('timeline-label').textContent = app.history ? `iteration ${s.iteration} (stored)` : `iteration ${s.iteration} (live)`;
  $('live').disabled = !app.history;
  $('view-info').textContent = `iteration ${s.iteration} · ${s.live.toLocaleString('en')} internodes`;
  const name = app.run ? encodeURIComponent(app.run.name) : '';
  for (const [id, format] of [['export-skeleton', 'skeleton'], ['export-obj', 'obj'], ['export-csv', 'csv']]) {
    $(id).href = app.run ? `api/runs/${name}/export?format=${format}&iteration=${s.iteration}` : '';
  }
  renderObstacles();
}

function renderStatus() {
  const st = app.run?.status || '';
  $('status').textContent = st;
  $('status').dataset.status = st;
  const ended = st === 'finished' || st === 'failed';
  $('start').disabled = !app.run || ended || st === 'running';
  $('pause').disabled = !app.run || st !== 'running';
  $('step').disabled = !app.run || ended;
  $('stop').disabled = !app.run || ended;
  for (const id of ['add-tree', 'add-obstacle', 'pick-corners', 'fork', 'light-show']) $(id).disabled = !app.run;
}

function renderObstacles() {
  const box = $('obstacles');
  box.textContent = '';
  for (const o of shown().obstacles) {
    const b = document.createElement('button');
    b.className = 'chip';
    b.textContent = `${o.id} ×`;
    b.title = `remove obstacle ${o.id}`;
    b.disabled = !!app.history;
    b.onclick = () => edit({ remove_obstacles: [o.id] }, `removed ${o.id}`);
    box.appendChild(b);
  }
}

function speciesOptions() {
  const sel = $('tree-species');
  const have = [...sel.options].map((o) => o.value).join('\n');
  if (have === app.live.species.join('\n')) return;
  sel.textContent = '';
  for (const s of app.live.species) sel.add(new Option(s, s));
}

// ---- controls ----------------------------------------------------------------------

async function control(action, extra = {}) {
  if (!app.run) return;
  try {
    const st = await change({ type: 'control', run: app.run.run, action, ...extra });
    handlers.status(st);
    message('');
  } catch (e) {
    message(e.message, true);
  }
}
$('start').onclick = () => control('start');
$('pause').onclick = () => control('pause');
$('stop').onclick = () => control('stop');
$('step').onclick = () => control('step', { count: Math.max(1, Number($('step-count').value) || 1) });

async function edit(fields, done) {
  try {
    await change({ type: 'edit', run: app.run.run, ...fields });
    message(done);
  } catch (e) {
    message(e.message, true);
  }
}

function freeId(prefix, taken) {
  for (let i = 1; ; i++) if (!taken.has(`${prefix}${i}`)) return `${prefix}${i}`;
}

const round = (v) => Math.round(v * 100) / 100;

$('add-tree').onclick = () => {
  app.mode = 'tree';
  message('click a ground point for the new tree');
};
$('pick-corners').onclick = () => {
  app.mode = 'corners';
  app.corners = [];
  message('click the first corner on the ground');
};
$('obstacle-kind').onchange = () => {
  const wall = $('obstacle-kind').value === 'wall';
  $('obstacle-z-label').firstChild.textContent = wall ? 'height ' : 'at z ';
};

function parsePoint(text) {
  const v = text.split(',').map((t) => Number(t.trim()));
  return v.length === 2 && v.every(Number.isFinite) ? v : null;
}

// An axis-aligned box from two ground corners: a wall stands on the ground up to
// its height, a board lies at its height; both at least `thickness` thick.
function obstacleBox(kind, a, b, z, t) {
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

$('add-obstacle').onclick = () => {
  const a = parsePoint($('corner-a').value), b = parsePoint($('corner-b').value);
  const z = Number($('obstacle-z').value), t = Number($('obstacle-t').value);
  if (!a || !b) { message('give both corners as "x, y" (or pick them on the ground)', true); return; }
  if (!Number.isFinite(z) || !Number.isFinite(t) || t <= 0) { message('height and thickness must be numbers', true); return; }
  const kind = $('obstacle-kind').value;
  const id = freeId(kind, new Set(app.live.obstacles.map((o) => o.id)));
  edit({ add_obstacles: [{ id, kind: 'box', ...obstacleBox(kind, a, b, z, t) }] }, `added ${id}`);
};

view.renderer.domElement.addEventListener('click', (ev) => {
  if (!app.mode || !app.run) return;
  const p = view.groundAt(ev.clientX, ev.clientY);
  if (!p) { message('that is not a ground point of the world', true); return; }
  const [x, y] = p.map(round);
  if (app.mode === 'tree') {
    app.mode = null;
    const species = $('tree-species').value;
    const id = freeId('tree', new Set(app.live.plants.map((q) => q.id)));
    edit({ add_plants: [{ id, species, roots: [[x, y, 0]] }] }, `added ${id} at ${x}, ${y}`);
  } else {
    app.corners.push([x, y]);
    $(app.corners.length === 1 ? 'corner-a' : 'corner-b').value = `${x}, ${y}`;
    if (app.corners.length === 2) { app.mode = null; message('corners set; press add'); }
    else message('click the second corner');
  }
});

// ---- timeline --------------------------------------------------------------------

$('timeline').oninput = () => {
  clearTimeout(app.timelineTimer);
  app.timelineTimer = setTimeout(() => showIteration(Number($('timeline').value)), 120);
};
$('live').onclick = () => goLive();

function goLive() {
  app.history = null;
  app.getSerial++;
  $('timeline').value = String(app.live.iteration);
  view.show(app.live);
  renderShown();
}

async function showIteration(it) {
  if (!app.run) return;
  if (it >= app.live.iteration) { goLive(); return; }
  const serial = ++app.getSerial;
  try {
    const snap = await conn.request({ type: 'get', run: app.run.run, iteration: it });
    if (serial !== app.getSerial) return;
    const h = new Skeleton();
    h.loadSnapshot(snap);
    app.history = h;
    view.show(h);
    renderShown();
  } catch (e) {
    message(e.message, true);
  }
}

// ---- light -----------------------------------------------------------------------

async function showLight() {
  const z = Number($('light-z').value);
  if (!Number.isFinite(z)) { message('the light height must be a number of metres', true); return; }
  try {
    const s = await conn.request({ type: 'light', run: app.run.run, z });
    view.setSlice(s);
    // seen edge-on from the front or the side, a horizontal slice would vanish
    if (view.viewName === 'front' || view.viewName === 'side') view.setView('top');
    app.slice = { z: s.z, iteration: s.iteration, nx: s.nx, ny: s.ny };
    $('legend').hidden = false;
    message(`light at ${s.z} m after iteration ${s.iteration}`);
  } catch (e) {
    message(e.message, true);
  }
}
$('light-show').onclick = () => showLight();
$('light-hide').onclick = () => { view.setSlice(null); app.slice = null; $('legend').hidden = true; };
$('legend').querySelector('.ramp').style.background =
  `linear-gradient(to right, ${[0, 0.25, 0.5, 0.75, 1].map((v) => `rgb(${lightColor(v)})`).join(', ')})`;

// ---- fork ------------------------------------------------------------------------

$('fork').onclick = async () => {
  const name = $('fork-name').value.trim();
  if (!name) { message('give the fork a name', true); return; }
  try {
    const c = await change({ type: 'fork', run: app.run.run, iteration: shown().iteration, name });
    await refreshRuns();
    select(c.run);
    message(`forked as ${c.name}`);
  } catch (e) {
    message(e.message, true);
  }
};

// ---- views -----------------------------------------------------------------------

for (const b of document.querySelectorAll('[data-view]')) b.onclick = () => view.setView(b.dataset.view);

// ---- creating runs ---------------------------------------------------------------

async function loadScenarios() {
  try {
    const r = await conn.request({ type: 'scenarios' });
    const sel = $('scenario-select');
    const keep = sel.value;
    sel.length = 1;
    for (const s of r.scenarios) sel.add(new Option(`${s.title} (${s.name})`, s.name));
    sel.value = keep;
  } catch { /* shown by the connection state */ }
}

function loadDocument(doc) {
  form.load(doc);
  $('create-name').value = typeof doc.name === 'string' ? doc.name : '';
  $('create-button').disabled = false;
  $('create-name-error').hidden = true;
}

$('scenario-select').onchange = async () => {
  const name = $('scenario-select').value;
  if (!name) return;
  try {
    const res = await fetch(`api/scenarios/${encodeURIComponent(name)}`);
    if (!res.ok) throw new Error(`${name}: ${res.status} ${res.statusText}`);
    const text = await res.text();
    $('scenario-text').value = text;
    loadDocument(JSON.parse(text));
  } catch (e) {
    message(e.message, true);
  }
};

function loadText(text) {
  const err = $('scenario-text-error');
  try {
    const doc = JSON.parse(text);
    if (doc === null || typeof doc !== 'object' || Array.isArray(doc)) throw new Error('a scenario is a JSON object');
    err.hidden = true;
    loadDocument(doc);
  } catch (e) {
    err.textContent = `not a scenario: ${e.message}`;
    err.hidden = false;
  }
}
$('scenario-load').onclick = () => loadText($('scenario-text').value);
$('scenario-file').onchange = async () => {
  const f = $('scenario-file').files[0];
  if (!f) return;
  const text = await f.text();
  $('scenario-text').value = text;
  loadText(text);
};

$('create-button').onclick = async () => {
  const name = $('create-name').value.trim();
  $('create-name-error').hidden = true;
  form.clearError();
  try {
    const c = await change({ type: 'create', scenario: form.doc, ...(name ? { name } : {}), start: $('create-start').checked });
    await refreshRuns();
    select(c.run);
    message(`created ${c.name}`);
  } catch (e) {
    if (/^\/name\b/.test(e.message) || /exists/.test(e.message)) {
      $('create-name-error').textContent = e.message;
      $('create-name-error').hidden = false;
    } else if (e.msg) {
      form.showError(e.message);
    } else {
      message(e.message, true);
    }
  }
};

renderStatus();

// ---- state for tests and debugging -------------------------------------------------

window.sylva = {
  state: () => ({
    connection: conn.state,
    run: app.run?.run ?? null,
    name: app.run?.name ?? null,
    status: app.run?.status ?? null,
    live: !app.history,
    iteration: shown().iteration,
    nodes: shown().live,
    liveIteration: app.live.iteration,
    liveNodes: app.live.live,
    seq: app.live.seq,
    obstacles: shown().obstacles.map((o) => o.id),
    plants: shown().plants.map((p) => p.id),
    species: app.live.species.slice(),
    slice: app.slice || null,
    drawnInstances: (view.branches.mesh?.geometry.instanceCount ?? 0) - (view.branches.sk?.deadCount ?? 0),
    drawnObstacles: view.obstacleGroup.children.filter((m) => m.name).map((m) => m.name.slice('obstacle:'.length)),
    frames: view.frames,
    auth: app.auth,
    authed: app.authed,
  }),
  timings: () => ({ applyMs: app.applyMs.slice(), parseMs: app.parseMs.slice(), bytes: app.bytes.slice(),
    renderMs: view.renderMs.slice(), held: app.held.slice(), tidyMs: app.tidyMs.slice() }),
  memory: () => ({ skeletonBytes: app.live.bytes() + (app.history ? app.history.bytes() : 0) }),
  plots: () => plots.points(),
  skeleton: () => shown().toExport(),
  project: (x, y, z) => view.project(x, y, z),
  setView: (name) => { view.setView(name); view.render(); },
  render: () => view.render(),
};
