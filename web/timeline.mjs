// The timeline: a slider over the stored iterations of the watched run. Moving it
// shows the chosen one (the daemon restores it from the store: `get`) while the
// live run goes on in the background; Live, or the slider at the live iteration,
// returns. A run whose earliest node birth is below 0 (a measured tree's past,
// docs/model.md "Measured trees") starts there: an iteration T < 0 shows stored
// iteration 0 as it was at T, the nodes born by T with the pipe model's radii
// (Skeleton.stageAt). Beside it the shown iteration (its calendar year first, in
// a run with a start year), and over the view its internodes.
import { $ } from './dom.mjs';
import { iterationLabel } from './helpers.mjs';
import { Skeleton } from './skeleton.mjs';

const SETTLE_MS = 120;   // the slider's resting time before its iteration is fetched

export class Timeline {
  constructor({ session, watch }) {
    this.session = session;
    this.watch = watch;
    this.timer = 0;    // the pending fetch after the slider moved
    this.serial = 0;   // the latest fetch; replies to older ones are dropped
    this.zero = null;  // {run, promise}: the run's stored iteration 0, for the stages before it
    this.slider = $('timeline');
    this.slider.oninput = () => {
      clearTimeout(this.timer);
      this.timer = setTimeout(() => this.showIteration(Number(this.slider.value)), SETTLE_MS);
    };
    $('live').onclick = () => this.goLive();
  }

  goLive() {
    this.serial++;
    this.slider.value = String(this.watch.live.iteration);
    this.watch.goLive();
  }

  // Moves the slider to an iteration and shows it (the conflicts table's rows).
  jumpTo(it) {
    clearTimeout(this.timer);
    this.slider.value = String(Math.min(it, this.watch.live.iteration));
    return this.showIteration(it);
  }

  async showIteration(it) {
    if (!this.watch.run) return;
    if (it >= this.watch.live.iteration) { this.goLive(); return; }
    const serial = ++this.serial;
    try {
      const sk = await (it < 0 ? this.iterationZero() : this.stored(it));
      if (serial !== this.serial) return;
      this.watch.showStored(it < 0 ? sk.stageAt(it) : sk);
    } catch (e) {
      this.session.message(e.message, true);
    }
  }

  // A stored iteration's skeleton, from the daemon.
  async stored(it) {
    const snap = await this.session.request({ type: 'get', run: this.watch.run.run, iteration: it });
    const sk = new Skeleton();
    sk.loadSnapshot(snap);
    return sk;
  }

  // The watched run's stored iteration 0, fetched once for all the stages before it.
  iterationZero() {
    const run = this.watch.run.run;
    if (this.zero?.run !== run) {
      const promise = this.stored(0);
      this.zero = { run, promise };
      promise.catch(() => { if (this.zero?.promise === promise) this.zero = null; });
    }
    return this.zero.promise;
  }

  // Another run is watched, or the live world was loaded again (after an edit,
  // which may have changed iteration 0): iteration 0 is fetched again when needed.
  reset() {
    this.zero = null;
  }

  // The live skeleton changed: the slider reaches its iteration (and follows it
  // while live), and starts at its earliest birth when that is below 0.
  liveChanged() {
    this.slider.min = String(Math.min(0, this.watch.live.earliest));
    this.slider.max = String(this.watch.live.iteration);
    if (!this.watch.history) this.slider.value = String(this.watch.live.iteration);
    this.render();
  }

  // The labels of the shown iteration.
  render() {
    const s = this.watch.shown(), stored = !!this.watch.history;
    const label = iterationLabel(s.iteration, s.startYear);
    $('timeline-label').textContent = `${label} (${stored ? 'stored' : 'live'})`;
    this.slider.title = label;
    $('live').disabled = !stored;
    $('view-info').textContent = `${label} · ${s.live.toLocaleString('en')} internodes`;
  }
}
