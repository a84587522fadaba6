// The edit tools in the bar: add a tree of one of the run's species at a clicked
// ground point; add a wall (standing on the ground up to its height) or a board
// (lying at its height) between two corners typed or picked on the ground; remove
// an obstacle with its × chip. The daemon applies edits between iterations.
import { $ } from './dom.mjs';
import { obstacleFromFields, plantAt, round } from './helpers.mjs';

export class EditTools {
  constructor({ session, watch, view }) {
    this.session = session;
    this.watch = watch;
    this.view = view;
    this.mode = null;    // 'tree' | 'corners' while waiting for ground clicks
    this.corners = [];   // the corners picked so far
    $('add-tree').onclick = () => {
      this.mode = 'tree';
      session.message('click a ground point for the new tree');
    };
    $('pick-corners').onclick = () => {
      this.mode = 'corners';
      this.corners = [];
      session.message('click the first corner on the ground');
    };
    $('obstacle-kind').onchange = () => {
      const wall = $('obstacle-kind').value === 'wall';
      $('obstacle-z-label').firstChild.textContent = wall ? 'height ' : 'at z ';
    };
    $('add-obstacle').onclick = () => this.addObstacle();
    view.renderer.domElement.addEventListener('click', (ev) => this.groundClick(ev));
  }

  edit(fields, done) {
    return this.session.act({ type: 'edit', run: this.watch.run.run, ...fields }, () => done);
  }

  addObstacle() {
    const taken = new Set(this.watch.live.obstacles.map((o) => o.id));
    const { obstacle, error } = obstacleFromFields({
      kind: $('obstacle-kind').value, cornerA: $('corner-a').value, cornerB: $('corner-b').value,
      z: $('obstacle-z').value, thickness: $('obstacle-t').value,
    }, taken);
    if (error) { this.session.message(error, true); return; }
    this.edit({ add_obstacles: [obstacle] }, `added ${obstacle.id}`);
  }

  groundClick(ev) {
    if (!this.mode || !this.watch.run) return;
    const p = this.view.groundAt(ev.clientX, ev.clientY);
    if (!p) { this.session.message('that is not a ground point of the world', true); return; }
    const [x, y] = p.map(round);
    if (this.mode === 'tree') {
      this.mode = null;
      const plant = plantAt(x, y, $('tree-species').value, new Set(this.watch.live.plants.map((q) => q.id)));
      this.edit({ add_plants: [plant] }, `added ${plant.id} at ${x}, ${y}`);
    } else {
      this.corners.push([x, y]);
      $(this.corners.length === 1 ? 'corner-a' : 'corner-b').value = `${x}, ${y}`;
      if (this.corners.length === 2) { this.mode = null; this.session.message('corners set; press add'); }
      else this.session.message('click the second corner');
    }
  }

  // The species of the run, to choose the new tree's from.
  speciesOptions() {
    const sel = $('tree-species');
    const have = [...sel.options].map((o) => o.value).join('\n');
    if (have === this.watch.live.species.join('\n')) return;
    sel.textContent = '';
    for (const s of this.watch.live.species) sel.add(new Option(s, s));
  }

  // The buttons work while a run is watched; a chip per obstacle of the shown
  // iteration (removable only from the live run).
  render() {
    for (const id of ['add-tree', 'add-obstacle', 'pick-corners']) $(id).disabled = !this.watch.run;
    const box = $('obstacles');
    box.textContent = '';
    for (const o of this.watch.shown().obstacles) {
      const b = document.createElement('button');
      b.className = 'chip';
      b.textContent = `${o.id} ×`;
      b.title = `remove obstacle ${o.id}`;
      b.disabled = !!this.watch.history;
      b.onclick = () => this.edit({ remove_obstacles: [o.id] }, `removed ${o.id}`);
      box.appendChild(b);
    }
  }
}
