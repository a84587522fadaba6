#include "light.h"

#include <math.h>

#include "world_impl.h"

void sylva__light_collect(sylva_world *w, int iteration, double *light) {
  sylva__skeleton *s = &w->nodes;
  int32_t cur_stem = -1;
  sylva__species *sp = NULL;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    if (s->stem[i] != cur_stem) {
      cur_stem = s->stem[i];
      sp = &w->species[w->stems[cur_stem].species];
    }
    int age = sylva__leaf_age(s, &sp->def, i, iteration);
    double L = 0.0;
    if (age >= 0) {
      int v[3];
      sylva__node_voxel(w, (int32_t)i, v);
      double l = sylva__grid_light(&w->grid, v);
      L = sylva__collected(sp->def.alpha, l, age > 0 ? sylva__species_age_pow(sp, age) : 0.0);
    }
    w->q[i] = L;
    if (light) light[i] = L;
  }
  /* Children sit in higher slots than their parents: one reverse sweep adds each
   * finished subtree total into its parent. */
  for (size_t i = s->count; i-- > 0;)
    if ((s->flags[i] & SYLVA__NODE_ALIVE) && s->parent[i] >= 0) w->q[s->parent[i]] += w->q[i];
}
