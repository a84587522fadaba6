// Where a leaf-bearing node's leaves are: server/export/foliage.c's foliage_place()
// in JavaScript, the same formula in the same order (docs/model.md, "Foliage"), so
// that the viewer's leaves are those of `sylva render` and the glTF export. Also the
// viewer's level of detail for leaves. Pure: no DOM, no three.js (node tests it).

const GOLDEN_ANGLE = (137.5 * 3.14159265358979323846) / 180.0;
const SQRT1_2 = 0.70710678118654752440;

function normalize(v) {
  const l = Math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (l > 0.0) for (let a = 0; a < 3; a++) v[a] /= l;
}

// Leaf k of n of a node at q whose parent is at p (null for a root), with leaves of
// edge size: out.centre, out.along (base to tip), out.across (unit vectors), out.edge.
// A node bearing leaves carries them along its internode, leaf k at t = (k + 0.5) / n
// of the way, turned around it by k golden angles from a frame fixed by the internode
// alone, its blade 45 degrees between the internode and the outward direction; a root
// takes a vertical internode of one leaf's length.
export function placeLeaf(p, q, k, n, size, out = { centre: [0, 0, 0], along: [0, 0, 0], across: [0, 0, 0], edge: 0 }) {
  return leafAt(leafFrame(p, q, size), k, n, size, out);
}

// placeLeaf in two halves, for a node's n leaves: its frame once (leafFrame), then
// each leaf (leafAt), the same operations in the same order as foliage_place().
export function newFrame() {
  return { base: [0, 0, 0], axis: [0, 0, 0], d: [0, 0, 0], e1: [0, 0, 0], e2: [0, 0, 0] };
}

// The internode's base, axis and direction d, and the frame e1, e2 fixed by it.
export function leafFrame(p, q, size, f = newFrame()) {
  const { base, axis, d, e1, e2 } = f;
  if (p) {
    for (let a = 0; a < 3; a++) {
      base[a] = p[a];
      axis[a] = q[a] - p[a];
    }
  } else {
    base[0] = q[0];
    base[1] = q[1];
    base[2] = q[2] - size;
    axis[0] = axis[1] = 0.0;
    axis[2] = size;
  }
  const length = Math.sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  d[0] = 0.0;
  d[1] = 0.0;
  d[2] = 1.0;
  if (length > 0.0) for (let a = 0; a < 3; a++) d[a] = axis[a] / length;
  // e1 = up x d, the horizontal perpendicular (x for a vertical internode); e2 = d x e1
  e1[0] = -d[1];
  e1[1] = d[0];
  e1[2] = 0.0;
  if (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2] < 1e-12) {
    e1[0] = 1.0;
    e1[1] = e1[2] = 0.0;
  }
  normalize(e1);
  e2[0] = d[1] * e1[2] - d[2] * e1[1];
  e2[1] = d[2] * e1[0] - d[0] * e1[2];
  e2[2] = d[0] * e1[1] - d[1] * e1[0];
  normalize(e2);
  return f;
}

// cos and sin of k golden angles, kept: the same doubles as computed each time.
const turnCos = [], turnSin = [];
function turn(k) {
  for (let j = turnCos.length; j <= k; j++) {
    const phi = GOLDEN_ANGLE * j;
    turnCos.push(Math.cos(phi));
    turnSin.push(Math.sin(phi));
  }
}

// Leaf k of n in a frame of leafFrame (placeLeaf's second half).
export function leafAt(f, k, n, size, out) {
  const { base, axis, d, e1, e2 } = f;
  if (k >= turnCos.length) turn(k);
  const c = turnCos[k], s = turnSin[k];
  const t = (k + 0.5) / (n > 0 ? n : 1);
  const along = out.along, across = out.across;
  const o0 = c * e1[0] + s * e2[0], o1 = c * e1[1] + s * e2[1], o2 = c * e1[2] + s * e2[2];
  along[0] = (o0 + d[0]) * SQRT1_2;
  along[1] = (o1 + d[1]) * SQRT1_2;
  along[2] = (o2 + d[2]) * SQRT1_2;
  across[0] = d[1] * o2 - d[2] * o1;
  across[1] = d[2] * o0 - d[0] * o2;
  across[2] = d[0] * o1 - d[1] * o0;
  normalize(along);
  normalize(across);
  for (let a = 0; a < 3; a++) out.centre[a] = base[a] + t * axis[a] + 0.5 * size * along[a];
  out.edge = size;
  return out;
}

// "#rrggbb" as three components in 0..1 (foliage_rgb).
export function leafRgb(colour) {
  const v = Number.parseInt(colour.slice(1), 16);
  return [((v >> 16) & 0xff) / 255, ((v >> 8) & 0xff) / 255, (v & 0xff) / 255];
}

// ---- level of detail -----------------------------------------------------------------

// The leaves the viewer draws at most (instances), and at least after lowering it.
export const LEAF_BUDGET = 400000;
export const LEAF_BUDGET_MIN = 25000;

// The thinning of a crown of `total` leaves under a budget: the least power of two
// s with total / s <= budget (1: every leaf drawn).
export function leafStride(total, budget) {
  let s = 1;
  while (total / s > budget && s < 1 << 20) s *= 2;
  return s;
}

// A node's drawn leaves under stride s: floor((n + r) / s) with r in 0..s-1 taken
// from its id, so that on average n / s of its n leaves are drawn and a node with
// fewer than s leaves draws one or none; every drawn leaf's edge is scaled by
// sqrt(s), so the drawn leaf area stays the crown's. The same node always draws the
// same leaves.
export function drawnLeaves(n, id, s) {
  if (s === 1) return n;
  const r = Math.imul(id, 2654435761) >>> 0;
  return Math.floor((n + (r % s)) / s);
}
