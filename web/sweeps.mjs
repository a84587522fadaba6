// The sweeps of the run list (protocol.md, "runs"): a run that `sylva sweep`
// stored carries its sweep's name, its position in the plan's product of axes and
// its value on each axis. The run list shows a sweep's runs together under its
// name, each by its place on the axes, and "compare species" opens those of its
// runs that differ on the species axes only. Pure functions: tests run them in node.

// The most runs the compare view shows side by side.
export const MAX_COMPARED = 4;

// A species axis: "species/KEY", one per species of the scenario that the plan varies.
export const isSpeciesAxis = (axis) => axis.startsWith('species/');

// The run list as the panel shows it: [{sweep, runs}] in creation order, a run of
// no sweep alone in its group (sweep null), a sweep's runs all in one group where
// its first run is, by position.
export function groupRuns(runs) {
  const groups = [], bySweep = new Map();
  for (const r of runs) {
    if (typeof r.sweep !== 'string') {
      groups.push({ sweep: null, runs: [r] });
      continue;
    }
    let g = bySweep.get(r.sweep);
    if (!g) {
      g = { sweep: r.sweep, runs: [] };
      bySweep.set(r.sweep, g);
      groups.push(g);
    }
    g.runs.push(r);
  }
  for (const g of bySweep.values()) g.runs.sort((a, b) => (a.position ?? 0) - (b.position ?? 0));
  return groups;
}

// How a species value reads: a preset's name as it is; a species object (its
// compact JSON) by the preset it starts from, else as a species of its own.
function speciesLabel(value) {
  if (!value.startsWith('{')) return value;
  try {
    const s = JSON.parse(value);
    if (typeof s.preset === 'string') return Object.keys(s).length > 1 ? `${s.preset} (changed)` : s.preset;
  } catch {
    // not JSON after all: shown as it is
    return value;
  }
  return 'own parameters';
}

// How a run's value on one axis reads: "street-tree: utdb:NoEast:PLAC", "seed 1",
// and a variant by its name.
export function axisLabel(axis, value) {
  if (isSpeciesAxis(axis)) return `${axis.slice('species/'.length)}: ${speciesLabel(value)}`;
  if (axis === 'seed') return `seed ${value}`;
  if (axis === 'variant') return value;
  return `${axis}: ${value}`;
}

// A run's place on its sweep's axes, one {axis, value, label} per axis in the
// plan's order ([] for a run of no sweep).
export function axesOf(run) {
  return Object.entries(run.axes || {}).map(([axis, value]) => ({ axis, value, label: axisLabel(axis, value) }));
}

// The runs "compare species" opens: of a sweep's runs (a group of groupRuns), those
// that have the first run's values on every axis but the species ones, at most
// `max`; [] when that leaves fewer than two, or the sweep varies no species.
export function speciesComparison(runs, max = MAX_COMPARED) {
  if (!runs.some((r) => Object.keys(r.axes || {}).some(isSpeciesAxis))) return [];
  const others = (r) => JSON.stringify(Object.entries(r.axes || {}).filter(([a]) => !isSpeciesAxis(a)));
  const base = others(runs[0]);
  const picked = runs.filter((r) => others(r) === base).slice(0, max);
  return picked.length >= 2 ? picked : [];
}
