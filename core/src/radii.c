/* Phase 6a: pipe-model radii, basipetal; radii never shrink; with heartwood, a node's
 * pipes also keep a share of its functional pipes each season. */
#include <math.h>
#include <string.h>

#include "world_impl.h"

/* The share of a tip's pipes in its parent's, for a species grown at rho below its
 * ref_rho (scale s > 1): the tip's shoot, counted back to the node it branched from,
 * is L nodes, L / s internodes of ref_rho; a shoot shorter than one such internode
 * carries L / s of a tip's pipes. A shoot of one fine node stands for resources that
 * at ref_rho grow no internode or one, a half on average (docs/model.md, "Species in
 * years", "Pipes at a finer rho"). At ref_rho, and without ref_rho, every tip counts
 * 1. */
static double tip_share(const sylva__skeleton *s, size_t i, double scale) {
  if (scale <= 1.0) return 1.0;
  int length = 1;
  int32_t n = (int32_t)i;
  for (int32_t p = s->parent[n]; p >= 0 && s->axis_child[p] == n && s->lateral_child[p] < 0 &&
                                 length < scale;
       n = p, p = s->parent[p])
    length++;
  return length >= scale ? 1.0 : (double)length / scale;
}

int sylva__radii(sylva_world *w, int iteration) {
  sylva__skeleton *s = &w->nodes;
  double *pipe = w->pipe, *sap = w->sap;
  memset(pipe, 0, s->count * sizeof *pipe);
  memset(sap, 0, s->count * sizeof *sap);
  int32_t cur_stem = -1;
  double v = 2.5, inv_v = 0.4, r_tip = 0.0, scale = 1.0, heartwood = 0.0;
  for (size_t i = s->count; i-- > 0;) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    if (s->stem[i] != cur_stem) {
      cur_stem = s->stem[i];
      const sylva_species_def *d = &w->species[w->stems[cur_stem].species].def;
      v = d->pipe_exponent;
      inv_v = 1.0 / v;
      r_tip = d->r_tip;
      scale = w->species[w->stems[cur_stem].species].scale;
      heartwood = d->heartwood;
    }
    bool terminal = s->axis_child[i] < 0 && s->lateral_child[i] < 0;
    double r = terminal ? r_tip : pow(pipe[i], inv_v);
    /* Heartwood h: the node's pipes r^v grow by h times its functional pipes, the
     * tips' above it; the pipes of its children still bound them from below
     * (docs/model.md, "Species in years", "Heartwood"). */
    if (heartwood > 0.0 && !terminal) {
      double kept = pow(pow((double)s->radius[i], v) + heartwood * sap[i], inv_v);
      if (kept > r) r = kept;
    }
    if (r > (double)s->radius[i]) {
      float old = s->radius[i];
      s->radius[i] = (float)r;
      if (s->radius[i] != old && s->birth[i] != iteration) {
        if (SYLVA__VEC_RESERVE(w->radii, w->radii.len + 1)) return SYLVA_ENOMEM;
        w->radii.data[w->radii.len++] = (sylva_radius_change){s->id[i], s->radius[i]};
      }
    }
    if (s->parent[i] >= 0) {
      /* a tip's pipes are functional; a cut end (a terminal wider than a tip) has none */
      bool tip = terminal && s->radius[i] <= (float)r_tip;
      double share = tip ? tip_share(s, i, scale) : 1.0;
      pipe[s->parent[i]] += pow((double)s->radius[i], v) * share;
      sap[s->parent[i]] += tip ? pow(r_tip, v) * share : terminal ? 0.0 : sap[i];
    }
  }
  /* the list was built apex to root; report it in id order */
  for (size_t a = 0, b = w->radii.len; a + 1 < b; a++, b--) {
    sylva_radius_change t = w->radii.data[a];
    w->radii.data[a] = w->radii.data[b - 1];
    w->radii.data[b - 1] = t;
  }
  return SYLVA_OK;
}
