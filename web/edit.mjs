// The edit tools in the bar: add a tree of one of the run's species at a clicked
// ground point; add a wall (standing on the ground up to its height), a board
// (lying at its height) or a clearance zone (from one height up to another)
// between two corners typed or picked on the ground; remove an obstacle or a zone
// with its × chip; prune a chosen zone now (every internode inside it goes, with
// what grows from it). The daemon applies edits between iterations.
import { $ } from './dom.mjs';
import { obstacleFromFields, plantAt, round, zoneFromFields } from './helpers.mjs';
import { isZone, zonesOf } from './zones.mjs';

// The label of the height field, by obstacle kind.
const HEIGHT_LABEL = { wall: 'height ', board: 'at z ', zone: 'up to z ' };

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
      const kind = $('obstacle-kind').value;
      $('obstacle-z-label').firstChild.textContent = HEIGHT_LABEL[kind];
      $('zone-base-label').hidden = kind !== 'zone';
    };
    $('add-obstacle').onclick = () => this.addObstacle();
    $('prune').onclick = () => this.prune();
    view.renderer.domElement.addEventListener('click', (ev) => this.groundClick(ev));
  }

  edit(fields, done) {
    return this.session.act({ type: 'edit', run: this.watch.run.run, ...fields }, () => done);
  }

  addObstacle() {
    const taken = new Set(this.watch.live.obstacles.map((o) => o.id));
    const kind = $('obstacle-kind').value;
    const fields = { cornerA: $('corner-a').value, cornerB: $('corner-b').value, thickness: $('obstacle-t').value };
    const { obstacle, error } = kind === 'zone'
      ? zoneFromFields({ ...fields, base: $('zone-base').value, top: $('obstacle-z').value }, taken)
      : obstacleFromFields({ ...fields, kind, z: $('obstacle-z').value }, taken);
    if (error) { this.session.message(error, true); return; }
    this.edit({ add_obstacles: [obstacle] }, `added ${obstacle.id}`);
  }

  // Prunes the chosen zone now: the daemon sends a fresh snapshot without its
  // internodes.
  prune() {
    const zone = $('prune-zone').value;
    if (!zone) { this.session.message('choose a zone to prune', true); return; }
    this.edit({ prune: { zone } }, `pruned ${zone}`);
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

  // The buttons work while a run is watched; a chip per obstacle and zone of the
  // shown iteration (removable only from the live run); the live run's zones to
  // prune (only while it is shown).
  render() {
    for (const id of ['add-tree', 'add-obstacle', 'pick-corners']) $(id).disabled = !this.watch.run;
    const box = $('obstacles');
    box.textContent = '';
    for (const o of this.watch.shown().obstacles) {
      const b = document.createElement('button');
      const zone = isZone(o);
      b.className = zone ? 'chip zone' : 'chip';
      b.textContent = `${o.id} ×`;
      b.title = `remove ${zone ? 'zone' : 'obstacle'} ${o.id}`;
      b.disabled = !!this.watch.history;
      b.onclick = () => this.edit({ remove_obstacles: [o.id] }, `removed ${o.id}`);
      box.appendChild(b);
    }
    const sel = $('prune-zone'), keep = sel.value;
    const zones = zonesOf(this.watch.live.obstacles).map((o) => o.id);
    if ([...sel.options].map((o) => o.value).join('\n') !== zones.join('\n')) {
      sel.textContent = '';
      for (const id of zones) sel.add(new Option(id, id));
      if (zones.includes(keep)) sel.value = keep;
    }
    sel.disabled = zones.length === 0;
    $('prune').disabled = !this.watch.run || zones.length === 0 || !!this.watch.history;
  }
}
