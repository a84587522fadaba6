// The compare view: two to four runs side by side, each in a 3D view of its own
// (scene.mjs) with its zone conflicts and clearances (conflicts.mjs), under one
// camera (orbiting, panning or zooming one view moves the others the same way)
// and one slider that shows every run at the same calendar year, or iteration
// (compare_scale.mjs). Each run's iterations come from the store as the
// timeline's do (timeline.mjs, StoredIterations), one request at a time, since
// the daemon restores only --max-jobs of them at once. Its conflicts are those of
// its last stored iteration, with the row of the shown one marked. The view
// opens over the single view and its bar, and Close goes back to them.
import { $ } from './dom.mjs';
import { View } from './scene.mjs';
import { ConflictsPanel } from './conflicts.mjs';
import { Skeleton } from './skeleton.mjs';
import { SETTLE_MS, StoredIterations } from './timeline.mjs';
import { iterationAt, scaleLabel, sharedScale } from './compare_scale.mjs';
import { MAX_COMPARED, axesOf } from './sweeps.mjs';
import { iterationLabel } from './helpers.mjs';

// One run's place in the grid. The views are made once and kept for the next
// comparison: a WebGL context per view, and each view's drawing loop lives as
// long as the page.
class Pane {
  constructor(grid, onJump) {
    this.el = $('compare-pane').content.firstElementChild.cloneNode(true);
    grid.append(this.el);
    const q = (c) => this.el.querySelector(c);
    this.view = new View(q('.pane-view'));
    this.info = q('.pane-info');
    this.entry = null;    // the run list's entry of the run
    this.source = null;   // StoredIterations of the run
    this.latest = new Skeleton();   // its last stored iteration: the conflicts' "now"
    this.shown = null;    // the skeleton the view shows
    this.hooked = null;   // the camera controls this pane listens to
    const pane = this;
    this.conflicts = new ConflictsPanel({
      // conflicts.mjs reads a watch: here the last stored iteration is "live"
      watch: {
        get run() { return pane.entry; },
        get live() { return pane.latest; },
        get history() { return pane.shown !== pane.latest ? pane.shown : null; },
        shown: () => pane.shown || pane.latest,
      },
      timeline: { jumpTo: (it) => onJump(this, it) },
      elements: { conflicts: q('.pane-zone-conflicts'), first: q('.pane-first'),
        empty: q('.pane-conflicts-empty'), clearances: q('.pane-clearances') },
    });
  }

  // Takes another run (an entry of the run list).
  reset(entry, session) {
    this.entry = entry;
    this.last = entry.iteration;   // its last stored iteration, as the run list says
    this.source = new StoredIterations(session, entry.run);
    this.latest = new Skeleton();
    this.shown = null;
    this.el.dataset.run = entry.run;
    // a sweep's runs are told apart by their axes, beside the sweep's name
    const name = this.el.querySelector('.pane-name');
    name.textContent = typeof entry.sweep === 'string' ? entry.sweep : entry.name;
    name.title = entry.name;
    const axes = this.el.querySelector('.pane-axes');
    axes.textContent = '';
    for (const a of axesOf(entry)) {
      const chip = document.createElement('span');
      chip.className = 'chip axis';
      chip.textContent = a.label;
      chip.title = `${a.axis}: ${a.value}`;
      axes.append(chip);
    }
    this.el.hidden = false;
    this.info.textContent = 'loading…';
    this.conflicts.render();
  }

  show(sk) {
    this.shown = sk;
    this.view.show(sk);
    this.info.textContent = `${iterationLabel(sk.iteration, sk.startYear)} · ${sk.live.toLocaleString('en')} internodes`;
    this.conflicts.render();
  }

  // What the slider needs of it (compare_scale.mjs).
  range() {
    return { startYear: this.latest.startYear, earliest: this.latest.earliest, last: this.last };
  }
}

export class CompareView {
  constructor({ session }) {
    this.session = session;
    this.slots = [];      // every Pane made so far
    this.panes = [];      // those of the compared runs, in order
    this.scale = sharedScale([]);
    this.opened = 0;      // the latest open(); a later one drops what an earlier one fetches
    this.moved = 0;       // the latest slider move; a fetch for an older one is not made
    this.chain = Promise.resolve();   // the fetches, one at a time
    this.pending = 0;     // fetches queued or in flight
    this.camera = null;   // the shared camera, as the view that moved last left it
    this.syncing = false;
    this.timer = 0;
    this.slider = $('compare-slider');
    this.slider.oninput = () => {
      clearTimeout(this.timer);
      this.timer = setTimeout(() => this.showAt(Number(this.slider.value)), SETTLE_MS);
    };
    $('compare-close').onclick = () => this.close();
    for (const b of document.querySelectorAll('[data-compare-view]')) b.onclick = () => this.setView(b.dataset.compareView);
  }

  get isOpen() { return !$('compare').hidden; }

  // Compares runs (entries of the run list, two to four; more are left out), each
  // at its last stored iteration, the slider at the end of its range. The slider
  // waits for them: its scale needs each run's start year and earliest birth.
  async open(entries) {
    const opened = ++this.opened;
    this.moved++;
    this.slider.disabled = true;
    entries = entries.slice(0, MAX_COMPARED);
    $('view').hidden = true;
    $('bar').hidden = true;
    $('compare').hidden = false;
    const grid = $('compare-grid');
    grid.dataset.count = entries.length;
    while (this.slots.length < entries.length) this.slots.push(new Pane(grid, (p, it) => this.jumpTo(p, it)));
    this.panes = this.slots.slice(0, entries.length);
    this.slots.forEach((p, i) => { if (i >= entries.length) p.el.hidden = true; });
    this.panes.forEach((p, i) => p.reset(entries[i], this.session));
    // a new comparison starts from the 3D camera, whatever the last one left
    this.camera = null;
    for (const p of this.panes) if (p.view.world) p.view.setView('persp');
    this.message('');
    this.rescale();
    this.renderLabel();
    for (const p of this.panes) {
      await this.queue(async () => {
        if (opened !== this.opened) return;
        const sk = await p.source.at(p.last);
        if (opened !== this.opened) return;
        p.latest = sk;
        this.showIn(p, sk);
      });
    }
    if (opened !== this.opened) return;
    this.rescale();
    this.slider.value = String(this.scale.max);
    this.slider.disabled = false;
    this.renderLabel();
    // runs of different worlds: the first one's camera for all, further back when
    // the panes are narrow, so that the width of its world fits
    if (!this.camera && this.panes.length) {
      const v = this.panes[0].view, el = v.container;
      const aspect = el.clientWidth / Math.max(1, el.clientHeight);
      if (v.camera === v.persp && aspect < 1) {
        const offset = v.camera.position.clone().sub(v.controls.target);
        v.camera.position.copy(v.controls.target).addScaledVector(offset, 1 / Math.max(aspect, 0.5));
        v.invalidate();
      }
      this.follow(this.panes[0]);
    }
  }

  close() {
    this.opened++;
    this.moved++;
    clearTimeout(this.timer);
    $('compare').hidden = true;
    $('view').hidden = false;
    $('bar').hidden = false;
  }

  // The run list was refreshed: a compared run that grew since reaches further.
  update(runs) {
    if (!this.isOpen) return;
    let grew = false;
    for (const p of this.panes) {
      const r = runs.find((x) => x.run === p.entry.run);
      if (r && r.iteration > p.last) {
        p.last = r.iteration;
        grew = true;
      }
    }
    if (grew) {
      this.rescale();
      this.renderLabel();
    }
  }

  // Runs fn after the fetches queued before it; resolves or rejects as it does
  // (the queue goes on either way).
  queue(fn) {
    this.pending++;
    const p = this.chain.then(fn).finally(() => { this.pending--; });
    this.chain = p.catch((e) => this.message(e.message, true));
    return p.catch(() => {});
  }

  // Shows every run at slider value v; resolves when they show it.
  showAt(v) {
    const moved = ++this.moved;
    this.renderLabel();
    const done = [];
    this.panes.forEach((p, i) => {
      const at = iterationAt(this.scale, i, p.range(), v);
      if (p.shown?.iteration === at) return;
      done.push(this.queue(async () => {
        if (moved !== this.moved) return;   // a later move asks for its own
        const sk = at === p.latest.iteration ? p.latest : await p.source.at(at);
        if (moved !== this.moved) return;
        if (sk.iteration > p.latest.iteration) p.latest = sk;
        this.showIn(p, sk);
      }));
    });
    return Promise.all(done);
  }

  // A conflicts row of pane p asks for its run's iteration `it`.
  jumpTo(p, it) {
    clearTimeout(this.timer);
    const v = it + this.scale.offsets[this.panes.indexOf(p)];
    this.slider.value = String(v);
    return this.showAt(Number(this.slider.value));
  }

  showIn(p, sk) {
    p.show(sk);
    this.hook(p);
    if (this.camera) this.applyCamera(p);
  }

  rescale() {
    this.scale = sharedScale(this.panes.map((p) => p.range()));
    this.slider.min = String(this.scale.min);
    this.slider.max = String(this.scale.max);
    $('compare-unit').textContent = this.scale.years ? 'Year' : 'Iteration';
  }

  renderLabel() {
    $('compare-label').textContent = scaleLabel(this.scale, Number(this.slider.value));
  }

  message(text, isError = false) {
    const el = $('compare-message');
    el.textContent = text;
    el.classList.toggle('error', isError);
  }

  // ---- one camera for all -------------------------------------------------------

  // Every view to one of the preset cameras (scene.mjs, setView).
  setView(name) {
    for (const p of this.panes) {
      p.view.setView(name);
      this.hook(p);
    }
    if (this.panes.length) this.follow(this.panes[0]);
  }

  // Listens to a pane's camera controls (a view makes new ones for each preset).
  hook(p) {
    const c = p.view.controls;
    if (p.hooked === c) return;
    p.hooked = c;
    c.addEventListener('change', () => { if (!this.syncing && p.view.controls === c) this.follow(p); });
  }

  // Pane p's camera moved: the others take its place.
  follow(p) {
    const v = p.view, cam = v.camera;
    this.camera = {
      name: v.viewName, position: cam.position.clone(), quaternion: cam.quaternion.clone(), zoom: cam.zoom,
      target: v.controls.target.clone(), orthoHalf: v.orthoHalf,
    };
    for (const q of this.panes) if (q !== p) this.applyCamera(q);
  }

  applyCamera(p) {
    const s = this.camera, v = p.view;
    this.syncing = true;
    if (v.viewName !== s.name) {
      v.setView(s.name);
      this.hook(p);
    }
    v.camera.position.copy(s.position);
    v.camera.quaternion.copy(s.quaternion);
    v.camera.zoom = s.zoom;
    if (v.camera === v.ortho) {
      v.orthoHalf = s.orthoHalf;
      v.fitOrtho();
    } else {
      v.camera.updateProjectionMatrix();
    }
    v.controls.target.copy(s.target);
    v.invalidate();
    this.syncing = false;
  }

  // ---- for tests and debugging --------------------------------------------------

  state() {
    return {
      open: this.isOpen,
      value: Number(this.slider.value),
      min: this.scale.min,
      max: this.scale.max,
      years: this.scale.years,
      label: $('compare-label').textContent,
      pending: this.pending,
      panes: this.panes.map((p) => ({
        run: p.entry.run,
        name: p.entry.name,
        axes: p.entry.axes ?? null,
        iteration: p.shown?.iteration ?? null,
        year: p.shown && p.shown.startYear != null ? p.shown.startYear + p.shown.iteration : null,
        nodes: p.shown?.live ?? 0,
        drawn: (p.view.branches.mesh?.geometry.instanceCount ?? 0) - (p.view.branches.sk?.deadCount ?? 0),
        info: p.info.textContent,
        view: p.view.viewName,
        camera: p.view.camera.position.toArray(),
        target: p.view.controls.target.toArray(),
        conflicts: p.conflicts.rows(),
        conflictRows: p.el.querySelectorAll('.pane-zone-conflicts tbody tr').length,
      })),
    };
  }

  // Each view's picture now, as a PNG data URL (drawn first: the canvas keeps no
  // picture between frames).
  images() {
    return this.panes.map((p) => {
      p.view.render();
      return p.view.renderer.domElement.toDataURL('image/png');
    });
  }
}
