// The leaves of the 3D view: one square card per leaf (docs/model.md, "Foliage"),
// placed by foliage.mjs (the rule of server/export/foliage.c), drawn as one
// THREE.InstancedMesh with a colour per instance (its species' leaf_colour), a
// leaf drawn on a canvas as its texture (alpha test: the blade only), double-sided
// and lit by the scene's lights; the cards cast the crown's shadow.
//
// Cards are kept by node id: a node's drawn leaves are one run of instances, so a
// delta changes only the runs of the nodes whose leaves changed (Skeleton.takeLeafLog);
// freed runs are reused by nodes drawing as many leaves. Level of detail: past a
// budget of instances every node draws fewer, larger leaves (foliage.mjs, leafStride
// and drawnLeaves), so the instances stay under the budget whatever the crown.
import * as THREE from 'three';
import { placeLeaf, drawnLeaves, leafStride, LEAF_BUDGET } from './foliage.mjs';

const MIN_CAPACITY = 4096;

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

export class Leaves {
  constructor(scene) {
    this.scene = scene;
    this.geometry = new THREE.PlaneGeometry(1, 1);
    this.material = new THREE.MeshLambertMaterial({ map: leafTexture(), alphaTest: 0.5, side: THREE.DoubleSide });
    this.mesh = null;
    this.sk = null;          // the skeleton the cards follow
    this.visible = true;
    this.budget = LEAF_BUDGET;
    this.stride = 1;         // leafStride of the drawn cards
    this.capacity = 0;
    this.matrix = null;      // 16 floats per instance (column-major), zero for a free one
    this.colour = null;      // 3 floats per instance, linear
    this.used = 0;           // instances up to the last one used
    this.live = 0;           // instances drawing a leaf
    this.first = new Int32Array(0);  // node id -> its first instance, -1: none
    this.drawn = new Uint16Array(0); // node id -> its instances
    this.free = new Map();   // run length -> first instances of free runs
    this.freed = 0;          // instances in free runs
    this.lo = Infinity;      // instances changed since the last upload
    this.hi = -1;
    this.rgb = [];           // per species: its colour, linear
    this.tmp = { centre: [0, 0, 0], along: [0, 0, 0], across: [0, 0, 0], edge: 0 };
    this.p = [0, 0, 0];
    this.q = [0, 0, 0];
  }

  // Shows or hides the cards; hidden, they are not kept up to date, and showing
  // them again builds them afresh.
  setVisible(on) {
    this.visible = on;
    if (!on) this.sk = null;
    if (this.mesh) this.mesh.visible = on;
  }

  // A lower budget of instances (the view lowers it when frames are slow).
  setBudget(budget) {
    this.budget = budget;
    this.sk = null;
  }

  // Brings the cards up to date with a skeleton; returns whether any changed.
  sync(sk) {
    if (!this.visible) return false;
    const same = sk === this.sk, taken = sk.takeLeafLog(), log = same ? taken : null;
    const stride = leafStride(sk.leafTotal, this.budget);
    // a thinner crown goes back to a lower stride only well under the budget
    const keep = stride < this.stride && sk.leafTotal / (this.stride / 2) > 0.8 * this.budget;
    if (log === null || (stride !== this.stride && !keep) || this.freed > 2 * this.live + 65536) {
      this.rebuild(sk, keep ? this.stride : stride);
      return true;
    }
    if (log.length === 0) return false;
    this.colours(sk);
    for (let i = 0; i < log.length; i++) {
      const nid = log[i], k = sk.slotOf(nid);
      this.release(nid);
      if (k >= 0 && sk.leaves[k] > 0) this.place(sk, k);
    }
    this.upload();
    return true;
  }

  rebuild(sk, stride) {
    this.sk = sk;
    this.stride = stride;
    this.colours(sk);
    const want = Math.ceil((sk.leafTotal / stride) * 1.25) + MIN_CAPACITY;
    if (!this.mesh || want > this.capacity || this.capacity > 4 * want) this.allocate(want);
    this.matrix.fill(0, 0, this.used * 16);
    this.used = 0;
    this.live = 0;
    this.free.clear();
    this.freed = 0;
    this.first.fill(-1);
    const { leaves, dead } = sk;
    for (let k = 0, n = sk.count; k < n; k++) if (leaves[k] > 0 && !dead[k]) this.place(sk, k);
    this.lo = 0;
    this.hi = Math.max(this.used - 1, 0);
    this.upload();
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
    const { matrix, colour, used } = this;
    this.allocate(Math.max(this.capacity * 2, this.used + n + MIN_CAPACITY));
    this.matrix.set(matrix.subarray(0, used * 16));
    this.colour.set(colour.subarray(0, used * 3));
    this.used = used;
    this.lo = 0;
    this.hi = Math.max(used - 1, 0);
  }

  mapIds(maxId) {
    if (maxId < this.first.length) return;
    let n = Math.max(1024, this.first.length);
    while (n <= maxId) n *= 2;
    const first = new Int32Array(n).fill(-1), drawn = new Uint16Array(n);
    first.set(this.first);
    drawn.set(this.drawn);
    this.first = first;
    this.drawn = drawn;
  }

  // The cards of the node in slot k (its leaves under the stride).
  place(sk, k) {
    const nid = sk.id[k];
    this.mapIds(nid);
    const n = sk.leaves[k], s = this.stride, m = drawnLeaves(n, nid, s);
    if (m === 0) return;
    const species = sk.plantSpecies[sk.plant[k]] ?? 0, f = sk.foliage[species];
    if (!f) return;
    let at;
    const runs = this.free.get(m);
    if (runs && runs.length) {
      at = runs.pop();
      this.freed -= m;
    } else {
      this.reserve(m);
      at = this.used;
      this.used += m;
    }
    this.first[nid] = at;
    this.drawn[nid] = m;
    this.live += m;
    const k3 = k * 3, p = this.p, q = this.q, rgb = this.rgb[species] ?? [1, 1, 1];
    for (let a = 0; a < 3; a++) {
      p[a] = sk.start[k3 + a];
      q[a] = sk.end[k3 + a];
    }
    const root = sk.parent[k] < 0;
    const size = s === 1 ? f.leaf_size : f.leaf_size * Math.sqrt(s);
    const out = this.tmp, M = this.matrix, C = this.colour;
    for (let j = 0; j < m; j++) {
      placeLeaf(root ? null : p, q, j, m, size, out);
      const { centre: c, along: y, across: x } = out, e = out.edge, i = (at + j) * 16;
      // columns: across x edge, along x edge, the card's normal (across x along), centre
      M[i] = x[0] * e; M[i + 1] = x[1] * e; M[i + 2] = x[2] * e; M[i + 3] = 0;
      M[i + 4] = y[0] * e; M[i + 5] = y[1] * e; M[i + 6] = y[2] * e; M[i + 7] = 0;
      M[i + 8] = x[1] * y[2] - x[2] * y[1]; M[i + 9] = x[2] * y[0] - x[0] * y[2];
      M[i + 10] = x[0] * y[1] - x[1] * y[0]; M[i + 11] = 0;
      M[i + 12] = c[0]; M[i + 13] = c[1]; M[i + 14] = c[2]; M[i + 15] = 1;
      C.set(rgb, (at + j) * 3);
    }
    if (at < this.lo) this.lo = at;
    if (at + m - 1 > this.hi) this.hi = at + m - 1;
  }

  // Frees a node's cards (zero matrices draw nothing) for reuse.
  release(nid) {
    if (nid >= this.first.length) return;
    const at = this.first[nid];
    if (at < 0) return;
    const m = this.drawn[nid];
    this.matrix.fill(0, at * 16, (at + m) * 16);
    this.first[nid] = -1;
    this.drawn[nid] = 0;
    this.live -= m;
    this.freed += m;
    let runs = this.free.get(m);
    if (!runs) this.free.set(m, (runs = []));
    runs.push(at);
    if (at < this.lo) this.lo = at;
    if (at + m - 1 > this.hi) this.hi = at + m - 1;
  }

  // Marks the changed instances for upload.
  upload() {
    const mesh = this.mesh;
    mesh.count = this.used;
    if (this.hi >= this.lo) {
      for (const [attr, size] of [[mesh.instanceMatrix, 16], [mesh.instanceColor, 3]]) {
        attr.clearUpdateRanges();
        attr.addUpdateRange(this.lo * size, (this.hi - this.lo + 1) * size);
        attr.needsUpdate = true;
      }
    }
    this.lo = Infinity;
    this.hi = -1;
  }
}
