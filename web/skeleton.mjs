// The skeleton a viewer holds: every live internode of a run in flat typed arrays,
// built from a `snapshot` and changed in place by each `delta` (protocol.md).
//
// Slots are kept in id order, which is birth order, so a parent always sits before
// its children: removing shed subtrees is one stable compaction pass from the first
// shed slot on, and the arrays can be handed to the GPU as they are (one instance
// per slot). Nothing here knows about three.js or the DOM.

const GROW = 1.5;

export class Skeleton {
  constructor(capacity = 1024) {
    this.count = 0;
    this.version = 0;        // bumps when the arrays are reallocated
    this.changedFrom = 0;    // lowest slot whose data changed since the last take
    this.iteration = 0;
    this.seq = -1;
    this.plants = [];        // [{id, stems}] as in the snapshot
    this.species = [];
    this.obstacles = [];
    this.world = null;
    this.voxel = 0;
    this.stats = [];
    this.idSlot = new Int32Array(1024).fill(-1);
    this.scratch = new Int32Array(0);
    this.allocate(capacity);
  }

  allocate(capacity) {
    const old = this.count ? this : null;
    const id = new Int32Array(capacity), parent = new Int32Array(capacity);
    const plant = new Uint16Array(capacity), stem = new Uint16Array(capacity);
    const birth = new Int32Array(capacity), radius = new Float32Array(capacity);
    const start = new Float32Array(capacity * 3), end = new Float32Array(capacity * 3);
    if (old) {
      id.set(this.id.subarray(0, this.count));
      parent.set(this.parent.subarray(0, this.count));
      plant.set(this.plant.subarray(0, this.count));
      stem.set(this.stem.subarray(0, this.count));
      birth.set(this.birth.subarray(0, this.count));
      radius.set(this.radius.subarray(0, this.count));
      start.set(this.start.subarray(0, this.count * 3));
      end.set(this.end.subarray(0, this.count * 3));
    }
    Object.assign(this, { id, parent, plant, stem, birth, radius, start, end });
    this.capacity = capacity;
    this.version++;
  }

  reserve(n) {
    if (n > this.capacity) this.allocate(Math.max(n, Math.ceil(this.capacity * GROW)));
  }

  slotOf(id) {
    return id >= 0 && id < this.idSlot.length ? this.idSlot[id] : -1;
  }

  mapId(id, slot) {
    if (id >= this.idSlot.length) {
      let n = this.idSlot.length;
      while (n <= id) n *= 2;
      const grown = new Int32Array(n).fill(-1);
      grown.set(this.idSlot);
      this.idSlot = grown;
    }
    this.idSlot[id] = slot;
  }

  // Appends one node; its parent (when it has one) must be held already.
  push(id, parentId, plant, stem, x, y, z, radius, birth) {
    const k = this.count++;
    this.id[k] = id;
    const p = parentId >= 0 ? this.slotOf(parentId) : -1;
    if (parentId >= 0 && p < 0) throw new Error(`node ${id}: parent ${parentId} is not held`);
    this.parent[k] = p;
    this.plant[k] = plant;
    this.stem[k] = stem;
    this.birth[k] = birth;
    this.radius[k] = radius;
    const e = this.end, s = this.start, k3 = k * 3;
    e[k3] = x; e[k3 + 1] = y; e[k3 + 2] = z;
    if (p >= 0) {
      const p3 = p * 3;
      s[k3] = e[p3]; s[k3 + 1] = e[p3 + 1]; s[k3 + 2] = e[p3 + 2];
    } else {
      s[k3] = x; s[k3 + 1] = y; s[k3 + 2] = z;
    }
    this.mapId(id, k);
  }

  // Replaces everything with a snapshot message (or a skeleton export).
  loadSnapshot(msg) {
    this.idSlot.fill(-1);
    this.count = 0;
    let total = 0;
    for (const p of msg.plants) for (const s of p.stems) total += s.nodes.length;
    if (total > this.capacity || this.capacity > 4 * total + 4096) {
      this.count = 0;
      this.allocate(Math.max(1024, Math.ceil(total * GROW)));
    }
    msg.plants.forEach((plant, pi) => {
      plant.stems.forEach((stem, si) => {
        // a stem's nodes come in id order, parents first
        for (const n of stem.nodes) this.push(n[0], n[1], pi, si, n[2], n[3], n[4], n[5], n[6]);
      });
    });
    this.plants = msg.plants.map((p) => ({ id: p.id, stems: p.stems.map((s) => ({ root: s.root })) }));
    this.species = msg.species || [];
    this.obstacles = msg.obstacles || [];
    this.world = msg.world;
    this.voxel = msg.voxel;
    this.iteration = msg.iteration;
    this.seq = msg.seq ?? -1;
    this.stats = msg.stats || [];
    this.changedFrom = 0;
    this.version++;
  }

  // Applies a delta message in place; returns the slots it touched as
  // {from, radii} so a renderer can upload only what changed.
  applyDelta(msg) {
    let from = this.count;
    if (msg.shed.length) from = Math.min(from, this.removeSubtrees(msg.shed));
    const added = msg.added;
    this.reserve(this.count + added.length);
    const firstNew = this.count;
    for (let i = 0; i < added.length; i++) {
      const a = added[i];
      this.push(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], msg.iteration);
    }
    from = Math.min(from, firstNew);
    const radii = msg.radii;
    for (let i = 0; i < radii.length; i++) {
      const k = this.slotOf(radii[i][0]);
      if (k >= 0) this.radius[k] = radii[i][1];
    }
    this.iteration = msg.iteration;
    this.seq = msg.seq;
    this.stats = msg.stats;
    this.changedFrom = Math.min(this.changedFrom, from);
    return { from, radii: radii.length };
  }

  // Removes the subtrees under these ids; returns the first slot that moved.
  removeSubtrees(roots) {
    let first = this.count;
    if (this.scratch.length < this.count) this.scratch = new Int32Array(this.capacity);
    const map = this.scratch;  // old slot -> new slot, or -1 when removed
    for (const id of roots) {
      const k = this.slotOf(id);
      if (k < 0) continue;
      if (k < first) first = k;
      map[k] = -2;  // a marked root; only slots >= first are read below
    }
    if (first === this.count) return first;
    for (let i = first; i < this.count; i++) if (map[i] !== -2) map[i] = 0;
    const { id, parent, plant, stem, birth, radius, start, end, idSlot } = this;
    let w = first;
    for (let i = first; i < this.count; i++) {
      const p = parent[i];
      if (map[i] === -2 || (p >= first && map[p] < 0)) {
        map[i] = -1;
        idSlot[id[i]] = -1;
        continue;
      }
      map[i] = w;
      if (w !== i) {
        id[w] = id[i];
        parent[w] = p >= first ? map[p] : p;
        plant[w] = plant[i];
        stem[w] = stem[i];
        birth[w] = birth[i];
        radius[w] = radius[i];
        start.copyWithin(w * 3, i * 3, i * 3 + 3);
        end.copyWithin(w * 3, i * 3, i * 3 + 3);
        idSlot[id[w]] = w;
      }
      w++;
    }
    this.count = w;
    return first;
  }

  // The lowest slot changed since the last call (for partial uploads).
  takeChanges() {
    const from = this.changedFrom;
    this.changedFrom = this.count;
    return from;
  }

  // The held skeleton in the `sylva.skeleton/1` export format (cli.md), for the
  // page's download button.
  toExport() {
    const stems = this.plants.map((p) => p.stems.map(() => []));
    for (let k = 0; k < this.count; k++) {
      const p = this.parent[k];
      stems[this.plant[k]][this.stem[k]].push([this.id[k], p >= 0 ? this.id[p] : -1,
        this.end[k * 3], this.end[k * 3 + 1], this.end[k * 3 + 2], this.radius[k], this.birth[k]]);
    }
    return {
      format: 'sylva.skeleton/1', iteration: this.iteration, voxel: this.voxel, world: this.world,
      obstacles: this.obstacles,
      plants: this.plants.map((p, pi) => ({ id: p.id,
        stems: p.stems.map((s, si) => ({ root: s.root, nodes: stems[pi][si] })) })),
    };
  }

  // Bytes held by the arrays (the page's memory is the skeleton plus this).
  bytes() {
    return this.capacity * (4 * 4 + 2 * 2 + 4 * 6) + this.idSlot.byteLength + this.scratch.byteLength;
  }
}
