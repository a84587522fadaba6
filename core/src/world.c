/* World lifecycle, plants and obstacles, the step that runs the phases, queries. */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "conflicts.h"
#include "world_impl.h"

int sylva__vec_reserve(void **data, size_t *cap, size_t n, size_t elem) {
  if (n <= *cap) return SYLVA_OK;
  size_t c = *cap ? *cap : 16;
  while (c < n) c += c / 2 + 1;
  void *p = sylva__realloc(*data, c * elem);
  if (!p) return SYLVA_ENOMEM;
  *data = p;
  *cap = c;
  return SYLVA_OK;
}

sylva_world_def sylva_default_world_def(void) {
  sylva_world_def d = {.min = {-5.0, -5.0, 0.0}, .max = {5.0, 5.0, 12.0}, .voxel = 0.05, .seed = 1};
  return d;
}

int sylva_world_def_check(const sylva_world_def *def) {
  if (!(def->voxel > 0.0) || !isfinite(def->voxel)) return SYLVA_EINVAL;
  double total = 1.0;
  for (int a = 0; a < 3; a++) {
    if (!isfinite(def->min[a]) || !isfinite(def->max[a]) || !(def->max[a] > def->min[a]))
      return SYLVA_EINVAL;
    total *= ceil((def->max[a] - def->min[a]) / def->voxel - 1e-9);
  }
  /* a sky: 1 to SYLVA_MAX_SKY finite directions pointing up, of weights >= 0 */
  if (def->sky_count < 0 || def->sky_count > SYLVA_MAX_SKY || (def->sky_count && !def->sky))
    return SYLVA_EINVAL;
  if (!(def->stand_area >= 0.0) || !isfinite(def->stand_area)) return SYLVA_EINVAL;
  if (def->threads < 0 || def->threads > SYLVA_MAX_THREADS) return SYLVA_EINVAL;
  for (int i = 0; i < def->sky_count; i++) {
    const sylva_sky_dir *s = &def->sky[i];
    double len = sqrt(s->d[0] * s->d[0] + s->d[1] * s->d[1] + s->d[2] * s->d[2]);
    if (!(fabs(len - 1.0) < 1e-6) || !(s->d[2] >= 0.0) || !(s->weight >= 0.0) ||
        !isfinite(s->weight))
      return SYLVA_EINVAL;
  }
  return total > SYLVA_MAX_VOXELS ? SYLVA_ETOOBIG : SYLVA_OK;
}

int sylva_world_create(const sylva_world_def *def, sylva_world **out) {
  *out = NULL;
  int rc = sylva_world_def_check(def);
  if (rc) return rc;
  sylva_world *w = sylva__calloc(1, sizeof *w);
  if (!w) return SYLVA_ENOMEM;
  w->def = *def;
  w->stand_stems = -1;
  rc = sylva__grid_init(&w->grid, def->min, def->max, def->voxel);
  if (rc) {
    sylva__free(w);
    return rc;
  }
  rc = sylva__grid_set_sky(&w->grid, def->sky, def->sky_count);
  if (rc) {
    sylva__grid_free(&w->grid);
    sylva__free(w);
    return rc;
  }
  w->def.sky = w->grid.sky; /* the world's own copy */
  w->def.sky_count = w->grid.sky_count;
  if (SYLVA__VEC_RESERVE(w->crown_bins, SYLVA__STATS_PIECES * 2 *
                                          sylva__crown_bins(def->max[2] - def->min[2])) ||
      sylva__canopy_init(w)) {
    sylva_world_destroy(w);
    return SYLVA_ENOMEM;
  }
  sylva__rng_seed(&w->rng, def->seed);
  sylva__pool_create(def->threads, &w->pool); /* one thread if it fails: the same world */
  *out = w;
  return SYLVA_OK;
}

/* The world's own pool stopped, or the shared one left. */
static void leave_pool(sylva_world *w) {
  if (!w->shared) sylva__pool_destroy(w->pool);
  w->pool = NULL;
  w->shared = NULL;
}

int sylva_world_set_threads(sylva_world *w, int threads) {
  if (threads < 0 || threads > SYLVA_MAX_THREADS) return SYLVA_EINVAL;
  if (!w->shared && (threads <= 1 ? 1 : threads) == sylva__pool_threads(w->pool)) return SYLVA_OK;
  leave_pool(w);
  w->def.threads = threads;
  int rc = sylva__pool_create(threads, &w->pool);
  if (rc) w->def.threads = 1;
  return rc;
}

int sylva_world_threads(const sylva_world *w) { return sylva__pool_threads(w->pool); }

struct sylva_threads {
  sylva__pool *pool; /* NULL for one thread */
};

int sylva_threads_create(int count, sylva_threads **out) {
  *out = NULL;
  if (count < 1 || count > SYLVA_MAX_THREADS) return SYLVA_EINVAL;
  sylva_threads *t = sylva__calloc(1, sizeof *t);
  if (!t) return SYLVA_ENOMEM;
  int rc = sylva__pool_create(count, &t->pool);
  if (rc) {
    sylva__free(t);
    return rc;
  }
  *out = t;
  return SYLVA_OK;
}

int sylva_threads_count(const sylva_threads *t) { return sylva__pool_threads(t->pool); }

void sylva_threads_destroy(sylva_threads *t) {
  if (!t) return;
  sylva__pool_destroy(t->pool);
  sylva__free(t);
}

void sylva_world_share_threads(sylva_world *w, sylva_threads *t) {
  leave_pool(w);
  if (t) {
    w->pool = t->pool;
    w->shared = t;
  }
  w->def.threads = sylva__pool_threads(w->pool);
}

sylva_threads *sylva_world_shared_threads(const sylva_world *w) { return w->shared; }

void sylva_world_destroy(sylva_world *w) {
  if (!w) return;
  leave_pool(w);
  sylva__grid_free(&w->grid);
  sylva__skeleton_free(&w->nodes);
  for (int i = 0; i < w->species_count; i++) {
    sylva__free(w->species[i].age_pow);
    sylva__free(w->species[i].shades);
  }
  sylva__free(w->species);
  sylva__free(w->plants);
  sylva__free(w->plant_index);
  sylva__free(w->stems);
  sylva__free(w->light);
  sylva__free(w->q);
  sylva__free(w->pipe);
  sylva__free(w->cols);
  sylva__free(w->foot);
  sylva__free(w->sprouts.data);
  sylva__free(w->order.data);
  sylva__free(w->axis.data);
  sylva__free(w->ranked.data);
  sylva__free(w->work.data);
  sylva__free(w->work_r.data);
  sylva__free(w->work_light.data);
  sylva__free(w->shoot.data);
  sylva__free(w->added.data);
  sylva__free(w->leaf_changes.data);
  sylva__free(w->radii.data);
  sylva__free(w->shed.data);
  sylva__free(w->stats.data);
  sylva__free(w->finishing.data);
  sylva__free(w->clock_next.data);
  sylva__free(w->stem_high.data);
  sylva__free(w->caps.data);
  sylva__free(w->stem_first.data);
  for (size_t p = 0; p < w->piece_sprouts.cap; p++) sylva__free(w->piece_sprouts.data[p].data);
  sylva__free(w->piece_sprouts.data);
  sylva__free(w->stem_top.data);
  sylva__free(w->crown_bins.data);
  sylva__free(w->lit.data);
  sylva__free(w->cells.data);
  sylva__free(w->cell_start.data);
  sylva__free(w->stamps.data);
  sylva__free(w->stamp_lists.data);
  sylva__free(w->cell_first.data);
  sylva__free(w->cell_items.data);
  sylva__free(w->cell_pos.data);
  sylva__free(w->cell_of.data);
  sylva__free(w->entered.data);
  sylva__free(w->prunes.data);
  sylva__free(w->zone_stats.data);
  sylva__free(w->clear_stats.data);
  sylva__free(w->stem_box.data);
  sylva__free(w->stem_nodes.data);
  sylva__free(w->stem_nodes_first.data);
  sylva__free(w->candidates.data);
  sylva__free(w->pruned_ids.data);
  sylva__free(w);
}

/* ---- species ---------------------------------------------------------------- */

static int first_t95(const sylva_equation *eq) {
  double target = 0.95 * sylva_equation_limit(eq);
  for (int t = 0; t < 1000000; t++)
    if (sylva_equation_value(eq, (double)t) >= target) return t;
  return INT_MAX;
}

static int round_count(double v, int lo, int hi) {
  double r = floor(v + 0.5);
  return r < lo ? lo : r > hi ? hi : (int)r;
}

/* The counts of a species with ref_rho, scaled by s = ref_rho / rho so that they act
 * as lengths (docs/model.md, "Species in years"): the growth equation, the initial
 * trunk, the apical zone and the marker cone in internodes, the shade pyramid in
 * voxels (whose edge follows rho) with its base taken to the power 1 / s, so that
 * it fades over the same metres. */
static void scale_counts(sylva__species *sp) {
  sylva_species_def *d = &sp->def;
  sp->scale = 1.0;
  sp->bud_every = 1;
  if (!(d->ref_rho > 0.0)) return;
  double s = d->ref_rho / d->rho;
  switch (d->growth.kind) {
  case SYLVA_EQ_LOGISTIC: d->growth.p[0] *= s; d->growth.p[1] *= s; break;
  default: d->growth.p[0] *= s; break; /* beta1, omega1 and A are the limits */
  }
  d->initial_nodes = round_count(d->initial_nodes * s, 1, 1000);
  d->apical_zone = round_count(d->apical_zone * s, 0, 100000);
  d->cone_radius *= s;
  d->pyramid_depth = round_count(d->pyramid_depth * s, 1, 64);
  d->b_min = pow(d->b_min, 1.0 / s);
  d->b_max = pow(d->b_max, 1.0 / s);
  sp->scale = s;
  sp->bud_every = round_count(s, 1, 1000);
}

int sylva__species_cap(const sylva__species *sp, int local) {
  return sylva__scaled_cap(sp, local, 1.0);
}

int sylva__scaled_cap(const sylva__species *sp, int local, double f) {
  if (!(sp->def.ref_rho > 0.0)) return sylva_equation_cap_scaled(&sp->def.growth, local, f);
  /* the difference of the rounded path lengths: over the years the caps add up to
   * f X(T) to within half an internode at any rho, where rounding each year's rate
   * would lose or gain up to half an internode a year */
  double a = floor(f * sylva_equation_value(&sp->def.growth, (double)local) + 0.5);
  double b = floor(f * sylva_equation_value(&sp->def.growth, (double)(local - 1)) + 0.5);
  return a > b ? (int)(a - b) : 0;
}

int sylva__clock_cap(const sylva__species *sp, double t0, double t1, double f) {
  double whole = floor(t1);
  if (t1 == whole && t0 == whole - 1.0 && whole >= -1e9 && whole <= 1e9)
    return sylva__scaled_cap(sp, (int)whole, f); /* a whole season: as before clocks */
  if (!(t1 > t0)) return 0;
  if (!(sp->def.ref_rho > 0.0)) {
    /* the rate at the season's start over the part of a season the clock ran */
    double r = f * (t1 - t0) * sylva_equation_rate(&sp->def.growth, t0);
    return !(r > 0.0) ? 0 : r > 1e6 ? 1000000 : (int)floor(r + 0.5);
  }
  double a = floor(f * sylva_equation_value(&sp->def.growth, t1) + 0.5);
  double b = floor(f * sylva_equation_value(&sp->def.growth, t0) + 0.5);
  return a > b ? (int)(a - b) : 0;
}

bool sylva__species_stops(const sylva__species *sp, int local) {
  /* A tree in years lives on: it grows as long as its equation and its light let it,
   * however slowly (the rule's one internode a season is 25 cm a year at a
   * ref_rho of 0.25 m, which a 40-year-old street tree still grows). Other species
   * are judged on the equation as given. */
  if (sp->def.years) return false;
  return sylva_equation_stops(&sp->given.growth, local);
}

int sylva_world_add_species(sylva_world *w, const sylva_species_def *def, const char *label) {
  w->light_at = 0; /* each change between steps: the next light phase reads the grid */
  if (!label || strlen(label) >= SYLVA_LABEL_MAX) return SYLVA_EINVAL;
  if (sylva_species_check(def, NULL)) return SYLVA_ERANGE;
  if (w->species_count == w->species_cap) {
    int cap = w->species_cap ? 2 * w->species_cap : 4;
    sylva__species *p = sylva__realloc(w->species, (size_t)cap * sizeof *p);
    if (!p) return SYLVA_ENOMEM;
    w->species = p;
    w->species_cap = cap;
  }
  sylva__species *sp = &w->species[w->species_count];
  memset(sp, 0, sizeof *sp);
  sp->def = *def;
  sp->given = *def;
  scale_counts(sp);
  strcpy(sp->label, label);
  sp->t95 = first_t95(&sp->def.growth);
  return w->species_count++;
}

double sylva__species_b(const sylva__species *sp, int t) {
  const sylva_species_def *d = &sp->def;
  if (t <= d->tau) return d->b_min;
  if (t >= sp->t95) return d->b_max;
  return d->b_min + (d->b_max - d->b_min) * (double)(t - d->tau) / (double)(sp->t95 - d->tau);
}

/* The weight of one node's pyramid. 1 without ref_rho. With it, nodes stand s =
 * ref_rho / rho times as close along a shoot, each two voxels from the next as at
 * ref_rho, and the base b (per voxel) is b_ref^(1/s): the weight makes the shade a
 * straight shoot casts on a point below it, sum over its nodes k of w b^-2k, equal to
 * that of the same shoot at ref_rho, sum of b_ref^-2k (docs/model.md, "Species in
 * years"). Measured: the plain 1 / s left the tree at rho / 2 with a fifth less DBH. */
static double chain_weight(const sylva__species *sp, double b) {
  if (sp->scale == 1.0) return 1.0;
  double s = sp->scale;
  double x = pow(b, -2.0 * s), y = pow(b, -2.0);
  return (x / (1.0 - x)) / (y / (1.0 - y));
}

/* The half-width of layer q of every pyramid of the species. */
static int shade_half(const sylva__species *sp, int q) {
  return (int)floor((double)q * sp->def.shade_spread);
}

int sylva__species_shade_reach(const sylva__species *sp) {
  return shade_half(sp, sp->def.pyramid_depth);
}

static void make_shade(const sylva__species *sp, int t, sylva__pyramid *p) {
  double b = sylva__species_b(sp, t);
  p->depth = sp->def.pyramid_depth;
  double weight = sp->def.shade_weight * chain_weight(sp, b);
  for (int q = 1; q <= p->depth; q++) {
    p->w[q - 1] = (int64_t)floor(pow(b, -(double)q) * weight * SYLVA__SHADE_ONE + 0.5);
    p->half[q - 1] = shade_half(sp, q);
  }
  /* the column: a point below a crown sums the nodes above it in its voxel column,
   * s times as many per metre of shoot in a voxel s^2 times smaller: weighted s, the
   * same crown casts the same column shade at any rho */
  p->column = (int64_t)floor(sp->def.shade_column * sp->scale * sp->def.shade_weight * SYLVA__SHADE_ONE + 0.5);
}

/* The table entry of local birth iteration t (see sylva__species.shades). */
static int64_t shade_entry(const sylva__species *sp, int t) {
  int64_t tau = sp->def.tau, hi = sp->t95 > sp->def.tau ? sp->t95 : tau + 1;
  return t <= tau ? 0 : t >= hi ? hi - tau : (int64_t)t - tau;
}

int sylva__species_shade_reserve(sylva__species *sp, int t) {
  int64_t k = shade_entry(sp, t);
  if (k < sp->shades_n) return SYLVA_OK;
  int64_t n = k + 16 > 2 * (int64_t)sp->shades_n ? k + 16 : 2 * (int64_t)sp->shades_n;
  if (n > INT_MAX / 2) return SYLVA_ENOMEM;
  sylva__pyramid *p = sylva__realloc(sp->shades, (size_t)n * sizeof *p);
  if (!p) return SYLVA_ENOMEM;
  for (int64_t i = sp->shades_n; i < n; i++) make_shade(sp, (int)(sp->def.tau + i), &p[i]);
  sp->shades = p;
  sp->shades_n = (int)n;
  return SYLVA_OK;
}

const sylva__pyramid *sylva__species_shade_at(const sylva__species *sp, int t) {
  SYLVA_ASSERT(shade_entry(sp, t) < sp->shades_n);
  return &sp->shades[shade_entry(sp, t)];
}

const sylva__pyramid *sylva__species_shade(sylva__species *sp, int t) {
  return sylva__species_shade_reserve(sp, t) ? NULL : sylva__species_shade_at(sp, t);
}

double sylva__species_age_pow(sylva__species *sp, int age) {
  if (age >= sp->age_pow_n) {
    int n = age + 64;
    double *p = sylva__realloc(sp->age_pow, (size_t)n * sizeof *p);
    if (!p) return pow((double)age, sp->def.sigma);
    for (int i = sp->age_pow_n; i < n; i++) p[i] = pow((double)i, sp->def.sigma);
    sp->age_pow = p;
    sp->age_pow_n = n;
  }
  return sp->age_pow[age];
}

/* ---- nodes ------------------------------------------------------------------- */

bool sylva__voxel_of(const sylva_world *w, const double p[3], float f[3], int v[3]) {
  for (int a = 0; a < 3; a++) f[a] = (float)p[a];
  return sylva__grid_voxel(&w->grid, f[0], f[1], f[2], v);
}

void sylva__node_voxel(const sylva_world *w, int32_t slot, int v[3]) {
  const sylva__skeleton *s = &w->nodes;
  bool inside = sylva__grid_voxel(&w->grid, s->x[slot], s->y[slot], s->z[slot], v);
  SYLVA_ASSERT(inside); /* nodes are only stored at positions whose voxel is inside */
  (void)inside;
}

int32_t sylva__add_node(sylva_world *w, int32_t parent, bool lateral, const double p[3],
                        int32_t stem, int iteration) {
  int v[3];
  float f[3];
  if (!sylva__voxel_of(w, p, f, v)) return SYLVA_EOUTSIDE;
  if (sylva__grid_blocked(&w->grid, v)) return SYLVA_EBLOCKED;
  if (sylva__skeleton_reserve(&w->nodes, 1)) return SYLVA_ENOMEM;
  int rc = sylva__grid_occupy(&w->grid, v, stem);
  if (rc) return rc;
  const sylva__species *sp = &w->species[w->stems[stem].species];
  int32_t depth = parent >= 0 ? w->nodes.depth[parent] + 1 : 0;
  int32_t slot = sylva__skeleton_append(&w->nodes, w->nodes.next_id++, parent, f[0], f[1], f[2],
                                        (float)sp->def.r_tip, iteration, stem, depth,
                                        lateral ? SYLVA__NODE_LATERAL : 0);
  if (parent >= 0) {
    /* only a free bud or an apex sprouts: the link is still empty */
    int32_t *link = lateral ? &w->nodes.lateral_child[parent] : &w->nodes.axis_child[parent];
    SYLVA_ASSERT(*link < 0);
    *link = slot;
  }
  return slot;
}

/* ---- plants and obstacles -------------------------------------------------- */

static size_t label_hash(const char *s) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (; *s; s++) h = (h ^ (unsigned char)*s) * 0x100000001b3ULL;
  return (size_t)(h ^ (h >> 32));
}

int sylva__find_plant(const sylva_world *w, const char *label) {
  if (!w->plant_index_cap) return -1;
  size_t mask = w->plant_index_cap - 1;
  for (size_t h = label_hash(label) & mask; w->plant_index[h] >= 0; h = (h + 1) & mask)
    if (strcmp(w->plants[w->plant_index[h]].label, label) == 0) return w->plant_index[h];
  return -1;
}

/* Files plant p, for which the table has room. */
static void file_plant(sylva_world *w, int p) {
  size_t mask = w->plant_index_cap - 1, h = label_hash(w->plants[p].label) & mask;
  while (w->plant_index[h] >= 0) h = (h + 1) & mask;
  w->plant_index[h] = p;
}

/* Makes room in the label index for n plants (at most half full). */
static int reserve_plant_index(sylva_world *w, size_t n) {
  if (2 * n <= w->plant_index_cap) return SYLVA_OK;
  size_t cap = w->plant_index_cap ? 2 * w->plant_index_cap : 16;
  while (cap < 2 * n) cap *= 2;
  int32_t *idx = sylva__malloc(cap * sizeof *idx);
  if (!idx) return SYLVA_ENOMEM;
  for (size_t i = 0; i < cap; i++) idx[i] = -1;
  sylva__free(w->plant_index);
  w->plant_index = idx;
  w->plant_index_cap = cap;
  for (int i = 0; i < w->plant_count; i++) file_plant(w, i);
  return SYLVA_OK;
}

int sylva__index_plant(sylva_world *w, int p) {
  SYLVA_ASSERT(p == w->plant_count);
  int rc = reserve_plant_index(w, (size_t)w->plant_count + 1);
  if (rc) return rc;
  file_plant(w, p);
  return SYLVA_OK;
}

static int reserve_scratch(sylva_world *w);

/* ---- taking back a call that failed -------------------------------------------- */

/* Notes the state a step or a new plant starts from (sylva__mark). */
static void set_mark(sylva_world *w) {
  w->mark = (sylva__mark){.iteration = w->iteration,
                          .rng = w->rng,
                          .count = w->nodes.count,
                          .shaded = w->nodes.count,
                          .next_id = w->nodes.next_id,
                          .stem_count = w->stem_count};
}

/* Puts the world back to its mark: the nodes appended since lose their shade,
 * occupancy and links, the stems planted since are dropped, the generator and the
 * iteration are restored. */
static void take_back(sylva_world *w) {
  w->light_at = 0; /* the step may have summed the kept pass */
  const sylva__mark *m = &w->mark;
  sylva__skeleton *s = &w->nodes;
  for (size_t i = s->count; i-- > m->count;) {
    if (i < m->shaded) {
      int rc = sylva__shade_node(w, (int32_t)i, -1);
      SYLVA_ASSERT(rc == SYLVA_OK); /* its blocks exist: removing allocates nothing */
      (void)rc;
    }
    int v[3];
    sylva__node_voxel(w, (int32_t)i, v);
    sylva__grid_vacate(&w->grid, v);
    int32_t parent = s->parent[i];
    if (parent >= 0) {
      if (s->flags[i] & SYLVA__NODE_LATERAL)
        s->lateral_child[parent] = -1;
      else
        s->axis_child[parent] = -1;
    }
    s->live--;
  }
  s->count = m->count;
  s->next_id = m->next_id;
  w->stem_count = m->stem_count;
  w->rng = m->rng;
  w->iteration = m->iteration;
}

/* Whether another stem's nodes in voxel v are branches a new trunk may cut: none of
 * them is that stem's root or one of the initial trunk nodes above it. */
static bool branches_only(const sylva_world *w, const int v[3], int32_t stem) {
  const sylva__skeleton *s = &w->nodes;
  const sylva__stem *st = &w->stems[stem];
  int32_t n = st->root_slot;
  for (int k = 0; k <= w->species[st->species].def.initial_nodes && n >= 0; k++) {
    int u[3];
    sylva__node_voxel(w, n, u);
    if (u[0] == v[0] && u[1] == v[1] && u[2] == v[2]) return false;
    n = s->axis_child[n];
  }
  return true;
}

/* Checks a new trunk's voxels: inside, free of obstacles, of the plant's other trunks
 * (taken) and of other stems, but for their branches, which go to cuts[*ncuts]
 * (docs/model.md, "Species in years", nursery). */
static int check_trunk(const sylva_world *w, const sylva_species_def *sp, const double root[3],
                       int (*taken)[3], int ntaken, int *nout, int (*out)[3], int (*cuts)[3],
                       int *ncuts) {
  int count = 0;
  for (int k = 0; k <= sp->initial_nodes; k++) {
    double p[3] = {root[0], root[1], root[2] + sp->rho * k};
    int v[3];
    float f[3];
    if (!sylva__voxel_of(w, p, f, v)) return SYLVA_EOUTSIDE;
    if (sylva__grid_blocked(&w->grid, v)) return SYLVA_EBLOCKED;
    int32_t occupant = sylva__grid_occupant(&w->grid, v);
    if (occupant >= 0) {
      if (!branches_only(w, v, occupant)) return SYLVA_EOCCUPIED;
      memcpy(cuts[(*ncuts)++], v, sizeof v);
    }
    for (int i = 0; i < ntaken; i++)
      if (taken[i][0] == v[0] && taken[i][1] == v[1] && taken[i][2] == v[2]) return SYLVA_EOCCUPIED;
    memcpy(out[count++], v, sizeof v);
  }
  *nout = count;
  return SYLVA_OK;
}

static void compact_nodes(sylva_world *w);

/* Cuts the branches of other stems in a new trunk's voxels, each with what it carries,
 * as a prune would (docs/model.md, "Species in years", nursery); room was reserved (pruned_ids,
 * scratch, the removal). Never fails. */
static void clear_trunks(sylva_world *w, int (*cuts)[3], int ncuts) {
  int T = w->iteration;
  w->pruned_ids.len = 0;
  size_t n = sylva__cut_voxels(w, cuts, (size_t)ncuts, T, w->pruned_ids.data, &w->pruned_ids.len);
  if (!n) return;
  sylva__light_collect(w, T + 1, NULL); /* as after a prune */
  sylva__stems_light(w, w->q);
  if (T == 0)
    for (int k = 0; k < w->stem_count; k++) sylva__stats_planted(w, k);
  else
    sylva__stats(w, T);
  compact_nodes(w);
}

/* ---- stems --------------------------------------------------------------------- */

/* A standard normal drawn from r (Box-Muller), held within 3 standard deviations so
 * that no plant is drawn absurdly vigorous or weak. */
static double normal_draw(sylva__rng *r) {
  double u1 = sylva__rng_unit(r), u2 = sylva__rng_unit(r);
  double z = sqrt(-2.0 * log(1.0 - u1)) * cos(6.283185307179586 * u2);
  return z < -3.0 ? -3.0 : z > 3.0 ? 3.0 : z;
}

/* A plant's draws (docs/model.md, "Stands"), from the world's seed and its label
 * alone, so that neither the order of planting nor the world's generator changes
 * them: its vigour (the clock's advance per season in full light, lognormal with
 * vigour_spread) and the rate its stock grew at in the nursery, chosen so that the
 * planted height's spread is stock_spread (the height's elasticity in the clock at
 * the planting's `seasons` turns the one into the other). 1 and 1 without spreads. */
static void plant_draws(const sylva_world *w, const sylva__species *sp, const char *label,
                        int seasons, double *stock, double *vigour) {
  const sylva_species_def *d = &sp->def;
  *stock = *vigour = 1.0;
  if (!(d->vigour_spread > 0.0) && !(d->stock_spread > 0.0)) return;
  sylva__rng r;
  sylva__rng_seed(&r, w->def.seed ^ (uint64_t)label_hash(label) ^ 0x7669676f7572ULL);
  double zv = normal_draw(&r), zs = normal_draw(&r);
  *vigour = exp(d->vigour_spread * zv);
  if (d->stock_spread > 0.0 && seasons > 0) {
    double t = (double)seasons, x = sylva_equation_value(&d->growth, t);
    double e = x > 0.0 ? t * sylva_equation_rate(&d->growth, t) / x : 1.0;
    if (!(e > 0.05)) e = 0.05;
    *stock = exp(d->stock_spread * zs / e);
  }
}

/* Starts stem `index` of plant pid, alive, planted at world iteration `born` with its
 * clock at `clock` seasons, advancing `rate` a season in full light. */
static sylva__stem *new_stem(sylva_world *w, int pid, int index, int species, int32_t born,
                             const double root[3], double clock, double rate) {
  sylva__stem *st = &w->stems[w->stem_count++];
  memset(st, 0, sizeof *st);
  st->plant = pid;
  st->index = index;
  st->species = species;
  st->born = born;
  st->root_slot = -1;
  memcpy(st->root, root, sizeof st->root);
  st->clock = clock;
  st->clock_prev = clock - 1.0;
  st->rate = rate;
  st->stats.alive = true;
  st->stats.died = st->stats.fallen = -1;
  st->stats.vigour = NAN;
  return st;
}

/* ---- the nursery --------------------------------------------------------------- */

/* Grows the plant alone under the open sky for `seasons` iterations, in a world of its
 * own around its roots with the voxel edge of w (docs/model.md, "Species in years").
 * Its generator is seeded from the world's seed and the plant's label, so the
 * nursery draws nothing from w's generator and a plant's stock depends only on them. */
static int grow_in_nursery(const sylva_world *w, const sylva_plant_def *def, int seasons,
                           double stock_rate, sylva_world **out) {
  const sylva__species *sp = &w->species[def->species];
  sylva_world_def nd = sylva_default_world_def();
  double reach = sylva_equation_limit(&sp->def.growth) * sp->def.rho;
  if (!(reach < 200.0)) reach = 200.0; /* taller than any tree: the box only bounds it */
  for (int a = 0; a < 3; a++) {
    nd.min[a] = nd.max[a] = def->roots[0][a];
    for (int r = 1; r < def->root_count; r++) {
      if (def->roots[r][a] < nd.min[a]) nd.min[a] = def->roots[r][a];
      if (def->roots[r][a] > nd.max[a]) nd.max[a] = def->roots[r][a];
    }
  }
  for (int a = 0; a < 2; a++) {
    nd.min[a] -= reach;
    nd.max[a] += reach;
  }
  nd.max[2] += reach + 1.0;
  nd.voxel = w->def.voxel;
  nd.seed = w->def.seed ^ (uint64_t)label_hash(def->label);
  sylva_world *n = NULL;
  int rc = sylva_world_create(&nd, &n);
  if (rc) return rc;
  sylva_species_def stock = sp->given;
  stock.nursery = 0; /* the nursery's own plant starts as a seedling */
  /* the nursery's tree neither dies nor draws: the outer world drew its stock's rate */
  stock.mortality = stock.mortality_light = 0.0;
  stock.stock_spread = stock.vigour_spread = 0.0;
  int sp_id = sylva_world_add_species(n, &stock, sp->label);
  sylva_plant_def pd = *def;
  pd.species = sp_id;
  pd.age = 0;
  rc = sp_id < 0 ? sp_id : sylva_world_add_plant(n, &pd, NULL);
  for (int k = 0; rc >= 0 && k < n->stem_count; k++) n->stems[k].rate = stock_rate;
  for (int t = 0; rc >= 0 && t < seasons; t++) {
    const sylva_journal *j;
    rc = sylva_world_step(n, &j);
    if (rc == SYLVA_EFINISHED) { /* a stem that stopped stays as it is */
      n->iteration++;
      rc = SYLVA_OK;
    }
  }
  if (rc < 0) {
    sylva_world_destroy(n);
    return rc;
  }
  *out = n;
  return SYLVA_OK;
}

/* Places the nursery's stems as stems first_stem.. of w, planted `seasons` iterations
 * before now: every node at its position, with its birth, radius and state. A node
 * that cannot be placed (outside the world, in an obstacle or another stem's voxel)
 * is left out with everything it carries, as a prune would cut it. Fails only for
 * memory, after which take_back() undoes it. */
static int transplant(sylva_world *w, const sylva_world *n, int first_stem, int seasons) {
  const sylva__skeleton *ns = &n->nodes;
  int32_t *map = sylva__malloc((ns->count ? ns->count : 1) * sizeof *map);
  if (!map) return SYLVA_ENOMEM;
  int rc = SYLVA_OK;
  int32_t shift = (int32_t)(w->iteration - seasons);
  /* planted `seasons` ago: each node's shade follows its local birth iteration */
  for (int k = 0; k < n->stem_count; k++) {
    sylva__stem *st = &w->stems[first_stem + k];
    st->born = shift;
    st->clock = n->stems[k].clock; /* the stock's clock goes on where it stood */
    st->clock_prev = n->stems[k].clock_prev;
  }
  for (size_t i = 0; i < ns->count && !rc; i++) {
    map[i] = -1;
    if (!(ns->flags[i] & SYLVA__NODE_ALIVE)) continue;
    int32_t parent = ns->parent[i] >= 0 ? map[ns->parent[i]] : -1;
    if (ns->parent[i] >= 0 && parent < 0) continue; /* its parent was left out */
    bool lateral = (ns->flags[i] & SYLVA__NODE_LATERAL) != 0;
    int stem = first_stem + ns->stem[i];
    double p[3] = {ns->x[i], ns->y[i], ns->z[i]};
    int32_t slot = sylva__add_node(w, parent, lateral, p, stem, ns->birth[i] + shift);
    if (slot == SYLVA_ENOMEM) {
      rc = SYLVA_ENOMEM;
      break;
    }
    if (slot < 0) {
      if (lateral) w->nodes.flags[parent] |= SYLVA__NODE_SCAR; /* its bud is spent */
      continue;
    }
    map[i] = slot;
    w->nodes.radius[slot] = ns->radius[i];
    w->nodes.flags[slot] |= ns->flags[i] & SYLVA__NODE_SCAR;
    if (parent < 0) w->stems[stem].root_slot = slot;
    rc = sylva__shade_node(w, slot, +1);
    if (!rc) w->mark.shaded = (size_t)slot + 1;
  }
  for (int k = 0; k < n->stem_count && !rc; k++) w->stems[first_stem + k].finished = n->stems[k].finished;
  sylva__free(map);
  return rc;
}

/* Room for one more plant with `stems` stems. */
static int reserve_plant_room(sylva_world *w, int stems) {
  if (w->plant_count == w->plant_cap) {
    int cap = w->plant_cap ? 2 * w->plant_cap : 8;
    sylva__plant *p = sylva__realloc(w->plants, (size_t)cap * sizeof *p);
    if (!p) return SYLVA_ENOMEM;
    w->plants = p;
    w->plant_cap = cap;
  }
  if (w->stem_count + stems > w->stem_cap) {
    int cap = w->stem_cap ? w->stem_cap : 8;
    while (cap < w->stem_count + stems) cap *= 2;
    sylva__stem *p = sylva__realloc(w->stems, (size_t)cap * sizeof *p);
    if (!p) return SYLVA_ENOMEM;
    w->stems = p;
    w->stem_cap = cap;
  }
  return SYLVA_OK;
}

/* Files the plant whose `stems` stems were just placed (from w->mark.stem_count) and
 * measures them; returns its id. */
static int finish_plant(sylva_world *w, const sylva_plant_def *def, int stems) {
  int pid = w->plant_count;
  sylva__plant *pl = &w->plants[pid];
  memset(pl, 0, sizeof *pl);
  strcpy(pl->label, def->label);
  pl->species = def->species;
  pl->first_stem = w->mark.stem_count;
  pl->stem_count = stems;
  file_plant(w, pid);
  w->plant_count++;
  /* its leaves as a snapshot taken now gives them (sylva_node_info.leaves): the next
   * journal lists the leaves that differ from those */
  for (size_t i = w->mark.count; i < w->nodes.count; i++)
    w->nodes.leaves[i] = (uint16_t)sylva__node_leaves(w, i);
  for (int r = 0; r < stems; r++) sylva__stats_planted(w, pl->first_stem + r);
  sylva__canopy(w);
  sylva__stand_stale(w); /* found when asked for, or by the next step */
  sylva__conflicts(w, w->iteration);
  SYLVA__CHECK_WORLD(w, SYLVA__BETWEEN_STEPS);
  return pid;
}

/* ---- measured plants ------------------------------------------------------------ */

/* Checks a measured plant's nodes (docs/model.md, "Measured trees"): parents before
 * children, one axis and one lateral child each, finite positions and radii above 0,
 * births at planting or before and never before their parent's, and every node in a
 * free voxel of the world (another stem's voxel, an obstacle or outside: refused).
 * Counts the roots. 0 or a status, *bad the node at fault. */
static int check_measured(const sylva_world *w, const sylva_plant_def *def, int *roots, int *bad) {
  int n = def->node_count, rc = SYLVA_OK;
  if (n < 1 || n > SYLVA_MAX_MEASURED_NODES) return n < 1 ? SYLVA_EINVAL : SYLVA_ETOOBIG;
  uint8_t *links = sylva__calloc((size_t)n, 1); /* 1: has an axis child, 2: a lateral */
  if (!links) return SYLVA_ENOMEM;
  *roots = 0;
  for (int i = 0; i < n && !rc; i++) {
    const sylva_plant_node *d = &def->nodes[i];
    *bad = i;
    bool finite = isfinite(d->p[0]) && isfinite(d->p[1]) && isfinite(d->p[2]) && isfinite(d->radius);
    if (!finite || !(d->radius > 0.0) || d->birth > 0 || d->parent < -1 || d->parent >= i ||
        (d->parent < 0 && d->lateral) || d->birth < -SYLVA_MAX_AGE - 1000) {
      rc = SYLVA_EINVAL;
      break;
    }
    if (d->parent < 0) {
      ++*roots;
    } else {
      uint8_t bit = d->lateral ? 2 : 1;
      if ((links[d->parent] & bit) || d->birth < def->nodes[d->parent].birth) {
        rc = SYLVA_EINVAL;
        break;
      }
      links[d->parent] |= bit;
    }
    int v[3];
    float f[3];
    if (!sylva__voxel_of(w, d->p, f, v))
      rc = SYLVA_EOUTSIDE;
    else if (sylva__grid_blocked(&w->grid, v))
      rc = SYLVA_EBLOCKED;
    else if (sylva__grid_occupant(&w->grid, v) >= 0)
      rc = SYLVA_EOCCUPIED;
  }
  sylva__free(links);
  if (!rc) *bad = -1;
  if (!rc && w->stem_count + *roots > SYLVA_MAX_STEMS) rc = SYLVA_ETOOBIG;
  return rc;
}

/* Adds a measured plant: its stems, its nodes as they stand (births counted from now,
 * radii kept), occupying and shading as grown nodes do. */
static int add_measured(sylva_world *w, const sylva_plant_def *def, int *bad) {
  if (def->species < 0 || def->species >= w->species_count || !def->label || !def->label[0] ||
      strlen(def->label) >= SYLVA_LABEL_MAX || sylva__find_plant(w, def->label) >= 0)
    return SYLVA_EINVAL;
  const sylva_species_def *sp = &w->species[def->species].def;
  if (def->age < 0 || def->age > SYLVA_MAX_AGE || (def->age > 0 && !sp->years)) return SYLVA_EINVAL;
  int roots = 0, unused;
  int rc = check_measured(w, def, &roots, bad ? bad : &unused); /* bad_root is optional */
  if (rc) return rc;
  if (reserve_plant_room(w, roots)) return SYLVA_ENOMEM;
  int32_t *map = sylva__malloc((size_t)def->node_count * sizeof *map);
  if (!map) return SYLVA_ENOMEM;
  if (sylva__skeleton_reserve(&w->nodes, (size_t)def->node_count) ||
      reserve_plant_index(w, (size_t)w->plant_count + 1) ||
      SYLVA__VEC_RESERVE(w->stem_top, sylva__canopy_room(w->stem_count + roots))) {
    sylva__free(map);
    return SYLVA_ENOMEM;
  }
  int pid = w->plant_count;
  set_mark(w);
  /* its stems count the seasons it has grown: a years species' cap goes on from there */
  int32_t born = (int32_t)w->iteration - (sp->years ? sp->nursery + def->age : 0);
  double stock, vigour;
  plant_draws(w, &w->species[def->species], def->label, 0, &stock, &vigour);
  for (int i = 0; i < def->node_count && !rc; i++) {
    const sylva_plant_node *d = &def->nodes[i];
    int stem = d->parent < 0 ? w->stem_count : w->nodes.stem[map[d->parent]];
    if (d->parent < 0)
      new_stem(w, pid, stem - w->mark.stem_count, def->species, born, d->p,
               (double)(w->iteration - born), vigour);
    int32_t slot = sylva__add_node(w, d->parent < 0 ? -1 : map[d->parent], d->lateral != 0, d->p,
                                   stem, w->iteration + d->birth);
    if (slot < 0) { /* memory, or a voxel its own other stem holds */
      rc = slot;
      *bad = i;
      break;
    }
    map[i] = slot;
    w->nodes.radius[slot] = (float)d->radius;
    if (d->parent < 0) w->stems[stem].root_slot = slot;
    rc = sylva__shade_node(w, slot, +1);
    if (!rc) w->mark.shaded = (size_t)slot + 1;
  }
  sylva__free(map);
  if (!rc && (sylva__conflicts_reserve(w, w->mark.stem_count) || reserve_scratch(w)))
    rc = SYLVA_ENOMEM;
  if (rc) {
    take_back(w);
    return rc;
  }
  return finish_plant(w, def, roots);
}

int sylva_world_add_plant(sylva_world *w, const sylva_plant_def *def, int *bad_root) {
  w->light_at = 0;
  if (bad_root) *bad_root = -1;
  if (w->status) return w->status;
  if (def && def->nodes) return add_measured(w, def, bad_root);
  if (!def || def->species < 0 || def->species >= w->species_count || def->root_count < 1 ||
      !def->roots || !def->label || !def->label[0] || strlen(def->label) >= SYLVA_LABEL_MAX)
    return SYLVA_EINVAL;
  if (sylva__find_plant(w, def->label) >= 0) return SYLVA_EINVAL;
  if (w->stem_count + def->root_count > SYLVA_MAX_STEMS) return SYLVA_ETOOBIG;
  const sylva_species_def *sp = &w->species[def->species].def;
  if (def->age < 0 || def->age > SYLVA_MAX_AGE || (def->age > 0 && !sp->years)) return SYLVA_EINVAL;
  int seasons = sp->years ? sp->nursery + def->age : 0;
  /* Check every trunk before changing anything: the voxels of earlier roots of the
   * same plant count as taken by another stem. */
  size_t per = (size_t)sp->initial_nodes + 1;
  int(*taken)[3] = sylva__malloc(2 * (size_t)def->root_count * per * sizeof *taken);
  if (!taken) return SYLVA_ENOMEM;
  int(*cuts)[3] = taken + (size_t)def->root_count * per;
  int ntaken = 0, ncuts = 0;
  for (int r = 0; r < def->root_count; r++) {
    int n = 0;
    int rc = check_trunk(w, sp, def->roots[r], taken, ntaken, &n, taken + ntaken, cuts, &ncuts);
    if (rc) {
      sylva__free(taken);
      if (bad_root) *bad_root = r;
      return rc;
    }
    ntaken += n;
  }
  /* Room for everything first; then only placing the trunks can fail (a voxel chunk
   * for their occupancy or shade), and that is taken back. */
  int rc = SYLVA_OK;
  if (reserve_plant_room(w, def->root_count) ||
      sylva__skeleton_reserve(&w->nodes, (size_t)def->root_count * per) ||
      reserve_plant_index(w, (size_t)w->plant_count + 1) ||
      SYLVA__VEC_RESERVE(w->stem_top, sylva__canopy_room(w->stem_count + def->root_count)) ||
      (ncuts && SYLVA__VEC_RESERVE(w->pruned_ids, w->nodes.count)) ||
      (ncuts && (reserve_scratch(w) || sylva__reserve_removal(w))))
    rc = SYLVA_ENOMEM;
  int pid = w->plant_count;
  double stock, vigour;
  plant_draws(w, &w->species[def->species], def->label, seasons, &stock, &vigour);
  sylva_world *nursery = NULL;
  if (!rc && seasons > 0) rc = grow_in_nursery(w, def, seasons, stock, &nursery);
  if (!rc && ncuts) clear_trunks(w, cuts, ncuts);
  sylva__free(taken);
  if (rc) return rc;
  set_mark(w);
  for (int r = 0; r < def->root_count && nursery; r++)
    new_stem(w, pid, r, def->species, w->iteration, def->roots[r], 0.0, vigour);
  if (nursery) {
    int rc = transplant(w, nursery, w->mark.stem_count, seasons);
    sylva_world_destroy(nursery);
    if (rc) {
      take_back(w);
      return rc;
    }
  }
  for (int r = 0; r < def->root_count && seasons == 0; r++) {
    int s = w->stem_count;
    sylva__stem *st = new_stem(w, pid, r, def->species, w->iteration, def->roots[r], 0.0, vigour);
    int32_t prev = -1;
    for (int k = 0; k <= sp->initial_nodes; k++) {
      double p[3] = {st->root[0], st->root[1], st->root[2] + sp->rho * k};
      int32_t slot = sylva__add_node(w, prev, false, p, s, w->iteration);
      int rc = slot < 0 ? slot : sylva__shade_node(w, slot, +1);
      if (rc) {
        SYLVA_ASSERT(rc == SYLVA_ENOMEM); /* the trunks were checked above */
        take_back(w);
        return rc;
      }
      w->mark.shaded = (size_t)slot + 1;
      if (k == 0) st->root_slot = slot;
      prev = slot;
    }
  }
  /* the scratch the measures use (the crown base's leaf heights) */
  if (sylva__conflicts_reserve(w, w->mark.stem_count) || reserve_scratch(w)) {
    take_back(w);
    return SYLVA_ENOMEM;
  }
  return finish_plant(w, def, def->root_count);
}

int sylva_world_add_obstacle(sylva_world *w, const sylva_obstacle_def *def) {
  w->light_at = 0;
  if (w->status) return w->status;
  int id = sylva__grid_add_obstacle_def(&w->grid, w->grid.next_obstacle_id, def);
  if (id < 0) return id;
  bool reports = w->reports;
  w->reports |= def->kind == SYLVA_OBSTACLE_ZONE;
  if (sylva__conflicts_update(w, 0)) {
    w->reports = reports;
    int next = w->grid.next_obstacle_id;
    sylva__grid_remove_obstacle(&w->grid, id);
    w->grid.next_obstacle_id = next - 1; /* as if never added */
    return SYLVA_ENOMEM;
  }
  w->foot_dirty = true; /* the canopy's open ground, measured at the next step */
  return id;
}

int sylva_world_remove_obstacle(sylva_world *w, int obstacle) {
  w->light_at = 0;
  if (w->status) return w->status;
  int rc = sylva__grid_remove_obstacle(&w->grid, obstacle);
  if (rc) return rc;
  /* fewer obstacles near fewer stems: the room reserved before is enough */
  rc = sylva__conflicts_update(w, 0);
  SYLVA_ASSERT(rc == SYLVA_OK);
  w->foot_dirty = true;
  return rc ? w->status = rc : SYLVA_OK;
}

int sylva_world_add_prune(sylva_world *w, const sylva_prune_def *def) {
  w->light_at = 0;
  if (w->status) return w->status;
  int slot = sylva__grid_obstacle_slot(&w->grid, def->zone);
  if (slot < 0 || !w->grid.obstacles[slot].zone || def->every < 0 || def->from < 1)
    return SYLVA_EINVAL;
  if (SYLVA__VEC_RESERVE(w->prunes, w->prunes.len + 1)) return SYLVA_ENOMEM;
  w->prunes.data[w->prunes.len++] = *def;
  w->reports = true;
  return SYLVA_OK;
}

int sylva_world_prune_count(const sylva_world *w) { return (int)w->prunes.len; }

int sylva_world_prune_at(const sylva_world *w, int i, sylva_prune_def *out) {
  if (i < 0 || (size_t)i >= w->prunes.len) return SYLVA_ENOTFOUND;
  *out = w->prunes.data[i];
  return SYLVA_OK;
}

/* Drops the dead slots of the skeleton (parents before children stay in order). */
static void compact_nodes(sylva_world *w) {
  if (w->nodes.count == w->nodes.live) return;
  size_t count = w->nodes.count;
  sylva__skeleton_compact(&w->nodes, w->remap);
  for (int s = 0; s < w->stem_count; s++) /* a fallen stem has no root */
    if (w->stems[s].root_slot >= 0) w->stems[s].root_slot = w->remap[w->stems[s].root_slot];
  if (w->light_at) /* the light kept moves with its nodes (remap[i] <= i) */
    for (size_t i = 0; i < count; i++)
      if (w->remap[i] >= 0) w->q[w->remap[i]] = w->q[i];
}

int64_t sylva_world_prune(sylva_world *w, const double min[3], const double max[3],
                          const int32_t **removed, size_t *removed_count) {
  w->light_at = 0;
  if (removed) *removed = NULL;
  if (removed_count) *removed_count = 0;
  if (w->status) return w->status;
  for (int a = 0; a < 3; a++)
    if (!isfinite(min[a]) || !isfinite(max[a]) || max[a] < min[a]) return SYLVA_EINVAL;
  w->pruned_ids.len = 0;
  /* a world that prunes reports conflicts from now on: room for them first */
  bool reports = w->reports;
  w->reports = true;
  if (reserve_scratch(w) || sylva__reserve_removal(w) ||
      SYLVA__VEC_RESERVE(w->pruned_ids, w->nodes.count) ||
      SYLVA__VEC_RESERVE(w->stem_top, sylva__canopy_room(w->stem_count)) ||
      sylva__conflicts_reserve(w, 0)) {
    w->reports = reports;
    return SYLVA_ENOMEM;
  }
  /* nothing fails from here on */
  int T = w->iteration;
  sylva__obstacle box = {.fp = NULL};
  memcpy(box.min, min, sizeof box.min);
  memcpy(box.max, max, sizeof box.max);
  size_t n = sylva__prune(w, &box, T, false, w->pruned_ids.data, &w->pruned_ids.len);
  if (!n) w->reports = reports; /* nothing cut: as it was */
  if (n) {
    sylva__light_collect(w, T + 1, NULL); /* as after a step's shedding */
    sylva__stems_light(w, w->q);
    /* the measures anew (stats.pruned goes on counting until the next step) */
    if (T == 0) {
      for (int k = 0; k < w->stem_count; k++) sylva__stats_planted(w, k);
      sylva__canopy(w);
      sylva__stand(w);
    } else
      sylva__stats(w, T);
  }
  sylva__conflicts(w, T);
  compact_nodes(w);
  SYLVA__CHECK_WORLD(w, SYLVA__BETWEEN_STEPS);
  if (removed) *removed = w->pruned_ids.data;
  if (removed_count) *removed_count = w->pruned_ids.len;
  return (int64_t)n;
}

int sylva_world_find_obstacle(const sylva_world *w, const char *label) {
  return sylva__grid_find_obstacle(&w->grid, label);
}

/* ---- step --------------------------------------------------------------------- */

void sylva_world_set_clock(sylva_world *w, double (*clock)(void *ctx), void *ctx) {
  w->def.clock = clock;
  w->def.clock_ctx = ctx;
}

static double now(const sylva_world *w) { return w->def.clock ? w->def.clock(w->def.clock_ctx) : 0.0; }

/* Grows one per-slot scratch array to n entries. */
static int grow_scratch(void **data, size_t n, size_t elem) {
  void *p = sylva__realloc(*data, n * elem);
  if (!p) return SYLVA_ENOMEM;
  *data = p;
  return SYLVA_OK;
}

static int reserve_scratch(sylva_world *w) {
  /* the live slots grouped by stem (radii, conflicts): its stems' firsts, and the
   * slots below with the rest */
  if (SYLVA__VEC_RESERVE(w->stem_nodes_first, (size_t)w->stem_count + 1)) return SYLVA_ENOMEM;
  size_t n = w->nodes.cap;
  /* the lit slots of a light pass under a site sky (sylva__light_collect) */
  if (w->grid.sky_count && SYLVA__VEC_RESERVE(w->lit, n)) return SYLVA_ENOMEM;
  if (n <= w->scratch_cap) return SYLVA_OK;
  if (SYLVA__VEC_RESERVE(w->stem_nodes, n) ||
      grow_scratch((void **)&w->light, n, sizeof *w->light) ||
      grow_scratch((void **)&w->q, n, sizeof *w->q) ||
      grow_scratch((void **)&w->pipe, n, sizeof *w->pipe))
    return SYLVA_ENOMEM;
  /* the later phases' views of light's block (world_impl.h) */
  _Static_assert(sizeof *w->light == sizeof *w->sap && sizeof *w->light == 2 * sizeof(int32_t),
                 "light's block holds a double or two int32s a slot");
  w->sap = w->light;
  w->leaves = w->canopy = w->remap = (int32_t *)(void *)w->light;
  w->scratch_cap = n;
  return SYLVA_OK;
}

int sylva__reserve_scratch(sylva_world *w) { return reserve_scratch(w); }

/* Room for everything the phases after the shoots write, so that from there on a
 * step cannot fail: per-slot scratch for the grown skeleton (with the grouping of
 * its slots by stem that radii and conflicts use), radius changes (at most
 * one per node born before T), shed roots (at most every node), the removal of
 * shed and pruned nodes (at most every node), the nodes added and the stats. */
static int reserve_rest(sylva_world *w) {
  size_t count = w->nodes.count;
  if (reserve_scratch(w) || sylva__reserve_removal(w) ||
      SYLVA__VEC_RESERVE(w->radii, w->mark.count) ||
      SYLVA__VEC_RESERVE(w->shed, count) ||
      SYLVA__VEC_RESERVE(w->added, count - w->mark.count) ||
      SYLVA__VEC_RESERVE(w->leaf_changes, count) ||
      SYLVA__VEC_RESERVE(w->stats, (size_t)w->stem_count) ||
      SYLVA__VEC_RESERVE(w->stem_top, sylva__canopy_room(w->stem_count)) ||
      sylva__conflicts_reserve(w, 0))
    return SYLVA_ENOMEM;
  return SYLVA_OK;
}

void sylva__group_by_stem(sylva_world *w) {
  const sylva__skeleton *s = &w->nodes;
  int32_t *first = w->stem_nodes_first.data;
  for (int k = 0; k <= w->stem_count; k++) first[k] = 0;
  for (size_t i = 0; i < s->count; i++)
    if (s->flags[i] & SYLVA__NODE_ALIVE) first[s->stem[i] + 1]++;
  for (int k = 0; k < w->stem_count; k++) first[k + 1] += first[k];
  for (size_t i = 0; i < s->count; i++)
    if (s->flags[i] & SYLVA__NODE_ALIVE) w->stem_nodes.data[first[s->stem[i]]++] = (int32_t)i;
  for (int k = w->stem_count; k > 0; k--) first[k] = first[k - 1];
  first[0] = 0;
}

static void node_info(const sylva_world *w, size_t slot, sylva_node_info *out) {
  const sylva__skeleton *s = &w->nodes;
  const sylva__stem *st = &w->stems[s->stem[slot]];
  out->id = s->id[slot];
  out->parent = s->parent[slot] >= 0 ? s->id[s->parent[slot]] : -1;
  out->plant = st->plant;
  out->stem = st->index;
  out->birth = s->birth[slot];
  out->x = s->x[slot];
  out->y = s->y[slot];
  out->z = s->z[slot];
  out->radius = s->radius[slot];
  out->leaves = sylva__node_leaves(w, slot);
}

/* The nodes born at T, the nodes whose leaves changed and the radius changes of
 * nodes still alive (room reserved). */
static void collect_journal(sylva_world *w, int T) {
  sylva__skeleton *s = &w->nodes;
  w->added.len = 0;
  w->leaf_changes.len = 0;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    int leaves = sylva__node_leaves(w, i);
    if (leaves != (int)s->leaves[i]) {
      SYLVA_ASSERT(w->leaf_changes.len < w->leaf_changes.cap);
      w->leaf_changes.data[w->leaf_changes.len++] = (sylva_leaf_change){s->id[i], leaves};
      s->leaves[i] = (uint16_t)leaves;
    }
    if (s->birth[i] != T) continue;
    SYLVA_ASSERT(w->added.len < w->added.cap);
    node_info(w, i, &w->added.data[w->added.len++]);
  }
  /* radii changes of nodes shed later in the same iteration are dropped: both lists
   * are in id order (ids increase with slots), so one walk finds each change's slot */
  size_t k = 0, slot = 0;
  for (size_t i = 0; i < w->radii.len; i++) {
    int32_t id = w->radii.data[i].id;
    while (slot < s->count && s->id[slot] < id) slot++;
    if (slot < s->count && s->id[slot] == id && (s->flags[slot] & SYLVA__NODE_ALIVE))
      w->radii.data[k++] = w->radii.data[i];
  }
  w->radii.len = k;
}

/* Phase 2: the stems whose growth equation stops at T, into finishing (room
 * reserved). Allocation gives them nothing; they are marked finished once the step
 * can no longer fail. */
static void stop_phase(sylva_world *w, int T) {
  w->finishing.len = 0;
  for (int s = 0; s < w->stem_count; s++) {
    const sylva__stem *st = &w->stems[s];
    if (!st->finished && !sylva__stem_dead(st) &&
        sylva__species_stops(&w->species[st->species], sylva__stem_local(st, T)))
      w->finishing.data[w->finishing.len++] = s;
  }
}

/* The phases after the shoots, which cannot fail once reserve_rest has succeeded. */
static int finish_step(sylva_world *w, int T) {
  sylva_journal *j = &w->journal;
  for (int k = 0; k < w->stem_count; k++) { /* the season's clocks (allocation) */
    w->stems[k].clock_prev = w->stems[k].clock;
    w->stems[k].clock = w->clock_next.data[k];
  }
  for (size_t k = 0; k < w->finishing.len; k++) w->stems[w->finishing.data[k]].finished = true;
  double t3 = now(w);
  int rc = sylva__radii(w, T);
  if (rc) return rc;
  SYLVA__CHECK_WORLD(w, SYLVA__AFTER_RADII);
  double t4 = now(w);
  j->phase_seconds[SYLVA_PHASE_RADII] = t4 - t3;

  rc = sylva__shed(w, T);
  if (rc) return rc;
  for (int k = 0; k < w->stem_count; k++) w->stems[k].stats.pruned = 0; /* counted anew at T */
  /* the zones entered by the nodes grown, before a prune cuts them: a branch cut
   * the iteration it grew in still dates the conflict, in every zone it reached */
  bool due = false;
  for (size_t i = 0; i < w->prunes.len; i++) due |= sylva__prune_due(&w->prunes.data[i], T);
  if (due) sylva__conflicts(w, T);
  bool pruned = false;
  for (size_t i = 0; i < w->prunes.len; i++) {
    const sylva_prune_def *d = &w->prunes.data[i];
    int slot = sylva__grid_obstacle_slot(&w->grid, d->zone);
    if (slot < 0 || !sylva__prune_due(d, T)) continue; /* the zone was removed */
    bool done = false; /* a zone two schedules name is cut once an iteration */
    for (size_t k = 0; k < i && !done; k++)
      done = w->prunes.data[k].zone == d->zone && sylva__prune_due(&w->prunes.data[k], T);
    if (done) continue;
    const sylva__obstacle *z = &w->grid.obstacles[slot];
    pruned |= sylva__prune(w, z, T, true, w->shed.data, &w->shed.len) > 0;
  }
  if (pruned) sylva__light_keep(w, T + 1); /* as after shedding */
  SYLVA__CHECK_WORLD(w, SYLVA__AFTER_SHEDDING);
  double t5 = now(w);
  j->phase_seconds[SYLVA_PHASE_SHEDDING] = t5 - t4;

  collect_journal(w, T);
  sylva__stats(w, T);
  sylva__conflicts(w, T);
  for (int s = 0; s < w->stem_count; s++) w->stats.data[s] = w->stems[s].stats;
  j->canopy_cover = w->canopy_cover;
  j->stand = w->stand;
  /* Keep the skeleton dense after every step: slots are node order, so queries
   * index live nodes directly. */
  compact_nodes(w);
  j->phase_seconds[SYLVA_PHASE_STATS] = now(w) - t5;
  return SYLVA_OK;
}

int sylva_world_step(sylva_world *w, const sylva_journal **journal) {
  if (journal) *journal = NULL;
  if (w->status) return w->status;
  if (sylva_world_finished(w)) return SYLVA_EFINISHED;
  /* Until the shoots are grown and room is made for the rest, a failure takes the
   * step back (take_back); after that nothing can fail. */
  if (reserve_scratch(w) || SYLVA__VEC_RESERVE(w->finishing, (size_t)w->stem_count))
    return SYLVA_ENOMEM;
  set_mark(w);
  int T = ++w->iteration;
  sylva_journal *j = &w->journal;
  memset(j, 0, sizeof *j);
  j->iteration = T;
  w->radii.len = w->shed.len = 0;

  double t0 = now(w);
  /* the pass after the last step's shedding, unless the world changed since */
  if (!sylva__light_kept(w, T)) sylva__light_collect(w, T, w->light);
  SYLVA__CHECK_WORLD(w, SYLVA__AFTER_LIGHT);
  double t1 = now(w);
  j->phase_seconds[SYLVA_PHASE_LIGHT] = t1 - t0;

  stop_phase(w, T);
  int rc = sylva__allocate(w, T);
  if (!rc) SYLVA__CHECK_WORLD(w, SYLVA__AFTER_ALLOCATION);
  double t2 = now(w);
  j->phase_seconds[SYLVA_PHASE_ALLOCATION] = t2 - t1;

  if (!rc) rc = sylva__shoots(w, T); /* records its shade time in the journal */
  if (!rc) rc = reserve_rest(w);
  if (rc) {
    take_back(w);
    SYLVA__CHECK_WORLD(w, SYLVA__BETWEEN_STEPS);
    return rc;
  }
  SYLVA__CHECK_WORLD(w, SYLVA__AFTER_SHOOTS);
  j->phase_seconds[SYLVA_PHASE_SHOOTS] = now(w) - t2 - j->phase_seconds[SYLVA_PHASE_SHADE];

  rc = finish_step(w, T);
  SYLVA_ASSERT(rc == SYLVA_OK); /* everything it needs was reserved */
  if (rc) return w->status = rc;
  SYLVA__CHECK_WORLD(w, SYLVA__BETWEEN_STEPS);

  j->added = w->added.data;
  j->added_count = w->added.len;
  j->radii = w->radii.data;
  j->radii_count = w->radii.len;
  j->leaves = w->leaf_changes.data;
  j->leaves_count = w->leaf_changes.len;
  j->shed = w->shed.data;
  j->shed_count = w->shed.len;
  j->stats = w->stats.data;
  j->stem_count = (size_t)w->stem_count;
  j->order = w->order.data;
  j->conflicts = sylva_world_conflicts(w);
  if (journal) *journal = j;
  return SYLVA_OK;
}

/* ---- queries ------------------------------------------------------------------ */

const sylva_world_def *sylva_world_get_def(const sylva_world *w) { return &w->def; }
int sylva_world_iteration(const sylva_world *w) { return w->iteration; }

bool sylva_world_finished(const sylva_world *w) {
  /* a dead stem is done once its snag fell: until then it still changes */
  for (int s = 0; s < w->stem_count; s++) {
    const sylva__stem *st = &w->stems[s];
    if (sylva__stem_dead(st) ? st->stats.fallen < 0 : !st->finished) return false;
  }
  return true;
}

/* Ids and indices from the caller are checked: a bad one is answered with NULL or
 * SYLVA_ENOTFOUND and nothing is read or written. */
static bool in_range(int i, int n) { return i >= 0 && i < n; }

int sylva_world_species_count(const sylva_world *w) { return w->species_count; }
const sylva_species_def *sylva_world_species(const sylva_world *w, int species) {
  return in_range(species, w->species_count) ? &w->species[species].given : NULL;
}
const char *sylva_world_species_label(const sylva_world *w, int species) {
  return in_range(species, w->species_count) ? w->species[species].label : NULL;
}
int sylva_world_plant_count(const sylva_world *w) { return w->plant_count; }
const char *sylva_world_plant_label(const sylva_world *w, int plant) {
  return in_range(plant, w->plant_count) ? w->plants[plant].label : NULL;
}
int sylva_world_plant_species(const sylva_world *w, int plant) {
  return in_range(plant, w->plant_count) ? w->plants[plant].species : SYLVA_ENOTFOUND;
}
int sylva_world_plant_stem_count(const sylva_world *w, int plant) {
  return in_range(plant, w->plant_count) ? w->plants[plant].stem_count : SYLVA_ENOTFOUND;
}
int sylva_world_stem_index(const sylva_world *w, int plant, int stem) {
  if (!in_range(plant, w->plant_count) || !in_range(stem, w->plants[plant].stem_count))
    return SYLVA_ENOTFOUND;
  return w->plants[plant].first_stem + stem;
}
int sylva_world_stem_count(const sylva_world *w) { return w->stem_count; }
int sylva_world_stem_root(const sylva_world *w, int stem, double root[3]) {
  if (!in_range(stem, w->stem_count)) return SYLVA_ENOTFOUND;
  memcpy(root, w->stems[stem].root, 3 * sizeof *root);
  return SYLVA_OK;
}
int sylva_world_stem_stats(const sylva_world *w, int stem, sylva_stem_stats *out) {
  if (!in_range(stem, w->stem_count)) return SYLVA_ENOTFOUND;
  *out = w->stems[stem].stats;
  return SYLVA_OK;
}
bool sylva_world_reports_conflicts(const sylva_world *w) { return w->reports; }

sylva_conflicts sylva_world_conflicts(const sylva_world *w) {
  return (sylva_conflicts){w->zone_stats.data, w->zone_stats.len, w->clear_stats.data,
                           w->clear_stats.len};
}

/* The first of n items of `size` bytes, sorted by their leading int32 stem, whose
 * stem is not below `stem`. */
static size_t first_of_stem(const void *items, size_t n, size_t size, int stem) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    int32_t at;
    memcpy(&at, (const char *)items + mid * size, sizeof at);
    if (at < stem) lo = mid + 1; else hi = mid;
  }
  return lo;
}

sylva_conflicts sylva_world_stem_conflicts(const sylva_world *w, int stem) {
  sylva_conflicts c = sylva_world_conflicts(w);
  size_t z = first_of_stem(c.zones, c.zone_count, sizeof *c.zones, stem), zn = 0;
  size_t k = first_of_stem(c.clearances, c.clearance_count, sizeof *c.clearances, stem), kn = 0;
  while (z + zn < c.zone_count && c.zones[z + zn].stem == stem) zn++;
  while (k + kn < c.clearance_count && c.clearances[k + kn].stem == stem) kn++;
  return (sylva_conflicts){c.zones + z, zn, c.clearances + k, kn};
}

int sylva_world_obstacle_count(const sylva_world *w) { return w->grid.obstacle_count; }
/* The def of a grid obstacle, its label pointing into the grid. */
static void obstacle_def(const sylva__obstacle *o, sylva_obstacle_def *out) {
  out->label = o->label;
  memcpy(out->min, o->min, sizeof out->min);
  memcpy(out->max, o->max, sizeof out->max);
  out->kind = o->zone ? SYLVA_OBSTACLE_ZONE : SYLVA_OBSTACLE_SOLID;
  out->footprint = o->fp ? sylva__footprint_view(o->fp) : (sylva_footprint){0};
}

int sylva_world_obstacle_at(const sylva_world *w, int i, int *id, sylva_obstacle_def *out) {
  if (!in_range(i, w->grid.obstacle_count)) return SYLVA_ENOTFOUND;
  const sylva__obstacle *o = sylva__grid_obstacle_at(&w->grid, i);
  if (id) *id = o->id;
  obstacle_def(o, out);
  return SYLVA_OK;
}

int sylva_world_obstacle(const sylva_world *w, int obstacle, sylva_obstacle_def *out) {
  int slot = sylva__grid_obstacle_slot(&w->grid, obstacle);
  if (slot < 0) return SYLVA_ENOTFOUND;
  obstacle_def(&w->grid.obstacles[slot], out);
  return SYLVA_OK;
}

size_t sylva_world_node_count(const sylva_world *w) { return w->nodes.live; }

int sylva_world_node_at(const sylva_world *w, size_t i, sylva_node_info *out) {
  if (i >= w->nodes.live) return SYLVA_ENOTFOUND;
  SYLVA_ASSERT(w->nodes.count == w->nodes.live);
  node_info(w, i, out); /* the skeleton is dense between steps: slot i is node i */
  return SYLVA_OK;
}

int64_t sylva_world_node_index(const sylva_world *w, int32_t id) {
  SYLVA_ASSERT(w->nodes.count == w->nodes.live);
  int32_t slot = sylva__skeleton_find(&w->nodes, id); /* slot i is node i */
  return slot >= 0 ? slot : SYLVA_ENOTFOUND;
}

double sylva_world_light_at(const sylva_world *w, const double p[3]) {
  int v[3];
  if (!sylva__grid_voxel(&w->grid, p[0], p[1], p[2], v)) return 0.0;
  /* 0 inside an obstacle too: a voxel inside one is below its top */
  return sylva__grid_light(&w->grid, v);
}

void sylva_world_dims(const sylva_world *w, int dims[3]) { memcpy(dims, w->grid.n, 3 * sizeof(int)); }

void sylva_world_memory(const sylva_world *w, sylva_memory *out) {
  out->voxels = sylva__grid_bytes(&w->grid);
  out->site = sylva__grid_site_bytes(&w->grid);
  out->skeleton = sylva__skeleton_bytes(&w->nodes);
  out->other = w->scratch_cap * 3 * sizeof(double) +
               (size_t)w->col_n[0] * (size_t)w->col_n[1] * sizeof(uint32_t) +
               ((size_t)w->col_n[0] * (size_t)w->col_n[1] + 7) / 8 +
               w->sprouts.cap * sizeof(sylva__sprout) + w->added.cap * sizeof(sylva_node_info) +
               w->leaf_changes.cap * sizeof(sylva_leaf_change) +
               w->radii.cap * sizeof(sylva_radius_change) +
               w->lit.cap * sizeof(sylva__lit) +
               (w->cells.cap + w->cell_start.cap) * sizeof(int32_t) + w->stamps.cap * sizeof(sylva__stamp) +
               w->stamp_lists.cap * sizeof(size_t) +
               (w->cell_first.cap + w->cell_items.cap + w->cell_of.cap + w->shed.cap +
                w->finishing.cap + w->caps.cap + w->stem_first.cap +
                w->stem_top.cap + w->axis.cap + w->work.cap) *
                   sizeof(int32_t) +
               (w->crown_bins.cap + w->work_r.cap + w->work_light.cap) * sizeof(double) +
               w->ranked.cap * sizeof(sylva__ranked) +
               w->cell_pos.cap * sizeof(float) +
               (size_t)w->stem_cap * sizeof(sylva__stem) +
               w->entered.cap * sizeof(sylva__entered) + w->prunes.cap * sizeof(sylva_prune_def) +
               w->zone_stats.cap * sizeof(sylva_zone_stat) +
               w->clear_stats.cap * sizeof(sylva_clearance_stat) +
               w->stem_box.cap * sizeof(sylva__box) + w->candidates.cap * sizeof(sylva__candidate) +
               (w->stem_nodes.cap + w->stem_nodes_first.cap + w->pruned_ids.cap) * sizeof(int32_t) +
               w->piece_sprouts.cap * sizeof(sylva__piece_sprouts);
  for (size_t p = 0; p < w->piece_sprouts.cap; p++)
    out->other += w->piece_sprouts.data[p].cap * sizeof(sylva__sprout);
}

static uint64_t fnv(uint64_t h, const void *data, size_t n) {
  const unsigned char *p = data;
  for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 0x100000001b3ULL;
  return h;
}

static inline uint32_t bits_of(float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  return u;
}

/* Hash 2's hash of one live node: its fields packed in five words, each mixed into
 * the last. */
static uint64_t node_hash2(const sylva__skeleton *s, size_t i) {
  uint32_t parent = (uint32_t)(s->parent[i] >= 0 ? s->id[s->parent[i]] : -1);
  uint64_t h = sylva__mix64(((uint64_t)(uint32_t)s->id[i] | (uint64_t)parent << 32) ^ 0x243f6a8885a308d3ULL);
  h = sylva__mix64(h ^ ((uint64_t)bits_of(s->x[i]) | (uint64_t)bits_of(s->y[i]) << 32));
  h = sylva__mix64(h ^ ((uint64_t)bits_of(s->z[i]) | (uint64_t)bits_of(s->radius[i]) << 32));
  h = sylva__mix64(h ^ ((uint64_t)(uint32_t)s->birth[i] | (uint64_t)(uint32_t)s->stem[i] << 32));
  return sylva__mix64(h ^ s->flags[i]);
}

/* The live nodes' hashes summed per piece of slots, then the pieces' sums: addition
 * mod 2^64 gives the same total however the slots are shared out, so the hash is
 * equal for every number of threads. */
#define HASH2_PIECES 64
typedef struct hash2_ctx {
  const sylva__skeleton *s;
  size_t grain;
  uint64_t sum[HASH2_PIECES], live[HASH2_PIECES];
} hash2_ctx;

static void hash2_piece(void *arg, size_t begin, size_t end) {
  hash2_ctx *c = arg;
  for (size_t b = begin; b < end; b += c->grain) {
    size_t e = b + c->grain < end ? b + c->grain : end;
    uint64_t sum = 0, live = 0;
    for (size_t i = b; i < e; i++) {
      if (!(c->s->flags[i] & SYLVA__NODE_ALIVE)) continue;
      sum += node_hash2(c->s, i);
      live++;
    }
    c->sum[b / c->grain] = sum;
    c->live[b / c->grain] = live;
  }
}

uint64_t sylva_world_hash_of(const sylva_world *w, int version) {
  if (version != 1 && version != 2) return 0;
  uint64_t h = 0xcbf29ce484222325ULL;
  h = fnv(h, &w->iteration, sizeof w->iteration);
  h = fnv(h, w->rng.s, sizeof w->rng.s);
  const sylva__skeleton *s = &w->nodes;
  if (version == 2) {
    hash2_ctx c = {.s = s, .grain = (s->count + HASH2_PIECES - 1) / HASH2_PIECES};
    if (c.grain < 4096) c.grain = 4096;
    sylva__pool_for(w->pool, s->count, c.grain, hash2_piece, &c);
    uint64_t sum = 0, live = 0;
    for (size_t k = 0; k * c.grain < s->count; k++) {
      sum += c.sum[k];
      live += c.live[k];
    }
    h = fnv(h, &live, sizeof live);
    h = fnv(h, &sum, sizeof sum);
  }
  for (size_t i = 0; version == 1 && i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    int32_t parent = s->parent[i] >= 0 ? s->id[s->parent[i]] : -1;
    h = fnv(h, &s->id[i], 4);
    h = fnv(h, &parent, 4);
    h = fnv(h, &s->x[i], 4);
    h = fnv(h, &s->y[i], 4);
    h = fnv(h, &s->z[i], 4);
    h = fnv(h, &s->radius[i], 4);
    h = fnv(h, &s->birth[i], 4);
    h = fnv(h, &s->stem[i], 4);
    h = fnv(h, &s->flags[i], 1);
  }
  for (int i = 0; i < w->stem_count; i++) {
    const sylva__stem *st = &w->stems[i];
    h = fnv(h, &st->finished, sizeof(bool));
    h = fnv(h, &st->stats.light, sizeof(double));
    /* a stem's clock, vigour and death where they are its own (docs/model.md, "Stands");
     * a stem that grows a season each season and lives hashes as before stands */
    double local = (double)(w->iteration - st->born);
    if (st->rate != 1.0 || st->clock != local || st->low || sylva__stem_dead(st)) {
      h = fnv(h, &st->clock, sizeof st->clock);
      h = fnv(h, &st->rate, sizeof st->rate);
      h = fnv(h, &st->low, sizeof st->low);
      h = fnv(h, &st->stats.died, sizeof st->stats.died);
      h = fnv(h, &st->stats.fallen, sizeof st->stats.fallen);
    }
  }
  for (int s = 0; s < w->grid.obstacle_slots; s++) {
    const sylva__obstacle *o = &w->grid.obstacles[s];
    if (!o->live || o->zone) continue; /* zones change nothing in the world */
    h = fnv(h, o->label, strlen(o->label));
    h = fnv(h, o->min, sizeof(double) * 3);
    h = fnv(h, o->max, sizeof(double) * 3);
    if (o->fp) {
      h = fnv(h, o->fp->ring_size, sizeof *o->fp->ring_size * (size_t)o->fp->ring_count);
      h = fnv(h, o->fp->pt, sizeof *o->fp->pt * (size_t)o->fp->point_count);
    }
  }
  return h;
}

uint64_t sylva_world_hash(const sylva_world *w) { return sylva_world_hash_of(w, 1); }
