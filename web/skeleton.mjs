// The skeleton a viewer holds: every live internode of a run in flat typed arrays,
// built from a `snapshot` and changed in place by each `delta` (protocol.md).
//
// Slots are kept in id order, which is birth order, so a parent always sits before
// its children, and the arrays can be handed to the GPU as they are (one instance
// per slot). A delta's shed subtrees are found in one pass from the first shed
// slot and marked dead (zero length, so they draw nothing); compact() squeezes
// them out later, in a task of its own, so that applying a delta stays short.
// Each slot also holds its node's leaf count (the snapshot's and deltas' `leaves`);
// the ids whose leaves changed are logged for the view's leaf cards (takeLeafLog).
// The stems that are dead (their stats' `alive`: stand.mjs) are kept as keys, and
// deadVersion bumps when they change, for the view's grey.
// Nothing here knows about three.js or the DOM.
import { pastStage } from './helpers.mjs';
import { deadStemKeys, sameKeys } from './stand.mjs';

const GROW = 2;
const NONE = 2 ** 31;
const LEAF_LOG_SLACK = 4096;   // ids logged beyond the slots held before the log gives up

export class Skeleton {
  constructor(capacity = 1024) {
    this.count = 0;          // slots in use, dead ones included
    this.deadCount = 0;      // dead slots waiting for compact()
    this.firstDead = NONE;   // no dead slot before this one
    this.version = 0;        // bumps when the arrays are reallocated
    this.changedFrom = 0;    // lowest slot whose data changed since the last take
    this.iteration = 0;
    this.seq = -1;
    this.detail = 'nodes';   // the snapshot's detail: 'stems' holds stats and no internodes
    this.plants = [];        // [{id, stems}] as in the snapshot
    this.species = [];
    this.obstacles = [];
    this.world = null;
    this.voxel = 0;
    this.stats = [];
    this.stand = null;       // the stand's figures (a stand's run: protocol.md), or null
    this.plantIndex = new Map();  // plant id -> its index in plants
    this.deadStems = new Set();   // keys (stand.mjs) of the stems whose stats say they are dead
    this.deadVersion = 0;    // bumps when deadStems changes
    this.startYear = null;   // the calendar year of iteration 0 (a run with a start year)
    this.earliest = 0;       // the earliest birth of the snapshot: below 0 for a tree with a past
    this.foliage = [];       // per species {species, leaf_size, leaf_density, leaf_colour}
    this.plantSpecies = [];  // each plant's species index
    this.leafTotal = 0;      // the leaves of all live slots
    this.leafLog = [];       // ids whose leaves changed since the last takeLeafLog()
    this.leafLogFull = true; // the log is not enough: every slot's leaves must be read again
    this.idSlot = new Int32Array(1024).fill(-1);
    this.scratch = new Int32Array(0);
    this.allocate(capacity);
  }

  allocate(capacity) {
    const old = this.count ? this : null;
    const id = new Int32Array(capacity), parent = new Int32Array(capacity);
    const plant = new Uint16Array(capacity), stem = new Uint16Array(capacity);
    const birth = new Int32Array(capacity), radius = new Float32Array(capacity);
    const dead = new Uint8Array(capacity), leaves = new Uint16Array(capacity);
    const start = new Float32Array(capacity * 3), end = new Float32Array(capacity * 3);
    if (old) {
      id.set(this.id.subarray(0, this.count));
      parent.set(this.parent.subarray(0, this.count));
      plant.set(this.plant.subarray(0, this.count));
      stem.set(this.stem.subarray(0, this.count));
      birth.set(this.birth.subarray(0, this.count));
      dead.set(this.dead.subarray(0, this.count));
      leaves.set(this.leaves.subarray(0, this.count));
      radius.set(this.radius.subarray(0, this.count));
      start.set(this.start.subarray(0, this.count * 3));
      end.set(this.end.subarray(0, this.count * 3));
    }
    Object.assign(this, { id, parent, plant, stem, birth, radius, start, end, dead, leaves });
    this.capacity = capacity;
    this.version++;
  }

  // Doubles the arrays ahead of need (in a quiet moment rather than while a delta
  // is applied); returns whether it did.
  growAhead() {
    if (this.count * 1.3 <= this.capacity) return false;
    this.allocate(this.capacity * GROW);
    return true;
  }

  reserve(n) {
    if (n > this.capacity) this.allocate(Math.max(n, Math.ceil(this.capacity * GROW)));
  }

  // Internodes held (dead slots aside).
  get live() { return this.count - this.deadCount; }

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

  // Appends nodes i0..i1-1 of typed node arrays (wire.mjs) whose parents are held
  // already or come earlier in the same arrays. birth is an array or one number.
  append(src, i0, i1, birth) {
    this.reserve(this.count + (i1 - i0));
    let maxId = -1;
    for (let i = i0; i < i1; i++) if (src.id[i] > maxId) maxId = src.id[i];
    if (maxId >= this.idSlot.length) this.mapId(maxId, -1);
    const { id, parent, plant, stem, radius, start, end, idSlot, leaves } = this;
    const births = this.birth, xyzr = src.xyzr, sid = src.id, spar = src.parent;
    const splant = src.plant, sstem = src.stem, slots = idSlot.length;
    const one = typeof birth === 'number', each = one ? null : birth;
    let k = this.count;
    for (let i = i0; i < i1; i++, k++) {
      const pid = spar[i];
      const p = pid >= 0 && pid < slots ? idSlot[pid] : -1;
      if (pid >= 0 && p < 0) {
        this.count = k;
        throw new Error(`node ${sid[i]}: parent ${pid} is not held`);
      }
      const nid = sid[i];
      id[k] = nid;
      parent[k] = p;
      plant[k] = splant[i];
      stem[k] = sstem[i];
      births[k] = one ? birth : each[i];
      leaves[k] = 0;
      const k3 = k * 3, i4 = i * 4;
      end[k3] = xyzr[i4];
      end[k3 + 1] = xyzr[i4 + 1];
      end[k3 + 2] = xyzr[i4 + 2];
      radius[k] = xyzr[i4 + 3];
      const q = p >= 0 ? p * 3 : k3;
      start[k3] = end[q];
      start[k3 + 1] = end[q + 1];
      start[k3 + 2] = end[q + 2];
      idSlot[nid] = k;
    }
    this.count = k;
  }

  // Replaces everything with a snapshot (wire.mjs's snapshotArrays form).
  loadSnapshot(msg) {
    this.idSlot.fill(-1);
    this.dead.fill(0, 0, this.count);
    this.leaves.fill(0, 0, this.count);
    this.count = 0;
    this.deadCount = 0;
    this.firstDead = NONE;
    const total = msg.nodes.n;
    if (total > this.capacity || this.capacity > 4 * total + 4096) {
      this.allocate(Math.max(1024, Math.ceil(total * GROW)));
    }
    // a stem's nodes come in id order, parents first
    this.append(msg.nodes, 0, total, msg.nodes.birth);
    // (a delta's nodes are born at its iteration, never before 1)
    let earliest = 0;
    for (let i = 0, b = msg.nodes.birth; i < total; i++) if (b[i] < earliest) earliest = b[i];
    this.earliest = earliest;
    this.leafTotal = 0;
    this.leafLog = [];
    this.leafLogFull = true;
    if (msg.leaves) this.setLeaves(msg.leaves);
    this.foliage = msg.foliage || [];
    this.plantSpecies = msg.plant_species || [];
    this.plants = msg.plants;
    this.species = msg.species || [];
    this.obstacles = msg.obstacles || [];
    this.sky = msg.sky ?? null; // 'site' or 'zenith' (protocol.md, "snapshot")
    this.startYear = msg.start_year ?? null;
    this.world = msg.world;
    this.voxel = msg.voxel;
    this.iteration = msg.iteration;
    this.seq = msg.seq ?? -1;
    this.detail = msg.detail ?? 'nodes';
    this.plantIndex = new Map((msg.plants || []).map((p, i) => [p.id, i]));
    this.setStats(msg.stats || [], msg.stand);
    this.changedFrom = 0;
    this.version++;
  }

  // Applies a delta (wire.mjs's deltaArrays form) in place; returns the first slot
  // that changed (radii aside) so a renderer can upload only what changed.
  applyDelta(msg) {
    let from = this.count;
    if (msg.shed.length) from = Math.min(from, this.markShed(msg.shed));
    this.append(msg.added, 0, msg.added.n, msg.iteration);
    const { idSlot, radius } = this, ids = msg.radii.id, r = msg.radii.r;
    for (let i = 0, n = msg.radii.n; i < n; i++) {
      const k = ids[i] < idSlot.length ? idSlot[ids[i]] : -1;
      if (k >= 0) radius[k] = r[i];
    }
    if (msg.leaves) this.setLeaves(msg.leaves);
    this.iteration = msg.iteration;
    this.seq = msg.seq;
    this.setStats(msg.stats, msg.stand);
    this.changedFrom = Math.min(this.changedFrom, from);
    return from;
  }

  // The stems' stats and the stand's figures of a message (undefined: none), and
  // the dead stems they name.
  setStats(stats, stand) {
    this.stats = stats;
    this.stand = stand ?? null;
    const keys = deadStemKeys(stats, this.plantIndex);
    if (sameKeys(keys, this.deadStems)) return;
    this.deadStems = keys;
    this.deadVersion++;
  }

  // Sets the leaf counts of a leaves list (wire.mjs: {n, id, count}) on the nodes
  // held, and logs their ids.
  setLeaves(list) {
    const { idSlot, leaves } = this;
    let total = this.leafTotal;
    for (let i = 0; i < list.n; i++) {
      const nid = list.id[i], k = nid < idSlot.length ? idSlot[nid] : -1;
      if (k < 0) continue;
      total += list.count[i] - leaves[k];
      leaves[k] = list.count[i];
      this.logLeaves(nid);
    }
    this.leafTotal = total;
  }

  logLeaves(nid) {
    if (this.leafLogFull) return;
    if (this.leafLog.length > this.count + LEAF_LOG_SLACK) {
      this.leafLogFull = true;
      this.leafLog = [];
    } else {
      this.leafLog.push(nid);
    }
  }

  // The ids whose leaves changed since the last call, or null when every slot must
  // be read again (after a snapshot, or too many changes unread).
  takeLeafLog() {
    const log = this.leafLogFull ? null : this.leafLog;
    this.leafLog = [];
    this.leafLogFull = false;
    return log;
  }

  // Marks the subtrees under these ids dead: unmapped, zero length and radius, no
  // leaves. Returns the first slot it changed.
  markShed(roots) {
    const { id, parent, dead, radius, start, end, idSlot, leaves } = this;
    let first = this.count;
    const kill = (k) => {
      dead[k] = 1;
      idSlot[id[k]] = -1;
      radius[k] = 0;
      if (leaves[k]) {
        this.leafTotal -= leaves[k];
        leaves[k] = 0;
        this.logLeaves(id[k]);
      }
      const k3 = k * 3;
      end[k3] = start[k3];
      end[k3 + 1] = start[k3 + 1];
      end[k3 + 2] = start[k3 + 2];
      this.deadCount++;
    };
    for (let i = 0; i < roots.length; i++) {
      const k = this.slotOf(roots[i]);
      if (k < 0) continue;
      kill(k);
      if (k < first) first = k;
    }
    for (let i = first + 1, n = this.count; i < n; i++) {
      const p = parent[i];
      if (p >= first && dead[p] && !dead[i]) kill(i);
    }
    if (first < this.firstDead) this.firstDead = first;
    return first;
  }

  // Squeezes the dead slots out (one stable pass from the first dead slot);
  // returns whether anything moved.
  compact() {
    if (this.deadCount === 0) return false;
    const first = this.firstDead;
    if (this.scratch.length < this.count) this.scratch = new Int32Array(this.capacity);
    const map = this.scratch;  // old slot -> new slot
    const { id, parent, plant, stem, birth, radius, start, end, dead, idSlot, leaves } = this;
    let w = first;
    for (let i = first, n = this.count; i < n; i++) {
      if (dead[i]) continue;
      map[i] = w;
      if (w !== i) {
        const nid = id[i], p = parent[i];
        id[w] = nid;
        parent[w] = p >= first ? map[p] : p;
        plant[w] = plant[i];
        stem[w] = stem[i];
        birth[w] = birth[i];
        radius[w] = radius[i];
        leaves[w] = leaves[i];
        const w3 = w * 3, i3 = i * 3;
        start[w3] = start[i3];
        start[w3 + 1] = start[i3 + 1];
        start[w3 + 2] = start[i3 + 2];
        end[w3] = end[i3];
        end[w3 + 1] = end[i3 + 1];
        end[w3 + 2] = end[i3 + 2];
        idSlot[nid] = w;
      }
      w++;
    }
    dead.fill(0, first, this.count);
    this.count = w;
    this.deadCount = 0;
    this.firstDead = NONE;
    this.changedFrom = Math.min(this.changedFrom, first);
    return true;
  }

  // The lowest slot changed since the last call (for partial uploads).
  takeChanges() {
    const from = this.changedFrom;
    this.changedFrom = this.count;
    return from;
  }

  // A new skeleton of this one's world as it was at an iteration T before this
  // one's: a measured tree's past stage (docs/model.md, "Measured trees"), the
  // nodes born by T with their radii by that stage's pipe model (helpers.mjs,
  // pastStage). Its iteration is T; it has no stats and no leaves (the messages do
  // not say which of a past stage's nodes bore them).
  stageAt(T) {
    const stage = pastStage(this, T);
    const n = stage.slots.length;
    const nodes = {
      n, id: new Int32Array(n), parent: new Int32Array(n), plant: new Uint16Array(n),
      stem: new Uint16Array(n), birth: new Int32Array(n), xyzr: new Float32Array(n * 4),
    };
    for (let i = 0; i < n; i++) {
      const k = stage.slots[i], p = this.parent[k];
      nodes.id[i] = this.id[k];
      nodes.parent[i] = p >= 0 ? this.id[p] : -1;
      nodes.plant[i] = this.plant[k];
      nodes.stem[i] = this.stem[k];
      nodes.birth[i] = this.birth[k];
      nodes.xyzr.set(this.end.subarray(k * 3, k * 3 + 3), i * 4);
      nodes.xyzr[i * 4 + 3] = stage.radius[i];
    }
    const sk = new Skeleton();
    sk.loadSnapshot({
      nodes, plants: this.plants, species: this.species, obstacles: this.obstacles, sky: this.sky,
      foliage: this.foliage, plant_species: this.plantSpecies,
      start_year: this.startYear, world: this.world, voxel: this.voxel, iteration: T, seq: -1, stats: [],
    });
    return sk;
  }

  // The held skeleton in the `sylva.skeleton/1` export format (cli.md), for the
  // page's download button.
  toExport() {
    const stems = this.plants.map((p) => p.stems.map(() => []));
    for (let k = 0; k < this.count; k++) {
      if (this.dead[k]) continue;
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
    return this.capacity * (4 * 4 + 2 * 2 + 1 + 2 + 4 * 6) + this.idSlot.byteLength + this.scratch.byteLength;
  }
}
