// The light panel: a horizontal slice of the watched run's light field at a
// chosen height (the daemon's `light`), drawn in the scene as a heat map from
// deep blue shade to yellow light, with its legend over the view. Seen edge-on
// from the front or the side a horizontal slice would vanish, so showing one
// from there turns the view to the top.
//
// The slice is named by the run's sky, which its snapshot names: "site light (sun
// and sky)" for a site's sky (the daemon's values hold the site's factor already),
// "zenith light" for the paper's.
import { $ } from './dom.mjs';
import { lightColor } from './scene.mjs';
import { skyLabel } from './helpers.mjs';

const RAMP_STOPS = [0, 0.25, 0.5, 0.75, 1];

export class LightPanel {
  constructor({ session, watch, view }) {
    this.session = session;
    this.watch = watch;
    this.view = view;
    this.slice = null;   // {z, iteration, nx, ny, sky} of the slice shown
    $('legend').querySelector('.ramp').style.background =
      `linear-gradient(to right, ${RAMP_STOPS.map((v) => `rgb(${lightColor(v)})`).join(', ')})`;
    $('light-show').onclick = () => this.show();
    $('light-hide').onclick = () => this.hide();
  }

  async show() {
    const z = Number($('light-z').value);
    if ($('light-z').value.trim() === '' || !Number.isFinite(z)) {
      this.session.message('the light height must be a number of metres', true);
      return;
    }
    try {
      const s = await this.session.request({ type: 'light', run: this.watch.run.run, z });
      this.view.setSlice(s);
      if (this.view.viewName === 'front' || this.view.viewName === 'side') this.view.setView('top');
      this.slice = { z: s.z, iteration: s.iteration, nx: s.nx, ny: s.ny, sky: this.sky };
      $('legend').hidden = false;
      this.session.message(`${skyLabel(this.sky)} at ${s.z} m after iteration ${s.iteration}`);
    } catch (e) {
      this.session.message(e.message, true);
    }
  }

  // Takes the slice away (also when another run is watched).
  hide() {
    this.view.setSlice(null);
    this.slice = null;
    $('legend').hidden = true;
  }

  // The watched run's sky: 'site', 'zenith', or null before its snapshot.
  get sky() {
    return this.watch.run ? this.watch.live.sky ?? null : null;
  }

  render() {
    $('light-show').disabled = !this.watch.run;
    const label = this.watch.run ? skyLabel(this.sky) : '';
    $('light-sky').textContent = label;
    $('legend-sky').textContent = label;
  }
}
