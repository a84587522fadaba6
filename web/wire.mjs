// Protocol messages (protocol.md) turned into typed arrays, so that a snapshot or a
// delta of a million internodes crosses from the socket worker to the page as a
// few transferable buffers, and applying it is a handful of tight loops.

// [[id, n], ...] leaf counts (protocol.md, "snapshot" and "delta": leaves) as
// {n, id, count}; a message without them (a skeleton export) gives none.
function leafArrays(list = []) {
  const n = list.length, out = { n, id: new Int32Array(n), count: new Uint16Array(n) };
  for (let i = 0; i < n; i++) {
    out.id[i] = list[i][0];
    out.count[i] = list[i][1];
  }
  return out;
}

// A delta: added [[id, parent, plant, stem, x, y, z, radius]], radii [[id, r]],
// shed [id] and leaves [[id, n]] become flat arrays (empty ones for a delta of
// `detail` "stems", which has none of them).
export function deltaArrays(msg) {
  const a = msg.added ?? [], n = a.length;
  const added = {
    n, id: new Int32Array(n), parent: new Int32Array(n), plant: new Uint16Array(n),
    stem: new Uint16Array(n), xyzr: new Float32Array(n * 4),
  };
  for (let i = 0; i < n; i++) {
    const e = a[i];
    added.id[i] = e[0];
    added.parent[i] = e[1];
    added.plant[i] = e[2];
    added.stem[i] = e[3];
    added.xyzr[i * 4] = e[4];
    added.xyzr[i * 4 + 1] = e[5];
    added.xyzr[i * 4 + 2] = e[6];
    added.xyzr[i * 4 + 3] = e[7];
  }
  const r = msg.radii ?? [], m = r.length;
  const radii = { n: m, id: new Int32Array(m), r: new Float32Array(m) };
  for (let i = 0; i < m; i++) {
    radii.id[i] = r[i][0];
    radii.r[i] = r[i][1];
  }
  return {
    type: 'delta', run: msg.run, seq: msg.seq, iteration: msg.iteration, detail: msg.detail,
    stats: msg.stats, canopy_cover: msg.canopy_cover, stand: msg.stand, added, radii,
    shed: Int32Array.from(msg.shed ?? []),
    leaves: leafArrays(msg.leaves), typed: true,
  };
}

// A snapshot (or a skeleton export): the plants' nodes [id, parent, x, y, z,
// radius, birth] and the leaves [[id, n]] become flat arrays, the nodes in plant,
// stem, id order (none for a snapshot of `detail` "stems"); the rest is kept.
export function snapshotArrays(msg) {
  let n = 0;
  for (const p of msg.plants) for (const s of p.stems) n += s.nodes?.length ?? 0;
  const nodes = {
    n, id: new Int32Array(n), parent: new Int32Array(n), plant: new Uint16Array(n),
    stem: new Uint16Array(n), birth: new Int32Array(n), xyzr: new Float32Array(n * 4),
  };
  let k = 0;
  msg.plants.forEach((p, pi) => p.stems.forEach((s, si) => {
    for (const e of s.nodes ?? []) {
      nodes.id[k] = e[0];
      nodes.parent[k] = e[1];
      nodes.plant[k] = pi;
      nodes.stem[k] = si;
      nodes.xyzr[k * 4] = e[2];
      nodes.xyzr[k * 4 + 1] = e[3];
      nodes.xyzr[k * 4 + 2] = e[4];
      nodes.xyzr[k * 4 + 3] = e[5];
      nodes.birth[k] = e[6];
      k++;
    }
  }));
  const { plants, leaves, ...rest } = msg;
  return {
    ...rest, typed: true, nodes, leaves: leafArrays(leaves),
    plants: plants.map((p) => ({ id: p.id, stems: p.stems.map((s) => ({ root: s.root })) })),
  };
}

// The buffers of a converted message, for postMessage's transfer list.
export function transferables(msg) {
  const out = [];
  for (const part of [msg.added, msg.radii, msg.nodes, msg.leaves]) {
    if (!part) continue;
    for (const v of Object.values(part)) if (ArrayBuffer.isView(v)) out.push(v.buffer);
  }
  if (msg.shed) out.push(msg.shed.buffer);
  return out;
}
