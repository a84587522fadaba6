/* Per-stem measures of docs/model.md: height, dbh, crown width and base, nodes, light. */
#include <math.h>

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
  o->finished = st->finished;
  st->ext[0] = st->ext[2] = INFINITY;
  st->ext[1] = st->ext[3] = st->ext[4] = -INFINITY;
}

/* Height, crown width, dbh (trunk internode crossing 1.3 m) and crown base (lowest
 * trunk node carrying a live lateral) from the extents and a walk up the trunk. */
static void stats_shape(const sylva_world *w, sylva__stem *st) {
  const sylva__skeleton *s = &w->nodes;
  sylva_stem_stats *o = &st->stats;
  double rz = s->z[st->root_slot];
  o->height = st->ext[4] - rz;
  o->crown_width = 0.5 * ((st->ext[1] - st->ext[0]) + (st->ext[3] - st->ext[2]));
  o->dbh = NAN;
  o->crown_base = NAN;
  for (int32_t n = st->root_slot; n >= 0; n = s->axis_child[n]) {
    double h = s->z[n] - rz;
    int32_t p = s->parent[n];
    if (isnan(o->dbh) && p >= 0 && h >= 1.3 && s->z[p] - rz < 1.3) o->dbh = 2.0 * s->radius[n];
    if (isnan(o->crown_base) && s->lateral_child[n] >= 0) o->crown_base = h;
  }
  o->crown_height = o->height - o->crown_base; /* NaN with the crown base */
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

void sylva__stats(sylva_world *w, int iteration) {
  const sylva__skeleton *s = &w->nodes;
  for (int k = 0; k < w->stem_count; k++) stats_reset(&w->stems[k]);
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    sylva__stem *st = &w->stems[s->stem[i]];
    st->stats.nodes++;
    extend(st, s, i);
  }
  for (int k = 0; k < w->stem_count; k++) {
    sylva__stem *st = &w->stems[k];
    stats_shape(w, st);
    st->stats.age = stem_age(w, st, iteration);
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
  for (size_t n = (size_t)st->root_slot; n < s->count; n++) {
    if (s->stem[n] != stem || !(s->flags[n] & SYLVA__NODE_ALIVE)) continue;
    st->stats.nodes++;
    extend(st, s, n);
    int age = sylva__leaf_age(s, &sp->def, n, next);
    if (age < 0) continue;
    int v[3];
    sylva__node_voxel(w, (int32_t)n, v);
    /* as the next iteration will collect it: every node one iteration older */
    st->stats.light += sylva__collected(sp->def.alpha, sylva__grid_light(&w->grid, v),
                                        sylva__species_age_pow(sp, age));
  }
  stats_shape(w, st);
  st->stats.age = stem_age(w, st, w->iteration);
}
