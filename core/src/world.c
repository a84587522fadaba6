/* World lifecycle, plants and obstacles, the step that runs the phases, queries. */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "world_impl.h"

int sylva__vec_reserve(void **data, size_t *cap, size_t n, size_t elem) {
  if (n <= *cap) return SYLVA_OK;
  size_t c = *cap ? *cap : 16;
  while (c < n) c += c / 2 + 1;
  void *p = realloc(*data, c * elem);
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
  return total > SYLVA_MAX_VOXELS ? SYLVA_ETOOBIG : SYLVA_OK;
}

int sylva_world_create(const sylva_world_def *def, sylva_world **out) {
  *out = NULL;
  int rc = sylva_world_def_check(def);
  if (rc) return rc;
  sylva_world *w = calloc(1, sizeof *w);
  if (!w) return SYLVA_ENOMEM;
  w->def = *def;
  rc = sylva__grid_init(&w->grid, def->min, def->max, def->voxel);
  if (rc) {
    free(w);
    return rc;
  }
  sylva__rng_seed(&w->rng, def->seed);
  *out = w;
  return SYLVA_OK;
}

void sylva_world_destroy(sylva_world *w) {
  if (!w) return;
  sylva__grid_free(&w->grid);
  sylva__skeleton_free(&w->nodes);
  for (int i = 0; i < w->species_count; i++) free(w->species[i].age_pow);
  free(w->species);
  free(w->plants);
  free(w->plant_index);
  free(w->stems);
  free(w->light);
  free(w->q);
  free(w->pipe);
  free(w->leaves);
  free(w->remap);
  free(w->sprouts.data);
  free(w->order.data);
  free(w->axis.data);
  free(w->ranked.data);
  free(w->work.data);
  free(w->work_r.data);
  free(w->shoot.data);
  free(w->added.data);
  free(w->radii.data);
  free(w->shed.data);
  free(w->stats.data);
  free(w->caps.data);
  free(w->stem_first.data);
  free(w->cells.data);
  free(w->cell_first.data);
  free(w->cell_items.data);
  free(w->cell_pos.data);
  free(w->cell_of.data);
  free(w);
}

/* ---- species ---------------------------------------------------------------- */

static int first_t95(const sylva_equation *eq) {
  double target = 0.95 * sylva_equation_limit(eq);
  for (int t = 0; t < 1000000; t++)
    if (sylva_equation_value(eq, (double)t) >= target) return t;
  return INT_MAX;
}

int sylva_world_add_species(sylva_world *w, const sylva_species_def *def, const char *label) {
  if (!label || strlen(label) >= SYLVA_LABEL_MAX) return SYLVA_EINVAL;
  if (sylva_species_check(def, NULL)) return SYLVA_ERANGE;
  if (w->species_count == w->species_cap) {
    int cap = w->species_cap ? 2 * w->species_cap : 4;
    sylva__species *p = realloc(w->species, (size_t)cap * sizeof *p);
    if (!p) return SYLVA_ENOMEM;
    w->species = p;
    w->species_cap = cap;
  }
  sylva__species *sp = &w->species[w->species_count];
  memset(sp, 0, sizeof *sp);
  sp->def = *def;
  strcpy(sp->label, label);
  sp->t95 = first_t95(&def->growth);
  sp->shade_cache_t = -1;
  return w->species_count++;
}

double sylva__species_b(const sylva__species *sp, int t) {
  const sylva_species_def *d = &sp->def;
  if (t <= d->tau) return d->b_min;
  if (t >= sp->t95) return d->b_max;
  return d->b_min + (d->b_max - d->b_min) * (double)(t - d->tau) / (double)(sp->t95 - d->tau);
}

const sylva__pyramid *sylva__species_shade(sylva__species *sp, int t) {
  if (sp->shade_cache_t != t) {
    sylva__pyramid *p = &sp->shade;
    double b = sylva__species_b(sp, t);
    p->depth = sp->def.pyramid_depth;
    for (int q = 1; q <= p->depth; q++) {
      p->w[q - 1] = (int64_t)floor(pow(b, -(double)q) * SYLVA__SHADE_ONE + 0.5);
      p->half[q - 1] = (int)floor((double)q * sp->def.shade_spread);
    }
    p->column = (int64_t)floor(sp->def.shade_column * SYLVA__SHADE_ONE + 0.5);
    sp->shade_cache_t = t;
  }
  return &sp->shade;
}

double sylva__species_age_pow(sylva__species *sp, int age) {
  if (age >= sp->age_pow_n) {
    int n = age + 64;
    double *p = realloc(sp->age_pow, (size_t)n * sizeof *p);
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
  (void)inside; /* nodes are only stored at positions whose voxel is inside */
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
    if (lateral)
      w->nodes.lateral_child[parent] = slot;
    else
      w->nodes.axis_child[parent] = slot;
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

int sylva__index_plant(sylva_world *w, int p) {
  if (2 * (size_t)(w->plant_count + 1) > w->plant_index_cap) {
    size_t cap = w->plant_index_cap ? 2 * w->plant_index_cap : 16;
    while (cap < 2 * (size_t)(w->plant_count + 1)) cap *= 2;
    int32_t *idx = malloc(cap * sizeof *idx);
    if (!idx) return SYLVA_ENOMEM;
    for (size_t i = 0; i < cap; i++) idx[i] = -1;
    free(w->plant_index);
    w->plant_index = idx;
    w->plant_index_cap = cap;
    for (int i = 0; i < w->plant_count; i++)
      if (i != p) sylva__index_plant(w, i); /* cannot fail: the table is large enough */
  }
  size_t mask = w->plant_index_cap - 1, h = label_hash(w->plants[p].label) & mask;
  while (w->plant_index[h] >= 0) h = (h + 1) & mask;
  w->plant_index[h] = p;
  return SYLVA_OK;
}

static int check_trunk(const sylva_world *w, const sylva_species_def *sp, const double root[3],
                       int (*taken)[3], int ntaken, int *nout, int (*out)[3]) {
  int count = 0;
  for (int k = 0; k <= sp->initial_nodes; k++) {
    double p[3] = {root[0], root[1], root[2] + sp->rho * k};
    int v[3];
    float f[3];
    if (!sylva__voxel_of(w, p, f, v)) return SYLVA_EOUTSIDE;
    if (sylva__grid_blocked(&w->grid, v)) return SYLVA_EBLOCKED;
    if (sylva__grid_occupant(&w->grid, v) >= 0) return SYLVA_EOCCUPIED;
    for (int i = 0; i < ntaken; i++)
      if (taken[i][0] == v[0] && taken[i][1] == v[1] && taken[i][2] == v[2]) return SYLVA_EOCCUPIED;
    memcpy(out[count++], v, sizeof v);
  }
  *nout = count;
  return SYLVA_OK;
}

int sylva_world_add_plant(sylva_world *w, const sylva_plant_def *def, int *bad_root) {
  if (bad_root) *bad_root = -1;
  if (w->status) return w->status;
  if (!def || def->species < 0 || def->species >= w->species_count || def->root_count < 1 ||
      !def->roots || !def->label || !def->label[0] || strlen(def->label) >= SYLVA_LABEL_MAX)
    return SYLVA_EINVAL;
  if (sylva__find_plant(w, def->label) >= 0) return SYLVA_EINVAL;
  if (w->stem_count + def->root_count > SYLVA_MAX_STEMS) return SYLVA_ETOOBIG;
  const sylva_species_def *sp = &w->species[def->species].def;
  /* Check every trunk before changing anything: the voxels of earlier roots of the
   * same plant count as taken by another stem. */
  size_t per = (size_t)sp->initial_nodes + 1;
  int(*taken)[3] = malloc((size_t)def->root_count * per * sizeof *taken);
  if (!taken) return SYLVA_ENOMEM;
  int ntaken = 0;
  for (int r = 0; r < def->root_count; r++) {
    int n = 0;
    int rc = check_trunk(w, sp, def->roots[r], taken, ntaken, &n, taken + ntaken);
    if (rc) {
      free(taken);
      if (bad_root) *bad_root = r;
      return rc;
    }
    ntaken += n;
  }
  free(taken);
  if (w->plant_count == w->plant_cap) {
    int cap = w->plant_cap ? 2 * w->plant_cap : 8;
    sylva__plant *p = realloc(w->plants, (size_t)cap * sizeof *p);
    if (!p) return SYLVA_ENOMEM;
    w->plants = p;
    w->plant_cap = cap;
  }
  if (w->stem_count + def->root_count > w->stem_cap) {
    int cap = w->stem_cap ? w->stem_cap : 8;
    while (cap < w->stem_count + def->root_count) cap *= 2;
    sylva__stem *p = realloc(w->stems, (size_t)cap * sizeof *p);
    if (!p) return SYLVA_ENOMEM;
    w->stems = p;
    w->stem_cap = cap;
  }
  if (sylva__skeleton_reserve(&w->nodes, (size_t)def->root_count * per)) return SYLVA_ENOMEM;
  int pid = w->plant_count;
  sylva__plant *pl = &w->plants[pid];
  memset(pl, 0, sizeof *pl);
  strcpy(pl->label, def->label);
  if (sylva__index_plant(w, pid)) return SYLVA_ENOMEM;
  w->plant_count++;
  pl->species = def->species;
  pl->first_stem = w->stem_count;
  pl->stem_count = def->root_count;
  for (int r = 0; r < def->root_count; r++) {
    int s = w->stem_count++;
    sylva__stem *st = &w->stems[s];
    memset(st, 0, sizeof *st);
    st->plant = pid;
    st->index = r;
    st->species = def->species;
    st->born = w->iteration;
    memcpy(st->root, def->roots[r], sizeof st->root);
    int32_t prev = -1;
    for (int k = 0; k <= sp->initial_nodes; k++) {
      double p[3] = {st->root[0], st->root[1], st->root[2] + sp->rho * k};
      int32_t slot = sylva__add_node(w, prev, false, p, s, w->iteration);
      if (slot < 0) return w->status = slot; /* checked above: only memory can fail */
      if (k == 0) st->root_slot = slot;
      int rc = sylva__shade_node(w, slot, +1);
      if (rc) return w->status = rc;
      prev = slot;
    }
  }
  for (int r = 0; r < def->root_count; r++) sylva__stats_planted(w, pl->first_stem + r);
  return pid;
}

int sylva_world_add_obstacle(sylva_world *w, const sylva_obstacle_def *def) {
  if (w->status) return w->status;
  return sylva__grid_add_obstacle(&w->grid, def->label, def->min, def->max);
}

int sylva_world_remove_obstacle(sylva_world *w, int obstacle) {
  if (w->status) return w->status;
  return sylva__grid_remove_obstacle(&w->grid, obstacle);
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

static int reserve_scratch(sylva_world *w) {
  size_t n = w->nodes.cap;
  if (n <= w->scratch_cap) return SYLVA_OK;
  double *l = realloc(w->light, n * sizeof *l);
  if (!l) return SYLVA_ENOMEM;
  w->light = l;
  double *q = realloc(w->q, n * sizeof *q);
  if (!q) return SYLVA_ENOMEM;
  w->q = q;
  double *p = realloc(w->pipe, n * sizeof *p);
  if (!p) return SYLVA_ENOMEM;
  w->pipe = p;
  int32_t *leaves = realloc(w->leaves, n * sizeof *leaves);
  if (!leaves) return SYLVA_ENOMEM;
  w->leaves = leaves;
  int32_t *remap = realloc(w->remap, n * sizeof *remap);
  if (!remap) return SYLVA_ENOMEM;
  w->remap = remap;
  w->scratch_cap = n;
  return SYLVA_OK;
}

int sylva__reserve_scratch(sylva_world *w) { return reserve_scratch(w); }

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
}

static int collect_journal(sylva_world *w, int T) {
  sylva__skeleton *s = &w->nodes;
  w->added.len = 0;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE) || s->birth[i] != T) continue;
    if (SYLVA__VEC_RESERVE(w->added, w->added.len + 1)) return SYLVA_ENOMEM;
    node_info(w, i, &w->added.data[w->added.len++]);
  }
  /* radii changes of nodes shed later in the same iteration are dropped */
  size_t k = 0;
  for (size_t i = 0; i < w->radii.len; i++)
    if (sylva__skeleton_find(s, w->radii.data[i].id) >= 0) w->radii.data[k++] = w->radii.data[i];
  w->radii.len = k;
  return SYLVA_OK;
}

int sylva_world_step(sylva_world *w, const sylva_journal **journal) {
  if (journal) *journal = NULL;
  if (w->status) return w->status;
  if (sylva_world_finished(w)) return SYLVA_EFINISHED;
  int T = ++w->iteration;
  sylva_journal *j = &w->journal;
  memset(j, 0, sizeof *j);
  j->iteration = T;
  w->radii.len = w->shed.len = 0;
  int rc = reserve_scratch(w);
  if (rc) return w->status = rc;

  double t0 = now(w);
  sylva__light_collect(w, T, w->light);
  double t1 = now(w);
  j->phase_seconds[SYLVA_PHASE_LIGHT] = t1 - t0;

  for (int s = 0; s < w->stem_count; s++) {
    sylva__stem *st = &w->stems[s];
    st->stats.shed = 0;
    if (!st->finished &&
        sylva_equation_stops(&w->species[st->species].def.growth, sylva__stem_local(st, T)))
      st->finished = true;
  }
  rc = sylva__allocate(w, T);
  if (rc) return w->status = rc;
  double t2 = now(w);
  j->phase_seconds[SYLVA_PHASE_ALLOCATION] = t2 - t1;

  rc = sylva__shoots(w, T); /* records its shade time in the journal */
  if (rc) return w->status = rc;
  double t3 = now(w);
  j->phase_seconds[SYLVA_PHASE_SHOOTS] = t3 - t2 - j->phase_seconds[SYLVA_PHASE_SHADE];

  rc = reserve_scratch(w);
  if (rc) return w->status = rc;
  rc = sylva__radii(w, T);
  if (rc) return w->status = rc;
  double t4 = now(w);
  j->phase_seconds[SYLVA_PHASE_RADII] = t4 - t3;

  rc = sylva__shed(w, T);
  if (rc) return w->status = rc;
  double t5 = now(w);
  j->phase_seconds[SYLVA_PHASE_SHEDDING] = t5 - t4;

  rc = collect_journal(w, T);
  if (rc) return w->status = rc;
  sylva__stats(w, T);
  if (SYLVA__VEC_RESERVE(w->stats, (size_t)w->stem_count)) return w->status = SYLVA_ENOMEM;
  for (int s = 0; s < w->stem_count; s++) w->stats.data[s] = w->stems[s].stats;
  /* Keep the skeleton dense after every step: slots are node order, so queries
   * index live nodes directly. */
  if (w->nodes.count != w->nodes.live) {
    sylva__skeleton_compact(&w->nodes, w->remap);
    for (int s = 0; s < w->stem_count; s++) w->stems[s].root_slot = w->remap[w->stems[s].root_slot];
  }
  j->phase_seconds[SYLVA_PHASE_STATS] = now(w) - t5;

  j->added = w->added.data;
  j->added_count = w->added.len;
  j->radii = w->radii.data;
  j->radii_count = w->radii.len;
  j->shed = w->shed.data;
  j->shed_count = w->shed.len;
  j->stats = w->stats.data;
  j->stem_count = (size_t)w->stem_count;
  j->order = w->order.data;
  if (journal) *journal = j;
  return SYLVA_OK;
}

/* ---- queries ------------------------------------------------------------------ */

const sylva_world_def *sylva_world_get_def(const sylva_world *w) { return &w->def; }
int sylva_world_iteration(const sylva_world *w) { return w->iteration; }

bool sylva_world_finished(const sylva_world *w) {
  for (int s = 0; s < w->stem_count; s++)
    if (!w->stems[s].finished) return false;
  return true;
}

int sylva_world_species_count(const sylva_world *w) { return w->species_count; }
const sylva_species_def *sylva_world_species(const sylva_world *w, int species) {
  return &w->species[species].def;
}
const char *sylva_world_species_label(const sylva_world *w, int species) {
  return w->species[species].label;
}
int sylva_world_plant_count(const sylva_world *w) { return w->plant_count; }
const char *sylva_world_plant_label(const sylva_world *w, int plant) { return w->plants[plant].label; }
int sylva_world_plant_species(const sylva_world *w, int plant) { return w->plants[plant].species; }
int sylva_world_plant_stem_count(const sylva_world *w, int plant) {
  return w->plants[plant].stem_count;
}
int sylva_world_stem_index(const sylva_world *w, int plant, int stem) {
  return w->plants[plant].first_stem + stem;
}
int sylva_world_stem_count(const sylva_world *w) { return w->stem_count; }
void sylva_world_stem_root(const sylva_world *w, int stem, double root[3]) {
  memcpy(root, w->stems[stem].root, 3 * sizeof *root);
}
void sylva_world_stem_stats(const sylva_world *w, int stem, sylva_stem_stats *out) {
  *out = w->stems[stem].stats;
}
int sylva_world_obstacle_count(const sylva_world *w) { return w->grid.obstacle_count; }
void sylva_world_obstacle_at(const sylva_world *w, int i, int *id, sylva_obstacle_def *out) {
  const sylva__obstacle *o = &w->grid.obstacles[i];
  if (id) *id = o->id;
  out->label = o->label;
  memcpy(out->min, o->min, sizeof out->min);
  memcpy(out->max, o->max, sizeof out->max);
}

size_t sylva_world_node_count(const sylva_world *w) { return w->nodes.live; }

void sylva_world_node_at(const sylva_world *w, size_t i, sylva_node_info *out) {
  node_info(w, i, out); /* the skeleton is dense between steps: slot i is node i */
}

double sylva_world_light_at(const sylva_world *w, const double p[3]) {
  int v[3];
  if (!sylva__grid_voxel(&w->grid, p[0], p[1], p[2], v)) return 0.0;
  if (sylva__grid_blocked(&w->grid, v)) return 0.0;
  return sylva__grid_light(&w->grid, v);
}

void sylva_world_dims(const sylva_world *w, int dims[3]) { memcpy(dims, w->grid.n, 3 * sizeof(int)); }

void sylva_world_memory(const sylva_world *w, sylva_memory *out) {
  out->voxels = sylva__grid_bytes(&w->grid);
  out->skeleton = sylva__skeleton_bytes(&w->nodes);
  out->other = w->scratch_cap * (3 * sizeof(double) + 2 * sizeof(int32_t)) +
               w->sprouts.cap * sizeof(sylva__sprout) + w->added.cap * sizeof(sylva_node_info) +
               w->radii.cap * sizeof(sylva_radius_change) +
               w->cells.cap * sizeof(sylva__keyed) +
               (w->cell_first.cap + w->cell_items.cap + w->cell_of.cap) * sizeof(int32_t) +
               w->cell_pos.cap * sizeof(float) +
               (size_t)w->stem_cap * sizeof(sylva__stem);
}

static uint64_t fnv(uint64_t h, const void *data, size_t n) {
  const unsigned char *p = data;
  for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 0x100000001b3ULL;
  return h;
}

uint64_t sylva_world_hash(const sylva_world *w) {
  uint64_t h = 0xcbf29ce484222325ULL;
  h = fnv(h, &w->iteration, sizeof w->iteration);
  h = fnv(h, w->rng.s, sizeof w->rng.s);
  const sylva__skeleton *s = &w->nodes;
  for (size_t i = 0; i < s->count; i++) {
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
    h = fnv(h, &w->stems[i].finished, sizeof(bool));
    h = fnv(h, &w->stems[i].stats.light, sizeof(double));
  }
  for (int i = 0; i < w->grid.obstacle_count; i++) {
    h = fnv(h, w->grid.obstacles[i].label, strlen(w->grid.obstacles[i].label));
    h = fnv(h, w->grid.obstacles[i].min, sizeof(double) * 3);
    h = fnv(h, w->grid.obstacles[i].max, sizeof(double) * 3);
  }
  return h;
}
