#include "grid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
  g->chunks = calloc(nchunks, sizeof *g->chunks);
  g->colsum = calloc(ncols, sizeof *g->colsum);
  if (!g->chunks || !g->colsum) {
    sylva__grid_free(g);
    return SYLVA_ENOMEM;
  }
  return SYLVA_OK;
}

void sylva__grid_free(sylva__grid *g) {
  if (g->chunks) {
    size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
    for (size_t i = 0; i < nchunks; i++) free(g->chunks[i]);
  }
  if (g->colsum) {
    size_t ncols = (size_t)g->c[0] * (size_t)g->c[1];
    for (size_t i = 0; i < ncols; i++) free(g->colsum[i]);
  }
  free(g->chunks);
  free(g->colsum);
  free(g->obstacles);
  memset(g, 0, sizeof *g);
}

size_t sylva__grid_bytes(const sylva__grid *g) {
  size_t nchunks = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2];
  size_t ncols = (size_t)g->c[0] * (size_t)g->c[1];
  return nchunks * sizeof(void *) + ncols * sizeof(void *) + g->chunk_count * sizeof(sylva__chunk) +
         g->colsum_count * (size_t)g->c[2] * 256 * sizeof(int64_t) +
         (size_t)g->obstacle_cap * sizeof(sylva__obstacle);
}

bool sylva__grid_voxel(const sylva__grid *g, double x, double y, double z, int v[3]) {
  double p[3] = {x, y, z};
  for (int a = 0; a < 3; a++) {
    double f = floor((p[a] - g->min[a]) * g->inv_voxel);
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
    *slot = calloc(1, sizeof **slot);
    if (!*slot) return NULL;
    g->chunk_count++;
  }
  return *slot;
}

static int64_t *colsum_get(sylva__grid *g, int cx, int cy) {
  int64_t **slot = &g->colsum[(size_t)cy * (size_t)g->c[0] + (size_t)cx];
  if (!*slot) {
    *slot = calloc((size_t)g->c[2] * 256, sizeof **slot);
    if (!*slot) return NULL;
    g->colsum_count++;
  }
  return *slot;
}

bool sylva__grid_blocked(const sylva__grid *g, const int v[3]) {
  for (int i = 0; i < g->obstacle_count; i++) {
    const sylva__obstacle *o = &g->obstacles[i];
    if (o->live && v[0] >= o->lo[0] && v[0] < o->hi[0] && v[1] >= o->lo[1] && v[1] < o->hi[1] &&
        v[2] >= o->lo[2] && v[2] < o->hi[2])
      return true;
  }
  return false;
}

bool sylva__grid_under_obstacle(const sylva__grid *g, const int v[3]) {
  for (int i = 0; i < g->obstacle_count; i++) {
    const sylva__obstacle *o = &g->obstacles[i];
    if (o->live && v[0] >= o->lo[0] && v[0] < o->hi[0] && v[1] >= o->lo[1] && v[1] < o->hi[1] &&
        v[2] < o->hi[2])
      return true;
  }
  return false;
}

int64_t sylva__grid_shade_raw(const sylva__grid *g, const int v[3]) {
  int64_t s = 0;
  const sylva__chunk *c = chunk_at(g, v);
  if (c) s = c->shade[local_index(v[0], v[1], v[2])];
  const int64_t *col = g->colsum[(size_t)(v[1] >> 4) * (size_t)g->c[0] + (size_t)(v[0] >> 4)];
  if (col) {
    int xy = (v[0] & 15) | ((v[1] & 15) << 4);
    for (int b = (v[2] >> 4) + 1; b < g->c[2]; b++) s += col[(size_t)b * 256 + (size_t)xy];
  }
  return s;
}

double sylva__grid_light(const sylva__grid *g, const int v[3]) {
  if (g->obstacle_count && sylva__grid_under_obstacle(g, v)) return 0.0;
  double l = 1.0 - (double)sylva__grid_shade_raw(g, v) / SYLVA__SHADE_ONE;
  return l > 0.0 ? l : 0.0;
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

/* Adds value to voxels [x0, x1] of row (y, z); the row may cross chunk borders. */
static int add_row(sylva__grid *g, int x0, int x1, int y, int z, int64_t value) {
  int cy = y >> 4, cz = z >> 4;
  int base = ((y & 15) << 4) | ((z & 15) << 8);
  for (int x = x0; x <= x1;) {
    int cx = x >> 4;
    int end = (cx << 4) + 15;
    if (end > x1) end = x1;
    sylva__chunk *c = chunk_get(g, cx, cy, cz);
    if (!c) return SYLVA_ENOMEM;
    int64_t *s = c->shade + base;
    for (int xx = x; xx <= end; xx++) s[xx & 15] += value;
    x = end + 1;
  }
  return SYLVA_OK;
}

int sylva__grid_stamp(sylva__grid *g, const int v[3], int depth, const int64_t *w, int sign) {
  /* Pyramid: q = 1..depth voxels below, half-width floor(q / 2). */
  for (int q = 1; q <= depth; q++) {
    int z = v[2] - q;
    if (z < 0) return SYLVA_OK;
    int h = q / 2;
    int x0 = v[0] - h, x1 = v[0] + h, y0 = v[1] - h, y1 = v[1] + h;
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 >= g->n[0]) x1 = g->n[0] - 1;
    if (y1 >= g->n[1]) y1 = g->n[1] - 1;
    int64_t value = sign * w[q - 1];
    for (int y = y0; y <= y1; y++) {
      int rc = add_row(g, x0, x1, y, z, value);
      if (rc) return rc;
    }
  }
  /* Column: every voxel of the base footprint from depth + 1 below down to the
   * ground gets w[depth - 1]. Stored as an in-block suffix (voxels of the top
   * block at or below ztop) plus one block sum that every lower block reads, so
   * the cost does not depend on the height of the tree. */
  int ztop = v[2] - depth - 1;
  if (ztop < 0) return SYLVA_OK;
  int h = depth / 2;
  int x0 = v[0] - h, x1 = v[0] + h, y0 = v[1] - h, y1 = v[1] + h;
  if (x0 < 0) x0 = 0;
  if (y0 < 0) y0 = 0;
  if (x1 >= g->n[0]) x1 = g->n[0] - 1;
  if (y1 >= g->n[1]) y1 = g->n[1] - 1;
  int64_t value = sign * w[depth - 1];
  int bz = ztop >> 4, zb = bz << 4;
  for (int y = y0; y <= y1; y++) {
    for (int x = x0; x <= x1;) {
      int cx = x >> 4, end = (cx << 4) + 15;
      if (end > x1) end = x1;
      sylva__chunk *c = chunk_get(g, cx, y >> 4, bz);
      int64_t *col = bz > 0 ? colsum_get(g, cx, y >> 4) : NULL;
      if (!c || (bz > 0 && !col)) return SYLVA_ENOMEM;
      for (int xx = x; xx <= end; xx++) {
        int xy = (xx & 15) | ((y & 15) << 4);
        for (int z = zb; z <= ztop; z++) c->shade[xy | ((z & 15) << 8)] += value;
        if (col) col[(size_t)bz * 256 + (size_t)xy] += value;
      }
      x = end + 1;
    }
  }
  return SYLVA_OK;
}

static void obstacle_voxels(const sylva__grid *g, sylva__obstacle *o) {
  for (int a = 0; a < 3; a++) {
    double lo = floor((o->min[a] - g->min[a]) * g->inv_voxel);
    double hi = ceil((o->max[a] - g->min[a]) * g->inv_voxel);
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
    if (g->obstacles[i].live && strcmp(g->obstacles[i].label, label) == 0)
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
    sylva__obstacle *o = realloc(g->obstacles, (size_t)cap * sizeof *o);
    if (!o) return SYLVA_ENOMEM;
    g->obstacles = o;
    g->obstacle_cap = cap;
  }
  sylva__obstacle *o = &g->obstacles[g->obstacle_count++];
  memset(o, 0, sizeof *o);
  o->id = g->next_obstacle_id++;
  o->live = true;
  strcpy(o->label, label);
  memcpy(o->min, min, sizeof o->min);
  memcpy(o->max, max, sizeof o->max);
  obstacle_voxels(g, o);
  return o->id;
}

int sylva__grid_remove_obstacle(sylva__grid *g, int id) {
  for (int i = 0; i < g->obstacle_count; i++) {
    if (g->obstacles[i].live && g->obstacles[i].id == id) {
      memmove(&g->obstacles[i], &g->obstacles[i + 1],
              (size_t)(g->obstacle_count - i - 1) * sizeof *g->obstacles);
      g->obstacle_count--;
      return SYLVA_OK;
    }
  }
  return SYLVA_ENOTFOUND;
}
