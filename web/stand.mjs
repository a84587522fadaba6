// Stands, as the page shows them (docs/model.md, "Stands"): which stems are dead
// (their stats' `alive` is false: drawn grey until their snag falls and the
// delta's shed ids take its nodes), which internodes belong to them, the stand's
// figures (a delta's or snapshot's `stand`, or stats.csv's columns) as the plots
// panel lists them, and the self-thinning points (stems per hectare against QMD). Pure, like
// helpers.mjs: no DOM, no network, no three.js; node runs the tests
// (tests/web/test_helpers.mjs). Stats without `alive` and messages without
// `stand` (an older daemon, a run of IGM presets) give no dead stems, no figures
// and no points. Nothing here changes its arguments, except the output array
// markDeadStems is given to fill.

// A stem's key: its plant's index in the snapshot times STEM_KEY, plus its index
// within the plant (both are 16-bit in the skeleton's arrays).
export const STEM_KEY = 65536;

// The keys of the dead stems in per-stem stats (`{plant: id, stem, alive}`), the
// plant's index looked up by its id in plantIndex (a Map).
export function deadStemKeys(stats, plantIndex) {
  const keys = new Set();
  for (const st of stats || []) {
    if (st.alive !== false) continue;
    const p = plantIndex.get(st.plant);
    if (p !== undefined) keys.add(p * STEM_KEY + st.stem);
  }
  return keys;
}

// Whether two sets of keys hold the same keys.
export function sameKeys(a, b) {
  if (a.size !== b.size) return false;
  for (const k of a) if (!b.has(k)) return false;
  return true;
}

// Marks slots from..to-1 of a skeleton's arrays (plant and stem per slot, dead:
// shed slots, or null) in out: 1 for a live slot of a dead stem, else 0.
export function markDeadStems(plant, stem, dead, from, to, keys, out) {
  if (keys.size === 0) {
    out.fill(0, from, to);
    return;
  }
  for (let k = from; k < to; k++) out[k] = !(dead && dead[k]) && keys.has(plant[k] * STEM_KEY + stem[k]) ? 1 : 0;
}

// The stand's figures the plots panel lists: the key in `stand`, the label, its
// unit and the decimals shown.
export const STAND_FIGURES = [
  { key: 'stems_per_ha', label: 'Stems', unit: '/ha', decimals: 0 },
  { key: 'basal_area', label: 'Basal area', unit: 'm²/ha', decimals: 2 },
  { key: 'qmd', label: 'QMD', unit: 'cm', decimals: 1 },
  { key: 'dominant_height', label: 'Dominant height', unit: 'm', decimals: 2 },
  { key: 'sdi', label: 'SDI', unit: '', decimals: 0 },
  { key: 'alive', label: 'Alive', unit: 'stems', decimals: 0 },
  { key: 'died', label: 'Died', unit: 'this iteration', decimals: 0 },
];

// The rows of the stand's figures: [label, value text] ("–" for a null figure),
// or [] without a stand.
export function standRows(stand) {
  if (!stand || typeof stand !== 'object') return [];
  return STAND_FIGURES.map(({ key, label, unit, decimals }) => {
    const v = stand[key];
    if (v == null) return [label, '–'];
    const text = v.toLocaleString('en', { minimumFractionDigits: decimals, maximumFractionDigits: decimals });
    return [label, unit ? `${text} ${unit}` : text];
  });
}

// The stand's figures of one iteration's rows of stats.csv (helpers.mjs,
// parseStatsCsv), which a run with stands gives on each row (cli.md, "export":
// its `died` as `stand_died`, its stems alive as the rows' `alive`; no `area`),
// or undefined for rows without them (a run without stands, an older daemon).
export function standOfRows(rows) {
  const row = rows?.[0];
  if (!row || !('stems_per_ha' in row)) return undefined;
  const stand = {
    alive: rows.some((r) => r.alive == null) ? null : rows.filter((r) => r.alive).length,
    died: row.stand_died ?? null,
  };
  for (const key of ['stems_per_ha', 'basal_area', 'qmd', 'dominant_height', 'sdi', 'cv_height', 'cv_dbh']) {
    stand[key] = row[key] ?? null;
  }
  return stand;
}

// A stand's point on the self-thinning plot, [QMD (cm), stems per ha], or null
// where log axes cannot place it (no stand, no QMD, no stems).
export function thinningPoint(stand) {
  const x = stand?.qmd, y = stand?.stems_per_ha;
  return x > 0 && y > 0 ? [x, y] : null;
}
