#include "light.h"

#include <math.h>

#include "world_impl.h"

typedef struct collect_ctx {
  sylva_world *w;
  int iteration;
  double *own;   /* each node's own L: w->q, summed over subtrees after the pass */
  double *light; /* a copy of it (allocation's w->light), or NULL */
  const sylva__lit *lit; /* the lit nodes under a site sky (w->lit), else NULL */
} collect_ctx;

/* Node i's species, looked up again only when the stem changes from *stem. */
static const sylva__species *species_of(const sylva_world *w, size_t i, int32_t *stem,
                                        const sylva__species **sp) {
  if (w->nodes.stem[i] != *stem) {
    *stem = w->nodes.stem[i];
    *sp = &w->species[w->stems[*stem].species];
  }
  return *sp;
}

/* The age whose light live node i collects at iteration T, -1 when it bears no
 * leaves; *sp is its species (species_of). The one test of which nodes read the
 * grid, made once a pass for each node. */
static int lit_age(const sylva_world *w, size_t i, int T, int32_t *stem,
                   const sylva__species **sp) {
  return sylva__leaf_age(&w->nodes, &species_of(w, i, stem, sp)->def, i, T);
}

/* The light live node i collects at age (0 when age < 0: no leaves, sp unread) in
 * voxel v: reads the grid (its own voxel) and the species' cached powers, writes only
 * its own entries of own and light. */
static void collect_node(const collect_ctx *c, size_t i, int age, const sylva__species *sp,
                         const int v[3]) {
  sylva_world *w = c->w;
  double L = 0.0;
  if (age >= 0) {
    double l = sylva__grid_light_shared(&w->grid, v);
    /* the cache holds age^sigma for every age a leaf has (warmed below) */
    double p = age == 0 ? 0.0
               : age < sp->age_pow_n ? sp->age_pow[age]
                                     : pow((double)age, sp->def.sigma);
    L = sylva__collected(sp->def.alpha, l, p);
  }
  c->own[i] = L;
  if (c->light) c->light[i] = L;
}

/* Nodes are read in batches: each batch's voxels asked of memory first (a crown's
 * chunks seldom sit in the nearer caches), then read; each node's light is its own. */
enum { COLLECT_BATCH = 16 };

typedef struct collect_batch {
  int n;
  size_t slot[COLLECT_BATCH];
  int age[COLLECT_BATCH];
  const sylva__species *sp[COLLECT_BATCH];
  int v[COLLECT_BATCH][3];
} collect_batch;

static void batch_add(const collect_ctx *c, collect_batch *b, size_t i, int age,
                      const sylva__species *sp) {
  int k = b->n++;
  b->slot[k] = i;
  b->age[k] = age;
  b->sp[k] = sp;
  if (age >= 0) {
    sylva__node_voxel(c->w, (int32_t)i, b->v[k]);
    sylva__grid_prefetch(&c->w->grid, b->v[k]);
  }
}

static void batch_collect(const collect_ctx *c, collect_batch *b) {
  for (int k = 0; k < b->n; k++) collect_node(c, b->slot[k], b->age[k], b->sp[k], b->v[k]);
  b->n = 0;
}

/* The light of the live nodes in slots [begin, end). */
static void collect_range(void *arg, size_t begin, size_t end) {
  const collect_ctx *c = arg;
  int32_t cur_stem = -1;
  const sylva__species *sp = NULL;
  collect_batch b;
  b.n = 0;
  for (size_t i = begin; i < end; i++) {
    if (!(c->w->nodes.flags[i] & SYLVA__NODE_ALIVE)) continue;
    int age = lit_age(c->w, i, c->iteration, &cur_stem, &sp);
    batch_add(c, &b, i, age, sp);
    if (b.n == COLLECT_BATCH) batch_collect(c, &b);
  }
  batch_collect(c, &b);
}

/* The light of the listed lit nodes [begin, end) of c->lit. */
static void collect_listed(void *arg, size_t begin, size_t end) {
  const collect_ctx *c = arg;
  int32_t cur_stem = -1;
  const sylva__species *sp = NULL;
  collect_batch b;
  b.n = 0;
  for (size_t k = begin; k < end; k++) {
    size_t i = (size_t)c->lit[k].slot;
    batch_add(c, &b, i, c->lit[k].age, species_of(c->w, i, &cur_stem, &sp));
    if (b.n == COLLECT_BATCH) batch_collect(c, &b);
  }
  batch_collect(c, &b);
}

/* Each live node's own light L at iteration T into own (and light, if not NULL). */
static void collect_own(sylva_world *w, int iteration, double *own, double *light) {
  sylva__skeleton *s = &w->nodes;
  /* What the threads only read: every species' powers of a leaf's ages, and under a
   * site sky the site factors' cache of the chunk of every voxel the pass reads. */
  for (int k = 0; k < w->species_count; k++) {
    const sylva_species_def *d = &w->species[k].def;
    sylva__species_age_pow(&w->species[k], d->leaf_age > 1 ? d->leaf_age : 1);
  }
  collect_ctx c = {w, iteration, own, light, NULL};
  if (!w->grid.sky_count) {
    sylva__pool_for(w->pool, s->count, 4096, collect_range, &c);
  } else {
    /* The caches are those of the lit nodes' own voxels (the wood's chunks get none),
     * so the lit nodes are found here, on one thread, and listed with their ages
     * (room: sylva__reserve_scratch) for the threads to walk; the wood collects 0. A
     * chunk left without a cache (no memory) reads the same factors, computed each
     * time. */
    SYLVA_ASSERT(w->lit.cap >= s->count);
    int32_t stem = -1;
    const sylva__species *sp = NULL;
    w->lit.len = 0;
    for (size_t i = 0; i < s->count; i++) {
      if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
      int age = lit_age(w, i, iteration, &stem, &sp);
      if (age < 0) {
        collect_node(&c, i, age, sp, NULL);
        continue;
      }
      int v[3];
      sylva__node_voxel(w, (int32_t)i, v);
      sylva__grid_site_reserve(&w->grid, v);
      w->lit.data[w->lit.len++] = (sylva__lit){(int32_t)i, age};
    }
    c.lit = w->lit.data;
    sylva__pool_for(w->pool, w->lit.len, 4096, collect_listed, &c);
  }
}

/* Children sit in higher slots than their parents: one reverse sweep adds each
 * finished subtree total into its parent, in the same order whatever the pass. */
static void sum_subtrees(const sylva__skeleton *s, double *q) {
  for (size_t i = s->count; i-- > 0;)
    if ((s->flags[i] & SYLVA__NODE_ALIVE) && s->parent[i] >= 0) q[s->parent[i]] += q[i];
}

void sylva__light_collect(sylva_world *w, int iteration, double *light) {
  w->light_at = 0; /* q holds sums now, no longer the kept pass */
  collect_own(w, iteration, w->q, light);
  sum_subtrees(&w->nodes, w->q);
}

void sylva__light_keep(sylva_world *w, int iteration) {
  sylva__skeleton *s = &w->nodes;
  collect_own(w, iteration, w->q, NULL);
  /* the sums go to light's block (free until the stats' canopy pass), for each
   * stem's Q */
  double *sum = w->light;
  for (size_t i = 0; i < s->count; i++) sum[i] = (s->flags[i] & SYLVA__NODE_ALIVE) ? w->q[i] : 0.0;
  sum_subtrees(s, sum);
  sylva__stems_light(w, sum);
  w->light_at = iteration;
}

void sylva__stems_light(sylva_world *w, const double *q) {
  for (int k = 0; k < w->stem_count; k++) {
    sylva__stem *st = &w->stems[k];
    st->light_next = st->root_slot >= 0 ? q[st->root_slot] : 0.0;
  }
}

bool sylva__light_kept(sylva_world *w, int iteration) {
  if (w->light_at != iteration) return false;
  w->light_at = 0;
  const sylva__skeleton *s = &w->nodes;
  for (size_t i = 0; i < s->count; i++) w->light[i] = w->q[i];
  sum_subtrees(s, w->q);
  return true;
}
