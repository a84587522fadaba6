#include "shoot.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "world_impl.h"

#define SYLVA__DEG (3.14159265358979323846 / 180.0)

static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross(const double a[3], const double b[3], double o[3]) {
  o[0] = a[1] * b[2] - a[2] * b[1];
  o[1] = a[2] * b[0] - a[0] * b[2];
  o[2] = a[0] * b[1] - a[1] * b[0];
}

static bool normalize(double v[3]) {
  double n = sqrt(dot(v, v));
  if (!(n > 1e-12)) return false;
  v[0] /= n, v[1] /= n, v[2] /= n;
  return true;
}

/* Two unit vectors completing d (unit) to an orthonormal basis. */
static void basis(const double d[3], double e1[3], double e2[3]) {
  double ref[3] = {1.0, 0.0, 0.0};
  if (fabs(d[0]) > 0.9) ref[0] = 0.0, ref[1] = 1.0;
  cross(d, ref, e1);
  normalize(e1);
  cross(d, e1, e2);
}

void sylva__lateral_direction(const double d[3], double theta, double phi, double out[3]) {
  double e1[3], e2[3];
  basis(d, e1, e2);
  double cp = cos(phi * SYLVA__DEG), sp = sin(phi * SYLVA__DEG);
  double a[3] = {e1[0] * cp + e2[0] * sp, e1[1] * cp + e2[1] * sp, e1[2] * cp + e2[2] * sp};
  /* rotate d by theta around a (a is perpendicular to d): d cos + (a x d) sin */
  double axd[3];
  cross(a, d, axd);
  double ct = cos(theta * SYLVA__DEG), st = sin(theta * SYLVA__DEG);
  for (int i = 0; i < 3; i++) out[i] = d[i] * ct + axd[i] * st;
  normalize(out);
}

static void internode_direction(const sylva__skeleton *s, int32_t n, double d[3]) {
  int32_t p = s->parent[n];
  if (p < 0) {
    d[0] = 0.0, d[1] = 0.0, d[2] = 1.0;
    return;
  }
  d[0] = (double)s->x[n] - s->x[p];
  d[1] = (double)s->y[n] - s->y[p];
  d[2] = (double)s->z[n] - s->z[p];
  if (!normalize(d)) d[0] = 0.0, d[1] = 0.0, d[2] = 1.0;
}

/* ---- competition index: sprouting nodes in a dense grid of cells ------------- */

typedef struct index_ctx {
  double min[3], cell;
  int64_t dims[3];
} index_ctx;

static int64_t cell_of(const index_ctx *ix, int a, double v) {
  double f = floor((v - ix->min[a]) / ix->cell);
  if (f < 0.0) return 0;
  if (f >= (double)ix->dims[a]) return ix->dims[a] - 1;
  return (int64_t)f;
}

/* Counting sort of the sprouts into cells of at least the longest marker cone over
 * their bounding box; positions are copied beside them for scanning. */
static int build_index(sylva_world *w, index_ctx *ix) {
  size_t n = w->sprouts.len;
  const sylva__skeleton *s = &w->nodes;
  double cell = 0.0;
  for (int k = 0; k < w->species_count; k++) {
    double c = w->species[k].def.cone_radius * w->species[k].def.rho;
    if (c > cell) cell = c;
  }
  double mn[3] = {0, 0, 0}, mx[3] = {0, 0, 0};
  for (size_t i = 0; i < n; i++) {
    int32_t slot = w->sprouts.data[i].slot;
    double p[3] = {s->x[slot], s->y[slot], s->z[slot]};
    for (int a = 0; a < 3; a++) {
      if (i == 0 || p[a] < mn[a]) mn[a] = p[a];
      if (i == 0 || p[a] > mx[a]) mx[a] = p[a];
    }
  }
  ix->cell = cell > 0.0 ? cell : 1.0;
  for (;;) {
    double cells = 1.0;
    for (int a = 0; a < 3; a++) cells *= floor((mx[a] - mn[a]) / ix->cell) + 1.0;
    if (cells <= (double)(1 << 22)) break;
    ix->cell *= 2.0; /* any cell size is correct; larger only scans more */
  }
  size_t ncells = 1;
  for (int a = 0; a < 3; a++) {
    ix->min[a] = mn[a];
    ix->dims[a] = (int64_t)floor((mx[a] - mn[a]) / ix->cell) + 1;
    ncells *= (size_t)ix->dims[a];
  }
  if (SYLVA__VEC_RESERVE(w->cell_first, ncells + 1) || SYLVA__VEC_RESERVE(w->cell_items, n + 1) ||
      SYLVA__VEC_RESERVE(w->cell_pos, 3 * n + 3) || SYLVA__VEC_RESERVE(w->cell_of, n + 1))
    return SYLVA_ENOMEM;
  int32_t *first = w->cell_first.data, *of = w->cell_of.data;
  /* Counting sort: first[c] counts cell c's items, then (summed) marks the end of
   * cell c; filling each cell from its end, last item first, keeps the items in order
   * and leaves first[c] at the cell's start. */
  for (size_t c = 0; c <= ncells; c++) first[c] = 0;
  for (size_t i = 0; i < n; i++) {
    int32_t slot = w->sprouts.data[i].slot;
    int64_t c = (cell_of(ix, 2, s->z[slot]) * ix->dims[1] + cell_of(ix, 1, s->y[slot])) *
                    ix->dims[0] + cell_of(ix, 0, s->x[slot]);
    of[i] = (int32_t)c;
    first[c]++;
  }
  for (size_t c = 1; c <= ncells; c++) first[c] += first[c - 1];
  for (size_t i = n; i-- > 0;) {
    int32_t at = --first[of[i]];
    int32_t slot = w->sprouts.data[i].slot;
    w->cell_items.data[at] = (int32_t)i;
    w->cell_pos.data[3 * at] = s->x[slot];
    w->cell_pos.data[3 * at + 1] = s->y[slot];
    w->cell_pos.data[3 * at + 2] = s->z[slot];
  }
  return SYLVA_OK;
}

/* True when a sprouting node other than self is closer to p than d2 (squared).
 * *hint is the index entry that answered true last (-1: none), asked first: three in
 * four markers are contested, and mostly by the sprout that took the shoot's previous
 * marker (the 100-tree stand and the lindens: 19 entries scanned a marker without
 * it). The answer is the same whichever entry gives it. */
static bool contested(const sylva_world *w, const index_ctx *ix, const double p[3], double d2,
                      int32_t self, int32_t *hint) {
  const int32_t *first = w->cell_first.data, *items = w->cell_items.data;
  const float *pos = w->cell_pos.data;
  if (*hint >= 0) {
    int32_t k = *hint;
    double dx = pos[3 * k] - p[0], dy = pos[3 * k + 1] - p[1], dz = pos[3 * k + 2] - p[2];
    if (dx * dx + dy * dy + dz * dz < d2 && items[k] != self) return true;
  }
  double d = sqrt(d2);
  int64_t lo[3], hi[3];
  for (int a = 0; a < 3; a++) {
    lo[a] = cell_of(ix, a, p[a] - d);
    hi[a] = cell_of(ix, a, p[a] + d);
  }
  for (int64_t cz = lo[2]; cz <= hi[2]; cz++)
    for (int64_t cy = lo[1]; cy <= hi[1]; cy++) {
      int64_t row = (cz * ix->dims[1] + cy) * ix->dims[0];
      for (int32_t k = first[row + lo[0]]; k < first[row + hi[0] + 1]; k++) {
        double dx = pos[3 * k] - p[0], dy = pos[3 * k + 1] - p[1], dz = pos[3 * k + 2] - p[2];
        if (dx * dx + dy * dy + dz * dz < d2 && items[k] != self) {
          *hint = k;
          return true;
        }
      }
    }
  return false;
}

/* ---- one shoot ----------------------------------------------------------------- */

/* Optimal direction Vo = normalise(sum of l_j v_j): unit vectors to the usable marker
 * points, drawn uniformly in the cone (spherical sector) around vd, weighted by their
 * light. */
static void optimal_direction(sylva_world *w, const index_ctx *ix, const sylva_species_def *d,
                              int markers, const double tip[3], const double vd[3],
                              int32_t self, int32_t *hint, double vo[3]) {
  vo[0] = vo[1] = vo[2] = 0.0;
  if (markers <= 0) return;
  double e1[3], e2[3];
  basis(vd, e1, e2);
  double cos_a = cos(d->cone_angle * SYLVA__DEG);
  double len = d->cone_radius * d->rho;
  /* the markers drawn first, their voxels asked of memory, then read in turn: the
   * same draws and the same sum in the same order */
  enum { BATCH = 32 };
  struct marker {
    double dir[3], p[3], r;
    int v[3];
    bool inside;
  } mk[BATCH];
  for (int m0 = 0; m0 < markers; m0 += BATCH) {
    int n = markers - m0 < BATCH ? markers - m0 : BATCH;
    for (int k = 0; k < n; k++) {
      struct marker *q = &mk[k];
      double u1 = sylva__rng_unit(&w->rng), u2 = sylva__rng_unit(&w->rng),
             u3 = sylva__rng_unit(&w->rng);
      double c = 1.0 - u1 * (1.0 - cos_a);
      double sn = sqrt(fmax(0.0, 1.0 - c * c));
      double psi = 2.0 * 3.14159265358979323846 * u2;
      q->r = len * cbrt(u3);
      for (int i = 0; i < 3; i++)
        q->dir[i] = c * vd[i] + sn * (cos(psi) * e1[i] + sin(psi) * e2[i]);
      for (int i = 0; i < 3; i++) q->p[i] = tip[i] + q->r * q->dir[i];
      /* a marker another sprout is nearer to is not used: three in four are, and
       * their voxels are then neither asked of memory nor read */
      q->inside = sylva__grid_voxel(&w->grid, q->p[0], q->p[1], q->p[2], q->v) &&
                  !contested(w, ix, q->p, q->r * q->r, self, hint);
      if (q->inside) sylva__grid_prefetch(&w->grid, q->v);
    }
    for (int k = 0; k < n; k++) {
      const struct marker *q = &mk[k];
      if (!q->inside) continue;
      if (w->grid.obstacle_count && sylva__grid_blocked(&w->grid, q->v)) continue;
      double l = sylva__grid_free_light(&w->grid, q->v);
      if (l < 0.0) continue; /* occupied */
      for (int i = 0; i < 3; i++) vo[i] += l * q->dir[i];
    }
  }
  /* only the direction counts: mu weighs it against Vd and Vt whatever the number
   * of markers (docs/model.md, "Shoots") */
  if (!normalize(vo)) vo[0] = vo[1] = vo[2] = 0.0;
}

static int grow_shoot(sylva_world *w, const index_ctx *ix, int32_t item, int iteration) {
  const sylva__sprout *sp = &w->sprouts.data[item];
  sylva__skeleton *s = &w->nodes;
  sylva__stem *st = &w->stems[sp->stem];
  const sylva_species_def *d = &w->species[st->species].def;
  int local = sylva__stem_local(st, iteration);
  int markers = d->m0 - local;
  if (markers < d->m_min) markers = d->m_min;
  /* the crown's widest reach for the stem's height (docs/model.md, "Species in years") */
  double reach = INFINITY;
  if (d->crown_max > 0.0) {
    double h = st->stats.height > d->rho ? st->stats.height : d->rho;
    reach = 0.5 * d->crown_max * pow(h, d->crown_max_exp);
  }
  w->shoot.len = 0;
  int32_t tip = sp->slot, hint = -1;
  for (int32_t k = 0; k < sp->n; k++) {
    double vd[3];
    internode_direction(s, tip, vd);
    bool lateral = k == 0 && !sp->apex;
    if (lateral) {
      double axis[3] = {vd[0], vd[1], vd[2]};
      /* successive buds of an axis stand divergence apart */
      int32_t bud = s->depth[tip] / w->species[st->species].bud_every;
      sylva__lateral_direction(axis, d->theta, (double)bud * d->divergence, vd);
    }
    double p0[3] = {s->x[tip], s->y[tip], s->z[tip]};
    double vo[3];
    optimal_direction(w, ix, d, markers, p0, vd, item, &hint, vo);
    double vu[3];
    for (int i = 0; i < 3; i++) vu[i] = vd[i] + d->mu * vo[i] + d->gamma * d->tropism[i];
    if (!normalize(vu)) memcpy(vu, vd, sizeof vu);
    double p[3] = {p0[0] + d->rho * vu[0], p0[1] + d->rho * vu[1], p0[2] + d->rho * vu[2]};
    double dx = p[0] - st->root[0], dy = p[1] - st->root[1];
    if (dx * dx + dy * dy > reach * reach) break; /* beyond the crown's reach: stops */
    int32_t slot = sylva__add_node(w, tip, lateral, p, sp->stem, iteration);
    if (slot == SYLVA_ENOMEM) return SYLVA_ENOMEM;
    if (slot < 0) break; /* outside, obstacle or another stem's voxel: the shoot stops */
    if (SYLVA__VEC_RESERVE(w->shoot, w->shoot.len + 1)) return SYLVA_ENOMEM;
    w->shoot.data[w->shoot.len++] = slot;
    tip = slot;
  }
  return SYLVA_OK;
}

int sylva__shoots(sylva_world *w, int iteration) {
  index_ctx ix;
  int rc = build_index(w, &ix);
  if (rc) return rc;
  if (SYLVA__VEC_RESERVE(w->order, (size_t)w->stem_count + 1)) return SYLVA_ENOMEM;
  sylva__rng_permutation(&w->rng, w->order.data, w->stem_count);
  w->order.len = (size_t)w->stem_count;
  double shade_time = 0.0;
  for (size_t o = 0; o < w->order.len; o++) {
    int32_t stem = w->order.data[o];
    for (int32_t i = w->stem_first.data[stem]; i < w->stem_first.data[stem + 1]; i++) {
      rc = grow_shoot(w, &ix, i, iteration);
      if (rc) return rc;
      /* the shoot's nodes shade the world before the next shoot grows (timed only
       * when it grew: two clock reads a shoot were 1.3% of a 40-year stand's run) */
      if (!w->shoot.len) continue;
      double t0 = w->def.clock ? w->def.clock(w->def.clock_ctx) : 0.0;
      for (size_t k = 0; k < w->shoot.len; k++) {
        rc = sylva__shade_node(w, w->shoot.data[k], +1);
        if (rc) return rc;
        w->mark.shaded = (size_t)w->shoot.data[k] + 1;
      }
      if (w->def.clock) shade_time += w->def.clock(w->def.clock_ctx) - t0;
    }
  }
  w->journal.phase_seconds[SYLVA_PHASE_SHADE] = shade_time;
  return SYLVA_OK;
}
