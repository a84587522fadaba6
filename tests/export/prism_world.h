/* The prisms of the export tests (test_mesh.c, test_gltf.c) and what a mesh of one
 * must measure. The world has no plants and three obstacles, in this order:
 *   0 "house": a solid L-shaped building, legs 8 m and 7 m long and 3 m wide, with
 *     a 1 m square courtyard in the corner where they meet, turned 30 degrees about
 *     the origin and moved by (-3, -4); z 0 to 9.5;
 *   1 "slab": a solid prism on the rectangle [1, 2] x [1, 3], its ring clockwise,
 *     z 1 to 4;
 *   2 "yard": a clearance zone, the house's footprint 20 m farther along x, z 0 to 4.5.
 * Another world holds the box of the slab's corners alone, "block" (in one world,
 * their vertices would coincide, and assimp would join them).
 * The house's points are snapped to 1/32 m, which the "%.5f" of OBJ and PLY and the
 * single precision of glTF hold exactly: the files hold the footprint itself, and
 * their measures agree with the footprint's to the rounding of the sums. */
#ifndef SYLVA_TEST_PRISM_WORLD_H
#define SYLVA_TEST_PRISM_WORLD_H

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "../check.h"
#include "sylva/sylva.h"

enum { PRISMS = 3, HOUSE_POINTS = 10 };

static double house_points[HOUSE_POINTS][2], yard_points[HOUSE_POINTS][2];
static const int house_rings[2] = {6, 4};
static const double slab_points[4][2] = {{1, 1}, {1, 3}, {2, 3}, {2, 1}};
static const int slab_rings[1] = {4};

/* A world of the default box without plants holding the n obstacles defs, or NULL. */
static sylva_world *obstacles_world(const sylva_obstacle_def *defs, int n) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w;
  if (sylva_world_create(&wd, &w) < 0) return NULL;
  for (int i = 0; i < n; i++)
    if (sylva_world_add_obstacle(w, &defs[i]) < 0) {
      sylva_world_destroy(w);
      return NULL;
    }
  return w;
}

/* The world above; NULL when it could not be made. */
static sylva_world *prism_world(void) {
  /* the L counter-clockwise, the courtyard in its corner square [0, 3] x [0, 3] */
  static const double plan[HOUSE_POINTS][2] = {{0, 0}, {8, 0}, {8, 3}, {3, 3}, {3, 7},
                                               {0, 7}, {1, 1}, {2, 1}, {2, 2}, {1, 2}};
  double c = sqrt(3.0) / 2, s = 0.5; /* 30 degrees */
  for (int k = 0; k < HOUSE_POINTS; k++) {
    double x = c * plan[k][0] - s * plan[k][1] - 3, y = s * plan[k][0] + c * plan[k][1] - 4;
    house_points[k][0] = round(32 * x) / 32;
    house_points[k][1] = round(32 * y) / 32;
    yard_points[k][0] = house_points[k][0] + 20;
    yard_points[k][1] = house_points[k][1];
  }
  sylva_footprint house = {(const double(*)[2])house_points, HOUSE_POINTS, house_rings, 2};
  sylva_footprint yard = {(const double(*)[2])yard_points, HOUSE_POINTS, house_rings, 2};
  sylva_footprint slab = {slab_points, 4, slab_rings, 1};
  const sylva_obstacle_def defs[PRISMS] = {
      {"house", {0, 0, 0}, {0, 0, 9.5}, SYLVA_OBSTACLE_SOLID, house},
      {"slab", {0, 0, 1}, {0, 0, 4}, SYLVA_OBSTACLE_SOLID, slab},
      {"yard", {0, 0, 0}, {0, 0, 4.5}, SYLVA_OBSTACLE_ZONE, yard}};
  return obstacles_world(defs, PRISMS);
}

/* The world of the box "block" alone; NULL when it could not be made. */
static sylva_world *block_world(void) {
  static const sylva_obstacle_def block = {
      "block", {1, 1, 1}, {2, 3, 4}, SYLVA_OBSTACLE_SOLID, {0}};
  return obstacles_world(&block, 1);
}

/* Twice the signed area of ring r of a footprint (counter-clockwise positive). */
static double ring_area2(const sylva_footprint *fp, int first, int n) {
  double sum = 0;
  for (int j = 0; j < n; j++) {
    const double *a = fp->points[first + j], *b = fp->points[first + (j + 1) % n];
    sum += a[0] * b[1] - b[0] * a[1];
  }
  return sum;
}

/* The area of an obstacle's footprint: a box's rectangle, or a prism's first ring
 * less the others (holes inside it, as the house's courtyard). */
static double footprint_area(const sylva_obstacle_def *o) {
  const sylva_footprint *fp = &o->footprint;
  if (fp->ring_count == 0) return (o->max[0] - o->min[0]) * (o->max[1] - o->min[1]);
  double area = 0;
  for (int r = 0, first = 0; r < fp->ring_count; first += fp->ring_sizes[r++]) {
    double a = fabs(ring_area2(fp, first, fp->ring_sizes[r])) / 2;
    area += r == 0 ? a : -a;
  }
  return area;
}

/* Whether (x, y) lies inside an obstacle's footprint (even-odd for a prism). */
static bool inside_footprint(const sylva_obstacle_def *o, double x, double y) {
  const sylva_footprint *fp = &o->footprint;
  if (fp->ring_count == 0) return x > o->min[0] && x < o->max[0] && y > o->min[1] && y < o->max[1];
  bool inside = false;
  for (int r = 0, first = 0; r < fp->ring_count; first += fp->ring_sizes[r++])
    for (int j = 0, n = fp->ring_sizes[r]; j < n; j++) {
      const double *a = fp->points[first + j], *b = fp->points[first + (j + 1) % n];
      if ((a[1] > y) != (b[1] > y) && x < a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1]))
        inside = !inside;
    }
  return inside;
}

/* What a triangle mesh of an obstacle measures. */
typedef struct mesh_measure {
  bool closed;        /* every edge in two triangles, once each way */
  double volume;      /* the divergence theorem: the sum of a . (b x c) / 6 */
  double top, bottom; /* the area of the triangles in the planes z = max and z = min,
                         facing up and down (one facing the other way subtracts) */
  double lo[3], hi[3];
  size_t walls;       /* the other triangles */
  size_t bad_walls;   /* walls not facing out of the footprint, or not vertical */
} mesh_measure;

static int compare_edges(const void *a, const void *b) {
  const size_t *s = a, *t = b;
  if (s[0] != t[0]) return s[0] < t[0] ? -1 : 1;
  return (s[1] > t[1]) - (s[1] < t[1]);
}

/* Whether each directed edge of the nf triangles f comes once, its reverse once. */
static bool mesh_closed(const size_t (*f)[3], size_t nf) {
  size_t n = 3 * nf;
  size_t(*e)[2] = malloc((n ? n : 1) * sizeof *e);
  if (!e) exit(1);
  for (size_t k = 0; k < nf; k++)
    for (int c = 0; c < 3; c++) {
      e[3 * k + (size_t)c][0] = f[k][c];
      e[3 * k + (size_t)c][1] = f[k][(c + 1) % 3];
    }
  qsort(e, n, sizeof *e, compare_edges);
  bool closed = n > 0;
  for (size_t k = 0; closed && k < n; k++) {
    size_t rev[2] = {e[k][1], e[k][0]};
    closed = (k + 1 == n || compare_edges(e[k], e[k + 1]) != 0) &&
             bsearch(rev, e, n, sizeof *e, compare_edges) != NULL;
  }
  free(e);
  return closed;
}

/* The measures of the nf triangles f (indices into v, world metres, z up) of
 * obstacle o. */
static mesh_measure measure_mesh(const double (*v)[3], const size_t (*f)[3], size_t nf,
                                 const sylva_obstacle_def *o) {
  mesh_measure m;
  memset(&m, 0, sizeof m);
  m.closed = mesh_closed(f, nf);
  for (size_t k = 0; k < nf; k++) {
    const double *a = v[f[k][0]], *b = v[f[k][1]], *c = v[f[k][2]];
    m.volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                 a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
    for (int q = 0; q < 3; q++)
      for (int d = 0; d < 3; d++) {
        double x = v[f[k][q]][d];
        if ((k == 0 && q == 0) || x < m.lo[d]) m.lo[d] = x;
        if ((k == 0 && q == 0) || x > m.hi[d]) m.hi[d] = x;
      }
    double e1[3], e2[3], n[3];
    for (int d = 0; d < 3; d++) e1[d] = b[d] - a[d], e2[d] = c[d] - a[d];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    bool flat_top = a[2] == o->max[2] && b[2] == o->max[2] && c[2] == o->max[2];
    bool flat_bottom = a[2] == o->min[2] && b[2] == o->min[2] && c[2] == o->min[2];
    if (flat_top) m.top += n[2] / 2;
    if (flat_bottom) m.bottom -= n[2] / 2;
    if (flat_top || flat_bottom) continue;
    /* a wall: vertical, with the footprint just behind it and not just before it */
    m.walls++;
    double h = hypot(n[0], n[1]), g[2] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3};
    double ux = n[0] / h * 1e-3, uy = n[1] / h * 1e-3;
    if (!(h > 0) || fabs(n[2]) > 1e-9 * h || inside_footprint(o, g[0] + ux, g[1] + uy) ||
        !inside_footprint(o, g[0] - ux, g[1] - uy))
      m.bad_walls++;
  }
  return m;
}

/* Checks m, the measures of a mesh of obstacle o: closed, of the footprint's volume
 * (its area x its height) and cap areas within 1e-9, `walls` wall triangles all
 * facing out of the footprint, o's bounds. */
static void check_measures(const mesh_measure *m, const sylva_obstacle_def *o, size_t walls) {
  double area = footprint_area(o), height = o->max[2] - o->min[2];
  CHECK(m->closed);
  CHECK_NEAR(m->volume / (area * height), 1.0, 1e-9);
  CHECK_NEAR(m->top / area, 1.0, 1e-9);
  CHECK_NEAR(m->bottom / area, 1.0, 1e-9);
  CHECK_INT(m->walls, walls);
  CHECK_INT(m->bad_walls, 0);
  for (int d = 0; d < 3; d++) {
    CHECK_NEAR(m->lo[d], o->min[d], 0);
    CHECK_NEAR(m->hi[d], o->max[d], 0);
  }
}

#endif
