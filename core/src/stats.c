/* Per-stem measures of docs/model.md: height, dbh, crown width and base, nodes, light. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "light.h"
#include "world_impl.h"

/* The tapered cylinder (a frustum) of the internode from slot p to slot n. */
static double internode_volume(const sylva__skeleton *s, int32_t p, int32_t n) {
  double dx = (double)s->x[n] - s->x[p], dy = (double)s->y[n] - s->y[p],
         dz = (double)s->z[n] - s->z[p];
  double r1 = s->radius[p], r2 = s->radius[n];
  return (3.14159265358979323846 / 3.0) * sqrt(dx * dx + dy * dy + dz * dz) *
         (r1 * r1 + r1 * r2 + r2 * r2);
}

/* Adds live node i's internode (none for a root) to its stem's wood. */
static void add_wood(sylva__stem *st, const sylva__skeleton *s, size_t i) {
  if (s->parent[i] >= 0) st->stats.wood_volume += internode_volume(s, s->parent[i], (int32_t)i);
}

/* Starts a stem's measures: counters zero, extents empty. */
static void stats_reset(sylva__stem *st) {
  sylva_stem_stats *o = &st->stats;
  o->plant = st->plant;
  o->stem = st->index;
  o->nodes = 0;
  o->age = -1;
  o->crown_height = NAN;
  o->leaf_area = 0.0;
  o->wood_volume = 0.0;
  o->finished = st->finished;
  st->ext[0] = st->ext[2] = INFINITY;
  st->ext[1] = st->ext[3] = st->ext[4] = -INFINITY;
}

/* The crown base (docs/model.md, "Measures"): the lowest leaves of the crown, going
 * down from its top, before a vertical gap of more than CROWN_GAP m without leaves
 * (the US Forest Service's inventory leaves lower branches apart so). The leaves'
 * heights are binned by CROWN_BIN (less than the gap): each bin keeps its lowest and
 * highest, and the gaps are measured between those. */
#define CROWN_GAP 1.5
#define CROWN_BIN 0.75

size_t sylva__crown_bins(double height) {
  return (size_t)floor((height > 0.0 ? height : 0.0) / CROWN_BIN) + 2;
}

/* The crown base above the root at rz, from the n leaf heights z (NaN for none);
 * bins holds 2 sylva__crown_bins(top - rz) doubles, where top is the highest z. */
static double crown_base_of(const double *z, size_t n, double rz, double top, double *bins) {
  if (!n) return NAN;
  size_t nb = sylva__crown_bins(top - rz);
  double *lo = bins, *hi = bins + nb;
  for (size_t b = 0; b < nb; b++) lo[b] = INFINITY, hi[b] = -INFINITY;
  for (size_t i = 0; i < n; i++) {
    double h = (z[i] - rz) / CROWN_BIN;
    size_t b = h <= 0.0 ? 0 : (size_t)h < nb ? (size_t)h : nb - 1;
    if (z[i] < lo[b]) lo[b] = z[i];
    if (z[i] > hi[b]) hi[b] = z[i];
  }
  double base = INFINITY;
  for (size_t b = nb; b-- > 0;) {
    if (!(hi[b] >= lo[b])) continue; /* no leaves */
    if (isfinite(base) && base - hi[b] > CROWN_GAP) break;
    if (lo[b] < base) base = lo[b];
  }
  return base - rz;
}

/* Height and crown width from the extents, dbh (trunk internode crossing 1.3 m) from a
 * walk up the trunk; the crown base is set apart. */
static void stats_shape(const sylva_world *w, sylva__stem *st) {
  const sylva__skeleton *s = &w->nodes;
  sylva_stem_stats *o = &st->stats;
  double rz = s->z[st->root_slot];
  o->height = st->ext[4] - rz;
  o->crown_width = 0.5 * ((st->ext[1] - st->ext[0]) + (st->ext[3] - st->ext[2]));
  o->dbh = NAN;
  for (int32_t n = st->root_slot; n >= 0 && isnan(o->dbh); n = s->axis_child[n]) {
    int32_t p = s->parent[n];
    if (p >= 0 && s->z[n] - rz >= 1.3 && s->z[p] - rz < 1.3) o->dbh = 2.0 * s->radius[n];
  }
}

static void set_crown_base(sylva__stem *st, double base) {
  st->stats.crown_base = base;
  st->stats.crown_height = st->stats.height - base; /* NaN with the crown base */
}

/* Years since planting: the stem's seasons less those it spent in the nursery. */
static int32_t stem_age(const sylva_world *w, const sylva__stem *st, int iteration) {
  const sylva_species_def *d = &w->species[st->species].def;
  return d->years ? (int32_t)(sylva__stem_local(st, iteration) - d->nursery) : -1;
}

static void extend(sylva__stem *st, const sylva__skeleton *s, size_t i) {
  double x = s->x[i], y = s->y[i], z = s->z[i];
  if (x < st->ext[0]) st->ext[0] = x;
  if (x > st->ext[1]) st->ext[1] = x;
  if (y < st->ext[2]) st->ext[2] = y;
  if (y > st->ext[3]) st->ext[3] = y;
  if (z > st->ext[4]) st->ext[4] = z;
}

/* Counts live node i in its stem's measures: nodes, extents, wood. */
static void measure_node(sylva__stem *st, const sylva__skeleton *s, size_t i) {
  st->stats.nodes++;
  extend(st, s, i);
  add_wood(st, s, i);
}

/* Is node i of a stem of species d leaf-bearing as the next season carries it (as
 * shedding judges it)? */
static bool leafy(const sylva__skeleton *s, const sylva_species_def *d, size_t i, int iteration) {
  return sylva__leaf_age(s, d, i, iteration + 1) >= 0;
}

typedef struct stats_ctx {
  sylva_world *w;
  int iteration;
  size_t grain, bins; /* stems a piece; doubles of a piece's crown bins */
} stats_ctx;

/* Stems [begin, end), one piece: each live stem's nodes in slot order (the grouping by
 * stem), its leaf heights into its own part of w->pipe, its crown base with the
 * piece's own bins. Writes only these stems' measures. */
static void stats_stems(void *arg, size_t begin, size_t end) {
  const stats_ctx *c = arg;
  sylva_world *w = c->w;
  const sylva__skeleton *s = &w->nodes;
  const int32_t *first = w->stem_nodes_first.data, *nodes = w->stem_nodes.data;
  double *bins = w->crown_bins.data + begin / c->grain * c->bins;
  for (size_t k = begin; k < end; k++) {
    sylva__stem *st = &w->stems[k];
    /* a dead stem keeps the measures of its last season alive (docs/model.md, "Stands") */
    if (sylva__stem_dead(st)) continue;
    const sylva_species_def *d = &w->species[st->species].def;
    double *z = w->pipe + first[k];
    size_t leaves = 0;
    stats_reset(st);
    for (int32_t at = first[k]; at < first[k + 1]; at++) {
      size_t i = (size_t)nodes[at];
      measure_node(st, s, i);
      if (leafy(s, d, i, c->iteration)) z[leaves++] = s->z[i];
    }
    stats_shape(w, st);
    set_crown_base(st, crown_base_of(z, leaves, s->z[st->root_slot], st->ext[4], bins));
    st->stats.leaf_area = (double)leaves * sylva__node_leaf_area(d);
  }
}

void sylva__stats(sylva_world *w, int iteration) {
  /* Stems share no node: each is measured on its own, on the world's threads, in at
   * most SYLVA__STATS_PIECES pieces (the crown bins' room, from creation). The
   * grouping's room is the per-slot scratch's, made before the step could fail. */
  SYLVA_ASSERT(w->stem_nodes.cap >= w->nodes.count &&
               w->stem_nodes_first.cap >= (size_t)w->stem_count + 1);
  sylva__group_by_stem(w);
  size_t n = (size_t)w->stem_count;
  stats_ctx c = {w, iteration, (n + SYLVA__STATS_PIECES - 1) / SYLVA__STATS_PIECES,
                 w->crown_bins.cap / SYLVA__STATS_PIECES};
  if (n) sylva__pool_for(w->pool, n, c.grain, stats_stems, &c);
  for (int k = 0; k < w->stem_count; k++) {
    sylva__stem *st = &w->stems[k];
    if (sylva__stem_dead(st)) {
      st->stats.co2_sequestered = isnan(st->stats.co2) ? NAN : 0.0;
      continue;
    }
    st->stats.age = stem_age(w, st, iteration);
    st->stats.light = st->light_next;
    st->stats.cap = sylva__clock_cap(&w->species[st->species], st->clock_prev, st->clock, 1.0);
    sylva__stats_carbon(w, k, st->stats.co2); /* the co2 before this pass */
  }
  sylva__canopy(w);
  sylva__stand(w);
}

void sylva__stats_planted(sylva_world *w, int stem) {
  const sylva__skeleton *s = &w->nodes;
  sylva__stem *st = &w->stems[stem];
  sylva__species *sp = &w->species[st->species];
  stats_reset(st);
  st->stats.shed = 0;
  st->stats.cap = 0;
  st->stats.light = 0.0;
  /* its nodes are the last slots: the initial trunk, or a stem grown in the nursery */
  int next = w->iteration + 1;
  double *z = w->pipe; /* the leaf heights, for the crown base */
  size_t leaves = 0;
  for (size_t n = (size_t)st->root_slot; n < s->count; n++) {
    if (s->stem[n] != stem || !(s->flags[n] & SYLVA__NODE_ALIVE)) continue;
    measure_node(st, s, n);
    int age = sylva__leaf_age(s, &sp->def, n, next);
    if (age < 0) continue;
    z[leaves++] = s->z[n];
    int v[3];
    sylva__node_voxel(w, (int32_t)n, v);
    /* as the next iteration will collect it: every node one iteration older */
    st->stats.light += sylva__collected(sp->def.alpha, sylva__grid_light(&w->grid, v),
                                        sylva__species_age_pow(sp, age));
  }
  stats_shape(w, st);
  set_crown_base(st, crown_base_of(z, leaves, s->z[st->root_slot], st->ext[4], w->crown_bins.data));
  st->stats.age = stem_age(w, st, w->iteration);
  st->stats.leaf_area = (double)leaves * sylva__node_leaf_area(&sp->def);
  sylva__stats_carbon(w, stem, NAN);
  st->stats.co2_sequestered = isnan(st->stats.co2) ? NAN : 0.0; /* 0 at planting */
  st->stats.crown_area = 0.0; /* the canopy pass after planting measures it */
}

void sylva__stats_leaf_area(sylva_world *w) {
  const sylva__skeleton *s = &w->nodes;
  /* counted first, then multiplied, as sylva__stats does: the same bits */
  /* a dead stem keeps its last measures (the image holds them) */
  for (int k = 0; k < w->stem_count; k++)
    if (!sylva__stem_dead(&w->stems[k])) w->stems[k].stats.leaf_area = 0.0;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    sylva__stem *st = &w->stems[s->stem[i]];
    if (leafy(s, &w->species[st->species].def, i, w->iteration)) st->stats.leaf_area += 1.0;
    /* the leaves as the last journal gave them: the next one lists what changes */
    w->nodes.leaves[i] = (uint16_t)sylva__node_leaves(w, i);
  }
  for (int k = 0; k < w->stem_count; k++)
    if (!sylva__stem_dead(&w->stems[k]))
      w->stems[k].stats.leaf_area *= sylva__node_leaf_area(&w->species[w->stems[k].species].def);
}

/* ---- wood and carbon (docs/model.md, "Wood and carbon") ---------------------------- */

/* Carbon is half the dry weight (GTR-253's biomass appendix), CO2 44/12 of carbon. */
#define CARBON_SHARE 0.5
#define CO2_PER_C (44.0 / 12.0)

/* Above-ground dry weight (kg) by the species' allometry at dbh D cm and height H m;
 * NaN without an allometry or a dbh. Never below 0: a form less the foliage turns
 * negative far below the dbh its equation was fitted on. */
static double biomass_of(const sylva_species_def *d, double dbh_m, double height) {
  if (!d->biomass_form || !(dbh_m > 0.0) || !(height > 0.0)) return NAN;
  double D = 100.0 * dbh_m;
  double v = d->biomass_a * pow(D, d->biomass_b);
  if (d->biomass_c != 0.0) v *= pow(height, d->biomass_c);
  if (d->biomass_form == 1) v *= d->wood_density;
  if (d->biomass_form == 3) v -= exp(d->biomass_p + d->biomass_q / D);
  v *= d->biomass_factor;
  return v > 0.0 ? v : 0.0;
}

void sylva__stats_carbon(sylva_world *w, int stem, double prev_co2) {
  sylva__stem *st = &w->stems[stem];
  const sylva_species_def *d = &w->species[st->species].def;
  sylva_stem_stats *o = &st->stats;
  o->biomass_model = d->wood_density > 0.0 ? o->wood_volume * d->wood_density : NAN;
  o->biomass = biomass_of(d, o->dbh, o->height);
  o->carbon = o->biomass * CARBON_SHARE;
  o->co2 = o->carbon * CO2_PER_C;
  o->co2_sequestered = isnan(o->co2) ? NAN : o->co2 - (isnan(prev_co2) ? 0.0 : prev_co2);
}

void sylva__stats_loaded(sylva_world *w) {
  const sylva__skeleton *s = &w->nodes;
  for (int k = 0; k < w->stem_count; k++)
    if (!sylva__stem_dead(&w->stems[k])) w->stems[k].stats.wood_volume = 0.0;
  for (size_t i = 0; i < s->count; i++)
    if ((s->flags[i] & SYLVA__NODE_ALIVE) && !sylva__stem_dead(&w->stems[s->stem[i]]))
      add_wood(&w->stems[s->stem[i]], s, i);
  for (int k = 0; k < w->stem_count; k++) {
    sylva_stem_stats *o = &w->stems[k].stats;
    if (sylva__stem_dead(&w->stems[k])) continue; /* as the image holds them */
    double sequestered = o->co2_sequestered; /* as the image holds it */
    sylva__stats_carbon(w, k, NAN);
    o->co2_sequestered = isnan(o->co2) ? NAN : sequestered;
  }
  sylva__canopy(w);
  sylva__stand(w);
}

/* ---- canopy (docs/model.md, "Canopy cover") ----------------------------------------- */

int sylva__canopy_init(sylva_world *w) {
  int n[3];
  sylva_world_dims(w, n);
  int f = 1;
  while ((int64_t)((n[0] + f - 1) / f) * ((n[1] + f - 1) / f) > SYLVA__CANOPY_MAX_COLS) f++;
  w->col_n[0] = (n[0] + f - 1) / f;
  w->col_n[1] = (n[1] + f - 1) / f;
  w->col_edge = w->def.voxel * f;
  size_t cells = (size_t)w->col_n[0] * (size_t)w->col_n[1];
  w->cols = sylva__calloc(cells, sizeof *w->cols);
  w->foot = sylva__calloc((cells + 7) / 8, 1);
  if (!w->cols || !w->foot) return SYLVA_ENOMEM;
  w->foot_dirty = true;
  return SYLVA_OK;
}

/* The cell of coordinate v on axis a, clamped to the grid. */
static int col_of(const sylva_world *w, int a, double v) {
  double c = floor((v - w->def.min[a]) / w->col_edge);
  return c < 0.0 ? 0 : c >= w->col_n[a] ? w->col_n[a] - 1 : (int)c;
}

/* Marks the cells whose centres lie under a solid obstacle standing on the floor, and
 * counts the others: the open ground. */
static void canopy_foot(sylva_world *w) {
  size_t cells = (size_t)w->col_n[0] * (size_t)w->col_n[1];
  memset(w->foot, 0, (cells + 7) / 8);
  int64_t covered = 0;
  const double e = w->col_edge, floor_z = w->def.min[2] + 0.5 * w->def.voxel;
  for (int k = 0; k < w->grid.obstacle_slots; k++) {
    const sylva__obstacle *ob = &w->grid.obstacles[k];
    if (!ob->live || ob->zone || ob->min[2] > floor_z) continue;
    /* cells whose centre min + (c + 0.5) e lies in [min, max) */
    int lo[2], hi[2];
    for (int a = 0; a < 2; a++) {
      lo[a] = (int)ceil((ob->min[a] - w->def.min[a]) / e - 0.5);
      hi[a] = (int)ceil((ob->max[a] - w->def.min[a]) / e - 0.5);
      if (lo[a] < 0) lo[a] = 0;
      if (hi[a] > w->col_n[a]) hi[a] = w->col_n[a];
    }
    for (int y = lo[1]; y < hi[1]; y++)
      for (int x = lo[0]; x < hi[0]; x++) {
        size_t c = (size_t)y * (size_t)w->col_n[0] + (size_t)x;
        if (ob->fp && !sylva__footprint_inside(ob->fp, w->def.min[0] + (x + 0.5) * e,
                                               w->def.min[1] + (y + 0.5) * e))
          continue; /* a prism covers the cells whose centres its footprint holds */
        if (!(w->foot[c >> 3] & (1u << (c & 7)))) covered++;
        w->foot[c >> 3] |= (uint8_t)(1u << (c & 7));
      }
  }
  w->open_cols = (int64_t)cells - covered;
  w->foot_dirty = false;
}

/* The cells a leaf-bearing internode a-b (x, y) covers: lo..hi (inclusive) bounds
 * them; within() tells which of those lie within r of it. */
typedef struct cover_reach {
  double a[2], d[2], len2, r;
  int lo[2], hi[2];
} cover_reach;

static cover_reach reach_of(const sylva_world *w, const double a[2], const double b[2],
                            double r) {
  cover_reach c = {.a = {a[0], a[1]}, .d = {b[0] - a[0], b[1] - a[1]}, .r = r};
  c.len2 = c.d[0] * c.d[0] + c.d[1] * c.d[1];
  for (int k = 0; k < 2; k++) {
    c.lo[k] = col_of(w, k, fmin(a[k], b[k]) - r);
    c.hi[k] = col_of(w, k, fmax(a[k], b[k]) + r);
  }
  return c;
}

static bool within(const cover_reach *c, double cx, double cy) {
  double t = c->len2 > 0.0 ? ((cx - c->a[0]) * c->d[0] + (cy - c->a[1]) * c->d[1]) / c->len2 : 0.0;
  t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
  double px = c->a[0] + t * c->d[0] - cx, py = c->a[1] + t * c->d[1] - cy;
  return px * px + py * py <= c->r * c->r;
}

/* a leaf reaches about its length from its internode (docs/model.md, "Foliage"); half
 * a cell's diagonal more, so that the cell holding a leaf-bearing node counts */
static double leaf_reach(const sylva_world *w, int stem) {
  return w->species[w->stems[stem].species].def.leaf_size + w->col_edge * 0.7071067811865476;
}

/* Node n's internode: from its parent's x, y (a root: its own point) to its own. */
static void internode_xy(const sylva__skeleton *s, int32_t n, double a[2], double b[2]) {
  int32_t p = s->parent[n];
  b[0] = s->x[n];
  b[1] = s->y[n];
  a[0] = p >= 0 ? s->x[p] : b[0];
  a[1] = p >= 0 ? s->y[p] : b[1];
}

/* Counts the cells within r of the segment a-b (x, y) in rows [rows[0], rows[1]) not
 * yet stamped by this stem's pass (stamp); the first stamp of the whole pass is first. */
static void cover_segment(sylva_world *w, const double a[2], const double b[2], double r,
                          const int rows[2], uint32_t stamp, uint32_t first, int64_t *area,
                          int64_t *cover) {
  const double e = w->col_edge;
  cover_reach reach = reach_of(w, a, b, r);
  int y0 = reach.lo[1] > rows[0] ? reach.lo[1] : rows[0];
  int y1 = reach.hi[1] < rows[1] - 1 ? reach.hi[1] : rows[1] - 1;
  for (int y = y0; y <= y1; y++) {
    double cy = w->def.min[1] + (y + 0.5) * e;
    size_t row = (size_t)y * (size_t)w->col_n[0];
    for (int x = reach.lo[0]; x <= reach.hi[0]; x++) {
      size_t c = row + (size_t)x;
      if (w->cols[c] == stamp) continue; /* counted already: most cells of a crown */
      if (!within(&reach, w->def.min[0] + (x + 0.5) * e, cy)) continue;
      if (w->cols[c] < first && !(w->foot[c >> 3] & (1u << (c & 7)))) (*cover)++;
      w->cols[c] = stamp;
      (*area)++;
    }
  }
}

/* The canopy pass on the world's threads: the floor's rows in CANOPY_BANDS bands, each
 * counted by one piece that passes every stem in stem order over its own rows only,
 * so its cells see the stamps one thread gives them. The counts are integers, summed
 * in band order after the loop: the same for any number of threads. */
#define CANOPY_BANDS 8

size_t sylva__canopy_room(int stems) { return ((size_t)stems + 1) * (3 + CANOPY_BANDS); }

typedef struct canopy_ctx {
  sylva_world *w;
  const int32_t *first; /* first[k] ends stem k's leaf-bearing slots in w->canopy */
  int32_t *bands;       /* the bands each of those can cover: lowest | highest << 8 */
  int32_t *stem_bands;  /* stem k's lowest and highest of those: 2 k, 2 k + 1 */
  int32_t *counts;      /* band b's: each stem's cells, then the cover, at b (stems + 1) */
  uint32_t pass;        /* the pass's first stamp: stem k's is pass + k */
} canopy_ctx;

/* The band holding row y of the floor's n rows (band b: rows n b / BANDS to n (b + 1)
 * / BANDS). */
static int32_t band_of(int y, int n) {
  return (int32_t)((CANOPY_BANDS * ((size_t)y + 1) - 1) / (size_t)n);
}

/* The bands that stems [begin, end)'s internodes can cover, as cover_segment finds
 * their rows. */
static void canopy_reach(void *arg, size_t begin, size_t end) {
  const canopy_ctx *c = arg;
  const sylva_world *w = c->w;
  for (size_t k = begin; k < end; k++) {
    double r = leaf_reach(w, (int)k);
    int32_t lo = CANOPY_BANDS, hi = -1; /* none without leaves */
    for (int32_t j = k ? c->first[k - 1] : 0; j < c->first[k]; j++) {
      double a[2], b[2];
      internode_xy(&w->nodes, w->canopy[j], a, b);
      int32_t blo = band_of(col_of(w, 1, fmin(a[1], b[1]) - r), w->col_n[1]);
      int32_t bhi = band_of(col_of(w, 1, fmax(a[1], b[1]) + r), w->col_n[1]);
      c->bands[j] = blo | bhi << 8;
      if (blo < lo) lo = blo;
      if (bhi > hi) hi = bhi;
    }
    c->stem_bands[2 * k] = lo;
    c->stem_bands[2 * k + 1] = hi;
  }
}

static void canopy_bands(void *arg, size_t begin, size_t end) {
  const canopy_ctx *c = arg;
  sylva_world *w = c->w;
  size_t stems = (size_t)w->stem_count;
  for (size_t band = begin; band < end; band++) {
    const int rows[2] = {(int)((size_t)w->col_n[1] * band / CANOPY_BANDS),
                         (int)((size_t)w->col_n[1] * (band + 1) / CANOPY_BANDS)};
    const int32_t at = (int32_t)band;
    int32_t *count = c->counts + band * (stems + 1);
    int64_t cover = 0;
    for (size_t k = 0; k < stems; k++) {
      int64_t area = 0;
      if (c->stem_bands[2 * k] <= at && c->stem_bands[2 * k + 1] >= at) {
        double r = leaf_reach(w, (int)k);
        for (int32_t j = k ? c->first[k - 1] : 0; j < c->first[k]; j++) {
          if ((c->bands[j] & 0xff) > at || c->bands[j] >> 8 < at) continue;
          double a[2], b[2];
          internode_xy(&w->nodes, w->canopy[j], a, b);
          cover_segment(w, a, b, r, rows, c->pass + (uint32_t)k, c->pass, &area, &cover);
        }
      }
      count[k] = (int32_t)area;
    }
    count[stems] = (int32_t)cover;
  }
}

void sylva__canopy(sylva_world *w) {
  const sylva__skeleton *s = &w->nodes;
  if (w->foot_dirty) canopy_foot(w);
  /* the leaf-bearing slots grouped by stem: first[k] .. first[k + 1] */
  int32_t *first = w->stem_top.data;
  SYLVA_ASSERT(w->stem_top.cap >= sylva__canopy_room(w->stem_count));
  for (int k = 0; k <= w->stem_count; k++) first[k] = 0;
  size_t leafy = 0; /* the leaf-bearing slots, in slot order, then grouped */
  for (size_t i = 0; i < s->count; i++)
    if ((s->flags[i] & SYLVA__NODE_ALIVE) && sylva__node_leaves(w, i) > 0) {
      first[s->stem[i] + 1]++;
      w->canopy[w->scratch_cap + leafy++] = (int32_t)i;
    }
  for (int k = 0; k < w->stem_count; k++) first[k + 1] += first[k];
  const int32_t *found = w->canopy + w->scratch_cap;
  for (size_t j = 0; j < leafy; j++) w->canopy[first[s->stem[found[j]]]++] = found[j];
  /* first[k] now ends stem k's slots */
  if (w->col_stamp > UINT32_MAX - (uint32_t)w->stem_count - 1) { /* stamps wrap: start over */
    memset(w->cols, 0, (size_t)w->col_n[0] * (size_t)w->col_n[1] * sizeof *w->cols);
    w->col_stamp = 0;
  }
  size_t stems = (size_t)w->stem_count;
  /* the second half of w->canopy is free once the slots are grouped */
  canopy_ctx c = {w, first, w->canopy + w->scratch_cap, first + stems + 1,
                  first + 3 * (stems + 1), w->col_stamp + 1};
  if (stems) sylva__pool_for(w->pool, stems, 1, canopy_reach, &c);
  sylva__pool_for(w->pool, CANOPY_BANDS, 1, canopy_bands, &c);
  w->col_stamp += (uint32_t)stems;
  int64_t cover = 0;
  for (size_t band = 0; band < CANOPY_BANDS; band++) cover += c.counts[band * (stems + 1) + stems];
  for (size_t k = 0; k < stems; k++) {
    int64_t area = 0;
    for (size_t band = 0; band < CANOPY_BANDS; band++) area += c.counts[band * (stems + 1) + k];
    /* a dead stem has no leaves to cover the ground; it keeps its last measures */
    if (!sylva__stem_dead(&w->stems[k]))
      w->stems[k].stats.crown_area = (double)area * w->col_edge * w->col_edge;
  }
  w->canopy_cover = w->open_cols > 0 ? (double)cover / (double)w->open_cols : 0.0;
}

double sylva_world_cell_edge(const sylva_world *w) { return w->col_edge; }

int64_t sylva_world_crown_cells(const sylva_world *w, int stem, int32_t **cells) {
  *cells = NULL;
  if (stem < 0 || stem >= w->stem_count) return SYLVA_EINVAL;
  const sylva__skeleton *s = &w->nodes;
  const double e = w->col_edge, r = leaf_reach(w, stem);
  /* the stem's leaf-bearing internodes, and the cells they can reach: one bit each */
  size_t nreach = 0, cap = 0;
  cover_reach *reach = NULL;
  int lo[2] = {INT32_MAX, INT32_MAX}, hi[2] = {-1, -1};
  for (size_t i = 0; i < s->count; i++) {
    if (s->stem[i] != stem || !(s->flags[i] & SYLVA__NODE_ALIVE) || sylva__node_leaves(w, i) <= 0)
      continue;
    if (nreach == cap) {
      cap = cap ? 2 * cap : 64;
      cover_reach *p = realloc(reach, cap * sizeof *p);
      if (!p) {
        free(reach);
        return SYLVA_ENOMEM;
      }
      reach = p;
    }
    double a[2], b[2];
    internode_xy(s, (int32_t)i, a, b);
    cover_reach *c = &reach[nreach++];
    *c = reach_of(w, a, b, r);
    for (int k = 0; k < 2; k++) {
      if (c->lo[k] < lo[k]) lo[k] = c->lo[k];
      if (c->hi[k] > hi[k]) hi[k] = c->hi[k];
    }
  }
  if (!nreach) return 0; /* no leaves */
  size_t nx = (size_t)(hi[0] - lo[0] + 1), ny = (size_t)(hi[1] - lo[1] + 1);
  uint8_t *bits = calloc((nx * ny + 7) / 8, 1);
  if (!bits) {
    free(reach);
    return SYLVA_ENOMEM;
  }
  int64_t count = 0;
  for (size_t j = 0; j < nreach; j++) {
    const cover_reach *c = &reach[j];
    for (int y = c->lo[1]; y <= c->hi[1]; y++)
      for (int x = c->lo[0]; x <= c->hi[0]; x++) {
        size_t bit = (size_t)(y - lo[1]) * nx + (size_t)(x - lo[0]);
        if (bits[bit >> 3] & (1u << (bit & 7))) continue;
        if (!within(c, w->def.min[0] + (x + 0.5) * e, w->def.min[1] + (y + 0.5) * e)) continue;
        bits[bit >> 3] |= (uint8_t)(1u << (bit & 7));
        count++;
      }
  }
  free(reach);
  int32_t *out = malloc((size_t)count * 2 * sizeof *out);
  if (!out) {
    free(bits);
    return SYLVA_ENOMEM;
  }
  size_t k = 0;
  for (size_t y = 0; y < ny; y++)
    for (size_t x = 0; x < nx; x++) {
      size_t bit = y * nx + x;
      if (!(bits[bit >> 3] & (1u << (bit & 7)))) continue;
      out[k++] = lo[0] + (int32_t)x;
      out[k++] = lo[1] + (int32_t)y;
    }
  free(bits);
  *cells = out;
  return count;
}

double sylva_world_canopy_cover(const sylva_world *w) { return w->canopy_cover; }
