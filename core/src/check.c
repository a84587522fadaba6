/* Debug builds: the invariants of a world at the boundaries of a step's phases
 * (world_impl.h, sylva__check_world). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "world_impl.h"

_Noreturn void sylva__assert_fail(const char *expr, const char *file, int line, const char *func) {
  fprintf(stderr, "sylva: %s:%d: %s: assertion failed: %s\n", file, line, func, expr);
  abort();
}

#ifdef NDEBUG
/* Not called: SYLVA__CHECK_WORLD compiles to nothing. */
void sylva__check_world(const sylva_world *w, sylva__boundary at) {
  (void)w;
  (void)at;
}
#else
/* One live node: its stem, birth, radius and voxel, and its links both ways. */
static void check_node(const sylva_world *w, size_t i) {
  const sylva__skeleton *s = &w->nodes;
  int32_t slot = (int32_t)i, parent = s->parent[i];
  SYLVA_ASSERT(s->stem[i] >= 0 && s->stem[i] < w->stem_count);
  const sylva__stem *st = &w->stems[s->stem[i]];
  SYLVA_ASSERT(s->birth[i] >= st->born && s->birth[i] <= w->iteration);
  SYLVA_ASSERT(s->radius[i] > 0.0f && isfinite(s->radius[i]));
  int v[3];
  SYLVA_ASSERT(sylva__grid_voxel(&w->grid, s->x[i], s->y[i], s->z[i], v));
  SYLVA_ASSERT(sylva__grid_occupant(&w->grid, v) == s->stem[i]);
  /* a dead stem's nodes are bare, and only theirs */
  SYLVA_ASSERT(((s->flags[i] & SYLVA__NODE_BARE) != 0) == (st->stats.died >= 0));
  if (parent < 0) {
    SYLVA_ASSERT(st->root_slot == slot && s->depth[i] == 0 && !(s->flags[i] & SYLVA__NODE_LATERAL));
  } else {
    /* slots are in birth order: a parent's slot is below its child's */
    SYLVA_ASSERT(parent < slot && (s->flags[parent] & SYLVA__NODE_ALIVE));
    SYLVA_ASSERT(s->stem[parent] == s->stem[i] && s->depth[i] == s->depth[parent] + 1);
    SYLVA_ASSERT(((s->flags[i] & SYLVA__NODE_LATERAL) ? s->lateral_child[parent]
                                                      : s->axis_child[parent]) == slot);
  }
  int32_t axis = s->axis_child[i], lateral = s->lateral_child[i];
  SYLVA_ASSERT(axis < 0 ||
               (axis > slot && (size_t)axis < s->count && s->parent[axis] == slot &&
                (s->flags[axis] & SYLVA__NODE_ALIVE) && !(s->flags[axis] & SYLVA__NODE_LATERAL)));
  SYLVA_ASSERT(lateral < 0 ||
               (lateral > slot && (size_t)lateral < s->count && s->parent[lateral] == slot &&
                (s->flags[lateral] & SYLVA__NODE_ALIVE) &&
                (s->flags[lateral] & SYLVA__NODE_LATERAL)));
}

static void check_skeleton(const sylva_world *w, sylva__boundary at) {
  const sylva__skeleton *s = &w->nodes;
  SYLVA_ASSERT(s->count <= s->cap && s->live <= s->count);
  size_t live = 0;
  for (size_t i = 0; i < s->count; i++) {
    SYLVA_ASSERT(s->id[i] < s->next_id && (i == 0 || s->id[i] > s->id[i - 1]));
    /* no transient bit (DOOMED) outlives its phase; a dead slot is all clear */
    SYLVA_ASSERT((s->flags[i] & ~SYLVA__NODE_STATE) == 0);
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) {
      SYLVA_ASSERT(s->flags[i] == 0);
      continue;
    }
    live++;
    check_node(w, i);
  }
  SYLVA_ASSERT(live == s->live);
  /* compaction keeps the skeleton dense between steps, and only shedding kills */
  if (at != SYLVA__AFTER_SHEDDING) SYLVA_ASSERT(s->count == s->live);
}

static void check_stems(const sylva_world *w) {
  int first = 0;
  for (int p = 0; p < w->plant_count; p++) {
    const sylva__plant *pl = &w->plants[p];
    SYLVA_ASSERT(pl->first_stem == first && pl->stem_count >= 1);
    SYLVA_ASSERT(pl->species >= 0 && pl->species < w->species_count);
    SYLVA_ASSERT(sylva__find_plant(w, pl->label) == p);
    for (int k = 0; k < pl->stem_count; k++) {
      const sylva__stem *st = &w->stems[first + k];
      SYLVA_ASSERT(st->plant == p && st->index == k && st->species == pl->species);
      /* a stem grown in the nursery was planted before the world's first iteration */
      SYLVA_ASSERT(st->born <= w->iteration &&
                   (st->born >= 0 || (w->species[st->species].def.years &&
                                      st->born >= w->iteration - SYLVA_MAX_AGE - 200)));
      /* a stem has its root until its snag falls; a dead stem's nodes are bare */
      SYLVA_ASSERT((st->root_slot < 0) == (st->stats.fallen >= 0));
      SYLVA_ASSERT(st->stats.alive == (st->stats.died < 0) && st->stats.fallen <= w->iteration &&
                   (st->stats.fallen < 0 || st->stats.fallen >= st->stats.died));
      if (st->root_slot < 0) continue;
      SYLVA_ASSERT((size_t)st->root_slot < w->nodes.count);
      SYLVA_ASSERT(w->nodes.stem[st->root_slot] == first + k);
    }
    first += pl->stem_count;
  }
  SYLVA_ASSERT(first == w->stem_count);
}

/* The sprouts of allocation: live nodes, grouped by stem in stem_first's ranges,
 * each within its stem's cap. */
static void check_sprouts(const sylva_world *w) {
  const sylva__skeleton *s = &w->nodes;
  SYLVA_ASSERT(w->stem_first.cap >= (size_t)w->stem_count + 1 &&
               w->caps.cap >= 2 * (size_t)w->stem_count);
  SYLVA_ASSERT(w->stem_first.data[0] == 0);
  SYLVA_ASSERT((size_t)w->stem_first.data[w->stem_count] == w->sprouts.len);
  /* a stem that stops at this step grows nothing, and is marked finished only once
   * the step cannot fail */
  for (size_t f = 0; f < w->finishing.len; f++)
    SYLVA_ASSERT(w->caps.data[w->finishing.data[f]] == 0 &&
                 !w->stems[w->finishing.data[f]].finished);
  for (int k = 0; k < w->stem_count; k++) {
    SYLVA_ASSERT(w->stem_first.data[k] <= w->stem_first.data[k + 1]);
    for (int32_t i = w->stem_first.data[k]; i < w->stem_first.data[k + 1]; i++) {
      const sylva__sprout *sp = &w->sprouts.data[i];
      SYLVA_ASSERT(sp->stem == k && sp->slot >= 0 && (size_t)sp->slot < s->count);
      SYLVA_ASSERT((s->flags[sp->slot] & SYLVA__NODE_ALIVE) && s->stem[sp->slot] == k);
      int32_t cap = w->caps.data[k], lateral = w->caps.data[w->stem_count + k];
      SYLVA_ASSERT(sp->n >= 1 && sp->n <= (cap > lateral ? cap : lateral) &&
                   !w->stems[k].finished);
      SYLVA_ASSERT(sp->apex == (s->axis_child[sp->slot] < 0));
    }
  }
}

void sylva__check_world(const sylva_world *w, sylva__boundary at) {
  SYLVA_ASSERT(w->status == 0 && w->iteration >= 0);
  SYLVA_ASSERT(w->species_count <= w->species_cap && w->plant_count <= w->plant_cap &&
               w->stem_count <= w->stem_cap);
  check_stems(w);
  check_skeleton(w, at);
  if (at == SYLVA__BETWEEN_STEPS) return;
  /* inside a step: the per-slot scratch (the grouping by stem too) covers the
   * skeleton, and the step's mark lies below what it has grown */
  SYLVA_ASSERT(w->scratch_cap >= w->nodes.cap && w->stem_nodes.cap >= w->scratch_cap &&
               w->stem_nodes_first.cap >= (size_t)w->stem_count + 1);
  SYLVA_ASSERT(w->mark.count <= w->nodes.count && w->mark.iteration == w->iteration - 1);
  if (at == SYLVA__AFTER_ALLOCATION) check_sprouts(w);
  if (at == SYLVA__AFTER_SHOOTS) {
    SYLVA_ASSERT(w->mark.shaded == w->nodes.count);
    SYLVA_ASSERT(w->order.len == (size_t)w->stem_count);
    for (size_t o = 0; o < w->order.len; o++)
      SYLVA_ASSERT(w->order.data[o] >= 0 && w->order.data[o] < w->stem_count);
    /* room for the rest of the step (reserve_rest) */
    SYLVA_ASSERT(w->radii.cap >= w->mark.count && w->shed.cap >= w->nodes.count &&
                 w->stats.cap >= (size_t)w->stem_count && w->cells.cap >= w->nodes.live &&
                 w->stamps.cap >= w->nodes.live);
  }
}
#endif
