// The stem-level view of a large run (protocol.md, "subscribe": `detail`
// "stems"): the daemon sends each stem's stats and no internodes, and the view
// draws each stem from them, a trunk (a cylinder from its root up to its height,
// as thick as its dbh) and a crown (an ellipsoid from its crown base to its
// height, crown_width across). Pure, like helpers.mjs: no DOM, no three.js (the
// meshes are scene.mjs's StemModels).

// Above this many live internodes (the run list's `nodes`, when the run is
// picked) the viewer watches a run at stem detail; `?stems=N` in the page's
// address sets another threshold.
export const STEMS_THRESHOLD = 200000;

// A stem's trunk radius (m) before it has a dbh (lower than 1.3 m), and the
// narrowest crown drawn.
const THIN_TRUNK = 0.01;
const MIN_CROWN = 0.05;

// The threshold of a page's address (location.search).
export function stemsThreshold(search = '') {
  const v = new URLSearchParams(search).get('stems');
  const n = v === null || v === '' ? NaN : Number(v);
  return Number.isFinite(n) && n >= 0 ? n : STEMS_THRESHOLD;
}

// The detail to watch a run at ({nodes}: its summary): 'stems' above the threshold.
export function detailFor(run, threshold = STEMS_THRESHOLD) {
  return (run?.nodes ?? 0) > threshold ? 'stems' : 'nodes';
}

// The shapes of the stems of per-stem stats ({plant: id, stem, height, dbh,
// crown_base, crown_width, alive}) over plants [{id, stems: [{root}]}] (plantIndex:
// plant id -> index): [{plant, root, height, trunkRadius, crownBase, crownRadius,
// dead}], heights above the root in m; a stem the plants do not hold is left out.
// A dead stem (alive false) has no crown (crownRadius 0).
export function stemShapes(plants, stats, plantIndex) {
  const out = [];
  for (const st of stats || []) {
    const plant = plantIndex.get(st.plant);
    const root = plants[plant]?.stems[st.stem]?.root;
    if (!root) continue;
    const height = Math.max(0, st.height || 0);
    const dead = st.alive === false;
    const crownBase = Math.min(height, Math.max(0, st.crown_base ?? 0));
    out.push({
      plant, root, height, dead, crownBase,
      trunkRadius: st.dbh > 0 ? st.dbh / 2 : THIN_TRUNK,
      crownRadius: dead || height <= crownBase ? 0 : Math.max(MIN_CROWN, (st.crown_width || 0) / 2),
    });
  }
  return out;
}
