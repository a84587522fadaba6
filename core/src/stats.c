/* Per-stem measures of docs/model.md: height, dbh, crown width and base, nodes, light. */
#include <math.h>
#include <stdint.h>

#include "light.h"
#include "world_impl.h"

/* Starts a stem's measures: counters zero, extents empty. */
static void stats_reset(sylva__stem *st) {
  sylva_stem_stats *o = &st->stats;
  o->plant = st->plant;
  o->stem = st->index;
  o->nodes = 0;
  o->age = -1;
  o->crown_height = NAN;
  o->leaf_area = 0.0;
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

/* Is node i of a stem of species d leaf-bearing as the next season carries it (as
 * shedding judges it)? */
static bool leafy(const sylva__skeleton *s, const sylva_species_def *d, size_t i, int iteration) {
  return sylva__leaf_age(s, d, i, iteration + 1) >= 0;
}

void sylva__stats(sylva_world *w, int iteration) {
  const sylva__skeleton *s = &w->nodes;
  /* first[k]: where stem k's leaf heights start in the scratch w->pipe */
  int32_t *first = w->stem_top.data;
  for (int k = 0; k <= w->stem_count; k++) first[k] = 0;
  for (int k = 0; k < w->stem_count; k++) stats_reset(&w->stems[k]);
  const sylva_species_def *d = NULL;
  for (size_t i = 0, stem = SIZE_MAX; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    sylva__stem *st = &w->stems[s->stem[i]];
    if ((size_t)s->stem[i] != stem) { /* looked up again only when the stem changes */
      stem = (size_t)s->stem[i];
      d = &w->species[st->species].def;
    }
    st->stats.nodes++;
    extend(st, s, i);
    if (leafy(s, d, i, iteration)) first[s->stem[i] + 1]++;
  }
  for (int k = 0; k < w->stem_count; k++) first[k + 1] += first[k];
  double *z = w->pipe;
  for (size_t i = 0, stem = SIZE_MAX; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    if ((size_t)s->stem[i] != stem) {
      stem = (size_t)s->stem[i];
      d = &w->species[w->stems[stem].species].def;
    }
    if (leafy(s, d, i, iteration)) z[first[s->stem[i]]++] = s->z[i];
  }
  /* each first[k] now ends stem k's heights: they start at first[k - 1] */
  for (int k = 0; k < w->stem_count; k++) {
    sylva__stem *st = &w->stems[k];
    stats_shape(w, st);
    size_t from = k ? (size_t)first[k - 1] : 0, to = (size_t)first[k];
    set_crown_base(st, crown_base_of(z + from, to - from, s->z[st->root_slot], st->ext[4],
                                     w->crown_bins.data));
    st->stats.age = stem_age(w, st, iteration);
    st->stats.leaf_area = (double)(to - from) * sylva__node_leaf_area(&w->species[st->species].def);
    st->stats.light = w->q[st->root_slot];
    int local = sylva__stem_local(st, iteration);
    st->stats.cap = local >= 1 ? sylva__species_cap(&w->species[st->species], local) : 0;
  }
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
    st->stats.nodes++;
    extend(st, s, n);
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
}

void sylva__stats_leaf_area(sylva_world *w) {
  const sylva__skeleton *s = &w->nodes;
  /* counted first, then multiplied, as sylva__stats does: the same bits */
  for (int k = 0; k < w->stem_count; k++) w->stems[k].stats.leaf_area = 0.0;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    sylva__stem *st = &w->stems[s->stem[i]];
    if (leafy(s, &w->species[st->species].def, i, w->iteration)) st->stats.leaf_area += 1.0;
    /* the leaves as the last journal gave them: the next one lists what changes */
    w->nodes.leaves[i] = (uint16_t)sylva__node_leaves(w, i);
  }
  for (int k = 0; k < w->stem_count; k++)
    w->stems[k].stats.leaf_area *= sylva__node_leaf_area(&w->species[w->stems[k].species].def);
}
