// The viewer's wiring: the session with the daemon, the watched run, the 3D view,
// the plots and the panels (runs, zone conflicts, new run, controls, edit tools,
// timeline, light), the compare view, and what each daemon message and each
// change of the watched run updates. window.sylva exposes the page's state for tests and debugging.
import { $ } from './dom.mjs';
import { Session } from './session.mjs';
import { Watch } from './watch.mjs';
import { View } from './scene.mjs';
import { Plots, StandFigures } from './plots.mjs';
import { RunsPanel } from './runs.mjs';
import { CreatePanel } from './create.mjs';
import { ControlsPanel } from './controls.mjs';
import { EditTools } from './edit.mjs';
import { Timeline } from './timeline.mjs';
import { LightPanel } from './light.mjs';
import { ShadePanel } from './shade.mjs';
import { ConflictsPanel } from './conflicts.mjs';
import { CompareView } from './compare.mjs';
import { countInZones, zonesOf } from './zones.mjs';
import { yearOf } from './helpers.mjs';
import { stemsThreshold } from './stems.mjs';

// What the daemon pushes (replies to requests go to their callers).
const handlers = {
  welcome: (msg) => session.welcome(msg),
  snapshot: (msg) => watch.snapshot(msg),
  delta: (msg, meta) => watch.delta(msg, meta),
  status: (msg) => {
    runs.status(msg);
    watch.status(msg);
  },
  error: (msg) => session.message(msg.message, true),
};

const session = new Session({
  onOpen: () => {
    runs.refresh();
    create.loadScenarios();
    watch.resume();
  },
  onMessage: (msg, meta) => handlers[msg.type]?.(msg, meta),
});
const view = new View($('view'));
const plots = new Plots($('charts'));
const stand = new StandFigures($('stand'), $('stand-figures'));
const watch = new Watch({ session, view, plots, onChange: changed, stemsThreshold: stemsThreshold(location.search) });

// Watches a run that was just created or forked ({run, name}), then refreshes the
// run list, which has it now.
async function open(entry) {
  runs.select(entry);
  await runs.refresh();
}

const compare = new CompareView({ session });
const runs = new RunsPanel({
  session, watch, onCompare: (entries) => compare.open(entries), onList: (list) => compare.update(list),
  // a run clicked in the list is watched in the single view
  onPick: () => compare.close(),
});
const create = new CreatePanel({ session, open });
const controls = new ControlsPanel({ session, watch, onStatus: handlers.status, open });
const edit = new EditTools({ session, watch, view });
const timeline = new Timeline({ session, watch });
const light = new LightPanel({ session, watch, view });
const shade = new ShadePanel({ session, watch, view });
const conflicts = new ConflictsPanel({ watch, timeline });

for (const b of document.querySelectorAll('[data-view]')) b.onclick = () => view.setView(b.dataset.view);

// Leaves or the bare skeleton: the button, or L outside a text field.
function toggleLeaves(on = !view.leaves.visible) {
  view.setLeaves(on);
  $('leaves-toggle').setAttribute('aria-pressed', String(on));
}
$('leaves-toggle').onclick = () => toggleLeaves();
// Stems (trunks and crowns from the stats) or every internode: the button.
function renderDetail() {
  $('detail-toggle').setAttribute('aria-pressed', String(watch.detail === 'stems'));
}
$('detail-toggle').onclick = () => watch.setDetail(watch.detail === 'stems' ? 'nodes' : 'stems');
document.addEventListener('keydown', (ev) => {
  if (ev.key !== 'l' && ev.key !== 'L') return;
  if (ev.ctrlKey || ev.metaKey || ev.altKey || ev.target.closest?.('input, textarea, select, [contenteditable]')) return;
  toggleLeaves();
});

// The panels that show what changed in the watched run (see watch.mjs).
function changed(what) {
  if (what === 'switch') {
    timeline.reset();
    runs.render();
    controls.switched();
    light.hide();
    light.render();
    shade.clear();
    shade.render();
    edit.render();
    conflicts.render();
    stand.render(watch.shown().stand);
    renderDetail();
  } else if (what === 'detail') {
    renderDetail();
  } else if (what === 'snapshot') {
    timeline.reset();
    edit.speciesOptions();
    light.render();
    shade.refresh();
  } else if (what === 'live') {
    timeline.liveChanged();
    controls.render();
    controls.renderExports();
    edit.render();
    conflicts.render();
    shade.refresh();
    stand.render(watch.shown().stand);
  } else if (what === 'shown') {
    shade.refresh();
    timeline.render();
    controls.renderExports();
    edit.render();
    conflicts.render();
    stand.render(watch.shown().stand);
  } else if (what === 'status') {
    controls.render();
  }
}

controls.render();
edit.render();
light.render();
shade.render();
conflicts.render();

// ---- state for tests and debugging -------------------------------------------------

window.sylva = {
  state: () => ({
    connection: session.state,
    run: watch.run?.run ?? null,
    name: watch.run?.name ?? null,
    status: watch.run?.status ?? null,
    live: !watch.history,
    iteration: watch.shown().iteration,
    startYear: watch.shown().startYear,
    year: yearOf(watch.shown().iteration, watch.shown().startYear),
    nodes: watch.shown().live,
    liveIteration: watch.live.iteration,
    liveNodes: watch.live.live,
    detail: watch.detail,
    liveDetail: watch.live.detail,
    drawnTrunks: view.stems.trunks,
    drawnCrowns: view.stems.crowns,
    seq: watch.live.seq,
    obstacles: watch.shown().obstacles.map((o) => o.id),
    plants: watch.shown().plants.map((p) => p.id),
    species: watch.live.species.slice(),
    slice: light.slice,
    shade: shade.state(),
    drawnInstances: (view.branches.mesh?.geometry.instanceCount ?? 0) - (view.branches.sk?.deadCount ?? 0),
    leaves: view.leaves.visible,
    drawnLeaves: view.leaves.visible ? view.leaves.live : 0,
    leafTotal: watch.shown().leafTotal,
    leafStride: view.leaves.stride,
    leafBudget: view.leaves.budget,
    leafPending: view.leaves.visible && view.leaves.pending(),
    drawnObstacles: view.drawnBounds('obstacle').map((b) => b.id),
    drawnZones: view.drawnBounds('zone'),
    zones: zonesOf(watch.shown().obstacles).map((o) => o.id),
    highlighted: view.branches.highlighted(),
    greyed: view.branches.greyed(),
    stand: watch.shown().stand,
    standFigures: stand.rows(),
    inZones: countInZones(watch.shown().end, watch.shown().dead, watch.shown().count, zonesOf(watch.shown().obstacles)),
    conflicts: conflicts.rows(),
    sky: light.sky,
    compass: view.compassAngle,
    frames: view.frames,
    auth: session.auth,
    authed: session.authed,
  }),
  timings: () => Object.fromEntries([...Object.entries(watch.timings).map(([k, v]) => [k, v.slice()]),
    ['renderMs', view.renderMs.slice()], ['frameMs', view.frameMs.slice()],
    ['leafRebuilds', view.leaves.rebuilds.map((r) => ({ ...r }))]]),
  setLeaves: (on) => toggleLeaves(on),
  // the leaves' budget of cards, kept (null: the default, lowered by slow frames)
  setLeafBudget: (n) => view.setLeafBudget(n),
  leafCards: () => view.leaves.cards(),
  memory: () => ({ skeletonBytes: watch.live.bytes() + (watch.history ? watch.history.bytes() : 0) }),
  plots: () => plots.points(),
  skeleton: () => watch.shown().toExport(),
  project: (x, y, z) => view.project(x, y, z),
  setView: (name) => { view.setView(name); view.render(); },
  orbit: (angle) => view.orbit(angle),
  lookAt: (from, to) => { view.lookAt(from, to); view.render(); },
  shadeAt: (x, y) => shade.groundAt(x, y),
  shadeTexel: (x, y) => view.shadeTexel(x, y),
  shadeQuads: () => view.shadeQuads(),
  setObstacleVisible: (id, on) => { view.setObstacleVisible(id, on); view.render(); },
  // an obstacle's or zone's mesh as drawn: its bounds, triangles and volume
  obstacleMesh: (id) => {
    const m = view.obstacleMesh(id);
    return m && { ...m, ...[...view.drawnBounds('obstacle'), ...view.drawnBounds('zone')].find((b) => b.id === id) };
  },
  // the obstacles and zones a vertical ray down through (x, y) meets, from the top
  obstaclesAt: (x, y) => view.obstaclesAt(x, y),
  render: () => view.render(),
  compare: () => compare.state(),
  compareImages: () => compare.images(),
};
