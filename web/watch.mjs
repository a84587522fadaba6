// The run the page watches: its summary, its live skeleton (a snapshot, then
// deltas applied in place), the stored iteration the timeline shows instead of
// it, the plots' points, and the page's timings of each delta. It tells the page
// what changed through onChange(what):
//   'switch'   another run (or its summary) is watched;
//   'snapshot' the live skeleton was loaded from a snapshot (species may differ);
//   'live'     the live skeleton changed (after a snapshot or a delta);
//   'shown'    the shown skeleton is another one (stored or live);
//   'status'   the run's status changed;
//   'detail'   the detail it is watched at changed ('nodes' or 'stems', stems.mjs:
//              by the run's size when it is picked, or as the user chose).
import { Skeleton } from './skeleton.mjs';
import { detailFor, STEMS_THRESHOLD } from './stems.mjs';
import { parseStatsCsv, runSummary } from './helpers.mjs';
import { standOfRows } from './stand.mjs';

const TIMINGS = 200;   // delta timings kept for the page's state

export class Watch {
  constructor({ session, view, plots, onChange, stemsThreshold = STEMS_THRESHOLD }) {
    this.session = session;
    this.stemsThreshold = stemsThreshold;
    this.detail = 'nodes';      // the detail the run is watched at
    this.view = view;
    this.plots = plots;
    this.onChange = onChange;
    this.run = null;            // runSummary() of the watched run
    this.live = new Skeleton();
    this.history = null;        // a stored iteration's skeleton while the timeline shows it
    this.statsLoaded = false;   // the plots have the run's stored stats
    // held: [iteration, internodes]; leafMs: the leaves' part of applyMs
    this.timings = { applyMs: [], parseMs: [], bytes: [], held: [], tidyMs: [], leafMs: [] };
    this.tidying = new Set();   // skeletons with a tidy task pending
  }

  // The skeleton the view shows: the stored iteration, or the live one.
  shown() { return this.history || this.live; }

  // Watches another run ({run, name}, or a whole entry of the run list).
  switchTo(summary) {
    if (this.run) this.session.send({ type: 'unsubscribe', run: this.run.run });
    this.run = runSummary(summary);
    this.detail = detailFor(this.run, this.stemsThreshold);
    this.live = new Skeleton();
    this.history = null;
    this.timings.held = [];
    this.statsLoaded = false;
    this.plots.reset();
    this.subscribe();
    this.onChange('switch');
  }

  // The watched run's latest summary from the run list; the iteration stays the
  // live skeleton's once it has one.
  update(summary) {
    const r = runSummary(summary);
    if (r.run !== this.run?.run) return;
    const was = this.run.status;
    Object.assign(this.run, r, { iteration: this.live.iteration || r.iteration });
    if (this.run.status !== was) this.onChange('status');
  }

  subscribe(since) {
    this.session.send({ type: 'subscribe', run: this.run.run, ...(since !== undefined ? { since } : {}),
      ...(this.detail === 'stems' ? { detail: 'stems' } : {}) });
  }

  // Watches the run at another detail ('nodes' or 'stems'): a fresh snapshot.
  setDetail(detail) {
    if (!this.run || detail === this.detail) return;
    this.detail = detail;
    this.live = new Skeleton();
    this.timings.held = [];
    this.subscribe();
    this.onChange('detail');
  }

  // Whether a snapshot or delta is of the detail watched (one of the other may
  // still arrive after a change of detail).
  ours(msg) {
    return msg.run === this.run?.run && (msg.detail ?? 'nodes') === this.detail;
  }

  // After a reconnection: subscribes again, asking for what was missed.
  resume() {
    if (this.run) this.subscribe(this.live.seq >= 0 ? this.live.seq : undefined);
  }

  snapshot(msg) {
    if (!this.ours(msg)) return;
    this.live.loadSnapshot(msg);
    this.run.iteration = msg.iteration;
    this.plots.setPlants(this.live.plants.map((p) => p.id));
    this.plots.setStartYear(this.live.startYear);
    this.plots.truncate(msg.iteration);
    if (msg.iteration > 0) this.plots.add(msg.iteration, msg.stats, msg.canopy_cover, msg.stand);
    if (!this.statsLoaded) {
      this.statsLoaded = true;
      this.loadStats();
    }
    if (!this.history) this.view.show(this.live);
    this.onChange('snapshot');
    this.onChange('live');
  }

  // meta: what the socket worker measured ({parseMs, bytes}).
  delta(msg, meta) {
    if (!this.ours(msg) || this.live.seq < 0) return;   // (no snapshot yet: it comes)
    if (msg.seq <= this.live.seq) return;   // already held (a replay after a snapshot)
    if (msg.seq !== this.live.seq + 1) {
      // a gap: ask for what was missed
      this.subscribe(this.live.seq);
      return;
    }
    const t0 = performance.now();
    this.live.applyDelta(msg);
    if (!this.history) this.view.show(this.live);
    const t = this.timings;
    t.applyMs.push(performance.now() - t0);
    t.leafMs.push(this.history ? 0 : this.view.leafMs);
    this.tidyLater(this.live);
    t.parseMs.push(meta.parseMs);
    t.bytes.push(meta.bytes);
    t.held.push([msg.iteration, this.live.live]);
    for (const a of [t.applyMs, t.parseMs, t.bytes, t.held, t.leafMs]) if (a.length > TIMINGS) a.shift();
    this.run.iteration = msg.iteration;
    this.plots.add(msg.iteration, msg.stats, msg.canopy_cover, msg.stand);
    this.onChange('live');
  }

  status(msg) {
    if (msg.run !== this.run?.run) return;
    this.run.status = msg.status;
    this.onChange('status');
  }

  // Shows a stored iteration's skeleton instead of the live one.
  showStored(sk) {
    this.history = sk;
    this.view.show(sk);
    this.onChange('shown');
  }

  goLive() {
    this.history = null;
    this.view.show(this.live);
    this.onChange('shown');
  }

  // The stats of every stored iteration (the plots' history), once per run.
  async loadStats() {
    const run = this.run;
    try {
      const res = await this.session.fetch(`api/runs/${encodeURIComponent(run.name)}/stats.csv`);
      if (!res.ok || this.run !== run) return;
      const rows = parseStatsCsv(await res.text());
      for (const [it, stats] of rows) {
        if (it <= this.live.iteration) this.plots.add(it, stats, stats[0]?.canopy_cover, standOfRows(stats));
      }
    } catch (e) {
      this.session.message(`stats could not be loaded: ${e.message}`, true);
    }
  }

  // Squeezing out shed slots and growing the arrays ahead of need run in a task of
  // their own after a delta, so that no single task holds the page for long.
  tidyLater(sk) {
    if (this.tidying.has(sk)) return;
    this.tidying.add(sk);
    setTimeout(() => {
      this.tidying.delete(sk);
      const t0 = performance.now();
      const moved = sk.compact(), grew = sk.growAhead();
      if ((moved || grew) && this.shown() === sk) this.view.show(sk);
      this.timings.tidyMs.push(performance.now() - t0);
      if (this.timings.tidyMs.length > TIMINGS) this.timings.tidyMs.shift();
    }, 0);
  }
}
