#include "light.h"

#include <math.h>

#include "world_impl.h"

typedef struct collect_ctx {
  sylva_world *w;
  int iteration;
  double *light;
} collect_ctx;

/* The age whose light live node i collects at iteration T, -1 when it bears no
 * leaves; *sp is its species, looked up again only when the stem changes from
 * *stem. The one test of which nodes read the grid, for the pass and for the
 * reservation before it. */
static int lit_age(const sylva_world *w, size_t i, int T, int32_t *stem,
                   const sylva__species **sp) {
  const sylva__skeleton *s = &w->nodes;
  if (s->stem[i] != *stem) {
    *stem = s->stem[i];
    *sp = &w->species[w->stems[*stem].species];
  }
  return sylva__leaf_age(s, &(*sp)->def, i, T);
}

/* The light each node in [begin, end) collects: reads the grid (each lit node's own
 * voxel) and the species' cached powers, writes only its own nodes' q and light. */
static void collect_range(void *arg, size_t begin, size_t end) {
  const collect_ctx *c = arg;
  sylva_world *w = c->w;
  int32_t cur_stem = -1;
  const sylva__species *sp = NULL;
  for (size_t i = begin; i < end; i++) {
    if (!(w->nodes.flags[i] & SYLVA__NODE_ALIVE)) continue;
    int age = lit_age(w, i, c->iteration, &cur_stem, &sp);
    double L = 0.0;
    if (age >= 0) {
      int v[3];
      sylva__node_voxel(w, (int32_t)i, v);
      double l = sylva__grid_light_shared(&w->grid, v);
      /* the cache holds age^sigma for every age a leaf has (warmed below) */
      double p = age == 0 ? 0.0
                 : age < sp->age_pow_n ? sp->age_pow[age]
                                       : pow((double)age, sp->def.sigma);
      L = sylva__collected(sp->def.alpha, l, p);
    }
    w->q[i] = L;
    if (c->light) c->light[i] = L;
  }
}

void sylva__light_collect(sylva_world *w, int iteration, double *light) {
  sylva__skeleton *s = &w->nodes;
  /* What the threads only read: every species' powers of a leaf's ages, and the
   * site factors' cache of the chunk of every voxel the pass reads, the lit nodes'
   * own (lit_age, as collect_range tests them): the wood's chunks get none. A
   * chunk left without one (no memory) reads the same factors, computed each time. */
  for (int k = 0; k < w->species_count; k++) {
    const sylva_species_def *d = &w->species[k].def;
    sylva__species_age_pow(&w->species[k], d->leaf_age > 1 ? d->leaf_age : 1);
  }
  if (w->grid.sky_count) {
    int32_t stem = -1;
    const sylva__species *sp = NULL;
    for (size_t i = 0; i < s->count; i++) {
      if (!(s->flags[i] & SYLVA__NODE_ALIVE) || lit_age(w, i, iteration, &stem, &sp) < 0) continue;
      int v[3];
      sylva__node_voxel(w, (int32_t)i, v);
      sylva__grid_site_reserve(&w->grid, v);
    }
  }
  collect_ctx c = {w, iteration, light};
  sylva__pool_for(w->pool, s->count, 4096, collect_range, &c);
  /* Children sit in higher slots than their parents: one reverse sweep adds each
   * finished subtree total into its parent. */
  for (size_t i = s->count; i-- > 0;)
    if ((s->flags[i] & SYLVA__NODE_ALIVE) && s->parent[i] >= 0) w->q[s->parent[i]] += w->q[i];
}
