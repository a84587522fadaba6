// Live plots of every stem against iteration (or against the calendar year, in a
// run with a start year): height, DBH, crown width, leaf area (docs/model.md,
// "Foliage"), internodes and the growth cap c(T), and in a run of species in years
// the crown diameter and crown height too.
// One point per iteration and stem, from the run's stored stats (stats.csv,
// parsed by helpers.mjs) and then from each delta's stats.
import uPlot from 'uplot';
import { plantColor } from './scene.mjs';
import { statsInYears } from './helpers.mjs';

// years: only in a run whose stats carry them (species in years).
export const MEASURES = [
  { key: 'height', title: 'Height (m)' },
  { key: 'dbh', title: 'DBH (m)' },
  { key: 'crown_width', title: 'Crown width (m)' },
  { key: 'crown_diameter', title: 'Crown diameter (m)', years: true },
  { key: 'crown_height', title: 'Crown height (m)', years: true },
  { key: 'leaf_area', title: 'Leaf area (m²)' },
  { key: 'nodes', title: 'Internodes' },
  { key: 'cap', title: 'Growth cap c(T)' },
];

// The x axis (iterations or calendar years) ticks at whole numbers only, and
// prints them without uPlot's thousands separators: 2030, not "2,030".
const WHOLE_INCRS = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000];
export const wholeNumbers = (u, splits) => splits.map((v) => (v == null ? null : String(Math.round(v))));

export class Plots {
  constructor(container) {
    this.container = container;
    this.charts = [];
    this.rebuild = false;   // the charts must be made again (new stems)
    this.reset();
  }

  reset() {
    this.iterations = [];        // x values (as iterations)
    this.startYear = null;       // the calendar year of iteration 0, when the run has one
    this.years = false;          // the stats carry the measures of species in years
    this.stems = new Map();      // "plant/stem" -> {label, plant, values: {measure: []}}
    this.plantIndex = new Map(); // plant id -> index (colours as in the 3D view)
    for (const c of this.charts) c.destroy();
    this.charts = [];
    this.container.textContent = '';
    this.scheduled = false;
  }

  setPlants(plantIds) {
    plantIds.forEach((id, i) => this.plantIndex.set(id, i));
  }

  // The run's start year (null: none): the x axis shows calendar years.
  setStartYear(startYear) {
    if (startYear === this.startYear) return;
    this.startYear = startYear;
    this.rebuild = true;
    this.schedule();
  }

  // The measures charted: those of species in years only in a run that has them.
  measures() {
    return MEASURES.filter((m) => !m.years || this.years);
  }

  // Adds (or replaces) the stats of one iteration.
  add(iteration, stats) {
    if (!this.years && statsInYears(stats)) {
      this.years = true;
      this.rebuild = true;
    }
    let i = this.iterations.indexOf(iteration);
    if (i < 0) {
      // iterations arrive in order; one that is older than the newest goes in its place
      i = this.iterations.findIndex((x) => x > iteration);
      if (i < 0) i = this.iterations.length;
      this.iterations.splice(i, 0, iteration);
      for (const s of this.stems.values()) for (const m of MEASURES) s.values[m.key].splice(i, 0, null);
    }
    for (const st of stats) {
      const key = `${st.plant}/${st.stem}`;
      let s = this.stems.get(key);
      if (!s) {
        s = { label: key, plant: st.plant, values: {} };
        for (const m of MEASURES) s.values[m.key] = new Array(this.iterations.length).fill(null);
        this.stems.set(key, s);
        this.rebuild = true;
      }
      for (const m of MEASURES) s.values[m.key][i] = st[m.key] ?? null;
    }
    this.schedule();
  }

  // Drops iterations after `iteration` (a run that was forked or rewound).
  truncate(iteration) {
    const i = this.iterations.findIndex((x) => x > iteration);
    if (i < 0) return;
    this.iterations.length = i;
    for (const s of this.stems.values()) for (const m of MEASURES) s.values[m.key].length = i;
    this.schedule();
  }

  // The x values: iterations, or calendar years with a start year.
  xs() {
    return this.startYear == null ? this.iterations : this.iterations.map((it) => this.startYear + it);
  }

  // What the charts show: per measure, the iterations (and the x axis's name and
  // values: iterations or years) and each stem's values (null where it has none),
  // for the page's state and the tests.
  points() {
    const stems = [...this.stems.keys()], measures = this.measures();
    return Object.fromEntries(this.charts.map((c, k) => [measures[k].key, {
      iterations: this.iterations.slice(0, c.data[0].length),
      axis: c.axes[0].label,
      ticks: (c.axes[0]._values || []).slice(),   // the x axis's labels as drawn (uPlot's own array)
      x: Array.from(c.data[0]),
      stems: Object.fromEntries(stems.map((s, i) => [s, Array.from(c.data[i + 1] || [])])),
    }]));
  }

  schedule() {
    if (this.scheduled) return;
    this.scheduled = true;
    requestAnimationFrame(() => {
      this.scheduled = false;
      this.draw();
    });
  }

  draw() {
    const stems = [...this.stems.values()], measures = this.measures();
    if (this.rebuild || this.charts.length === 0) {
      this.rebuild = false;
      for (const c of this.charts) c.destroy();
      this.container.textContent = '';
      const width = Math.max(200, this.container.clientWidth - 8);
      const axis = this.startYear == null ? 'iteration' : 'year';
      this.charts = measures.map((m) => new uPlot({
        title: m.title, width, height: 150,
        legend: { show: false },
        cursor: { drag: { x: false, y: false } },
        scales: { x: { time: false } },
        axes: [{ label: axis, size: 36, incrs: WHOLE_INCRS, values: wholeNumbers }, { size: 60 }],
        series: [{ label: axis }, ...stems.map((s) => ({
          label: s.label, stroke: plantColor(this.plantIndex.get(s.plant) ?? 0), width: 1.5, spanGaps: false,
        }))],
      }, [[], ...stems.map(() => [])], this.container));
    }
    const xs = this.xs();
    this.charts.forEach((c, k) => {
      const key = measures[k].key;
      c.setData([xs, ...stems.map((s) => s.values[key])]);
    });
  }
}
