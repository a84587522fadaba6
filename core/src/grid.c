#include "grid.h"

#include <math.h>
#include <string.h>

#include "alloc.h"

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
  g->colsum = sylva__calloc(ncols, sizeof *g->colsum);
  if (!g->chunks || !g->colsum) {
    sylva__grid_free(g);
    return SYLVA_ENOMEM;
  }
  return SYLVA_OK;
}

void sylva__grid_free(sylva__grid *g) {
  if (g->chunks) {
    size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
    for (size_t i = 0; i < nchunks; i++) {
      if (g->chunks[i]) sylva__free(g->chunks[i]->column);
      sylva__free(g->chunks[i]);
    }
  }
  if (g->colsum) {
    size_t ncols = (size_t)g->c[0] * (size_t)g->c[1];
    for (size_t i = 0; i < ncols; i++) sylva__free(g->colsum[i]);
  }
  sylva__free(g->chunks);
  sylva__free(g->colsum);
  sylva__free(g->obstacles);
  memset(g, 0, sizeof *g);
}

size_t sylva__grid_bytes(const sylva__grid *g) {
  size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
  size_t ncols = (size_t)g->c[0] * (size_t)g->c[1];
  return nchunks * sizeof(void *) + ncols * sizeof(void *) + g->chunk_count * sizeof(sylva__chunk) +
         g->column_count * SYLVA__CHUNK_VOXELS * sizeof(int64_t) +
         g->colsum_count * (size_t)g->c[2] * 256 * sizeof(int64_t) +
         (size_t)g->obstacle_cap * sizeof(sylva__obstacle);
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
  return ((size_t)cz * (size_t)g->c[1] + (size_t)cy) * (size_t)g->c[0] + (size_t)cx;
}

static inline int local_index(int x, int y, int z) {
  return (x & (SYLVA__CHUNK - 1)) | ((y & (SYLVA__CHUNK - 1)) << 4) |
         ((z & (SYLVA__CHUNK - 1)) << 8);
}

static inline const sylva__chunk *chunk_at(const sylva__grid *g, const int v[3]) {
  return g->chunks[chunk_index(g, v[0] >> 4, v[1] >> 4, v[2] >> 4)];
}

static sylva__chunk *chunk_get(sylva__grid *g, int cx, int cy, int cz) {
  sylva__chunk **slot = &g->chunks[chunk_index(g, cx, cy, cz)];
  if (!*slot) {
    *slot = sylva__calloc(1, sizeof **slot);
    if (!*slot) return NULL;
    g->chunk_count++;
  }
  return *slot;
}

static int64_t *colsum_get(sylva__grid *g, int cx, int cy) {
  int64_t **slot = &g->colsum[(size_t)cy * (size_t)g->c[0] + (size_t)cx];
  if (!*slot) {
    *slot = sylva__calloc((size_t)g->c[2] * 256, sizeof **slot);
    if (!*slot) return NULL;
    g->colsum_count++;
  }
  return *slot;
}

bool sylva__grid_blocked(const sylva__grid *g, const int v[3]) {
  for (int i = 0; i < g->obstacle_count; i++) {
    const sylva__obstacle *o = &g->obstacles[i];
    if (v[0] >= o->lo[0] && v[0] < o->hi[0] && v[1] >= o->lo[1] && v[1] < o->hi[1] &&
        v[2] >= o->lo[2] && v[2] < o->hi[2])
      return true;
  }
  return false;
}

bool sylva__grid_under_obstacle(const sylva__grid *g, const int v[3]) {
  for (int i = 0; i < g->obstacle_count; i++) {
    const sylva__obstacle *o = &g->obstacles[i];
    if (v[0] >= o->lo[0] && v[0] < o->hi[0] && v[1] >= o->lo[1] && v[1] < o->hi[1] &&
        v[2] < o->hi[2])
      return true;
  }
  return false;
}

/* Shade of voxel v given its chunk c (may be NULL). */
static int64_t shade_in(const sylva__grid *g, const sylva__chunk *c, const int v[3]) {
  int64_t s = 0;
  if (c) {
    const int64_t *row = c->shade + ((v[2] & 15) << 8) + (v[1] & 15);
    for (int x = 0; x <= (v[0] & 15); x++) s += row[x << 4];
    int i = local_index(v[0], v[1], v[2]);
    if (c->column) {
      const int64_t *col = c->column + (i & 255);
      for (int z = v[2] & 15; z < SYLVA__CHUNK; z++) s += col[z << 8];
    }
  }
  const int64_t *col = g->colsum[(size_t)(v[1] >> 4) * (size_t)g->c[0] + (size_t)(v[0] >> 4)];
  if (col) {
    int xy = (v[0] & 15) | ((v[1] & 15) << 4);
    for (int b = (v[2] >> 4) + 1; b < g->c[2]; b++) s += col[(size_t)b * 256 + (size_t)xy];
  }
  return s;
}

int64_t sylva__grid_shade_raw(const sylva__grid *g, const int v[3]) {
  return shade_in(g, chunk_at(g, v), v);
}

static double light_in(const sylva__grid *g, const sylva__chunk *c, const int v[3]) {
  if (g->obstacle_count && sylva__grid_under_obstacle(g, v)) return 0.0;
  double l = 1.0 - (double)shade_in(g, c, v) / SYLVA__SHADE_ONE;
  return l > 0.0 ? l : 0.0;
}

double sylva__grid_light(const sylva__grid *g, const int v[3]) {
  return light_in(g, chunk_at(g, v), v);
}

double sylva__grid_free_light(const sylva__grid *g, const int v[3]) {
  const sylva__chunk *c = chunk_at(g, v);
  if (c && c->occ[local_index(v[0], v[1], v[2])]) return -1.0;
  return light_in(g, c, v);
}

int32_t sylva__grid_occupant(const sylva__grid *g, const int v[3]) {
  const sylva__chunk *c = chunk_at(g, v);
  if (!c) return -1;
  uint32_t o = c->occ[local_index(v[0], v[1], v[2])];
  return o ? (int32_t)(o >> SYLVA__OCC_COUNT_BITS) - 1 : -1;
}

int sylva__grid_occupy(sylva__grid *g, const int v[3], int32_t stem) {
  sylva__chunk *c = chunk_get(g, v[0] >> 4, v[1] >> 4, v[2] >> 4);
  if (!c) return SYLVA_ENOMEM;
  uint32_t *o = &c->occ[local_index(v[0], v[1], v[2])];
  if (*o == 0) {
    *o = ((uint32_t)(stem + 1) << SYLVA__OCC_COUNT_BITS) | 1u;
    return SYLVA_OK;
  }
  if ((int32_t)(*o >> SYLVA__OCC_COUNT_BITS) - 1 != stem ||
      (*o & SYLVA__OCC_COUNT_MAX) == SYLVA__OCC_COUNT_MAX)
    return SYLVA_EOCCUPIED;
  (*o)++;
  return SYLVA_OK;
}

void sylva__grid_vacate(sylva__grid *g, const int v[3]) {
  sylva__chunk *c = g->chunks[chunk_index(g, v[0] >> 4, v[1] >> 4, v[2] >> 4)];
  if (!c) return;
  uint32_t *o = &c->occ[local_index(v[0], v[1], v[2])];
  if ((*o & SYLVA__OCC_COUNT_MAX) <= 1)
    *o = 0;
  else
    (*o)--;
}

static int clip_lo(int v, int lo) { return v > lo ? v : lo; }
static int clip_hi(int v, int hi) { return v < hi ? v : hi; }

/* One pass of a stamp: sign +1 or -1 writes it; sign 0 only makes every chunk,
 * column block and block sum the writes will touch. */
static int stamp(sylva__grid *g, const int v[3], const sylva__pyramid *p, int sign) {
  /* Pyramid: q = 1..depth voxels below, half-width half[q - 1]; walked chunk by
   * chunk so that each chunk is looked up once per stamp. */
  int depth = p->depth;
  const int64_t *w = p->w;
  int h = p->half[depth - 1];
  int zlo = clip_lo(v[2] - depth, 0), zhi = v[2] - 1;
  int xlo = clip_lo(v[0] - h, 0), xhi = clip_hi(v[0] + h, g->n[0] - 1);
  int ylo = clip_lo(v[1] - h, 0), yhi = clip_hi(v[1] + h, g->n[1] - 1);
  for (int cz = zlo >> 4; zhi >= 0 && cz <= zhi >> 4; cz++)
    for (int cy = ylo >> 4; cy <= yhi >> 4; cy++)
      for (int cx = xlo >> 4; cx <= xhi >> 4; cx++) {
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
          int64_t value = sign * w[q - 1];
          int64_t *layer = c->shade + ((z & 15) << 8);
          int e = (x1 & 15) + 1; /* the difference ends after x1, unless at the row's end */
          int64_t *start = layer + ((x0 & 15) << 4);
          for (int y = y0 & 15; y <= (y1 & 15); y++) start[y] += value;
          if (e < SYLVA__CHUNK) {
            int64_t *stop = layer + (e << 4);
            for (int y = y0 & 15; y <= (y1 & 15); y++) stop[y] -= value;
          }
        }
      }
  /* Column: every voxel of the base footprint from depth + 1 below down to the
   * ground gets p->column. Stored as one entry at its top voxel (summed by the
   * voxels of that chunk below it) plus one block sum read by every lower chunk, so
   * the cost does not depend on the height of the tree. */
  int ztop = v[2] - depth - 1;
  if (ztop < 0 || p->column == 0) return SYLVA_OK;
  int64_t value = sign * p->column;
  int bz = ztop >> 4, zl = ztop & 15;
  for (int cy = ylo >> 4; cy <= yhi >> 4; cy++)
    for (int cx = xlo >> 4; cx <= xhi >> 4; cx++) {
      sylva__chunk *c = chunk_get(g, cx, cy, bz);
      if (!c) return SYLVA_ENOMEM;
      if (!c->column) {
        c->column = sylva__calloc(SYLVA__CHUNK_VOXELS, sizeof *c->column);
        if (!c->column) return SYLVA_ENOMEM;
        g->column_count++;
      }
      int64_t *sum = NULL;
      if (bz > 0) {
        sum = colsum_get(g, cx, cy);
        if (!sum) return SYLVA_ENOMEM;
        sum += (size_t)bz * 256;
      }
      if (!sign) continue;
      int y0 = clip_lo(ylo, cy << 4), y1 = clip_hi(yhi, (cy << 4) + 15);
      int x0 = clip_lo(xlo, cx << 4), x1 = clip_hi(xhi, (cx << 4) + 15);
      for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) {
          int xy = (x & 15) | ((y & 15) << 4);
          c->column[(zl << 8) | xy] += value;
          if (sum) sum[xy] += value;
        }
    }
  return SYLVA_OK;
}

int sylva__grid_stamp(sylva__grid *g, const int v[3], const sylva__pyramid *p, int sign) {
  /* Every block first, then the writes: a stamp that runs out of memory has written
   * nothing, and the blocks it made hold zeros, so the shade is as it was. */
  int rc = stamp(g, v, p, 0);
  return rc ? rc : stamp(g, v, p, sign);
}

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

int sylva__grid_find_obstacle(const sylva__grid *g, const char *label) {
  for (int i = 0; i < g->obstacle_count; i++)
    if (strcmp(g->obstacles[i].label, label) == 0)
      return g->obstacles[i].id;
  return SYLVA_ENOTFOUND;
}

int sylva__grid_add_obstacle(sylva__grid *g, const char *label, const double min[3],
                             const double max[3]) {
  if (!label || !label[0] || strlen(label) >= SYLVA_LABEL_MAX) return SYLVA_EINVAL;
  for (int a = 0; a < 3; a++)
    if (!isfinite(min[a]) || !isfinite(max[a]) || !(max[a] > min[a])) return SYLVA_EINVAL;
  if (sylva__grid_find_obstacle(g, label) >= 0) return SYLVA_EINVAL;
  if (g->obstacle_count == g->obstacle_cap) {
    int cap = g->obstacle_cap ? g->obstacle_cap * 2 : 8;
    sylva__obstacle *o = sylva__realloc(g->obstacles, (size_t)cap * sizeof *o);
    if (!o) return SYLVA_ENOMEM;
    g->obstacles = o;
    g->obstacle_cap = cap;
  }
  sylva__obstacle *o = &g->obstacles[g->obstacle_count++];
  memset(o, 0, sizeof *o);
  o->id = g->next_obstacle_id++;
  strcpy(o->label, label);
  memcpy(o->min, min, sizeof o->min);
  memcpy(o->max, max, sizeof o->max);
  obstacle_voxels(g, o);
  return o->id;
}

int sylva__grid_remove_obstacle(sylva__grid *g, int id) {
  for (int i = 0; i < g->obstacle_count; i++) {
    if (g->obstacles[i].id == id) {
      memmove(&g->obstacles[i], &g->obstacles[i + 1],
              (size_t)(g->obstacle_count - i - 1) * sizeof *g->obstacles);
      g->obstacle_count--;
      return SYLVA_OK;
    }
  }
  return SYLVA_ENOTFOUND;
}
