// The run's controls in the bar under the view: the watched run's title in the
// header, start, pause, step (count) and stop with the run's status beside them,
// fork at the shown iteration, and the export links of the shown iteration (neither
// for a measured tree's past stage before iteration 0, which the store does not hold).
import { $ } from './dom.mjs';
import { controlsDisabled, exportHref, stepCount } from './helpers.mjs';

const EXPORTS = [['export-skeleton', 'skeleton'], ['export-obj', 'obj'], ['export-glb', 'glb'],
  ['export-csv', 'csv']];

export class ControlsPanel {
  // onStatus(msg): the daemon's `status` reply to a control; open({run, name}):
  // watches the fork and refreshes the run list.
  constructor({ session, watch, onStatus, open }) {
    this.session = session;
    this.watch = watch;
    this.onStatus = onStatus;
    this.open = open;
    $('start').onclick = () => this.control('start');
    $('pause').onclick = () => this.control('pause');
    $('stop').onclick = () => this.control('stop');
    $('step').onclick = () => this.control('step', { count: stepCount($('step-count').value) });
    $('fork').onclick = () => this.fork();
    // with a token for reading, the links fetch with it (a plain link cannot)
    for (const [id] of EXPORTS) {
      $(id).onclick = (ev) => {
        if (this.session.publicRead || !$(id).href) return;
        ev.preventDefault();
        this.session.download($(id).getAttribute('href'));
      };
    }
  }

  async control(action, extra = {}) {
    if (!this.watch.run) return;
    const st = await this.session.act({ type: 'control', run: this.watch.run.run, action, ...extra }, () => '');
    if (st) this.onStatus(st);
  }

  async fork() {
    const name = $('fork-name').value.trim();
    if (!name) { this.session.message('give the fork a name', true); return; }
    const c = await this.session.act({ type: 'fork', run: this.watch.run.run, iteration: this.watch.shown().iteration, name },
      (reply) => `forked as ${reply.name}`);
    if (c) await this.open(c);
  }

  // Another run is watched.
  switched() {
    $('run-title').textContent = this.watch.run.name;
    $('fork-name').value = `${this.watch.run.name}-fork`;
    this.render();
  }

  // The status badge and which buttons work.
  render() {
    const st = this.watch.run?.status ?? null;
    $('status').textContent = st ?? '';
    $('status').dataset.status = st ?? '';
    const off = controlsDisabled(st);
    for (const id of ['start', 'pause', 'step', 'stop']) $(id).disabled = off[id];
    $('fork').disabled = !this.watch.run || this.watch.shown().iteration < 0;
  }

  // The export links and the fork name the shown iteration; a stage before
  // iteration 0 has neither (the links lose their href).
  renderExports() {
    const run = this.watch.run, it = this.watch.shown().iteration;
    for (const [id, format] of EXPORTS) {
      if (run && it >= 0) $(id).href = exportHref(run.name, format, it);
      else $(id).removeAttribute('href');
    }
    $('fork').disabled = !run || it < 0;
  }
}
