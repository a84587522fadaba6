// The runs panel: every run of the daemon with its status, iteration, stems and
// internodes, refreshed every 2 s; a click watches a run. The location hash names
// the watched run (`#run=NAME`), so a reload or a bookmark opens it again. A page
// that watches nothing opens the run its hash names, or else the most recently
// active run (helpers.mjs, initialRun), as soon as the list has one.
import { $ } from './dom.mjs';
import { initialRun, runCells, runFromHash, runHash } from './helpers.mjs';

const REFRESH_MS = 2000;

export class RunsPanel {
  constructor({ session, watch }) {
    this.session = session;
    this.watch = watch;
    this.runs = [];   // the `runs` message's list, in creation order
    this.body = $('runs').tBodies[0];
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
    this.render();
  }

  render() {
    this.body.textContent = '';
    const watched = this.watch.run?.run;
    for (const r of this.runs) {
      const tr = this.body.insertRow();
      tr.dataset.run = r.run;
      tr.classList.toggle('selected', watched === r.run);
      for (const v of runCells(r)) tr.insertCell().textContent = v;
      tr.cells[0].title = r.name;
      tr.onclick = () => this.select(r);
    }
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
