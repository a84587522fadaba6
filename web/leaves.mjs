// The leaves of the 3D view: one square card per leaf (docs/model.md, "Foliage"),
// placed by foliage.mjs (the rule of server/export/foliage.c), drawn as one
// THREE.InstancedMesh with a colour per instance (its species' leaf_colour), a
// leaf drawn on a canvas as its texture (alpha test: the blade only), double-sided
// and lit by the scene's lights; the cards cast the crown's shadow.
//
// Cards are kept by node id: a node's drawn leaves are one run of instances, so a
// delta changes only the runs of the nodes whose leaves changed (Skeleton.takeLeafLog);
// freed runs are reused by nodes drawing as many leaves, and squeezed out when
// they pile up. Level of detail: past a budget of instances every node draws
// fewer, larger leaves (foliage.mjs, leafStride and drawnLeaves), so the
// instances stay under the budget whatever the crown.
//
// The work is cut into slices: sync() places cards for about SLICE_MS and leaves
// the rest (the nodes of a large delta, a change of stride, a crown shown afresh)
// to tasks of their own (of SLICE_MS, or LONG_SLICE_MS for one that waited long
// for its turn), so that no task holds the page for long whatever the crown.
// Meanwhile each node keeps the cards it had (a node drawn at the former stride
// keeps its leaf area too) until its turn, and the view draws the cards again
// once the work is done; pending() tells whether any is left.
import * as THREE from 'three';
import { leafFrame, leafAt, newFrame, drawnLeaves, leafStride, LEAF_BUDGET } from './foliage.mjs';

const MIN_CAPACITY = 4096;
const SLICE_MS = 8;       // the most one slice of work takes, about
// ... or this much, when the page's thread was held elsewhere for STARVED_MS since
// the last slice (frames that WebGL draws on the CPU): no frame is due sooner
const STARVED_MS = 100;
const LONG_SLICE_MS = 50;
const CHECK_EVERY = 64;   // queued nodes between two looks at the clock
const PASS_STEP = 1024;   // node ids of a pass between two looks at the clock
const NO_SCAN = -1;

// The leaf texture: transparent, the blade (the ellipse inscribed in the card, as
// the leaf area counts it) near-white so the instance colour gives it its species'
// colour, and a grey midrib from the base (the bottom edge) towards the tip.
function leafTexture() {
  const n = 64, c = document.createElement('canvas');
  c.width = c.height = n;
  const g = c.getContext('2d');
  g.fillStyle = '#f2f2f2';
  g.beginPath();
  g.ellipse(n / 2, n / 2, n / 2 - 0.5, n / 2 - 0.5, 0, 0, 2 * Math.PI);
  g.fill();
  g.strokeStyle = '#999999';
  g.lineWidth = n / 32;
  g.lineCap = 'round';
  g.beginPath();
  g.moveTo(n / 2, n - 1);
  g.lineTo(n / 2, 0.1 * n);
  g.stroke();
  const t = new THREE.CanvasTexture(c);
  t.colorSpace = THREE.SRGBColorSpace;
  return t;
}

// log2 of a stride, plus one (0: no cards placed)
const strideCode = (s) => 32 - Math.clz32(s);

export class Leaves {
  // onWork(): the work that sync() left to slices of their own is done (the view
  // draws the cards again).
  constructor(scene, onWork = () => {}) {
    this.scene = scene;
    this.onWork = onWork;
    this.geometry = new THREE.PlaneGeometry(1, 1);
    this.material = new THREE.MeshLambertMaterial({ map: leafTexture(), alphaTest: 0.5, side: THREE.DoubleSide });
    this.mesh = null;
    this.sk = null;          // the skeleton the cards follow
    this.visible = true;
    this.budget = LEAF_BUDGET;
    this.stride = 1;         // leafStride of the cards (those placed from now on)
    this.capacity = 0;
    this.matrix = null;      // 16 floats per instance (column-major), zero for a free one
    this.colour = null;      // 3 floats per instance, linear
    this.owner = null;       // node id per instance, -1 for a free one
    this.used = 0;           // instances up to the last one used
    this.live = 0;           // instances drawing a leaf
    this.first = new Int32Array(0);  // node id -> its first instance, -1: none
    this.drawn = new Uint16Array(0); // node id -> its instances
    this.placed = new Uint8Array(0); // node id -> strideCode of its cards' stride, 0: none
    this.free = [];          // run length -> first instances of free runs
    this.freeMax = 0;        // no free run is longer
    this.freed = 0;          // instances in free runs
    this.queue = [];         // node ids whose leaves changed, to place again
    this.queued = 0;         // of them, those done
    this.scan = NO_SCAN;     // the next node id of a pass over every node, NO_SCAN: none
    this.timer = 0;          // 1: the next slice is on its way
    // (a message to itself: a task without setTimeout's clamp of 4 ms)
    this.channel = new MessageChannel();
    this.channel.port1.onmessage = () => this.next();
    this.lo = Infinity;      // instances changed since the last upload
    this.hi = -1;
    this.rgb = [];           // per species: its colour, linear
    this.frame = newFrame();
    this.out = { centre: [0, 0, 0], along: [0, 0, 0], across: [0, 0, 0], edge: 0 };
    this.p = [0, 0, 0];
    this.q = [0, 0, 0];
    this.rebuilds = [];      // {why, ms, wall, cards, stride}: the larger pieces of work (log())
    this.pass = null;        // the pass under way: {why, t0, ms}
    this.touched = false;    // cards changed since takeSettled() said so
    this.lastSlice = 0;      // when the last slice ended (performance.now())
  }

  // Shows or hides the cards; hidden, they are not kept up to date, and showing
  // them again places them afresh.
  setVisible(on) {
    this.visible = on;
    if (!on) {
      this.sk = null;
      this.stop();
    }
    if (this.mesh) this.mesh.visible = on;
  }

  // Another budget of instances (the view lowers it when frames are slow); the
  // next sync() takes the stride it calls for.
  setBudget(budget) {
    this.budget = budget;
  }

  // Whether cards remain to be placed (or moved) by slices to come.
  pending() {
    return this.queued < this.queue.length || this.scan !== NO_SCAN;
  }

  // Whether the cards changed and are all in place (once: then false until they
  // change again); the crown's shadow is drawn again then.
  takeSettled() {
    if (!this.touched || this.pending()) return false;
    this.touched = false;
    return true;
  }

  // The stride for a crown of `total` leaves: leafStride under the budget, but a
  // thinner crown goes back to a lower stride only well under the budget.
  strideFor(total) {
    const stride = leafStride(total, this.budget);
    if (stride < this.stride && total / (this.stride / 2) > 0.8 * this.budget) return this.stride;
    return stride;
  }

  // Brings the cards up to date with a skeleton, or starts to; returns whether any
  // changed.
  sync(sk) {
    if (!this.visible) return false;
    const log = sk.takeLeafLog();
    let changed = false;
    if (sk !== this.sk || log === null) {
      // another crown, or too much changed to tell: every card afresh
      this.reset(sk);
      this.startPass('all');
      changed = true;
    } else {
      if (log.length) {
        if (this.queued === this.queue.length) {
          this.queue = log;
          this.queued = 0;
        } else {
          for (let i = 0; i < log.length; i++) this.queue.push(log[i]);
        }
      }
      const stride = this.strideFor(sk.leafTotal);
      if (stride !== this.stride) {
        this.stride = stride;
        this.startPass('stride');
      }
    }
    if (this.pending()) changed = this.work() || changed;
    return changed;
  }

  startPass(why) {
    this.scan = 0;
    this.pass = { why, t0: performance.now(), ms: 0 };
  }

  stop() {
    this.timer = 0;
    this.queue = [];
    this.queued = 0;
    this.scan = NO_SCAN;
    this.pass = null;
  }

  // One slice: the queued nodes, then the pass over every node, for about SLICE_MS;
  // the rest in a task of its own. Returns whether any card changed.
  work(sliceMs = SLICE_MS) {
    const sk = this.sk, t0 = performance.now();
    const { idSlot, leaves, dead } = sk;
    const code = strideCode(this.stride);
    let changes = 0;
    this.mapIds(idSlot.length - 1);   // (so that the maps by id stay the same arrays)
    // the nodes whose leaves changed (or that were shed)
    while (this.queued < this.queue.length) {
      if (changes % CHECK_EVERY === CHECK_EVERY - 1 && performance.now() - t0 > sliceMs) break;
      const nid = this.queue[this.queued++], k = nid < idSlot.length ? idSlot[nid] : -1;
      if (nid < idSlot.length && this.first[nid] >= 0) this.release(nid);
      if (k >= 0 && !dead[k] && leaves[k] > 0) this.place(sk, k);
      changes++;
    }
    // the pass: every node not drawn at this stride, in id order (ids stay put when
    // slots move), PASS_STEP ids at a time
    while (this.queued === this.queue.length && this.scan !== NO_SCAN && performance.now() - t0 <= sliceMs) {
      const end = Math.min(this.scan + PASS_STEP, idSlot.length);
      const { placed, first } = this;
      for (let nid = this.scan; nid < end; nid++) {
        const k = idSlot[nid];
        if (k < 0 || dead[k] || leaves[k] === 0) {
          if (first[nid] >= 0) {
            this.release(nid);
            changes++;
          }
          continue;
        }
        if (placed[nid] === code) continue;
        this.release(nid);
        this.place(sk, k);
        changes++;
      }
      this.scan = end;
      if (end >= idSlot.length) {
        this.scan = NO_SCAN;
        this.endPass();
      }
    }
    if (this.freed > this.live + 65536) {
      const t1 = performance.now();
      this.squeeze();
      this.log('squeeze', performance.now() - t1);
    }
    if (changes) {
      this.upload();
      this.touched = true;
    }
    this.lastSlice = performance.now();
    if (this.pass) this.pass.ms += this.lastSlice - t0;
    if (!this.pending()) {
      this.queue = [];
      this.queued = 0;
    } else if (!this.timer) {
      this.timer = 1;
      this.channel.port2.postMessage(0);
    }
    return changes > 0;
  }

  // The next slice, in a task of its own; the view hears of the work once it is
  // done (the frames in between would draw a crown half at each stride, and cost
  // the slices their time where WebGL is drawn on the CPU).
  next() {
    if (!this.timer) return;   // stopped
    this.timer = 0;
    if (!this.sk || !this.pending()) return;
    this.work(performance.now() - this.lastSlice > STARVED_MS ? LONG_SLICE_MS : SLICE_MS);
    if (!this.pending()) this.onWork();
  }

  endPass() {
    const p = this.pass;
    if (!p) return;
    this.log(p.why, p.ms, performance.now() - p.t0);
    this.pass = null;
  }

  // For the page's timings: a pass over every node ('all', 'stride'), the free
  // runs squeezed out ('squeeze'), the arrays grown ('grow'), with the time it
  // took (and for a pass, from its start to its end).
  log(why, ms, wall = ms) {
    this.rebuilds.push({ why, ms, wall, cards: this.live, stride: this.stride });
    if (this.rebuilds.length > 200) this.rebuilds.shift();
  }

  // Forgets every card and follows sk at the stride its crown calls for.
  reset(sk) {
    this.stop();
    this.sk = sk;
    this.stride = leafStride(sk.leafTotal, this.budget);
    this.colours(sk);
    const want = Math.ceil((sk.leafTotal / this.stride) * 1.25) + MIN_CAPACITY;
    if (!this.mesh || want > this.capacity || this.capacity > 4 * want) this.allocate(want);
    // (every instance below `used` is written and uploaded again before it is drawn)
    this.matrix.fill(0, 0, this.used * 16);
    this.owner.fill(-1, 0, this.used);
    this.used = 0;
    this.live = 0;
    this.free = [];
    this.freeMax = 0;
    this.freed = 0;
    this.first.fill(-1);
    this.drawn.fill(0);
    this.placed.fill(0);
    this.lo = Infinity;
    this.hi = -1;
    this.mesh.count = 0;
    this.touched = true;
  }

  // Each species' colour, linear (three's working colour space).
  colours(sk) {
    this.rgb = sk.foliage.map((f) => {
      const c = new THREE.Color();
      c.setStyle(f.leaf_colour);
      return [c.r, c.g, c.b];
    });
  }

  allocate(capacity) {
    if (this.mesh) {
      this.scene.remove(this.mesh);
      this.mesh.dispose();
    }
    this.capacity = capacity;
    this.matrix = new Float32Array(capacity * 16);
    this.colour = new Float32Array(capacity * 3);
    this.owner = new Int32Array(capacity).fill(-1);
    this.used = 0;
    // (made for no instances, then given the arrays: three.js would fill its own)
    const mesh = new THREE.InstancedMesh(this.geometry, this.material, 0);
    mesh.instanceMatrix = new THREE.InstancedBufferAttribute(this.matrix, 16);
    mesh.instanceColor = new THREE.InstancedBufferAttribute(this.colour, 3);
    mesh.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
    mesh.instanceColor.setUsage(THREE.DynamicDrawUsage);
    mesh.count = 0;
    mesh.frustumCulled = false;
    mesh.castShadow = true;
    mesh.visible = this.visible;
    mesh.name = 'leaves';
    this.mesh = mesh;
    this.scene.add(mesh);
  }

  // Grows the instance arrays (keeping what they hold) to take n more.
  reserve(n) {
    if (this.used + n <= this.capacity) return;
    const t0 = performance.now();
    const { matrix, colour, owner, used } = this;
    this.allocate(Math.max(this.capacity * 2, this.used + n + MIN_CAPACITY));
    this.matrix.set(matrix.subarray(0, used * 16));
    this.colour.set(colour.subarray(0, used * 3));
    this.owner.set(owner.subarray(0, used));
    this.used = used;
    this.lo = 0;
    this.hi = Math.max(used - 1, 0);
    this.log('grow', performance.now() - t0);
  }

  mapIds(maxId) {
    if (maxId < this.first.length) return;
    let n = Math.max(1024, this.first.length);
    while (n <= maxId) n *= 2;
    const first = new Int32Array(n).fill(-1), drawn = new Uint16Array(n), placed = new Uint8Array(n);
    first.set(this.first);
    drawn.set(this.drawn);
    placed.set(this.placed);
    this.first = first;
    this.drawn = drawn;
    this.placed = placed;
  }

  // The cards of the node in slot k (its leaves under the stride), with none yet.
  // (work() has mapped every id of sk)
  place(sk, k) {
    const nid = sk.id[k];
    const n = sk.leaves[k], s = this.stride, m = drawnLeaves(n, nid, s);
    this.placed[nid] = strideCode(s);
    if (m === 0) return;
    const species = sk.plantSpecies[sk.plant[k]] ?? 0, f = sk.foliage[species];
    if (!f) return;
    const at = this.take(m);
    this.first[nid] = at;
    this.drawn[nid] = m;
    this.live += m;
    const k3 = k * 3, p = this.p, q = this.q, rgb = this.rgb[species] ?? [1, 1, 1];
    for (let a = 0; a < 3; a++) {
      p[a] = sk.start[k3 + a];
      q[a] = sk.end[k3 + a];
    }
    const size = s === 1 ? f.leaf_size : f.leaf_size * Math.sqrt(s);
    const frame = leafFrame(sk.parent[k] < 0 ? null : p, q, size, this.frame);
    const out = this.out, M = this.matrix, C = this.colour, O = this.owner;
    const { centre: c, along: y, across: x } = out;
    for (let j = 0; j < m; j++) {
      leafAt(frame, j, m, size, out);
      const e = out.edge, i = (at + j) * 16, i3 = (at + j) * 3;
      // columns: across x edge, along x edge, the card's normal (across x along), centre
      M[i] = x[0] * e; M[i + 1] = x[1] * e; M[i + 2] = x[2] * e; M[i + 3] = 0;
      M[i + 4] = y[0] * e; M[i + 5] = y[1] * e; M[i + 6] = y[2] * e; M[i + 7] = 0;
      M[i + 8] = x[1] * y[2] - x[2] * y[1]; M[i + 9] = x[2] * y[0] - x[0] * y[2];
      M[i + 10] = x[0] * y[1] - x[1] * y[0]; M[i + 11] = 0;
      M[i + 12] = c[0]; M[i + 13] = c[1]; M[i + 14] = c[2]; M[i + 15] = 1;
      C[i3] = rgb[0]; C[i3 + 1] = rgb[1]; C[i3 + 2] = rgb[2];
      O[at + j] = nid;
    }
    if (at < this.lo) this.lo = at;
    if (at + m - 1 > this.hi) this.hi = at + m - 1;
  }

  // m instances in a row: a free run of m, else the head of the shortest longer
  // free run (its tail stays free), else new ones at the end.
  take(m) {
    const free = this.free;
    if (this.freed > 0) {
      for (let len = m; len <= this.freeMax; len++) {
        const runs = free[len];
        if (!runs || runs.length === 0) continue;
        const at = runs.pop();
        this.freed -= len;
        if (len > m) this.freeRun(at + m, len - m);
        return at;
      }
    }
    this.reserve(m);
    const at = this.used;
    this.used += m;
    return at;
  }

  freeRun(at, m) {
    const runs = this.free[m];
    if (runs) runs.push(at);
    else this.free[m] = [at];
    if (m > this.freeMax) this.freeMax = m;
    this.freed += m;
  }

  // Frees a node's cards (zero matrices draw nothing) for reuse.
  release(nid) {
    if (nid >= this.first.length) return;
    this.placed[nid] = 0;
    const at = this.first[nid];
    if (at < 0) return;
    const m = this.drawn[nid], M = this.matrix, O = this.owner;
    for (let i = at * 16, e = (at + m) * 16; i < e; i++) M[i] = 0;
    for (let i = at; i < at + m; i++) O[i] = -1;
    this.first[nid] = -1;
    this.drawn[nid] = 0;
    this.live -= m;
    this.freeRun(at, m);
    if (at < this.lo) this.lo = at;
    if (at + m - 1 > this.hi) this.hi = at + m - 1;
  }

  // Squeezes the free runs out: the cards move down, in order, over them.
  squeeze() {
    const { matrix: M, colour: C, owner: O, first } = this;
    let w = 0;
    for (let i = 0, used = this.used; i < used; i++) {
      const nid = O[i];
      if (nid < 0) continue;
      if (w !== i) {
        for (let a = 0, i16 = i * 16, w16 = w * 16; a < 16; a++) M[w16 + a] = M[i16 + a];
        for (let a = 0, i3 = i * 3, w3 = w * 3; a < 3; a++) C[w3 + a] = C[i3 + a];
        O[w] = nid;
        if (first[nid] === i) first[nid] = w;
      }
      w++;
    }
    M.fill(0, w * 16, this.used * 16);
    O.fill(-1, w, this.used);
    this.lo = 0;
    this.hi = Math.max(this.used - 1, 0);
    this.used = w;
    this.free = [];
    this.freeMax = 0;
    this.freed = 0;
  }

  // The cards drawn, for tests: the ids of the nodes with cards, each one's count,
  // and per card its centre and its edges (the lengths of its matrix's first two
  // columns).
  cards() {
    const ids = [], counts = [], cards = [], M = this.matrix, len = (i) => Math.hypot(M[i], M[i + 1], M[i + 2]);
    for (let nid = 0; nid < this.first.length; nid++) {
      const at = this.first[nid];
      if (at < 0) continue;
      ids.push(nid);
      counts.push(this.drawn[nid]);
      for (let j = at; j < at + this.drawn[nid]; j++) {
        const i = j * 16;
        cards.push(M[i + 12], M[i + 13], M[i + 14], len(i), len(i + 4));
      }
    }
    return { ids, counts, cards };
  }

  // Marks the changed instances for upload, with those of slices before it that
  // no frame has uploaded yet (three.js clears the ranges it uploads).
  upload() {
    const mesh = this.mesh;
    mesh.count = this.used;
    if (this.hi >= this.lo) {
      for (const [attr, size] of [[mesh.instanceMatrix, 16], [mesh.instanceColor, 3]]) {
        let lo = this.lo * size, end = (this.hi + 1) * size;
        for (const r of attr.updateRanges) {
          lo = Math.min(lo, r.start);
          end = Math.max(end, r.start + r.count);
        }
        attr.clearUpdateRanges();
        attr.addUpdateRange(lo, end - lo);
        attr.needsUpdate = true;
      }
    }
    this.lo = Infinity;
    this.hi = -1;
  }
}
