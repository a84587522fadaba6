// The runs panel: every run of the daemon with its status, iteration, stems and
// internodes, refreshed every 2 s; a click watches a run. The location hash names
// the watched run (`#run=NAME`), so a reload or a bookmark opens it again. A page
// that watches nothing opens the run its hash names, or else the most recently
// active run (helpers.mjs, initialRun), as soon as the list has one.
//
// The runs of a sweep are listed together under a row of the sweep's name, each
// by its place on the sweep's axes (sweeps.mjs). Each run has a box to tick: two
// to four ticked runs open side by side in the compare view (compare.mjs), and a
// sweep that varies species has "compare species" in its row, which ticks and
// opens those of its runs that differ on species alone. The sweep's row keeps
// its links and buttons together (sweepActions), for what else acts on a whole
// sweep: its report (`sylva report`, as the daemon serves it at
// api/sweeps/NAME/report.EXT) as HTML, CSV or PDF.
import { $ } from './dom.mjs';
import { initialRun, runCells, runFromHash, runHash } from './helpers.mjs';
import { MAX_COMPARED, axesOf, groupRuns, speciesComparison } from './sweeps.mjs';

const REFRESH_MS = 2000;
// The formats of a sweep's report: the route's extension and the link's label.
const REPORTS = [['html', 'HTML'], ['csv', 'CSV'], ['pdf', 'PDF']];

// The daemon's route of a sweep's report (relative, as the page's other routes).
function reportHref(sweep, ext) {
  return `api/sweeps/${encodeURIComponent(sweep)}/report.${ext}`;
}

// A label that a narrow cell may break after its colons (a preset's name such as
// utdb:NoEast:PLAC) rather than anywhere.
function breakable(text) {
  return text.split(/(?<=:)/).flatMap((part, i) => (i ? [document.createElement('wbr'), part] : [part]));
}

export class RunsPanel {
  // onCompare(entries): open the compare view on these runs; onList(runs): the
  // list was refreshed; onPick(): a run's row was clicked, to be watched.
  constructor({ session, watch, onCompare = () => {}, onList = () => {}, onPick = () => {} }) {
    this.session = session;
    this.watch = watch;
    this.onCompare = onCompare;
    this.onList = onList;
    this.onPick = onPick;
    this.runs = [];   // the `runs` message's list, in creation order
    this.picked = new Set();   // the ids of the runs ticked for comparing
    this.body = $('runs').tBodies[0];
    $('compare-button').onclick = () => this.onCompare(this.pickedRuns());
    setInterval(() => { if (session.state === 'open') this.refresh(); }, REFRESH_MS);
    // the hash changed by hand, or by going back or forward
    addEventListener('hashchange', () => this.followHash());
  }

  async refresh() {
    try {
      const r = await this.session.request({ type: 'list' });
      this.runs = r.runs;
    } catch {
      return;   // the connection state says why
    }
    for (const r of this.runs) this.watch.update(r);
    if (!this.watch.run) {
      const r = initialRun(this.runs, location.hash);
      if (r) this.select(r, { replaceHash: true });
    }
    this.onList(this.runs);
    this.render();
  }

  render() {
    this.body.textContent = '';
    for (const g of groupRuns(this.runs)) {
      if (g.sweep !== null) this.sweepRow(g);
      for (const r of g.runs) this.runRow(r, g.sweep !== null);
    }
    this.renderPicked();
  }

  runRow(r, swept) {
    const tr = this.body.insertRow();
    tr.dataset.run = r.run;
    if (swept) tr.dataset.sweep = r.sweep;
    tr.classList.toggle('selected', this.watch.run?.run === r.run);
    for (const v of runCells(r)) tr.insertCell().textContent = v;
    const first = tr.cells[0];
    first.title = r.name;
    const box = document.createElement('input');
    box.type = 'checkbox';
    box.className = 'pick';
    box.title = 'compare';
    box.checked = this.picked.has(r.run);
    box.disabled = !box.checked && this.picked.size >= MAX_COMPARED;
    box.onclick = (e) => {
      e.stopPropagation();   // ticking is not watching
      if (box.checked) this.picked.add(r.run);
      else this.picked.delete(r.run);
      this.render();
    };
    if (swept) {
      // the sweep's row names it: the run is told by its place on the axes
      first.textContent = '';
      for (const a of axesOf(r)) {
        const chip = document.createElement('span');
        chip.className = 'chip axis';
        chip.dataset.axis = a.axis;
        chip.append(...breakable(a.label));
        first.append(chip, ' ');
      }
    }
    first.prepend(box);
    tr.onclick = () => {
      this.onPick();
      this.select(r);
    };
  }

  // The row of a sweep's name, above its runs.
  sweepRow(g) {
    const tr = this.body.insertRow();
    tr.className = 'sweep';
    tr.dataset.sweep = g.sweep;
    const td = tr.insertCell();
    td.colSpan = 5;
    const name = document.createElement('span');
    name.className = 'sweep-name';
    name.textContent = g.sweep;
    const count = document.createElement('span');
    count.className = 'note';
    count.textContent = `${g.runs.length} run${g.runs.length === 1 ? '' : 's'}`;
    td.append(name, ' ', count, ' ', this.sweepActions(g));
  }

  // What acts on a whole sweep, beside its name.
  sweepActions(g) {
    const actions = document.createElement('span');
    actions.className = 'sweep-actions';
    const species = speciesComparison(g.runs, MAX_COMPARED);
    if (species.length) {
      const b = document.createElement('button');
      b.className = 'compare-species';
      b.textContent = 'compare species';
      b.title = `${species.length} runs of this sweep that differ in species alone, side by side`;
      b.onclick = () => {
        this.picked = new Set(species.map((r) => r.run));
        this.render();
        this.onCompare(species);
      };
      actions.append(b);
    }
    actions.append(this.reportLinks(g.sweep));
    return actions;
  }

  // "report HTML CSV PDF": the sweep's report at the years `sylva report` takes by
  // default, downloaded as a file.
  reportLinks(sweep) {
    const span = document.createElement('span');
    span.className = 'sweep-report';
    span.title = 'this sweep\'s report (sylva report): the runs compared at years 10, 20 and 40';
    span.append('report');
    for (const [ext, label] of REPORTS) {
      const a = document.createElement('a');
      a.className = 'report';
      a.dataset.format = ext;
      a.href = reportHref(sweep, ext);
      a.download = '';
      a.textContent = label;
      // with a token for reading, the link fetches with it (a plain link cannot)
      a.onclick = (ev) => {
        if (this.session.publicRead) return;
        ev.preventDefault();
        this.session.download(a.getAttribute('href'));
      };
      span.append(' ', a);
    }
    return span;
  }

  // The ticked runs that the list still has, in its order.
  pickedRuns() {
    return groupRuns(this.runs).flatMap((g) => g.runs).filter((r) => this.picked.has(r.run));
  }

  renderPicked() {
    const n = this.pickedRuns().length;
    $('compare-button').disabled = n < 2 || n > MAX_COMPARED;
    $('compare-picked').textContent = n ? `${n} ticked` : `tick 2 to ${MAX_COMPARED} runs to compare them`;
  }

  // Watches a run ({run, name}: an entry of the list, or a `created` reply) and
  // names it in the location hash: a new history entry, or with replaceHash the
  // current one replaced (the page's first run).
  select(entry, { replaceHash = false } = {}) {
    if (this.watch.run?.run === entry.run) return;
    this.watch.switchTo(this.runs.find((x) => x.run === entry.run) || entry);
    const hash = runHash(this.watch.run.name);
    if (location.hash !== hash) {
      if (replaceHash) history.replaceState(null, '', hash);
      else location.hash = hash;
    }
  }

  // Watches the run the location hash names, when the list has it; otherwise
  // the hash names the watched run again.
  followHash() {
    const name = runFromHash(location.hash);
    const r = this.runs.find((x) => x.name === name);
    if (r) this.select(r);
    else if (this.watch.run) history.replaceState(null, '', runHash(this.watch.run.name));
  }

  // A run's status changed (the daemon's `status` message).
  status(msg) {
    const r = this.runs.find((x) => x.run === msg.run);
    if (r) r.status = msg.status;
    this.render();
  }
}
