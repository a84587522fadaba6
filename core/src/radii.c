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

typedef struct radii_ctx {
  sylva_world *w;
  int iteration;
} radii_ctx;

/* Stems [begin, end): each stem's nodes apex to root (its slots downwards, as its
 * children sit above their parents), writing only that stem's radii and pipes; a
 * radius reported this iteration is marked SYLVA__NODE_THICKER. */
static void radii_stems(void *arg, size_t begin, size_t end) {
  const radii_ctx *c = arg;
  sylva_world *w = c->w;
  sylva__skeleton *s = &w->nodes;
  double *pipe = w->pipe, *sap = w->sap;
  const int32_t *first = w->stem_nodes_first.data, *nodes = w->stem_nodes.data;
  for (size_t k = begin; k < end; k++) {
    const sylva__species *sp = &w->species[w->stems[k].species];
    const sylva_species_def *d = &sp->def;
    double v = d->pipe_exponent, inv_v = 1.0 / v, r_tip = d->r_tip, scale = sp->scale,
           heartwood = d->heartwood;
    /* the pipes of a tip, asked of pow once a stem: the same values */
    const float r_tip_f = (float)r_tip;
    const double tip_pipes = pow(r_tip, v), tip_radius_pipes = pow((double)r_tip_f, v);
    for (int32_t at = first[k + 1]; at-- > first[k];) {
      int32_t i = nodes[at];
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
        if (s->radius[i] != old && s->birth[i] != c->iteration) s->flags[i] |= SYLVA__NODE_THICKER;
      }
      if (s->parent[i] >= 0) {
        /* a tip's pipes are functional; a cut end (a terminal wider than a tip) has none */
        bool tip = terminal && s->radius[i] <= (float)r_tip;
        double share = tip ? tip_share(s, (size_t)i, scale) : 1.0;
        double pipes = s->radius[i] == r_tip_f ? tip_radius_pipes : pow((double)s->radius[i], v);
        pipe[s->parent[i]] += pipes * share;
        sap[s->parent[i]] += tip ? tip_pipes * share : terminal ? 0.0 : sap[i];
      }
    }
  }
}

int sylva__radii(sylva_world *w, int iteration) {
  sylva__skeleton *s = &w->nodes;
  memset(w->pipe, 0, s->count * sizeof *w->pipe);
  memset(w->sap, 0, s->count * sizeof *w->sap);
  /* Stems share no node: each grows its radii on its own, on the world's threads.
   * The grouping's room is the per-slot scratch's (sylva__reserve_scratch), made
   * before the step could no longer fail. */
  SYLVA_ASSERT(w->stem_nodes.cap >= s->count &&
               w->stem_nodes_first.cap >= (size_t)w->stem_count + 1);
  sylva__group_by_stem(w);
  radii_ctx c = {w, iteration};
  sylva__pool_for(w->pool, (size_t)w->stem_count, 1, radii_stems, &c);
  /* the radii that changed, in id order (slot order) */
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_THICKER)) continue;
    s->flags[i] &= (uint8_t)~SYLVA__NODE_THICKER;
    if (SYLVA__VEC_RESERVE(w->radii, w->radii.len + 1)) return SYLVA_ENOMEM;
    w->radii.data[w->radii.len++] = (sylva_radius_change){s->id[i], s->radius[i]};
  }
  return SYLVA_OK;
}
