// Live plots of every stem against iteration (or against the calendar year, in a
// run with a start year): height, DBH, crown width, leaf area (docs/model.md,
// "Foliage"), crown area ("Canopy cover"), internodes and the growth cap c(T); in a
// run of species in years the crown diameter and crown height too; where stems
// carry carbon ("Wood and carbon") the CO2 they store and sequestered in the
// iteration. And the run-level curves: the site's canopy cover (last), and in a
// stand's run (docs/model.md, "Stands": messages with `stand`) the self-thinning
// plot (first), stems per hectare against the quadratic mean diameter on log-log
// axes, one point per iteration joined in time order. A measure a stem lacks at
// an iteration is a gap, not a zero.
// One point per iteration and stem, from the run's stored stats (stats.csv,
// parsed by helpers.mjs) and then from each delta's stats; the stand's points
// likewise (stats.csv's stand columns, stand.mjs's standOfRows, then each
// snapshot's and delta's `stand`).
// Above the charts, StandFigures lists the shown iteration's stand figures.
import uPlot from 'uplot';
import { plantColor } from './scene.mjs';
import { statsInYears } from './helpers.mjs';
import { standRows, thinningPoint } from './stand.mjs';

// years: only in a run whose stats carry them (species in years); carbon: only
// once a stem carries it (a species with an allometry or a wood density).
export const MEASURES = [
  { key: 'height', title: 'Height (m)' },
  { key: 'dbh', title: 'DBH (m)' },
  { key: 'crown_width', title: 'Crown width (m)' },
  { key: 'crown_diameter', title: 'Crown diameter (m)', years: true },
  { key: 'crown_height', title: 'Crown height (m)', years: true },
  { key: 'leaf_area', title: 'Leaf area (m²)' },
  { key: 'crown_area', title: 'Crown area (m²)' },
  { key: 'co2', title: 'CO₂ stored (kg CO₂e)', carbon: true },
  { key: 'co2_sequestered', title: 'CO₂ sequestered (kg CO₂e per iteration)', carbon: true },
  { key: 'nodes', title: 'Internodes' },
  { key: 'cap', title: 'Growth cap c(T)' },
];

// The x axis (iterations or calendar years) ticks at whole numbers only, and
// prints them without uPlot's thousands separators: 2030, not "2,030".
const WHOLE_INCRS = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000];
export const wholeNumbers = (u, splits) => splits.map((v) => (v == null ? null : String(Math.round(v))));

// The run-level chart: the share of the site's open ground under leaves, in per cent.
const COVER = { key: 'canopy_cover', title: 'Canopy cover (%)', stroke: '#333333' };
// The stand's chart: stems per hectare (y) against QMD (x), both logarithmic.
const THINNING = { key: 'self_thinning', title: 'Self-thinning (stems/ha against QMD)', x: 'QMD (cm)',
  y: 'stems/ha', stroke: '#6b4f2a' };

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
    this.carbon = false;         // a stem carried carbon
    this.cover = [];             // the site's canopy cover per iteration (0..1, null: none)
    this.stand = [];             // the stand's figures per iteration (null: none)
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

  // The measures charted: those of species in years and of carbon only in a run
  // that has them.
  measures() {
    return MEASURES.filter((m) => (!m.years || this.years) && (!m.carbon || this.carbon));
  }

  // Whether the run-level canopy cover is charted: once an iteration carried it.
  hasCover() {
    return this.cover.some((v) => v != null);
  }

  // Whether the self-thinning plot is drawn: once an iteration's stand has a point.
  hasThinning() {
    return this.stand.some((v) => thinningPoint(v) !== null);
  }

  // The self-thinning plot's points in time order: {iterations, x (QMD), y (stems/ha)}.
  thinning() {
    const out = { iterations: [], x: [], y: [] };
    this.stand.forEach((v, i) => {
      const p = thinningPoint(v);
      if (!p) return;
      out.iterations.push(this.iterations[i]);
      out.x.push(p[0]);
      out.y.push(p[1]);
    });
    return out;
  }

  // Adds (or replaces) the stats of one iteration, the site's canopy cover after
  // it (undefined or null: not given) and the stand's figures (undefined: not
  // given, a figure already held is kept; null: none).
  add(iteration, stats, canopyCover, stand) {
    if (!this.years && statsInYears(stats)) {
      this.years = true;
      this.rebuild = true;
    }
    if (!this.carbon && stats.some((st) => st.co2 != null)) {
      this.carbon = true;
      this.rebuild = true;
    }
    if (!this.hasCover() && canopyCover != null) this.rebuild = true;
    if (!this.hasThinning() && thinningPoint(stand) !== null) this.rebuild = true;
    let i = this.iterations.indexOf(iteration);
    if (i < 0) {
      // iterations arrive in order; one that is older than the newest goes in its place
      i = this.iterations.findIndex((x) => x > iteration);
      if (i < 0) i = this.iterations.length;
      this.iterations.splice(i, 0, iteration);
      this.cover.splice(i, 0, null);
      this.stand.splice(i, 0, null);
      for (const s of this.stems.values()) for (const m of MEASURES) s.values[m.key].splice(i, 0, null);
    }
    this.cover[i] = canopyCover ?? null;
    if (stand !== undefined) this.stand[i] = stand;
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
    this.rebuild = true;   // (the run-level charts may have lost their points)
    this.iterations.length = i;
    this.cover.length = i;
    this.stand.length = i;
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
  // The canopy cover's chart has one series, `site`; the self-thinning plot's x
  // is QMD, its one series `stand` stems per hectare, and its iterations those of
  // its points.
  points() {
    const stems = [...this.stems.keys()], keys = this.chartKeys();
    return Object.fromEntries(this.charts.map((c, k) => {
      const ticks = (c.axes[0]._values || []).slice();   // the x axis's labels as drawn (uPlot's own array)
      if (keys[k] === THINNING.key) {
        const [x, y] = c.data[1];
        const t = this.thinning();
        return [keys[k], { iterations: t.iterations.slice(0, x.length), axis: c.axes[0].label, ticks,
          x: Array.from(x), stems: { stand: Array.from(y) } }];
      }
      return [keys[k], {
        iterations: this.iterations.slice(0, c.data[0].length),
        axis: c.axes[0].label,
        ticks,
        x: Array.from(c.data[0]),
        stems: Object.fromEntries((keys[k] === COVER.key ? ['site'] : stems)
          .map((s, i) => [s, Array.from(c.data[i + 1] || [])])),
      }];
    }));
  }

  // The keys of the charts, in order: the self-thinning plot (under the stand's
  // figures), the measures, then the canopy cover.
  chartKeys() {
    return [...(this.hasThinning() ? [THINNING.key] : []), ...this.measures().map((m) => m.key),
      ...(this.hasCover() ? [COVER.key] : [])];
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
      const chart = (title, series) => new uPlot({
        title, width, height: 150,
        legend: { show: false },
        cursor: { drag: { x: false, y: false } },
        scales: { x: { time: false } },
        axes: [{ label: axis, size: 36, incrs: WHOLE_INCRS, values: wholeNumbers }, { size: 60 }],
        series: [{ label: axis }, ...series.map((s) => ({ ...s, width: 1.5, spanGaps: false }))],
      }, [[], ...series.map(() => [])], this.container);
      const stemSeries = stems.map((s) => ({ label: s.label, stroke: plantColor(this.plantIndex.get(s.plant) ?? 0) }));
      this.charts = this.hasThinning() ? [thinningChart(width, this.container)] : [];
      this.charts.push(...measures.map((m) => chart(m.title, stemSeries)));
      if (this.hasCover()) this.charts.push(chart(COVER.title, [{ label: 'site', stroke: COVER.stroke }]));
    }
    const xs = this.xs(), keys = this.chartKeys();
    this.charts.forEach((c, k) => {
      if (keys[k] === THINNING.key) {
        const t = this.thinning();
        c.setData([null, [t.x, t.y]]);
      } else if (keys[k] === COVER.key) {
        c.setData([xs, this.cover.map((v) => (v == null ? null : 100 * v))]);
      } else {
        c.setData([xs, ...stems.map((s) => s.values[keys[k]])]);
      }
    });
  }
}

// The self-thinning plot: uPlot's x-y mode (the points in time order, QMD need
// not grow), both scales logarithmic.
function thinningChart(width, container) {
  return new uPlot({
    mode: 2, title: THINNING.title, width, height: 180,
    legend: { show: false },
    cursor: { drag: { x: false, y: false } },
    scales: { x: { time: false, distr: 3 }, y: { distr: 3 } },
    axes: [{ label: THINNING.x, size: 36 }, { label: THINNING.y, size: 60 }],
    series: [{}, {
      label: 'stand', stroke: THINNING.stroke, width: 1.5,
      // (in this mode uPlot draws only the point its window starts at, unless
      // the filter lists every point)
      points: { show: true, size: 5, fill: THINNING.stroke, filter: (u, i) => u.data[i][0].map((_, k) => k) },
      facets: [{ scale: 'x', auto: true }, { scale: 'y', auto: true }],
    }],
  }, [null, [[], []]], container);
}

// The stand's figures of the shown iteration, above the charts: a table of
// stand.mjs's rows, hidden for a run without them.
export class StandFigures {
  constructor(section, table) {
    this.section = section;
    this.body = table.tBodies[0];
  }

  // stand: the shown iteration's figures (Skeleton.stand), or null.
  render(stand) {
    const rows = standRows(stand);
    this.section.hidden = rows.length === 0;
    this.body.textContent = '';
    for (const [label, value] of rows) {
      const tr = this.body.insertRow();
      tr.insertCell().textContent = label;
      tr.insertCell().textContent = value;
    }
  }

  // The figures as shown: [[label, value], ...].
  rows() {
    return this.section.hidden ? [] : [...this.body.rows].map((tr) => [...tr.cells].map((td) => td.textContent));
  }
}
