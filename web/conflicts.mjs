// The conflicts panel: one row per stem and clearance zone it ever entered, from
// the live run's latest stats (each stem's `zones`: the iteration a node of it
// first entered the zone, a calendar year in a run with a start year, and its
// nodes inside now). A click on a row shows that first iteration on the
// timeline; the row of the shown stored iteration is marked. Below, each stem's
// clearance: the nearest solid obstacle within 10 m and how far its nodes keep
// from it, with the nodes pruned at the iteration.
import { $ } from './dom.mjs';
import { clearanceRows, conflictRows, stemLabel } from './zones.mjs';

// The page's panel (index.html); the compare view gives each of its runs a panel
// of its own, with these elements.
const pageElements = () => ({
  conflicts: $('conflicts'), first: $('conflicts-first'), empty: $('conflicts-empty'), clearances: $('clearances'),
});

export class ConflictsPanel {
  constructor({ watch, timeline, elements = pageElements() }) {
    this.watch = watch;
    this.timeline = timeline;
    this.el = elements;
    this.body = elements.conflicts.tBodies[0];
    this.clearBody = elements.clearances.tBodies[0];
    this.key = '';   // what the table shows, to rebuild it only when that changes
  }

  // The rows of the live run's latest stats (zones.mjs, conflictRows).
  rows() { return conflictRows(this.watch.live.stats); }

  // The clearances of the live run's latest stats (zones.mjs, clearanceRows).
  clearances() { return clearanceRows(this.watch.live.stats); }

  render() {
    const rows = this.rows(), clear = this.clearances();
    // `first` is a calendar year in a run with a start year, else an iteration
    const start = this.watch.live.startYear ?? 0;
    const shown = this.watch.history ? start + this.watch.shown().iteration : null;
    const key = JSON.stringify([this.watch.run?.run ?? null, shown, rows, clear]);
    if (key === this.key) return;
    this.key = key;
    const stems = new Map(this.watch.live.plants.map((p) => [p.id, p.stems.length]));
    this.el.first.textContent = start ? 'first year' : 'first';
    this.body.textContent = '';
    for (const r of rows) {
      const tr = this.body.insertRow();
      Object.assign(tr.dataset, { plant: r.plant, stem: r.stem, zone: r.zone, first: r.first, nodes: r.nodes });
      tr.title = `show ${start ? r.first : `iteration ${r.first}`}, when ${r.plant} first grew into ${r.zone}`;
      tr.classList.toggle('selected', shown === r.first);
      for (const v of [stemLabel(r.plant, r.stem, stems.get(r.plant) ?? 1), r.zone, String(r.first),
        r.nodes.toLocaleString('en')]) tr.insertCell().textContent = v;
      tr.onclick = () => this.timeline.jumpTo(r.first - start);
    }
    this.el.empty.hidden = rows.length > 0;
    this.clearBody.textContent = '';
    for (const r of clear) {
      const tr = this.clearBody.insertRow();
      Object.assign(tr.dataset, { plant: r.plant, stem: r.stem, obstacle: r.obstacle });
      for (const v of [stemLabel(r.plant, r.stem, stems.get(r.plant) ?? 1), r.obstacle,
        r.distance.toFixed(2), String(r.pruned)]) tr.insertCell().textContent = v;
    }
    this.el.clearances.hidden = clear.length === 0;
  }
}
