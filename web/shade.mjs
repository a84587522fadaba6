// The shade layer: the hours of sun the trees take from the ground and the facades
// over one day (date, from, to) in the year shown, from the daemon's
// /api/runs/NAME/shade (docs/protocol.md, "The shade layer"), drawn by the view as
// coloured cells (View.setShade) with a legend of its scale. While it is on it
// follows the iteration shown: one request at a time, then the latest wanted.
import { $ } from './dom.mjs';
import { shadeColor } from './scene.mjs';

const RAMP_STOPS = [0, 0.25, 0.5, 0.75, 1];

// The legend's scale for a largest value of hours: whole half hours, at least one.
export const shadeScale = (max) => Math.max(0.5, Math.ceil(max * 2) / 2);

export class ShadePanel {
  constructor({ session, watch, view }) {
    this.session = session;
    this.watch = watch;
    this.view = view;
    this.on = false;
    this.data = null;     // the reply drawn
    this.shown = null;    // what it is of: {run, iteration, date, from, to}
    this.failed = null;   // the request that failed last (not asked again by itself)
    this.busy = false;    // a request is under way
    $('shade-legend').querySelector('.ramp').style.background =
      `linear-gradient(to right, ${RAMP_STOPS.map((v) => `rgb(${shadeColor(v)})`).join(', ')})`;
    $('shade-toggle').onclick = () => this.toggle();
    for (const id of ['shade-date', 'shade-from', 'shade-to']) $(id).onchange = () => this.refresh();
  }

  // Switches the layer on or off.
  toggle(on = !this.on) {
    this.on = on;
    $('shade-toggle').setAttribute('aria-pressed', String(on));
    this.failed = null;
    if (on) this.refresh();
    else this.clear();
  }

  // Takes the layer's cells and legend away (the toggle stays as it is).
  clear() {
    this.view.setShade(null);
    this.data = null;
    this.shown = null;
    $('shade-legend').hidden = true;
  }

  // What the layer should show now.
  wanted() {
    return {
      run: this.watch.run?.name ?? null, iteration: this.watch.shown().iteration,
      date: $('shade-date').value.trim(), from: $('shade-from').value.trim(), to: $('shade-to').value.trim(),
    };
  }

  // Brings the layer to the iteration shown and the day asked, when it is on.
  async refresh() {
    if (!this.on || !this.watch.run) return;
    if (this.busy) {
      this.again = true;
      return;
    }
    const want = this.wanted(), key = JSON.stringify(want);
    if (key === JSON.stringify(this.shown) || key === this.failed) return;
    if (want.iteration < 0) {
      this.clear();
      this.session.message('the shade layer shows stored iterations (0 and later) only', true);
      this.failed = key;
      return;
    }
    this.busy = true;
    try {
      const q = new URLSearchParams({ iteration: want.iteration, date: want.date, from: want.from, to: want.to });
      const res = await this.session.fetch(`api/runs/${encodeURIComponent(want.run)}/shade?${q}`);
      const text = await res.text();
      if (!this.on || this.watch.run?.name !== want.run) return;
      if (!res.ok) {
        this.failed = key;
        this.session.message(`shade: ${text.trim()}`, true);
        return;
      }
      const data = JSON.parse(text), scale = shadeScale(data.max);
      this.view.setShade(data, scale);
      this.data = data;
      this.shown = want;
      this.scale = scale;
      $('shade-legend-max').textContent = `${scale} h`;
      $('shade-legend-day').textContent = `${data.date} ${data.from}–${data.to}${data.year != null ? ` ${data.year}` : ''}`;
      $('shade-legend').hidden = false;
    } catch (e) {
      this.failed = key;
      this.session.message(`shade: ${e.message}`, true);
    } finally {
      this.busy = false;
      if (this.again) {
        this.again = false;
        this.refresh();
      }
    }
  }

  // The hours of tree shade of the ground cell at (x, y), or null outside the
  // layer.
  groundAt(x, y) {
    const d = this.data;
    if (!d) return null;
    const i = Math.floor((x - d.origin[0]) / d.voxel), j = Math.floor((y - d.origin[1]) / d.voxel);
    return i < 0 || j < 0 || i >= d.nx || j >= d.ny ? null : d.ground[i + d.nx * j];
  }

  state() {
    return {
      on: this.on, busy: this.busy, ...(this.shown || {}), max: this.data?.max ?? null, scale: this.data ? this.scale : null,
      meshes: this.view.shadeGroup.children.map((m) => m.name),
    };
  }

  render() {
    $('shade-toggle').disabled = !this.watch.run;
  }
}
