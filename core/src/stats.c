/* Per-stem measures of MODEL.md: height, dbh, crown width and base, nodes, light. */
#include <math.h>

#include "light.h"
#include "world_impl.h"

void sylva__stats(sylva_world *w, int iteration) {
  sylva__skeleton *s = &w->nodes;
  for (int k = 0; k < w->stem_count; k++) {
    sylva__stem *st = &w->stems[k];
    sylva_stem_stats *o = &st->stats;
    o->plant = st->plant;
    o->stem = st->index;
    o->nodes = 0;
    o->height = 0.0;
    o->crown_width = 0.0;
  }
  for (int k = 0; k < w->stem_count; k++) {
    sylva__stem *st = &w->stems[k];
    st->stats.height = -INFINITY;
  }
  int32_t cur = -1;
  double minx = 0, maxx = 0, miny = 0, maxy = 0, maxz = 0;
  sylva__stem *st = NULL;
  for (size_t i = 0;; i++) {
    bool end = i >= s->count;
    if (!end && !(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    if (end || s->stem[i] != cur) {
      if (st) {
        /* a stem's nodes may interleave with others: merge into its running extents */
        sylva_stem_stats *o = &st->stats;
        if (o->height == -INFINITY) {
          st->ext[0] = minx, st->ext[1] = maxx, st->ext[2] = miny, st->ext[3] = maxy,
          st->ext[4] = maxz;
          o->height = 0.0;
        } else {
          if (minx < st->ext[0]) st->ext[0] = minx;
          if (maxx > st->ext[1]) st->ext[1] = maxx;
          if (miny < st->ext[2]) st->ext[2] = miny;
          if (maxy > st->ext[3]) st->ext[3] = maxy;
          if (maxz > st->ext[4]) st->ext[4] = maxz;
        }
      }
      if (end) break;
      cur = s->stem[i];
      st = &w->stems[cur];
      minx = maxx = s->x[i];
      miny = maxy = s->y[i];
      maxz = s->z[i];
    }
    st->stats.nodes++;
    if (s->x[i] < minx) minx = s->x[i];
    if (s->x[i] > maxx) maxx = s->x[i];
    if (s->y[i] < miny) miny = s->y[i];
    if (s->y[i] > maxy) maxy = s->y[i];
    if (s->z[i] > maxz) maxz = s->z[i];
  }
  for (int k = 0; k < w->stem_count; k++) {
    sylva__stem *t = &w->stems[k];
    sylva_stem_stats *o = &t->stats;
    const sylva__species *sp = &w->species[t->species];
    double rz = s->z[t->root_slot];
    o->height = t->ext[4] - rz;
    o->crown_width = 0.5 * ((t->ext[1] - t->ext[0]) + (t->ext[3] - t->ext[2]));
    o->dbh = NAN;
    o->crown_base = NAN;
    for (int32_t n = t->root_slot; n >= 0; n = s->axis_child[n]) {
      double h = s->z[n] - rz;
      int32_t p = s->parent[n];
      if (isnan(o->dbh) && p >= 0 && h >= 1.3 && s->z[p] - rz < 1.3) o->dbh = 2.0 * s->radius[n];
      if (isnan(o->crown_base) && s->lateral_child[n] >= 0) o->crown_base = h;
    }
    o->light = w->q[t->root_slot];
    int local = sylva__stem_local(t, iteration);
    o->cap = local >= 1 ? sylva_equation_cap(&sp->def.growth, local) : 0;
    o->finished = t->finished;
  }
}

void sylva__stats_planted(sylva_world *w, int stem) {
  const sylva__skeleton *s = &w->nodes;
  sylva__stem *st = &w->stems[stem];
  sylva__species *sp = &w->species[st->species];
  sylva_stem_stats *o = &st->stats;
  o->plant = st->plant;
  o->stem = st->index;
  o->nodes = 0;
  o->shed = 0;
  o->light = 0.0;
  o->dbh = NAN;
  o->crown_base = NAN;
  o->crown_width = 0.0;
  o->cap = 0;
  o->finished = st->finished;
  double rz = s->z[st->root_slot];
  for (int32_t n = st->root_slot; n >= 0; n = s->axis_child[n]) {
    o->nodes++;
    o->height = s->z[n] - rz;
    int32_t p = s->parent[n];
    if (isnan(o->dbh) && p >= 0 && o->height >= 1.3 && s->z[p] - rz < 1.3) o->dbh = 2.0 * s->radius[n];
    int v[3];
    sylva__node_voxel(w, n, v);
    /* as the first iteration will collect it: every node one iteration old */
    o->light += sylva__collected(sp->def.alpha, sylva__grid_light(&w->grid, v),
                                 sylva__species_age_pow(sp, 1));
  }
}
