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

export const SETTLE_MS = 120;   // the slider's resting time before its iteration is fetched
const BUSY_TRIES = 40;          // `get` answered busy (--max-jobs): tries in all
const BUSY_WAIT_MS = 150;       // and the wait before the next

// A run's stored iterations as skeletons, from the daemon: `get` for iteration 0
// and later ones; for an iteration T below 0 (a measured tree's past), the stage
// of stored iteration 0 at T (Skeleton.stageAt), iteration 0 fetched once. The
// timeline has one for the watched run, and the compare view one for each run.
export class StoredIterations {
  constructor(session, run) {
    this.session = session;
    this.run = run;
    this.zero = null;   // the promise of stored iteration 0
  }

  at(it) {
    return it < 0 ? this.iterationZero().then((sk) => sk.stageAt(it)) : this.stored(it);
  }

  // A stored iteration's skeleton. The daemon restores it as a job, and refuses
  // one past its --max-jobs with `busy` (other pages, or the compare view's other
  // runs, may hold them): that is asked again a moment later.
  async stored(it) {
    for (let tries = 1; ; tries++) {
      try {
        const snap = await this.session.request({ type: 'get', run: this.run, iteration: it });
        const sk = new Skeleton();
        sk.loadSnapshot(snap);
        return sk;
      } catch (e) {
        if (e.code !== 'busy' || tries >= BUSY_TRIES) throw e;
        await new Promise((r) => setTimeout(r, BUSY_WAIT_MS));
      }
    }
  }

  iterationZero() {
    if (!this.zero) {
      const promise = this.stored(0);
      this.zero = promise;
      promise.catch(() => { if (this.zero === promise) this.zero = null; });
    }
    return this.zero;
  }
}

export class Timeline {
  constructor({ session, watch }) {
    this.session = session;
    this.watch = watch;
    this.timer = 0;    // the pending fetch after the slider moved
    this.serial = 0;   // the latest fetch; replies to older ones are dropped
    this.source = null; // StoredIterations of the watched run
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
      const run = this.watch.run.run;
      if (this.source?.run !== run) this.source = new StoredIterations(this.session, run);
      const sk = await this.source.at(it);
      if (serial !== this.serial) return;
      this.watch.showStored(sk);
    } catch (e) {
      this.session.message(e.message, true);
    }
  }

  // Another run is watched, or the live world was loaded again (after an edit,
  // which may have changed iteration 0): iteration 0 is fetched again when needed.
  reset() {
    this.source = null;
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
