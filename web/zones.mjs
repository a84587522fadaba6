// Clearance zones, as the page works them out: which obstacles are zones, which
// internodes lie inside one (from their positions and the zones' boxes or prisms,
// bounds included, metres), and the conflicts table's rows from the stems' stats. Pure,
// like helpers.mjs: no DOM, no network, no three.js; node runs the tests
// (tests/web/test_helpers.mjs). Nothing here changes its arguments, except the
// output array markInZones is given to fill.

// Whether an obstacle is a clearance zone (`"kind": "zone"`); anything else is
// solid, as every obstacle was before zones.
export const isZone = (o) => o?.kind === 'zone';

// The zones and the solid obstacles of a list, each in the list's order.
export const zonesOf = (obstacles) => (obstacles || []).filter(isZone);
export const solidsOf = (obstacles) => (obstacles || []).filter((o) => !isZone(o));

// Whether the point (x, y, z) lies in the box {min, max}, bounds included.
export function insideBox(box, x, y, z) {
  return x >= box.min[0] && x <= box.max[0] && y >= box.min[1] && y <= box.max[1] &&
    z >= box.min[2] && z <= box.max[2];
}

// The box that holds an obstacle {min, max}: a box's own corners, or a prism's
// (`polygon`, `holes`, `z`) footprint's bounds over its z range.
export function boundsOf(o) {
  if (!o.polygon) return { min: o.min, max: o.max };
  const min = [Infinity, Infinity, o.z[0]], max = [-Infinity, -Infinity, o.z[1]];
  for (const ring of [o.polygon, ...(o.holes || [])]) {
    for (const [x, y] of ring) {
      min[0] = Math.min(min[0], x);
      min[1] = Math.min(min[1], y);
      max[0] = Math.max(max[0], x);
      max[1] = Math.max(max[1], y);
    }
  }
  return { min, max };
}

// Whether (x, y) lies in a prism's footprint by the core's rule (core/src/prism.c):
// inside its bounds, and a ray from it towards +x crosses its rings (the polygon
// and its holes, each closed from its last point to its first) an odd number of
// times, counting an edge whose ends lie on either side of y, one strictly above.
export function insideFootprint(prism, x, y) {
  let inside = false;
  for (const ring of [prism.polygon, ...(prism.holes || [])]) {
    for (let i = 0, n = ring.length; i < n; i++) {
      const p = ring[i], q = ring[(i + 1) % n];
      if ((p[1] > y) !== (q[1] > y) && x < p[0] + (y - p[1]) * (q[0] - p[0]) / (q[1] - p[1])) inside = !inside;
    }
  }
  return inside;
}

// Whether (x, y, z) lies in an obstacle, a box or a prism, bounds included.
export function insideObstacle(o, x, y, z) {
  return insideBox(boundsOf(o), x, y, z) && (!o.polygon || insideFootprint(o, x, y));
}

// The zones' bounds (boundsOf) as the page's Float32Arrays hold node positions: a
// node the daemon places on a bound (at 4 decimals) is held as Math.fround of it,
// so the bounds are rounded the same way and the test keeps "bounds included".
function f32Bounds(zones) {
  const b = new Float64Array(zones.length * 6);
  zones.forEach((z, i) => {
    const { min, max } = boundsOf(z);
    for (let a = 0; a < 3; a++) {
      b[i * 6 + a] = Math.fround(min[a]);
      b[i * 6 + 3 + a] = Math.fround(max[a]);
    }
  });
  return b;
}

// Whether (x, y, z) lies in zone i of zones, whose bounds are b (f32Bounds): in
// its box, and for a prism in its footprint too.
function inZone(b, zones, i, x, y, z) {
  const o = i * 6;
  if (!(x >= b[o] && x <= b[o + 3] && y >= b[o + 1] && y <= b[o + 4] && z >= b[o + 2] && z <= b[o + 5])) return false;
  return !zones[i].polygon || insideFootprint(zones[i], x, y);
}

// Marks slots from..to-1 of a skeleton's arrays (`end`: x, y, z per slot;
// `dead`: 1 for a shed slot, or null): out[k] = 1 + the index in `zones` of the
// first zone that holds node k, 0 when none does or the slot is dead.
export function markInZones(end, dead, from, to, zones, out) {
  const b = f32Bounds(zones), nz = zones.length;
  for (let k = from; k < to; k++) {
    let mark = 0;
    if (!(dead && dead[k])) {
      const x = end[k * 3], y = end[k * 3 + 1], z = end[k * 3 + 2];
      for (let i = 0; i < nz && !mark; i++) if (inZone(b, zones, i, x, y, z)) mark = i + 1;
    }
    out[k] = mark;
  }
}

// The live nodes of slots 0..count-1 inside each zone, by zone id (a node in
// two zones counts in both).
export function countInZones(end, dead, count, zones) {
  const b = f32Bounds(zones), counts = Object.fromEntries(zones.map((z) => [z.id, 0]));
  for (let k = 0; k < count; k++) {
    if (dead && dead[k]) continue;
    const x = end[k * 3], y = end[k * 3 + 1], z = end[k * 3 + 2];
    zones.forEach((zone, i) => {
      if (inZone(b, zones, i, x, y, z)) counts[zone.id]++;
    });
  }
  return counts;
}

// The conflicts table's rows from the per-stem stats (a snapshot's or a
// delta's): one per stem and zone it ever entered, in stats order, then in the
// order of the stem's `zones`: {plant, stem, zone, first, nodes}. Stats without
// `zones` (a daemon from before zones) have none.
export function conflictRows(stats) {
  const rows = [];
  for (const st of stats || []) {
    for (const [zone, z] of Object.entries(st.zones || {})) {
      rows.push({ plant: st.plant, stem: st.stem, zone, first: z.first, nodes: z.nodes });
    }
  }
  return rows;
}

// The clearances table's rows from the per-stem stats: one per stem that has a
// solid obstacle within range (the stats' `clearance`), naming the nearest (the
// first of the stem's order on a tie) and its distance in metres, with the
// nodes pruned at this iteration: {plant, stem, obstacle, distance, pruned}.
export function clearanceRows(stats) {
  const rows = [];
  for (const st of stats || []) {
    let best = null;
    for (const [obstacle, distance] of Object.entries(st.clearance || {})) {
      if (!best || distance < best.distance) best = { obstacle, distance };
    }
    if (best) rows.push({ plant: st.plant, stem: st.stem, ...best, pruned: st.pruned ?? 0 });
  }
  return rows;
}

// The plant cell of a conflicts row: the plant's id, with the stem's index
// after a slash when the plant has several stems (a shrub).
export function stemLabel(plant, stem, stemsOfPlant) {
  return stemsOfPlant > 1 ? `${plant}/${stem}` : plant;
}
