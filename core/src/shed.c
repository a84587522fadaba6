/* Phase 6b: shedding of lateral branches whose mean relative light E = Q / (alpha N)
 * is below r_s (after Takenaka 1994). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "world_impl.h"

int sylva__reserve_removal(sylva_world *w) {
  int half = 0;
  for (int k = 0; k < w->species_count; k++) {
    int h = sylva__species_shade_reach(&w->species[k]);
    if (h > half) half = h;
  }
  size_t n = w->nodes.live;
  const sylva__grid *g = &w->grid;
  size_t chunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
  if (SYLVA__VEC_RESERVE(w->cells, n) || SYLVA__VEC_RESERVE(w->cell_start, chunks + 1) ||
      SYLVA__VEC_RESERVE(w->stamps, n) ||
      SYLVA__VEC_RESERVE(w->stamp_lists, sylva__grid_stamp_scratch_max(&w->grid, w->pool, n, half)))
    return SYLVA_ENOMEM;
  return SYLVA_OK;
}

void sylva__remove_doomed(sylva_world *w, bool pruned) {
  sylva__skeleton *s = &w->nodes;
  /* Shade sums are exact integers, so the removals may run in any order and on any
   * number of threads: take them chunk by chunk (z, y, x of 16-voxel chunks) so that
   * neighbouring pyramids share the cache. Each node's pyramid is in its species'
   * table already, as it cast its shade through it. */
  const sylva__grid *g = &w->grid;
  size_t chunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
  SYLVA_ASSERT(w->cell_start.cap > chunks);
  /* A counting sort by chunk, stable (slots ascending within a chunk): start[c] counts
   * chunk c's doomed nodes, then (summed) marks where they go. */
  int32_t *start = w->cell_start.data;
  memset(start, 0, (chunks + 1) * sizeof *start);
  size_t doomed = 0;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_DOOMED)) continue;
    int v[3];
    sylva__node_voxel(w, (int32_t)i, v);
    start[sylva__grid_chunk_of(g, v) + 1]++;
    doomed++;
  }
  SYLVA_ASSERT(doomed <= w->cells.cap);
  for (size_t c = 1; c <= chunks; c++) start[c] += start[c - 1];
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_DOOMED)) continue;
    int v[3];
    sylva__node_voxel(w, (int32_t)i, v);
    w->cells.data[start[sylva__grid_chunk_of(g, v)]++] = (int32_t)i;
  }
  w->cells.len = doomed;
  w->stamps.len = 0;
  for (size_t k = 0; k < w->cells.len; k++) {
    int32_t i = w->cells.data[k];
    const sylva__stem *st = &w->stems[s->stem[i]];
    sylva__stamp *it = &w->stamps.data[w->stamps.len++];
    sylva__node_voxel(w, i, it->v);
    it->p = sylva__species_shade_at(&w->species[st->species], s->birth[i] - st->born);
  }
  SYLVA_ASSERT(sylva__grid_stamp_scratch(&w->grid, w->pool, w->stamps.data, w->stamps.len) <=
               w->stamp_lists.cap);
  sylva__grid_stamp_many(&w->grid, w->pool, w->stamps.data, w->stamps.len, -1, w->stamp_lists.data);
  /* then their voxels, slots and counts */
  for (size_t k = 0; k < w->cells.len; k++) {
    int32_t i = w->cells.data[k];
    int v[3];
    sylva__node_voxel(w, i, v);
    sylva__grid_vacate(&w->grid, v);
    s->flags[i] = 0;
    s->live--;
    if (pruned)
      w->stems[s->stem[i]].stats.pruned++;
    else
      w->stems[s->stem[i]].stats.shed++;
  }
}

/* Dooms the branch that starts at node i, born before or at `iteration`: a lateral
 * leaves a scar on its bearing node, an axis's continuation leaves that node its
 * axis's apex. Returns 0 or SYLVA_ENOMEM (nothing doomed). */
static int doom_branch(sylva_world *w, size_t i, int iteration) {
  sylva__skeleton *s = &w->nodes;
  /* a branch born this iteration was never announced as added: it is not reported
   * as shed either */
  if (s->birth[i] != iteration) {
    if (SYLVA__VEC_RESERVE(w->shed, w->shed.len + 1)) return SYLVA_ENOMEM;
    w->shed.data[w->shed.len++] = s->id[i];
  }
  s->flags[i] |= SYLVA__NODE_DOOMED;
  int32_t p = s->parent[i];
  if (s->flags[i] & SYLVA__NODE_LATERAL) {
    s->lateral_child[p] = -1;
    s->flags[p] |= SYLVA__NODE_SCAR;
  } else {
    s->axis_child[p] = -1;
  }
  return SYLVA_OK;
}

/* Lifts the crowns of the species with `lift`: along the stem's main path, from the
 * root to its highest node, a branch that leaves the path below lift times the
 * stem's height is doomed unless it reaches the top tenth of the height (a
 * codominant stem is no low branch), so the leader is never cut whichever axis
 * carries it. One pass finds every stem's highest node, one backward pass every
 * subtree's reach. Uses w->pipe and the second half of light's block (the first
 * holds the leaf counts, world_impl.h) as scratch. Returns the number doomed,
 * or SYLVA_ENOMEM. */
static int64_t lift_crowns(sylva_world *w, int iteration) {
  sylva__skeleton *s = &w->nodes;
  bool any = false;
  for (int k = 0; k < w->stem_count && !any; k++)
    any = w->species[w->stems[k].species].def.lift > 0.0;
  if (!any) return 0;
  if (SYLVA__VEC_RESERVE(w->stem_top, (size_t)w->stem_count)) return SYLVA_ENOMEM;
  int32_t *top = w->stem_top.data;
  for (int k = 0; k < w->stem_count; k++) top[k] = w->stems[k].root_slot;
  double *reach = w->pipe; /* the highest z of each node's subtree */
  for (size_t i = 0; i < s->count; i++) {
    reach[i] = s->z[i];
    int32_t k = s->stem[i];
    if ((s->flags[i] & SYLVA__NODE_ALIVE) && (top[k] < 0 || s->z[i] > s->z[top[k]])) top[k] = (int32_t)i;
  }
  for (size_t i = s->count; i-- > 0;)
    if ((s->flags[i] & SYLVA__NODE_ALIVE) && s->parent[i] >= 0 && reach[i] > reach[s->parent[i]])
      reach[s->parent[i]] = reach[i];
  int64_t doomed = 0;
  int32_t *next = w->leaves + w->scratch_cap; /* on the main path: the path's next node */
  for (int k = 0; k < w->stem_count; k++) {
    double lift = w->species[w->stems[k].species].def.lift;
    int32_t root = w->stems[k].root_slot, tk = top[k];
    if (!(lift > 0.0) || root < 0 || sylva__stem_dead(&w->stems[k])) continue;
    next[tk] = -1;
    for (int32_t n = tk; n != root; n = s->parent[n]) next[s->parent[n]] = n;
    double below = s->z[root] + lift * (s->z[tk] - s->z[root]);
    /* a branch that reaches the top tenth of the stem's height competes for the lead */
    double codominant = s->z[root] + 0.9 * (s->z[tk] - s->z[root]);
    for (int32_t n = root; n != tk && s->z[n] < below; n = next[n]) {
      int32_t off = s->axis_child[n] == next[n] ? s->lateral_child[n] : s->axis_child[n];
      if (off < 0 || (s->flags[off] & SYLVA__NODE_DOOMED) || reach[off] >= codominant) continue;
      if (doom_branch(w, (size_t)off, iteration)) return SYLVA_ENOMEM;
      doomed++;
    }
  }
  return doomed;
}

/* A uniform draw in [0, 1) for stem k's background death at `iteration`, from the
 * world's seed, the plant's label and the stem alone (docs/model.md, "Stands"): the
 * same whatever the order of the stems, and the same in a resumed run. */
static double death_draw(const sylva_world *w, int k, int iteration) {
  const sylva__stem *st = &w->stems[k];
  uint64_t h = 0xcbf29ce484222325ULL;
  for (const char *c = w->plants[st->plant].label; *c; c++)
    h = (h ^ (unsigned char)*c) * 0x100000001b3ULL;
  sylva__rng r;
  sylva__rng_seed(&r, w->def.seed ^ h ^ ((uint64_t)(uint32_t)st->index << 32) ^
                          ((uint64_t)(uint32_t)iteration * 0x9e3779b97f4a7c15ULL));
  return sylva__rng_unit(&r);
}

/* Whole stems (docs/model.md, "Stands"), judged on their vigour (the mean light E of
 * their leaves, in stats.vigour) and the background rate: a stem that dies loses its
 * leaves at once, and with them its leaf-bearing twigs (n[i] > 0 for a node that bears
 * leaves next season), which are doomed with their shade; its other nodes go bare. A
 * dead stem whose snag has stood snag_years falls: every node, its root too. Returns
 * the nodes doomed, or SYLVA_ENOMEM. */
static int64_t stem_deaths(sylva_world *w, int iteration, const int32_t *n) {
  sylva__skeleton *s = &w->nodes;
  int64_t doomed = 0;
  bool any = false;
  for (int k = 0; k < w->stem_count; k++) {
    sylva__stem *st = &w->stems[k];
    const sylva_species_def *d = &w->species[st->species].def;
    if (sylva__stem_dead(st)) {
      if (st->stats.fallen < 0 && iteration - st->stats.died >= d->snag_years) any = true;
      continue;
    }
    bool dies = false;
    if (d->mortality_light > 0.0) {
      st->low = st->stats.vigour < d->mortality_light ? st->low + 1 : 0;
      dies = st->low >= d->mortality_years;
    }
    if (!dies && d->mortality > 0.0) dies = death_draw(w, k, iteration) < d->mortality;
    if (!dies) continue;
    st->stats.alive = false;
    st->stats.died = iteration;
    st->stats.light = 0.0;
    any = true;
  }
  if (!any) return 0;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    sylva__stem *st = &w->stems[s->stem[i]];
    if (!sylva__stem_dead(st) || st->stats.fallen >= 0) continue;
    const sylva_species_def *d = &w->species[st->species].def;
    int32_t p = s->parent[i];
    bool falls = iteration - st->stats.died >= d->snag_years;
    if (p >= 0 && (s->flags[p] & SYLVA__NODE_DOOMED)) {
      s->flags[i] |= SYLVA__NODE_DOOMED;
      doomed++;
    } else if (falls && p < 0) { /* the root: the whole stem goes */
      if (s->birth[i] != iteration) {
        if (SYLVA__VEC_RESERVE(w->shed, w->shed.len + 1)) return SYLVA_ENOMEM;
        w->shed.data[w->shed.len++] = s->id[i];
      }
      s->flags[i] |= SYLVA__NODE_DOOMED;
      doomed++;
    } else if (p >= 0 && st->stats.died == iteration && n[i] > 0 &&
               sylva__leaf_age(s, d, i, iteration + 1) >= 0) {
      /* a twig that bore leaves the season it died (n[i] > 0: its subtree has
       * leaves, so it is not yet bare) */
      if (doom_branch(w, i, iteration)) return SYLVA_ENOMEM;
      doomed++;
      continue;
    }
    if (!(s->flags[i] & SYLVA__NODE_DOOMED)) s->flags[i] |= SYLVA__NODE_BARE;
  }
  for (int k = 0; k < w->stem_count; k++) {
    sylva__stem *st = &w->stems[k];
    if (!sylva__stem_dead(st) || st->stats.fallen >= 0 ||
        iteration - st->stats.died < w->species[st->species].def.snag_years)
      continue;
    st->stats.fallen = iteration;
    st->root_slot = -1; /* removed with the other doomed nodes below */
  }
  return doomed;
}

int sylva__shed(sylva_world *w, int iteration) {
  sylva__skeleton *s = &w->nodes;
  for (int k = 0; k < w->stem_count; k++) w->stems[k].stats.shed = 0; /* counted anew at T */
  /* E is judged on the light the nodes will collect next iteration (every node at
   * least one iteration old): a newborn node's l^0 = 1 would otherwise count full
   * light in any shade and hold up dark branches only while they still grow. */
  sylva__light_collect(w, iteration + 1, NULL);
  int32_t *n = w->leaves;
  const sylva_species_def *d = NULL;
  for (size_t i = 0, stem = SIZE_MAX; i < s->count; i++) {
    if ((size_t)s->stem[i] != stem) { /* looked up again only when the stem changes */
      stem = (size_t)s->stem[i];
      d = &w->species[w->stems[stem].species].def;
    }
    n[i] = sylva__leaf_age(s, d, i, iteration + 1) >= 0 ? 1 : 0;
  }
  for (size_t i = s->count; i-- > 0;)
    if ((s->flags[i] & SYLVA__NODE_ALIVE) && s->parent[i] >= 0) n[s->parent[i]] += n[i];
  /* A branch is shed below r_s, or (acclimation a) below r_s times the stem's own
   * mean light E to the power a: a stem in shade keeps the branches that are as
   * lit as the rest of its crown (docs/model.md, "Shedding"). */
  for (int k = 0; k < w->stem_count; k++) {
    sylva__stem *st = &w->stems[k];
    const sylva_species_def *sd = &w->species[st->species].def;
    st->shed_below = sd->r_s;
    int32_t root = st->root_slot;
    if (sylva__stem_dead(st) || root < 0) continue;
    double mean = n[root] > 0 ? w->q[root] / (sd->alpha * (double)n[root]) : 0.0;
    st->stats.vigour = mean; /* the stem's vigour (docs/model.md, "Stands") */
    if (sd->acclimation > 0.0 && mean < 1.0) st->shed_below = sd->r_s * pow(mean, sd->acclimation);
  }
  int64_t died = stem_deaths(w, iteration, n);
  if (died < 0) return (int)died;
  int64_t lifted = lift_crowns(w, iteration);
  if (lifted < 0) return (int)lifted;
  size_t doomed = (size_t)lifted + (size_t)died;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE) || (s->flags[i] & SYLVA__NODE_DOOMED)) continue;
    int32_t p = s->parent[i];
    if (p >= 0 && (s->flags[p] & SYLVA__NODE_DOOMED)) {
      s->flags[i] |= SYLVA__NODE_DOOMED;
      doomed++;
    } else if ((s->flags[i] & SYLVA__NODE_LATERAL) && !sylva__stem_dead(&w->stems[s->stem[i]])) {
      const sylva_species_def *d = &w->species[w->stems[s->stem[i]].species].def;
      /* mean relative light per leaf-bearing node; a branch without leaves is dead */
      double e = n[i] > 0 ? w->q[i] / (d->alpha * (double)n[i]) : 0.0;
      if (e < w->stems[s->stem[i]].shed_below || (n[i] == 0 && d->acclimation > 0.0)) {
        int rc = doom_branch(w, i, iteration);
        if (rc) return rc;
        doomed++;
      }
    }
  }
  if (!doomed) {
    sylva__stems_light(w, w->q);
    return SYLVA_OK;
  }
  sylva__remove_doomed(w, false);
  /* the removed subtrees no longer send light to their parents: the pass of the next
   * iteration, which its light phase takes as it is (docs/performance.md, "The light
   * kept") */
  sylva__light_keep(w, iteration + 1);
  return SYLVA_OK;
}
