// The compare view's one slider for all its runs. When every run has a start year
// the slider is in calendar years, so that runs that start in different years are
// compared at the same year; otherwise it is in iterations. Each run shows the
// iteration of the slider's value within its own range: from its earliest stage
// (below 0 for a measured tree's past) to its last stored iteration. Pure
// functions: tests run them in node.

// runs: [{startYear (null: none), earliest, last}] ->
// {years, offsets (a run's slider value at its iteration 0), min, max}.
export function sharedScale(runs) {
  const years = runs.length > 0 && runs.every((r) => r.startYear != null);
  const offsets = runs.map((r) => (years ? r.startYear : 0));
  const lo = runs.map((r, i) => Math.min(0, r.earliest) + offsets[i]);
  const hi = runs.map((r, i) => r.last + offsets[i]);
  return { years, offsets, min: runs.length ? Math.min(...lo) : 0, max: runs.length ? Math.max(...hi) : 0 };
}

// The iteration run i ({earliest, last}) shows at slider value v.
export function iterationAt(scale, i, run, v) {
  return Math.max(Math.min(0, run.earliest), Math.min(run.last, v - scale.offsets[i]));
}

// How the slider's value reads.
export function scaleLabel(scale, v) {
  return scale.years ? String(v) : `iteration ${v}`;
}
