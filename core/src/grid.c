#include "grid.h"
#include "prism.h"

#include <limits.h>
#include <math.h>
#include <stdatomic.h>
#include <string.h>

#include "alloc.h"
#include "site.h"

int sylva__grid_init(sylva__grid *g, const double min[3], const double max[3], double voxel) {
  memset(g, 0, sizeof *g);
  if (!(voxel > 0.0) || !isfinite(voxel)) return SYLVA_EINVAL;
  double total = 1.0;
  for (int a = 0; a < 3; a++) {
    if (!isfinite(min[a]) || !isfinite(max[a]) || !(max[a] > min[a])) return SYLVA_EINVAL;
    double cells = ceil((max[a] - min[a]) / voxel - 1e-9);
    if (cells < 1.0) cells = 1.0;
    if (cells > (double)(1 << 24)) return SYLVA_ETOOBIG;
    total *= cells;
    g->n[a] = (int)cells;
    g->c[a] = (g->n[a] + SYLVA__CHUNK - 1) / SYLVA__CHUNK;
    g->min[a] = min[a];
    g->max[a] = max[a];
  }
  if (total > SYLVA_MAX_VOXELS) return SYLVA_ETOOBIG;
  g->voxel = voxel;
  g->inv_voxel = 1.0 / voxel;
  size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
  size_t ncols = (size_t)g->c[0] * (size_t)g->c[1];
  g->chunks = sylva__calloc(nchunks, sizeof *g->chunks);
  g->occ = sylva__calloc(nchunks, sizeof *g->occ);
  g->colsum = sylva__calloc(nchunks, sizeof *g->colsum);
  g->colsum_top = sylva__calloc(ncols, sizeof *g->colsum_top);
  if (!g->chunks || !g->occ || !g->colsum || !g->colsum_top) {
    sylva__grid_free(g);
    return SYLVA_ENOMEM;
  }
  return SYLVA_OK;
}

void sylva__grid_free(sylva__grid *g) {
  if (g->occ) {
    size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
    for (size_t i = 0; i < nchunks; i++) sylva__free(g->occ[i]);
  }
  while (g->slabs) {
    sylva__slab *next = g->slabs->next;
    sylva__free(g->slabs);
    g->slabs = next;
  }
  if (g->colsum) {
    size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
    for (size_t i = 0; i < nchunks; i++) sylva__free(g->colsum[i]);
  }
  if (g->obstacle_cols) {
    size_t ncols = (size_t)g->c[0] * (size_t)g->c[1];
    for (size_t i = 0; i < ncols; i++) sylva__free(g->obstacle_cols[i]);
  }
  for (int s = 0; s < g->obstacle_slots; s++) sylva__footprint_free(g->obstacles[s].fp);
  if (g->site) {
    size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
    for (size_t i = 0; i < nchunks; i++) sylva__free(g->site->chunk[i]);
    sylva__free(g->site->chunk);
  }
  sylva__free(g->site);
  sylva__free(g->sky);
  sylva__free(g->chunks);
  sylva__free(g->occ);
  sylva__free(g->colsum);
  sylva__free(g->colsum_top);
  sylva__free(g->obstacles);
  sylva__free(g->obstacle_rank);
  sylva__free(g->label_slot);
  sylva__free(g->obstacle_cols);
  memset(g, 0, sizeof *g);
}

size_t sylva__grid_site_bytes(const sylva__grid *g) {
  size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
  return g->site ? nchunks * sizeof(float *) + g->site->count * SYLVA__CHUNK_VOXELS * sizeof(float)
                 : 0;
}

size_t sylva__grid_bytes(const sylva__grid *g) {
  size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
  size_t ncols = (size_t)g->c[0] * (size_t)g->c[1];
  return 3 * nchunks * sizeof(void *) + ncols * sizeof(int32_t) + g->chunk_count * sizeof(sylva__chunk) +
         g->occ_bytes +
         g->colsum_count * 256 * sizeof(int64_t) +
         (size_t)g->obstacle_cap * (sizeof(sylva__obstacle) + sizeof(int32_t)) +
         (g->obstacle_rank ? sizeof(int32_t) : 0) + (size_t)g->label_cap * sizeof(int32_t) +
         (g->obstacle_cols ? ncols * sizeof(void *) : 0) + g->obstacle_list_bytes + g->footprint_bytes +
         (size_t)g->sky_count * sizeof(sylva_sky_dir) + sylva__grid_site_bytes(g);
}

bool sylva__grid_voxel(const sylva__grid *g, double x, double y, double z, int v[3]) {
  double p[3] = {x, y, z};
  for (int a = 0; a < 3; a++) {
    double f = floor((p[a] - g->min[a]) / g->voxel);
    if (!(f >= 0.0) || f >= (double)g->n[a]) return false;
    v[a] = (int)f;
  }
  return true;
}

static inline size_t chunk_index(const sylva__grid *g, int cx, int cy, int cz) {
  return sylva__grid_chunk_index(g, cx, cy, cz);
}

static inline int local_index(int x, int y, int z) {
  return (x & (SYLVA__CHUNK - 1)) | ((y & (SYLVA__CHUNK - 1)) << 4) |
         ((z & (SYLVA__CHUNK - 1)) << 8);
}

/* Drops the cached site factors (obstacles changed; the caller keeps sky_top). */
static void site_forget(sylva__grid *g) {
  if (!g->site) return;
  size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
  for (size_t i = 0; i < nchunks && g->site->count; i++)
    if (g->site->chunk[i]) {
      sylva__free(g->site->chunk[i]);
      g->site->chunk[i] = NULL;
      g->site->count--;
    }
}

int sylva__grid_set_sky(sylva__grid *g, const sylva_sky_dir *dirs, int count) {
  if (count <= 0) return SYLVA_OK;
  size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
  sylva_sky_dir *sky = sylva__calloc((size_t)count, sizeof *sky);
  sylva__site_cache *site = sylva__calloc(1, sizeof *site);
  sylva__site_factor_t **chunk = sylva__calloc(nchunks, sizeof *chunk);
  if (!sky || !site || !chunk) {
    sylva__free(sky);
    sylva__free(site);
    sylva__free(chunk);
    return SYLVA_ENOMEM;
  }
  memcpy(sky, dirs, (size_t)count * sizeof *sky);
  site->chunk = chunk;
  g->sky = sky;
  g->sky_count = count;
  g->site = site;
  g->sky_top = sylva__site_top(g);
  return SYLVA_OK;
}

static sylva__site_factor_t *site_chunk_make(const sylva__grid *g, size_t ci) {
  sylva__site_factor_t *f = sylva__malloc(SYLVA__CHUNK_VOXELS * sizeof *f);
  if (!f) return NULL;
  for (int i = 0; i < SYLVA__CHUNK_VOXELS; i++) atomic_init(&f[i], -1.0f);
  g->site->chunk[ci] = f;
  g->site->count++;
  return f;
}

/* The factor of voxel v in its chunk's cache f (NULL: none, computed unkept). */
static double site_factor_in(const sylva__grid *g, sylva__site_factor_t *f, const int v[3]) {
  if (!f) return (float)sylva__site_factor(g, g->sky, g->sky_count, g->sky_top, v);
  sylva__site_factor_t *at = &f[local_index(v[0], v[1], v[2])];
  float x = atomic_load_explicit(at, memory_order_relaxed);
  if (x < 0.0f) {
    x = (float)sylva__site_factor(g, g->sky, g->sky_count, g->sky_top, v);
    atomic_store_explicit(at, x, memory_order_relaxed);
  }
  return x;
}

double sylva__grid_site_factor(const sylva__grid *g, const int v[3]) {
  if (!g->sky_count) return 1.0;
  size_t ci = chunk_index(g, v[0] >> 4, v[1] >> 4, v[2] >> 4);
  sylva__site_factor_t *f = g->site->chunk[ci];
  if (!f) f = site_chunk_make(g, ci); /* each factor computed when first read */
  return site_factor_in(g, f, v);
}

bool sylva__grid_site_reserve(const sylva__grid *g, const int v[3]) {
  if (!g->sky_count) return true;
  size_t ci = chunk_index(g, v[0] >> 4, v[1] >> 4, v[2] >> 4);
  return g->site->chunk[ci] || site_chunk_make(g, ci);
}

static inline const sylva__chunk *chunk_at(const sylva__grid *g, const int v[3]) {
  return g->chunks[chunk_index(g, v[0] >> 4, v[1] >> 4, v[2] >> 4)];
}

/* A zeroed chunk from the newest slab, or a new slab twice the last's size. The
 * chunks sit in ordinary 4 KB pages: in huge pages (madvise) a new page cost this
 * VM 0.4-0.9 s of the 100-tree stand, and the hectare was no faster
 * (docs/performance.md, "4 KB pages"). */
static sylva__chunk *chunk_new(sylva__grid *g) {
  sylva__slab *s = g->slabs;
  if (!s || s->used == s->count) {
    const uintptr_t page = 4096;
    size_t n = s ? 2 * s->count : 4;
    if (n > 128) n = 128;
    size_t bytes = sizeof *s + page + n * sizeof(sylva__chunk);
    s = sylva__calloc(1, bytes); /* untouched pages: the slack costs no memory */
    if (!s) return NULL;
    s->chunk = (sylva__chunk *)(((uintptr_t)(s + 1) + page - 1) & ~(page - 1));
    s->count = n;
    s->next = g->slabs;
    g->slabs = s;
  }
  return &s->chunk[s->used++];
}

static sylva__chunk *chunk_get(sylva__grid *g, int cx, int cy, int cz) {
  sylva__chunk **slot = &g->chunks[chunk_index(g, cx, cy, cz)];
  if (!*slot) {
    *slot = chunk_new(g);
    if (!*slot) return NULL;
    g->chunk_count++;
  }
  return *slot;
}

/* The block sum of chunk (cx, cy, cz), made when a column first starts in it. */
static int64_t *colsum_get(sylva__grid *g, int cx, int cy, int cz) {
  int64_t **slot = &g->colsum[chunk_index(g, cx, cy, cz)];
  if (!*slot) {
    *slot = sylva__calloc(256, sizeof **slot);
    if (!*slot) return NULL;
    g->colsum_count++;
  }
  return *slot;
}

/* The obstacles over voxel v's chunk column, or NULL. */
static inline const sylva__obstacle_list *obstacles_over(const sylva__grid *g, const int v[3]) {
  if (!g->obstacle_cols) return NULL;
  return g->obstacle_cols[(size_t)(v[1] >> 4) * (size_t)g->c[0] + (size_t)(v[0] >> 4)];
}

bool sylva__grid_blocked(const sylva__grid *g, const int v[3]) {
  const sylva__obstacle_list *l = obstacles_over(g, v);
  if (!l) return false;
  for (int32_t i = 0; i < l->count; i++) {
    const sylva__obstacle_box *o = &l->box[i];
    if (v[0] >= o->lo[0] && v[0] < o->hi[0] && v[1] >= o->lo[1] && v[1] < o->hi[1] &&
        v[2] >= o->lo[2] && v[2] < o->hi[2])
      return true;
  }
  return false;
}

bool sylva__grid_under_obstacle(const sylva__grid *g, const int v[3]) {
  const sylva__obstacle_list *l = obstacles_over(g, v);
  if (!l) return false;
  for (int32_t i = 0; i < l->count; i++) {
    const sylva__obstacle_box *o = &l->box[i];
    if (v[0] >= o->lo[0] && v[0] < o->hi[0] && v[1] >= o->lo[1] && v[1] < o->hi[1] &&
        v[2] < o->hi[2])
      return true;
  }
  return false;
}

/* The row of chunk c that voxel v's shade sums (x = 0 up to v's, stride 16). */
static inline const int64_t *shade_row(const sylva__chunk *c, const int v[3]) {
  return c->shade + ((v[2] & 15) << 8) + (v[1] & 15);
}

/* Shade of voxel v given its chunk c (may be NULL). */
static int64_t shade_in(const sylva__grid *g, const sylva__chunk *c, const int v[3]) {
  int64_t s = 0;
  if (c) {
    const int64_t *row = shade_row(c, v);
    for (int x = 0; x <= (v[0] & 15); x++) s += row[x << 4];
  }
  /* the block sums above, up to the highest a column starts in */
  size_t ci = (size_t)(v[1] >> 4) * (size_t)g->c[0] + (size_t)(v[0] >> 4);
  size_t plane = (size_t)g->c[0] * (size_t)g->c[1];
  for (int b = (v[2] >> 4) + 1; b <= g->colsum_top[ci]; b++) {
    const int64_t *sum = g->colsum[(size_t)b * plane + ci];
    if (!sum) continue;
    const int64_t *row = sum + (v[1] & 15);
    for (int x = 0; x <= (v[0] & 15); x++) s += row[x << 4];
  }
  return s;
}

int64_t sylva__grid_shade_raw(const sylva__grid *g, const int v[3]) {
  return shade_in(g, chunk_at(g, v), v);
}

/* shared: never allocates (the site factor unkept where its chunk has no cache). */
static double light_in(const sylva__grid *g, const sylva__chunk *c, const int v[3], bool shared) {
  if (g->sky_count) { /* a site's sky: what reaches the voxel, under the plants' shade */
    double l = 1.0 - (double)shade_in(g, c, v) / SYLVA__SHADE_ONE;
    if (!(l > 0.0)) return 0.0;
    if (!shared) return sylva__grid_site_factor(g, v) * l;
    size_t ci = chunk_index(g, v[0] >> 4, v[1] >> 4, v[2] >> 4);
    return site_factor_in(g, g->site->chunk[ci], v) * l;
  }
  if (g->obstacle_count && sylva__grid_under_obstacle(g, v)) return 0.0;
  double l = 1.0 - (double)shade_in(g, c, v) / SYLVA__SHADE_ONE;
  return l > 0.0 ? l : 0.0;
}

double sylva__grid_light(const sylva__grid *g, const int v[3]) {
  return light_in(g, chunk_at(g, v), v, false);
}

double sylva__grid_light_shared(const sylva__grid *g, const int v[3]) {
  return light_in(g, chunk_at(g, v), v, true);
}

/* ---- occupancy ------------------------------------------------------------------ */

static inline uint32_t occ_home(const sylva__occ *o, int i) {
  return ((uint32_t)i * 0x9E3779B1u) & (o->cap - 1);
}

/* The slot of local voxel i in table o, or the empty slot where it would go. */
static inline uint32_t occ_find(const sylva__occ *o, int i) {
  uint64_t key = (uint64_t)(i + 1) << 32;
  uint32_t k = occ_home(o, i);
  while (o->slot[k] && (o->slot[k] & 0xFFFFFFFF00000000ULL) != key) k = (k + 1) & (o->cap - 1);
  return k;
}

/* The occupancy word of voxel v (0: free). */
static inline uint32_t occ_word(const sylva__grid *g, const int v[3]) {
  const sylva__occ *o = g->occ[chunk_index(g, v[0] >> 4, v[1] >> 4, v[2] >> 4)];
  return o ? (uint32_t)o->slot[occ_find(o, local_index(v[0], v[1], v[2]))] : 0;
}

/* A table of cap slots holding o's entries (o NULL: none); NULL without memory. */
static sylva__occ *occ_table(sylva__grid *g, const sylva__occ *o, uint32_t cap) {
  sylva__occ *t = sylva__calloc(1, sizeof *t + (size_t)cap * sizeof t->slot[0]);
  if (!t) return NULL;
  t->cap = cap;
  g->occ_bytes += sizeof *t + (size_t)cap * sizeof t->slot[0];
  if (o)
    for (uint32_t k = 0; k < o->cap; k++)
      if (o->slot[k]) {
        int i = (int)(o->slot[k] >> 32) - 1;
        t->slot[occ_find(t, i)] = o->slot[k];
        t->count++;
      }
  return t;
}

static void occ_free(sylva__grid *g, sylva__occ *o) {
  if (!o) return;
  g->occ_bytes -= sizeof *o + (size_t)o->cap * sizeof o->slot[0];
  sylva__free(o);
}

void sylva__grid_prefetch(const sylva__grid *g, const int v[3]) {
  size_t ci = chunk_index(g, v[0] >> 4, v[1] >> 4, v[2] >> 4);
  const sylva__occ *o = g->occ[ci];
  if (o) __builtin_prefetch(&o->slot[occ_home(o, local_index(v[0], v[1], v[2]))]);
  const sylva__chunk *c = g->chunks[ci];
  if (!c) return;
  const int64_t *row = shade_row(c, v);
  for (int x = 0; x <= (v[0] & 15); x++) __builtin_prefetch(row + (x << 4));
}

double sylva__grid_free_light(const sylva__grid *g, const int v[3]) {
  if (occ_word(g, v)) return -1.0;
  return light_in(g, chunk_at(g, v), v, false);
}

uint32_t sylva__grid_occ_word(const sylva__grid *g, const int v[3]) {
  return occ_word(g, v);
}

int32_t sylva__grid_occupant(const sylva__grid *g, const int v[3]) {
  uint32_t o = occ_word(g, v);
  return o ? (int32_t)(o >> SYLVA__OCC_COUNT_BITS) - 1 : -1;
}

int sylva__grid_occupy(sylva__grid *g, const int v[3], int32_t stem) {
  sylva__occ **table = &g->occ[chunk_index(g, v[0] >> 4, v[1] >> 4, v[2] >> 4)];
  int i = local_index(v[0], v[1], v[2]);
  if (*table) {
    uint64_t *slot = &(*table)->slot[occ_find(*table, i)];
    if (*slot) {
      uint32_t o = (uint32_t)*slot;
      if ((int32_t)(o >> SYLVA__OCC_COUNT_BITS) - 1 != stem ||
          (o & SYLVA__OCC_COUNT_MAX) == SYLVA__OCC_COUNT_MAX)
        return SYLVA_EOCCUPIED;
      (*slot)++;
      return SYLVA_OK;
    }
  }
  if (!*table || 4 * ((*table)->count + 1) > 3 * (*table)->cap) { /* room for one more */
    sylva__occ *t = occ_table(g, *table, *table ? 2 * (*table)->cap : 16);
    if (!t) return SYLVA_ENOMEM;
    if (*table)
      occ_free(g, *table);
    else
      g->occ_count++;
    *table = t;
  }
  (*table)->slot[occ_find(*table, i)] =
      (uint64_t)(i + 1) << 32 | ((uint32_t)(stem + 1) << SYLVA__OCC_COUNT_BITS) | 1u;
  (*table)->count++;
  return SYLVA_OK;
}

void sylva__grid_vacate(sylva__grid *g, const int v[3]) {
  sylva__occ **table = &g->occ[chunk_index(g, v[0] >> 4, v[1] >> 4, v[2] >> 4)];
  sylva__occ *o = *table;
  if (!o) return;
  uint32_t k = occ_find(o, local_index(v[0], v[1], v[2]));
  if (!o->slot[k]) return;
  if ((o->slot[k] & SYLVA__OCC_COUNT_MAX) > 1) {
    o->slot[k]--;
    return;
  }
  if (--o->count == 0) { /* the chunk's last node left */
    occ_free(g, o);
    *table = NULL;
    g->occ_count--;
    return;
  }
  /* take the slot out, moving later slots of its probe run back into the gap */
  uint32_t mask = o->cap - 1;
  for (uint32_t j = (k + 1) & mask; o->slot[j]; j = (j + 1) & mask) {
    uint32_t home = occ_home(o, (int)(o->slot[j] >> 32) - 1);
    bool stays = k <= j ? (home > k && home <= j) : (home > k || home <= j);
    if (stays) continue;
    o->slot[k] = o->slot[j];
    k = j;
  }
  o->slot[k] = 0;
  /* A table a quarter full (shedding empties crowns' chunks) is rebuilt at half its
   * size, at most half full again: the tables stay between a quarter and three
   * quarters full instead of keeping the size of the most nodes a chunk ever held.
   * Without memory it stays as it is: a lookup is the same either way. */
  if (o->cap > 16 && 4 * o->count < o->cap) {
    sylva__occ *t = occ_table(g, o, o->cap / 2);
    if (t) {
      occ_free(g, o);
      *table = t;
    }
  }
}

static int clip_lo(int v, int lo) { return v > lo ? v : lo; }
static int clip_hi(int v, int hi) { return v < hi ? v : hi; }

/* Adds value to the voxels x0..x1, y0..y1 (chunk-local) of a 16 x 16 layer held as
 * differences along x, y fastest: two runs of writes. */
static inline void row_runs(int64_t *layer, int x0, int x1, int y0, int y1, int64_t value) {
  int64_t *start = layer + (x0 << 4);
  for (int y = y0; y <= y1; y++) start[y] += value;
  if (x1 + 1 < SYLVA__CHUNK) { /* the difference ends after x1, unless at the row's end */
    int64_t *stop = layer + ((x1 + 1) << 4);
    for (int y = y0; y <= y1; y++) stop[y] -= value;
  }
}

/* A stamp's writes to one layer of one chunk (or one block sum): row_runs of value
 * over x0..x1, y0..y1. A stamp lists them all, asking memory for each layer's two
 * runs as it lists it, and then writes them: the writes wait for the slowest run
 * rather than for each in turn (a crown's chunks seldom sit in the nearer caches;
 * on the 100-tree stand the shade phase took 1.4-2.0 s writing as it went, 0.9-1.1 s
 * so). The order of a stamp's writes changes no sum. */
typedef struct stamp_run {
  int64_t *layer;
  int64_t value;
  int8_t x0, x1, y0, y1;
} stamp_run;

enum { STAMP_RUNS = 256 };

typedef struct stamp_runs {
  int n;
  stamp_run run[STAMP_RUNS];
} stamp_runs;

static void runs_write(stamp_runs *r) {
  for (int k = 0; k < r->n; k++) {
    const stamp_run *u = &r->run[k];
    row_runs(u->layer, u->x0, u->x1, u->y0, u->y1, u->value);
  }
  r->n = 0;
}

static inline void runs_add(stamp_runs *r, int64_t *layer, int x0, int x1, int y0, int y1,
                            int64_t value) {
  if (r->n == STAMP_RUNS) runs_write(r);
  r->run[r->n++] = (stamp_run){layer, value, (int8_t)x0, (int8_t)x1, (int8_t)y0, (int8_t)y1};
  __builtin_prefetch(layer + (x0 << 4) + y0, 1);
  __builtin_prefetch(layer + (x0 << 4) + y1, 1);
  if (x1 + 1 < SYLVA__CHUNK) {
    __builtin_prefetch(layer + ((x1 + 1) << 4) + y0, 1);
    __builtin_prefetch(layer + ((x1 + 1) << 4) + y1, 1);
  }
}

/* One pass of a stamp over the chunk columns cx_min..cx_max: sign +1 or -1 writes
 * it; sign 0 only makes every chunk and block sum the writes will touch. */
static int stamp(sylva__grid *g, const int v[3], const sylva__pyramid *p, int sign, int cx_min,
                 int cx_max) {
  /* Pyramid: q = 1..depth voxels below, half-width half[q - 1]; walked chunk by
   * chunk so that each chunk is looked up once per stamp. */
  int depth = p->depth;
  const int64_t *w = p->w;
  int h = p->half[depth - 1];
  int zlo = clip_lo(v[2] - depth, 0), zhi = v[2] - 1;
  int xlo = clip_lo(v[0] - h, 0), xhi = clip_hi(v[0] + h, g->n[0] - 1);
  int ylo = clip_lo(v[1] - h, 0), yhi = clip_hi(v[1] + h, g->n[1] - 1);
  int cx0 = clip_lo(xlo >> 4, cx_min), cx1 = clip_hi(xhi >> 4, cx_max);
  stamp_runs runs;
  runs.n = 0;
  for (int cz = zlo >> 4; zhi >= 0 && cz <= zhi >> 4; cz++)
    for (int cy = ylo >> 4; cy <= yhi >> 4; cy++)
      for (int cx = cx0; cx <= cx1; cx++) {
        int z0 = clip_lo(zlo, cz << 4), z1 = clip_hi(zhi, (cz << 4) + 15);
        /* the widest layer of this chunk is its lowest: skip chunks it misses */
        int hw = p->half[v[2] - z0 - 1];
        if (v[0] + hw < (cx << 4) || v[0] - hw > (cx << 4) + 15 || v[1] + hw < (cy << 4) ||
            v[1] - hw > (cy << 4) + 15)
          continue;
        sylva__chunk *c = chunk_get(g, cx, cy, cz);
        if (!c) return SYLVA_ENOMEM;
        if (!sign) continue;
        for (int z = z0; z <= z1; z++) {
          int q = v[2] - z, hq = p->half[q - 1];
          int x0 = clip_lo(clip_lo(v[0] - hq, cx << 4), 0);
          int x1 = clip_hi(clip_hi(v[0] + hq, (cx << 4) + 15), g->n[0] - 1);
          int y0 = clip_lo(clip_lo(v[1] - hq, cy << 4), 0);
          int y1 = clip_hi(clip_hi(v[1] + hq, (cy << 4) + 15), g->n[1] - 1);
          if (x0 > x1 || y0 > y1) continue; /* this layer misses the chunk */
          runs_add(&runs, c->shade + ((z & 15) << 8), x0 & 15, x1 & 15, y0 & 15, y1 & 15,
                   sign * w[q - 1]);
        }
      }
  /* Column: every voxel of the base footprint from depth + 1 below down to the
   * ground gets p->column. Every chunk below the block of its top reads it from one
   * block sum, so the cost does not depend on the height of the tree. Inside that
   * block it is written into the rows of the layers, as the pyramid's are: the layers
   * at and below its top; or, when its top lies in the block's upper half, the block
   * sum of the block above holds it for the whole block and the layers above its top
   * take it away again. Either way at most 8 layers, the same shade to the bit. */
  int ztop = v[2] - depth - 1;
  if (ztop >= 0 && p->column != 0) {
    int64_t value = sign * p->column;
    int bz = ztop >> 4, zl = ztop & 15;
    bool above = zl >= 8 && bz + 1 < g->c[2];
    int sb = above ? bz + 1 : bz; /* the block whose sum holds the column */
    int z0 = above ? zl + 1 : 0, z1 = above ? 15 : zl;
    int64_t layer_value = above ? -value : value;
    for (int cy = ylo >> 4; cy <= yhi >> 4; cy++)
      for (int cx = cx0; cx <= cx1; cx++) {
        sylva__chunk *c = NULL;
        if (z0 <= z1) {
          c = chunk_get(g, cx, cy, bz);
          if (!c) return SYLVA_ENOMEM;
        }
        int64_t *sum = NULL;
        if (sb > 0) {
          sum = colsum_get(g, cx, cy, sb);
          if (!sum) return SYLVA_ENOMEM;
        }
        if (!sign) continue;
        int y0 = clip_lo(ylo, cy << 4) & 15, y1 = clip_hi(yhi, (cy << 4) + 15) & 15;
        int x0 = clip_lo(xlo, cx << 4) & 15, x1 = clip_hi(xhi, (cx << 4) + 15) & 15;
        for (int z = z0; z <= z1; z++)
          runs_add(&runs, c->shade + (z << 8), x0, x1, y0, y1, layer_value);
        if (sum) {
          runs_add(&runs, sum, x0, x1, y0, y1, value);
          int32_t *top = &g->colsum_top[(size_t)cy * (size_t)g->c[0] + (size_t)cx];
          if (sb > *top) *top = sb;
        }
      }
  }
  runs_write(&runs);
  return SYLVA_OK;
}

int sylva__grid_stamp(sylva__grid *g, const int v[3], const sylva__pyramid *p, int sign) {
  /* Every block first, then the writes: a stamp that runs out of memory has written
   * nothing, and the blocks it made hold zeros, so the shade is as it was. */
  int rc = stamp(g, v, p, 0, 0, g->c[0] - 1);
  return rc ? rc : stamp(g, v, p, sign, 0, g->c[0] - 1);
}

/* A batch is written in parts, each a range of chunk columns along x that one thread
 * writes alone: one part on one thread, else four per thread (a part over the
 * crowns takes longer than one beside them), at most one per chunk column. */
static int stamp_part_count(const sylva__grid *g, const sylva__pool *pool) {
  int threads = sylva__pool_threads(pool);
  int parts = threads == 1 ? 1 : 4 * threads;
  return parts > g->c[0] ? g->c[0] : parts;
}

/* The first chunk column of part k. */
static int part_column(const sylva__grid *g, int parts, int k) {
  return (int)((int64_t)k * g->c[0] / parts);
}

/* The parts k0..k1 whose columns a stamp writes: those of its widest layer and the
 * column below it, clipped to the grid. part_column(k) <= cx holds for every k up
 * to ((cx + 1) parts - 1) / columns, so that is the part of column cx. */
static void stamp_span(const sylva__grid *g, int parts, const sylva__stamp *it, int *k0, int *k1) {
  int h = it->p->half[it->p->depth - 1];
  int cx0 = clip_lo(it->v[0] - h, 0) >> 4, cx1 = clip_hi(it->v[0] + h, g->n[0] - 1) >> 4;
  *k0 = (int)((((int64_t)cx0 + 1) * parts - 1) / g->c[0]);
  *k1 = (int)((((int64_t)cx1 + 1) * parts - 1) / g->c[0]);
}

/* How many times the n items are listed under the parts they write in; per part
 * too, into count[k + 1] (count NULL: the total alone). */
static size_t count_listings(const sylva__grid *g, int parts, const sylva__stamp *items, size_t n,
                             size_t *count) {
  size_t total = 0;
  for (size_t i = 0; i < n; i++) {
    int k0, k1;
    stamp_span(g, parts, &items[i], &k0, &k1);
    total += (size_t)(k1 - k0 + 1);
    for (int k = k0; count && k <= k1; k++) count[k + 1]++;
  }
  return total;
}

size_t sylva__grid_stamp_scratch(const sylva__grid *g, const sylva__pool *pool,
                                 const sylva__stamp *items, size_t n) {
  int parts = stamp_part_count(g, pool);
  return parts == 1 ? 0 : (size_t)parts + 1 + count_listings(g, parts, items, n, NULL);
}

size_t sylva__grid_stamp_scratch_max(const sylva__grid *g, const sylva__pool *pool, size_t n,
                                     int half) {
  int parts = stamp_part_count(g, pool);
  if (parts == 1) return 0;
  /* A stamp writes the columns of 2 half + 1 voxels (stamp_span): at most
   * ceil(2 half / 16) + 1. Every part has at least columns / parts of them: p > 1
   * parts written hold the p - 2 between the first and the last whole, and one
   * column at least of each of those two. */
  int64_t columns = (((int64_t)2 * half + 15) >> 4) + 1, least = g->c[0] / parts;
  int64_t per = columns == 1 ? 1 : (columns - 2) / least + 2;
  if (per > parts) per = parts;
  return (size_t)parts + 1 + n * (size_t)per;
}

typedef struct stamp_many_ctx {
  sylva__grid *g;
  const sylva__stamp *items;
  size_t n;
  int sign, parts;
  /* With more than one part: part k's items are list[first[k]] .. list[first[k + 1] - 1],
   * in the batch's order. */
  const size_t *first, *list;
} stamp_many_ctx;

/* Parts [begin, end) of a batch: part k writes the chunk columns of its own range of
 * cx, the share of them of every stamp listed under it. */
static void stamp_parts(void *arg, size_t begin, size_t end) {
  const stamp_many_ctx *c = arg;
  for (size_t k = begin; k < end; k++) {
    int cx_min = part_column(c->g, c->parts, (int)k);
    int cx_max = part_column(c->g, c->parts, (int)k + 1) - 1;
    size_t from = c->first ? c->first[k] : 0, to = c->first ? c->first[k + 1] : c->n;
    for (size_t j = from; j < to; j++) {
      const sylva__stamp *it = &c->items[c->list ? c->list[j] : j];
      stamp(c->g, it->v, it->p, c->sign, cx_min, cx_max); /* its blocks exist: no failure */
    }
  }
}

int sylva__grid_stamp_many(sylva__grid *g, sylva__pool *pool, const sylva__stamp *items, size_t n,
                           int sign, size_t *scratch) {
  if (sign > 0)
    for (size_t i = 0; i < n; i++) {
      int rc = stamp(g, items[i].v, items[i].p, 0, 0, g->c[0] - 1);
      if (rc) return rc; /* the blocks made so far hold zeros: the shade is as it was */
    }
  int parts = stamp_part_count(g, pool);
  stamp_many_ctx c = {g, items, n, sign, parts, NULL, NULL};
  if (parts > 1) {
    /* Each item listed under every part it writes in (a counting sort, in the
     * batch's order within a part): a part takes only its own items, and the
     * batch costs its items and what each part writes, not items times parts. */
    size_t *first = scratch, *list = scratch + parts + 1;
    for (int k = 0; k <= parts; k++) first[k] = 0;
    count_listings(g, parts, items, n, first);
    for (int k = 0; k < parts; k++) first[k + 1] += first[k];
    for (size_t i = 0; i < n; i++) {
      int k0, k1;
      stamp_span(g, parts, &items[i], &k0, &k1);
      for (int k = k0; k <= k1; k++) list[first[k]++] = i;
    }
    for (int k = parts; k > 0; k--) first[k] = first[k - 1]; /* the fill moved each up one part */
    first[0] = 0;
    c.first = first;
    c.list = list;
  }
  sylva__pool_for(pool, (size_t)parts, 1, stamp_parts, &c);
  return SYLVA_OK;
}

/* ---- obstacles ------------------------------------------------------------------ */

static void obstacle_voxels(const sylva__grid *g, sylva__obstacle *o) {
  for (int a = 0; a < 3; a++) {
    double lo = floor((o->min[a] - g->min[a]) / g->voxel);
    double hi = ceil((o->max[a] - g->min[a]) / g->voxel);
    if (hi <= lo) hi = lo + 1.0;
    if (lo < 0.0) lo = 0.0;
    if (hi > (double)g->n[a]) hi = (double)g->n[a];
    if (lo > (double)g->n[a]) lo = (double)g->n[a];
    if (hi < 0.0) hi = 0.0;
    o->lo[a] = (int)lo;
    o->hi[a] = (int)hi;
  }
}

/* The chunk columns an obstacle is listed under: [c0[a], c1[a]) per horizontal axis;
 * false when its box misses the grid horizontally (it is listed nowhere). An
 * obstacle above the grid's top, clipped to an empty z range, still darkens its
 * columns and is listed. */
static bool obstacle_columns(const sylva__obstacle *o, int c0[2], int c1[2]) {
  for (int a = 0; a < 2; a++) {
    if (o->hi[a] <= o->lo[a]) return false;
    c0[a] = o->lo[a] >> 4;
    c1[a] = ((o->hi[a] - 1) >> 4) + 1;
  }
  return true;
}

/* Labels: FNV-1a, folded so the high bits reach the table index. */
static size_t label_home(const sylva__grid *g, const char *label) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (const unsigned char *p = (const unsigned char *)label; *p; p++)
    h = (h ^ *p) * 0x100000001b3ULL;
  return (size_t)(h ^ (h >> 32)) & (size_t)(g->label_cap - 1);
}

/* The table entry holding label's slot, or the empty entry where it would go; -1
 * without a table. */
static ptrdiff_t label_entry(const sylva__grid *g, const char *label) {
  if (!g->label_cap) return -1;
  size_t mask = (size_t)g->label_cap - 1, i = label_home(g, label);
  while (g->label_slot[i] >= 0 && strcmp(g->obstacles[g->label_slot[i]].label, label) != 0)
    i = (i + 1) & mask;
  return (ptrdiff_t)i;
}

/* Files every live slot in the table (all entries -1 before). */
static void label_fill(sylva__grid *g) {
  for (int s = 0; s < g->obstacle_slots; s++)
    if (g->obstacles[s].live) g->label_slot[label_entry(g, g->obstacles[s].label)] = s;
}

/* Takes the entry at i out of the table, moving later entries of its probe run back
 * into the gap (no tombstones). */
static void label_erase(sylva__grid *g, size_t i) {
  size_t mask = (size_t)g->label_cap - 1;
  for (size_t j = (i + 1) & mask; g->label_slot[j] >= 0; j = (j + 1) & mask) {
    size_t home = label_home(g, g->obstacles[g->label_slot[j]].label);
    /* the entry at j may fill the gap at i unless its home lies in (i, j] */
    bool stays = i <= j ? (home > i && home <= j) : (home > i || home <= j);
    if (stays) continue;
    g->label_slot[i] = g->label_slot[j];
    i = j;
  }
  g->label_slot[i] = -1;
}

/* Fenwick tree over the slots: live counts. */
static int rank_before(const sylva__grid *g, int k) { /* live slots among the first k */
  int32_t n = 0;
  for (int i = k; i > 0; i -= i & -i) n += g->obstacle_rank[i];
  return n;
}

static int rank_select(const sylva__grid *g, int k) { /* slot of the k-th live one */
  int pos = 0, step = 1;
  while (step * 2 <= g->obstacle_slots) step *= 2;
  for (; step; step /= 2)
    if (pos + step <= g->obstacle_slots && g->obstacle_rank[pos + step] <= k) {
      pos += step;
      k -= g->obstacle_rank[pos];
    }
  return pos;
}

const sylva__obstacle *sylva__grid_obstacle_at(const sylva__grid *g, int i) {
  if (g->obstacle_slots == g->obstacle_count) return &g->obstacles[i];
  return &g->obstacles[rank_select(g, i)];
}

/* Slot of the live obstacle with this id, or -1. */
static int slot_of(const sylva__grid *g, int id) {
  int lo = 0, hi = g->obstacle_slots;
  while (lo < hi) {
    int mid = lo + (hi - lo) / 2;
    if (g->obstacles[mid].id < id)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < g->obstacle_slots && g->obstacles[lo].id == id && g->obstacles[lo].live ? lo : -1;
}

int sylva__grid_obstacle_slot(const sylva__grid *g, int id) { return slot_of(g, id); }

/* Drops the dead slots, keeping the order; the labels and ranks follow. Allocates
 * nothing, and costs the slots, not the label table. */
static void compact_obstacles(sylva__grid *g) {
  int n = 0;
  size_t mask = (size_t)g->label_cap - 1;
  for (int s = 0; s < g->obstacle_slots; s++) {
    if (!g->obstacles[s].live) continue;
    if (n != s) {
      /* its entry is the one holding s: those done hold less than n, the rest more */
      size_t e = label_home(g, g->obstacles[s].label);
      while (g->label_slot[e] != s) e = (e + 1) & mask;
      g->label_slot[e] = n;
      g->obstacles[n] = g->obstacles[s];
    }
    n++;
  }
  g->obstacle_slots = n;
  for (int i = 1; i <= n; i++) g->obstacle_rank[i] = i & -i; /* every slot live */
}

int sylva__grid_find_obstacle(const sylva__grid *g, const char *label) {
  ptrdiff_t e = label ? label_entry(g, label) : -1;
  if (e < 0 || g->label_slot[e] < 0) return SYLVA_ENOTFOUND;
  return g->obstacles[g->label_slot[e]].id;
}

/* Frees the empty lists of columns [c0, c1): a column without obstacles has none. */
static void drop_empty_lists(sylva__grid *g, const int c0[2], const int c1[2]) {
  for (int cy = c0[1]; cy < c1[1]; cy++)
    for (int cx = c0[0]; cx < c1[0]; cx++) {
      sylva__obstacle_list **l = &g->obstacle_cols[(size_t)cy * (size_t)g->c[0] + (size_t)cx];
      if (!*l || (*l)->count) continue;
      g->obstacle_list_bytes -= sizeof **l + (size_t)(*l)->cap * sizeof(sylva__obstacle_box);
      sylva__free(*l);
      *l = NULL;
    }
}

/* The i-th voxel box of o (0 <= i < box_count(o)) over its z range. */
static int box_count(const sylva__obstacle *o) { return o->fp ? o->fp->rect_count : 1; }
static sylva__obstacle_box box_of(const sylva__obstacle *o, int i) {
  if (!o->fp) return (sylva__obstacle_box){{o->lo[0], o->lo[1], o->lo[2]}, {o->hi[0], o->hi[1], o->hi[2]}, o->id};
  const int32_t *r = o->fp->rect[i];
  return (sylva__obstacle_box){{r[0], r[1], o->lo[2]}, {r[2], r[3], o->hi[2]}, o->id};
}

/* Runs the statements given for every chunk column that a box of o overlaps, with
 * list (its list's place) and box (the box) in scope. */
#define FOR_EACH_LISTING(g, o, list, box, ...)                                               \
  for (int i_ = 0; i_ < box_count(o); i_++) {                                                 \
    const sylva__obstacle_box box = box_of(o, i_);                                            \
    if (box.hi[0] <= box.lo[0] || box.hi[1] <= box.lo[1]) continue;                           \
    for (int cy_ = box.lo[1] >> 4; cy_ <= (box.hi[1] - 1) >> 4; cy_++)                        \
      for (int cx_ = box.lo[0] >> 4; cx_ <= (box.hi[0] - 1) >> 4; cx_++) {                    \
        sylva__obstacle_list **list = &(g)->obstacle_cols[(size_t)cy_ * (size_t)(g)->c[0] + (size_t)cx_]; \
        __VA_ARGS__                                                                           \
      }                                                                                       \
  }

/* Makes room for one more slot, label and entry in every column of o (as many as
 * its boxes over the column); the grid holds the same obstacles whether it succeeds
 * or not. */
static int obstacle_reserve(sylva__grid *g, const sylva__obstacle *o, bool zone) {
  if (g->obstacle_slots == g->obstacle_cap) {
    if (g->obstacle_cap > INT32_MAX / 4) return SYLVA_ENOMEM;
    int cap = g->obstacle_cap ? g->obstacle_cap * 2 : 8;
    sylva__obstacle *slots = sylva__realloc(g->obstacles, (size_t)cap * sizeof *slots);
    if (!slots) return SYLVA_ENOMEM;
    g->obstacles = slots;
    int32_t *rank = sylva__realloc(g->obstacle_rank, ((size_t)cap + 1) * sizeof *rank);
    if (!rank) return SYLVA_ENOMEM;
    g->obstacle_rank = rank;
    g->obstacle_cap = cap;
  }
  if (2 * (g->obstacle_count + 1) > g->label_cap) {
    int cap = g->label_cap ? g->label_cap * 2 : 16;
    int32_t *table = sylva__malloc((size_t)cap * sizeof *table);
    if (!table) return SYLVA_ENOMEM;
    sylva__free(g->label_slot);
    g->label_slot = table;
    g->label_cap = cap;
    for (int i = 0; i < cap; i++) table[i] = -1;
    label_fill(g);
  }
  int c0[2], c1[2];
  if (zone || !obstacle_columns(o, c0, c1)) return SYLVA_OK; /* a zone blocks nothing */
  size_t ncols = (size_t)g->c[0] * (size_t)g->c[1];
  if (!g->obstacle_cols) {
    g->obstacle_cols = sylva__calloc(ncols, sizeof *g->obstacle_cols);
    if (!g->obstacle_cols) return SYLVA_ENOMEM;
  }
  /* each listing counted in its list's count (room made as needed), then given back */
  size_t counted = 0;
  bool failed = false;
  FOR_EACH_LISTING(g, o, l, box, {
    (void)box;
    if (failed) continue;
    int32_t count = *l ? (*l)->count : 0, cap = *l ? (*l)->cap : 0;
    if (count == cap) {
      int32_t grown = cap ? cap * 2 : 4;
      sylva__obstacle_list *m = cap > INT32_MAX / 4 ? NULL :
          sylva__realloc(*l, sizeof **l + (size_t)grown * sizeof(sylva__obstacle_box));
      if (!m) {
        failed = true;
        continue;
      }
      m->count = count;
      m->cap = grown;
      *l = m;
      g->obstacle_list_bytes += (size_t)(grown - cap) * sizeof(sylva__obstacle_box) +
                                (cap ? 0 : sizeof **l);
    }
    (*l)->count++;
    counted++;
  })
  FOR_EACH_LISTING(g, o, l, box, {
    (void)box;
    if (counted == 0) continue;
    (*l)->count--;
    counted--;
  })
  if (failed) {
    drop_empty_lists(g, c0, c1); /* the lists made for o, so that empty means absent */
    return SYLVA_ENOMEM;
  }
  return SYLVA_OK;
}

int sylva__grid_add_obstacle_def(sylva__grid *g, int id, const sylva_obstacle_def *def) {
  const char *label = def->label;
  bool zone = def->kind == SYLVA_OBSTACLE_ZONE;
  if (!label || !label[0] || strlen(label) >= SYLVA_LABEL_MAX) return SYLVA_EINVAL;
  if (def->kind != SYLVA_OBSTACLE_SOLID && !zone) return SYLVA_EINVAL;
  bool prism = def->footprint.ring_count != 0;
  for (int a = prism ? 2 : 0; a < 3; a++)
    if (!isfinite(def->min[a]) || !isfinite(def->max[a]) || !(def->max[a] > def->min[a]))
      return SYLVA_EINVAL;
  if (id < g->next_obstacle_id || id == INT_MAX) return SYLVA_EINVAL;
  if (sylva__grid_find_obstacle(g, label) >= 0) return SYLVA_EINVAL;
  sylva__obstacle ob;
  memset(&ob, 0, sizeof ob);
  ob.id = id;
  ob.live = true;
  ob.zone = zone;
  strcpy(ob.label, label);
  memcpy(ob.min, def->min, sizeof ob.min);
  memcpy(ob.max, def->max, sizeof ob.max);
  if (prism) {
    int rc = sylva__footprint_copy(&def->footprint, &ob.fp);
    if (rc) return rc;
    for (int a = 0; a < 2; a++) {
      ob.min[a] = ob.fp->min[a];
      ob.max[a] = ob.fp->max[a];
    }
    if (!(ob.max[0] > ob.min[0]) || !(ob.max[1] > ob.min[1])) {
      sylva__footprint_free(ob.fp);
      return SYLVA_EINVAL;
    }
    /* a zone's columns are never listed: it needs no rectangles */
    rc = zone ? SYLVA_OK : sylva__footprint_voxelize(ob.fp, g->min, g->voxel, g->n);
    if (rc) {
      sylva__footprint_free(ob.fp);
      return rc;
    }
  }
  obstacle_voxels(g, &ob);
  int rc = obstacle_reserve(g, &ob, zone);
  if (rc) {
    sylva__footprint_free(ob.fp);
    return rc;
  }
  /* nothing fails from here on */
  int s = g->obstacle_slots++;
  g->obstacles[s] = ob;
  int k = s + 1;
  g->obstacle_rank[k] = 1 + rank_before(g, s) - rank_before(g, k - (k & -k));
  g->label_slot[label_entry(g, label)] = s;
  g->obstacle_count++;
  g->next_obstacle_id = id + 1;
  if (ob.fp) g->footprint_bytes += sylva__footprint_bytes(ob.fp);
  if (zone) return id; /* listed by id and label only: it blocks and darkens nothing */
  if (g->obstacle_cols) FOR_EACH_LISTING(g, &ob, l, box, { (*l)->box[(*l)->count++] = box; })
  site_forget(g);
  if (ob.hi[2] > g->sky_top) g->sky_top = ob.hi[2];
  return id;
}

int sylva__grid_add_obstacle(sylva__grid *g, const char *label, const double min[3],
                             const double max[3]) {
  sylva_obstacle_def def = {.label = label};
  memcpy(def.min, min, sizeof def.min);
  memcpy(def.max, max, sizeof def.max);
  return sylva__grid_add_obstacle_def(g, g->next_obstacle_id, &def);
}

int sylva__grid_remove_obstacle(sylva__grid *g, int id) {
  int s = slot_of(g, id);
  if (s < 0) return SYLVA_ENOTFOUND;
  sylva__obstacle *o = &g->obstacles[s];
  bool zone = o->zone;
  int c0[2], c1[2];
  if (!zone && obstacle_columns(o, c0, c1)) {
    for (int cy = c0[1]; cy < c1[1]; cy++)
      for (int cx = c0[0]; cx < c1[0]; cx++) {
        sylva__obstacle_list *l = g->obstacle_cols[(size_t)cy * (size_t)g->c[0] + (size_t)cx];
        for (int32_t i = 0; l && i < l->count;) /* a prism may have several boxes here */
          if (l->box[i].id == id)
            l->box[i] = l->box[--l->count];
          else
            i++;
      }
    drop_empty_lists(g, c0, c1); /* a column left without obstacles costs nothing again */
  }
  label_erase(g, (size_t)label_entry(g, o->label));
  if (o->fp) g->footprint_bytes -= sylva__footprint_bytes(o->fp);
  sylva__footprint_free(o->fp);
  o->fp = NULL;
  o->live = false;
  for (int k = s + 1; k <= g->obstacle_slots; k += k & -k) g->obstacle_rank[k]--;
  g->obstacle_count--;
  if (g->obstacle_slots - g->obstacle_count > g->obstacle_count) compact_obstacles(g);
  if (zone) return SYLVA_OK;
  site_forget(g);
  if (g->site) g->sky_top = sylva__site_top(g); /* a scan: removals are rare */
  return SYLVA_OK;
}
