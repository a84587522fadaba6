#include "site.h"

#include <math.h>

/* Whether the ray p + t d (t > 0) passes through the box [lo, hi) (slab test). */
static bool hits_box(const double p[3], const double d[3], const int32_t lo[3],
                     const int32_t hi[3]) {
  double near = 0.0, far = INFINITY;
  for (int a = 0; a < 3; a++) {
    if (d[a] == 0.0) {
      if (p[a] < lo[a] || p[a] >= hi[a]) return false;
      continue;
    }
    double t0 = (lo[a] - p[a]) / d[a], t1 = (hi[a] - p[a]) / d[a];
    if (t0 > t1) {
      double t = t0;
      t0 = t1;
      t1 = t;
    }
    if (t0 > near) near = t0;
    if (t1 < far) far = t1;
    if (near >= far) return false;
  }
  return far > 0.0;
}

double sylva__site_top(const sylva__grid *g) {
  double top = 0.0;
  for (int s = 0; s < g->obstacle_slots; s++)
    if (g->obstacles[s].live && !g->obstacles[s].zone && g->obstacles[s].hi[2] > top) top = g->obstacles[s].hi[2];
  return top;
}

bool sylva__site_blocked(const sylva__grid *g, const double p[3], const double d[3], double top) {
  if (!g->obstacle_cols || p[2] >= top) return false;
  /* the chunk columns under the ray's path, in order (2D DDA over 16-voxel cells) */
  int cx = (int)floor(p[0] / SYLVA__CHUNK), cy = (int)floor(p[1] / SYLVA__CHUNK);
  int step[2] = {d[0] > 0.0 ? 1 : -1, d[1] > 0.0 ? 1 : -1};
  double next[2], delta[2];
  for (int a = 0; a < 2; a++) {
    int c = a == 0 ? cx : cy;
    if (d[a] == 0.0) {
      next[a] = delta[a] = INFINITY;
    } else {
      double edge = (double)(c + (step[a] > 0 ? 1 : 0)) * SYLVA__CHUNK;
      next[a] = (edge - p[a]) / d[a];
      delta[a] = SYLVA__CHUNK / fabs(d[a]);
    }
  }
  double t = 0.0;
  while (cx >= 0 && cy >= 0 && cx < g->c[0] && cy < g->c[1]) {
    /* above every obstacle from here on */
    if (d[2] >= 0.0 && p[2] + t * d[2] >= top) return false;
    const sylva__obstacle_list *l = g->obstacle_cols[(size_t)cy * (size_t)g->c[0] + (size_t)cx];
    if (l)
      for (int32_t i = 0; i < l->count; i++)
        if (hits_box(p, d, l->box[i].lo, l->box[i].hi)) return true;
    if (next[0] < next[1]) {
      t = next[0];
      next[0] += delta[0];
      cx += step[0];
    } else {
      t = next[1];
      next[1] += delta[1];
      cy += step[1];
    }
    if (!isfinite(t)) break; /* a vertical ray: its one column is done */
  }
  return false;
}

double sylva__site_factor(const sylva__grid *g, const sylva_sky_dir *dirs, int count, double top,
                          const int v[3]) {
  double p[3] = {v[0] + 0.5, v[1] + 0.5, v[2] + 0.5}, f = 0.0;
  /* above every obstacle no ray is blocked: the same sum, in the same order */
  bool open = p[2] >= top || !g->obstacle_cols;
  for (int i = 0; i < count; i++)
    if (open || !sylva__site_blocked(g, p, dirs[i].d, top)) f += dirs[i].weight;
  return f;
}
