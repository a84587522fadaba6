// Live plots of every stem against iteration: height, DBH, crown width,
// internodes and the growth cap c(T). One point per iteration and stem, from the
// run's stored stats (stats.csv, parsed by helpers.mjs) and then from each
// delta's stats.
import uPlot from 'uplot';
import { plantColor } from './scene.mjs';

export const MEASURES = [
  { key: 'height', title: 'Height (m)' },
  { key: 'dbh', title: 'DBH (m)' },
  { key: 'crown_width', title: 'Crown width (m)' },
  { key: 'nodes', title: 'Internodes' },
  { key: 'cap', title: 'Growth cap c(T)' },
];

export class Plots {
  constructor(container) {
    this.container = container;
    this.charts = [];
    this.rebuild = false;   // the charts must be made again (new stems)
    this.reset();
  }

  reset() {
    this.iterations = [];        // x values
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

  // Adds (or replaces) the stats of one iteration.
  add(iteration, stats) {
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

  // What the charts show: per measure, the iterations on the x axis and each
  // stem's values (null where it has none), for the page's state and the tests.
  points() {
    const stems = [...this.stems.keys()];
    return Object.fromEntries(this.charts.map((c, k) => [MEASURES[k].key, {
      iterations: Array.from(c.data[0]),
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
    const stems = [...this.stems.values()];
    if (this.rebuild || this.charts.length === 0) {
      this.rebuild = false;
      for (const c of this.charts) c.destroy();
      this.container.textContent = '';
      const width = Math.max(200, this.container.clientWidth - 8);
      this.charts = MEASURES.map((m) => new uPlot({
        title: m.title, width, height: 150,
        legend: { show: false },
        cursor: { drag: { x: false, y: false } },
        scales: { x: { time: false } },
        axes: [{ label: 'iteration', size: 36 }, { size: 60 }],
        series: [{ label: 'iteration' }, ...stems.map((s) => ({
          label: s.label, stroke: plantColor(this.plantIndex.get(s.plant) ?? 0), width: 1.5, spanGaps: false,
        }))],
      }, [[], ...stems.map(() => [])], this.container));
    }
    this.charts.forEach((c, k) => {
      const key = MEASURES[k].key;
      c.setData([this.iterations, ...stems.map((s) => s.values[key])]);
    });
  }
}
