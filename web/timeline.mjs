// The timeline: a slider over the stored iterations of the watched run. Moving it
// shows the chosen one (the daemon restores it from the store: `get`) while the
// live run goes on in the background; Live, or the slider at the live iteration,
// returns. Beside it the shown iteration (its calendar year first, in a run with a
// start year), and over the view its internodes.
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
      const snap = await this.session.request({ type: 'get', run: this.watch.run.run, iteration: it });
      if (serial !== this.serial) return;
      const sk = new Skeleton();
      sk.loadSnapshot(snap);
      this.watch.showStored(sk);
    } catch (e) {
      this.session.message(e.message, true);
    }
  }

  // The live skeleton changed: the slider reaches its iteration (and follows it
  // while live).
  liveChanged() {
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
