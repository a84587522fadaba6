#include "prism.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "alloc.h"

void sylva__footprint_free(sylva__footprint *f) {
  if (!f) return;
  sylva__free(f->ring_size);
  sylva__free(f->pt);
  sylva__free(f->rect);
  sylva__free(f);
}

/* Twice the signed area of ring r starting at point first (shoelace). */
static double ring_area2(const double (*pt)[2], int first, int size) {
  double a = 0.0;
  for (int i = 0; i < size; i++) {
    const double *p = pt[first + i], *q = pt[first + (i + 1) % size];
    a += p[0] * q[1] - q[0] * p[1];
  }
  return a;
}

int sylva__footprint_copy(const sylva_footprint *in, sylva__footprint **out) {
  *out = NULL;
  if (in->ring_count < 1 || in->point_count < 3 || in->point_count > SYLVA_FOOTPRINT_MAX_POINTS ||
      in->ring_count > in->point_count / 3 || !in->points || !in->ring_sizes)
    return SYLVA_EINVAL;
  int sum = 0;
  for (int r = 0; r < in->ring_count; r++) {
    if (in->ring_sizes[r] < 3 || in->ring_sizes[r] > in->point_count - sum) return SYLVA_EINVAL;
    if (ring_area2(in->points, sum, in->ring_sizes[r]) == 0.0) return SYLVA_EINVAL;
    sum += in->ring_sizes[r];
  }
  if (sum != in->point_count) return SYLVA_EINVAL;
  for (int i = 0; i < in->point_count; i++)
    if (!isfinite(in->points[i][0]) || !isfinite(in->points[i][1])) return SYLVA_EINVAL;
  sylva__footprint *f = sylva__calloc(1, sizeof *f);
  if (!f) return SYLVA_ENOMEM;
  f->ring_size = sylva__malloc((size_t)in->ring_count * sizeof *f->ring_size);
  f->pt = sylva__malloc((size_t)in->point_count * sizeof *f->pt);
  if (!f->ring_size || !f->pt) {
    sylva__footprint_free(f);
    return SYLVA_ENOMEM;
  }
  f->ring_count = in->ring_count;
  f->point_count = in->point_count;
  memcpy(f->ring_size, in->ring_sizes, (size_t)in->ring_count * sizeof *f->ring_size);
  memcpy(f->pt, in->points, (size_t)in->point_count * sizeof *f->pt);
  for (int a = 0; a < 2; a++) {
    f->min[a] = INFINITY;
    f->max[a] = -INFINITY;
  }
  for (int i = 0; i < f->point_count; i++)
    for (int a = 0; a < 2; a++) {
      f->min[a] = fmin(f->min[a], f->pt[i][a]);
      f->max[a] = fmax(f->max[a], f->pt[i][a]);
    }
  *out = f;
  return SYLVA_OK;
}

/* The x where the edge p-q crosses the line y = yc, when it does: p and q on either
 * side, one strictly above (the crossing rule of the inside test). */
static bool crossing(const double p[2], const double q[2], double yc, double *x) {
  if ((p[1] > yc) == (q[1] > yc)) return false;
  *x = p[0] + (yc - p[1]) * (q[0] - p[0]) / (q[1] - p[1]);
  return true;
}

bool sylva__footprint_inside(const sylva__footprint *f, double x, double y) {
  if (x < f->min[0] || x > f->max[0] || y < f->min[1] || y > f->max[1]) return false;
  bool in = false;
  for (int r = 0, first = 0; r < f->ring_count; first += f->ring_size[r++])
    for (int i = 0; i < f->ring_size[r]; i++) {
      double xc;
      if (crossing(f->pt[first + i], f->pt[first + (i + 1) % f->ring_size[r]], y, &xc) && x < xc)
        in = !in;
    }
  return in;
}

double sylva__footprint_dist2(const sylva__footprint *f, double x, double y) {
  if (sylva__footprint_inside(f, x, y)) return 0.0;
  double best = INFINITY;
  for (int r = 0, first = 0; r < f->ring_count; first += f->ring_size[r++])
    for (int i = 0; i < f->ring_size[r]; i++) {
      const double *p = f->pt[first + i], *q = f->pt[first + (i + 1) % f->ring_size[r]];
      double dx = q[0] - p[0], dy = q[1] - p[1], len2 = dx * dx + dy * dy;
      double t = len2 > 0.0 ? ((x - p[0]) * dx + (y - p[1]) * dy) / len2 : 0.0;
      t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
      double ex = p[0] + t * dx - x, ey = p[1] + t * dy - y;
      best = fmin(best, ex * ex + ey * ey);
    }
  return best;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* A growable array of int32_t[4]. */
typedef struct {
  int32_t (*v)[4];
  int len, cap;
} rects;

static bool rects_push(rects *r, int32_t x0, int32_t y0, int32_t x1, int32_t y1) {
  if (r->len == r->cap) {
    int cap = r->cap ? r->cap * 2 : 8;
    void *m = r->cap > INT32_MAX / 4 ? NULL : sylva__realloc(r->v, (size_t)cap * sizeof *r->v);
    if (!m) return false;
    r->v = m;
    r->cap = cap;
  }
  int32_t *e = r->v[r->len++];
  e[0] = x0;
  e[1] = y0;
  e[2] = x1;
  e[3] = y1;
  return true;
}

int sylva__footprint_voxelize(sylva__footprint *f, const double min[2], double voxel,
                              const int n[2]) {
  sylva__free(f->rect);
  f->rect = NULL;
  f->rect_count = 0;
  /* the rows whose centres the bounds may hold */
  int y0 = (int)fmax(0.0, floor((f->min[1] - min[1]) / voxel - 0.5));
  int y1 = (int)fmin((double)n[1], ceil((f->max[1] - min[1]) / voxel + 0.5));
  rects out = {0}, prev = {0}, cur = {0}; /* prev, cur: runs {x0, x1, rect, 0} */
  double *xs = sylva__malloc((size_t)f->point_count * sizeof *xs);
  bool ok = xs != NULL;
  for (int y = y0; ok && y < y1; y++) {
    double yc = min[1] + (y + 0.5) * voxel;
    int k = 0;
    for (int r = 0, first = 0; r < f->ring_count; first += f->ring_size[r++])
      for (int i = 0; i < f->ring_size[r]; i++)
        if (crossing(f->pt[first + i], f->pt[first + (i + 1) % f->ring_size[r]], yc, &xs[k])) k++;
    qsort(xs, (size_t)k, sizeof *xs, cmp_double);
    cur.len = 0;
    int p = 0; /* the previous row's runs, in order of x0 */
    for (int m = 0; ok && m + 1 < k; m += 2) {
      /* centres x + 0.5 in [xs[m], xs[m + 1]) in voxel units */
      double a = ceil((xs[m] - min[0]) / voxel - 0.5), b = ceil((xs[m + 1] - min[0]) / voxel - 0.5);
      a = fmax(a, 0.0);
      b = fmin(b, (double)n[0]);
      if (!(b > a)) continue;
      int32_t x0 = (int32_t)a, x1 = (int32_t)b;
      while (p < prev.len && prev.v[p][0] < x0) p++;
      int32_t rect;
      if (p < prev.len && prev.v[p][0] == x0 && prev.v[p][1] == x1) {
        rect = prev.v[p][2]; /* the same run as the row below: its rectangle grows */
        out.v[rect][3] = y + 1;
      } else {
        rect = out.len;
        ok = rects_push(&out, x0, y, x1, y + 1);
      }
      ok = ok && rects_push(&cur, x0, x1, rect, 0);
    }
    rects t = prev;
    prev = cur;
    cur = t;
  }
  sylva__free(xs);
  sylva__free(prev.v);
  sylva__free(cur.v);
  if (!ok) {
    sylva__free(out.v);
    return SYLVA_ENOMEM;
  }
  f->rect = out.v;
  f->rect_count = out.len;
  return SYLVA_OK;
}

sylva_footprint sylva__footprint_view(const sylva__footprint *f) {
  return (sylva_footprint){(const double(*)[2])f->pt, f->point_count, f->ring_size, f->ring_count};
}

size_t sylva__footprint_bytes(const sylva__footprint *f) {
  return sizeof *f + (size_t)f->ring_count * sizeof *f->ring_size +
         (size_t)f->point_count * sizeof *f->pt + (size_t)f->rect_count * sizeof *f->rect;
}
