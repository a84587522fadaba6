/* Prism meshes (prism_mesh.h): GLU's tessellator over the footprint's rings, then
 * the points the triangles use renumbered in their order and the boundary edges
 * sorted.
 *
 * With an edge-flag callback the tessellator gives separate triangles only (no fans
 * or strips), and the flag in effect when a corner comes says whether the edge from
 * it to the next corner lies on the inside's boundary. Vertex data are the point's
 * number plus one, carried as a pointer. */
#include "prism_mesh.h"

#include <GL/glu.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/status.h"

/* One tessellation as it comes: the points (the footprint's, then the crossings),
 * the triangles and, per triangle, bit k set when its edge from corner k to corner
 * k + 1 (mod 3) lies on the boundary. */
typedef struct tess_state {
  double (*xy)[2];
  size_t points, cap_points;
  size_t (*tri)[3];
  unsigned char *boundary;
  size_t triangles, cap_triangles, cap_boundary;
  int corner;      /* corners of the current triangle received */
  bool edge;       /* the edge flag in effect */
  bool nomem;      /* an allocation failed, here or in the tessellator */
  bool refused;    /* any other error of the tessellator */
} tess_state;

static void *point_data(size_t i) { return (void *)(uintptr_t)(i + 1); }

static size_t data_point(const void *data) { return (size_t)(uintptr_t)data - 1; }

/* p (capacity *cap items of `size` bytes) with room for `need` items: p itself or
 * its reallocation; NULL when out of memory (p is kept). */
static void *reserve(void *p, size_t *cap, size_t need, size_t size) {
  if (need <= *cap) return p;
  size_t n = *cap ? *cap : 16;
  while (n < need) {
    if (n > SIZE_MAX / 2 / size) return NULL;
    n *= 2;
  }
  void *q = realloc(p, n * size);
  if (q) *cap = n;
  return q;
}

static void GLAPIENTRY on_begin(GLenum type, void *data) {
  tess_state *t = data;
  if (type != GL_TRIANGLES) t->refused = true;
  t->corner = 0;
}

static void GLAPIENTRY on_edge_flag(GLboolean flag, void *data) {
  tess_state *t = data;
  t->edge = flag != GL_FALSE;
}

static void GLAPIENTRY on_vertex(void *vertex, void *data) {
  tess_state *t = data;
  if (t->nomem) return;
  if (t->corner == 0) {
    size_t(*tri)[3] = reserve(t->tri, &t->cap_triangles, t->triangles + 1, sizeof *t->tri);
    if (tri) t->tri = tri;
    unsigned char *boundary =
        reserve(t->boundary, &t->cap_boundary, t->triangles + 1, sizeof *t->boundary);
    if (boundary) t->boundary = boundary;
    if (!tri || !boundary) {
      t->nomem = true;
      return;
    }
    t->boundary[t->triangles] = 0;
  }
  t->tri[t->triangles][t->corner] = data_point(vertex);
  if (t->edge) t->boundary[t->triangles] |= (unsigned char)(1u << t->corner);
  if (++t->corner == 3) {
    t->corner = 0;
    t->triangles++;
  }
}

static void GLAPIENTRY on_end(void *data) { (void)data; }

/* Where points coincide, the first of them; where rings cross, a new point. */
static void GLAPIENTRY on_combine(GLdouble coords[3], void *vertex_data[4], GLfloat weight[4],
                                  void **out, void *data) {
  (void)weight;
  tess_state *t = data;
  *out = vertex_data[0]; /* also a valid answer when the point cannot be kept */
  const double *first = t->xy[data_point(vertex_data[0])];
  if (t->nomem || (first[0] == coords[0] && first[1] == coords[1])) return;
  double(*xy)[2] = reserve(t->xy, &t->cap_points, t->points + 1, sizeof *t->xy);
  if (!xy) {
    t->nomem = true;
    return;
  }
  t->xy = xy;
  t->xy[t->points][0] = coords[0];
  t->xy[t->points][1] = coords[1];
  *out = point_data(t->points++);
}

static void GLAPIENTRY on_error(GLenum error, void *data) {
  tess_state *t = data;
  if (error == GLU_OUT_OF_MEMORY) t->nomem = true;
  else t->refused = true;
}

/* Runs the tessellator over the footprint into t (t->xy holds its points). */
static void tessellate(const sylva_footprint *fp, tess_state *t) {
  size_t n = (size_t)fp->point_count;
  GLdouble(*coords)[3] = malloc(n * sizeof *coords);
  GLUtesselator *tess = coords ? gluNewTess() : NULL;
  if (!tess) {
    free(coords);
    t->nomem = true;
    return;
  }
  gluTessProperty(tess, GLU_TESS_WINDING_RULE, GLU_TESS_WINDING_ODD);
  gluTessNormal(tess, 0.0, 0.0, 1.0);
  gluTessCallback(tess, GLU_TESS_BEGIN_DATA, (_GLUfuncptr)on_begin);
  gluTessCallback(tess, GLU_TESS_EDGE_FLAG_DATA, (_GLUfuncptr)on_edge_flag);
  gluTessCallback(tess, GLU_TESS_VERTEX_DATA, (_GLUfuncptr)on_vertex);
  gluTessCallback(tess, GLU_TESS_END_DATA, (_GLUfuncptr)on_end);
  gluTessCallback(tess, GLU_TESS_COMBINE_DATA, (_GLUfuncptr)on_combine);
  gluTessCallback(tess, GLU_TESS_ERROR_DATA, (_GLUfuncptr)on_error);
  gluTessBeginPolygon(tess, t);
  size_t k = 0;
  for (int r = 0; r < fp->ring_count; r++) {
    gluTessBeginContour(tess);
    for (int j = 0; j < fp->ring_sizes[r]; j++, k++) {
      coords[k][0] = fp->points[k][0];
      coords[k][1] = fp->points[k][1];
      coords[k][2] = 0.0;
      gluTessVertex(tess, coords[k], point_data(k));
    }
    gluTessEndContour(tess);
  }
  gluTessEndPolygon(tess);
  gluDeleteTess(tess);
  free(coords);
  if (t->corner != 0) t->refused = true;
}

static int compare_walls(const void *a, const void *b) {
  const size_t *s = a, *u = b;
  if (s[0] != u[0]) return s[0] < u[0] ? -1 : 1;
  return (s[1] > u[1]) - (s[1] < u[1]);
}

/* The used points of t renumbered in their order, the triangles and walls in those
 * numbers, into out. */
static int collect(tess_state *t, prism_mesh *out) {
  size_t *number = malloc((t->points ? t->points : 1) * sizeof *number);
  if (!number) return SYLVA_ENOMEM;
  for (size_t i = 0; i < t->points; i++) number[i] = SIZE_MAX;
  size_t walls = 0;
  for (size_t f = 0; f < t->triangles; f++) {
    for (int c = 0; c < 3; c++) number[t->tri[f][c]] = 0;
    for (int c = 0; c < 3; c++) walls += (t->boundary[f] >> c) & 1;
  }
  size_t used = 0;
  for (size_t i = 0; i < t->points; i++)
    if (number[i] == 0) {
      number[i] = used;
      /* in place: the kept points only move down */
      memmove(t->xy[used], t->xy[i], sizeof *t->xy);
      used++;
    }
  out->wall = malloc((walls ? walls : 1) * sizeof *out->wall);
  if (!out->wall) {
    free(number);
    return SYLVA_ENOMEM;
  }
  size_t w = 0;
  for (size_t f = 0; f < t->triangles; f++) {
    for (int c = 0; c < 3; c++) t->tri[f][c] = number[t->tri[f][c]];
    for (int c = 0; c < 3; c++)
      if ((t->boundary[f] >> c) & 1) {
        out->wall[w][0] = t->tri[f][c];
        out->wall[w][1] = t->tri[f][(c + 1) % 3];
        w++;
      }
  }
  free(number);
  qsort(out->wall, walls, sizeof *out->wall, compare_walls);
  out->walls = walls;
  out->xy = t->xy;
  out->points = used;
  out->tri = t->tri;
  out->triangles = t->triangles;
  t->xy = NULL;
  t->tri = NULL;
  return 0;
}

int prism_mesh_build(const sylva_obstacle_def *def, prism_mesh *out) {
  memset(out, 0, sizeof *out);
  const sylva_footprint *fp = &def->footprint;
  if (fp->ring_count == 0) return 0;
  tess_state t = {0};
  size_t n = (size_t)fp->point_count;
  t.xy = malloc(n * sizeof *t.xy);
  int rc = 0;
  if (!t.xy) {
    rc = SYLVA_ENOMEM;
  } else {
    memcpy(t.xy, fp->points, n * sizeof *t.xy);
    t.points = t.cap_points = n;
    tessellate(fp, &t);
    rc = t.nomem ? SYLVA_ENOMEM : t.refused ? SYLVA_EINVAL : collect(&t, out);
  }
  free(t.xy);
  free(t.tri);
  free(t.boundary);
  if (rc < 0) {
    prism_mesh_free(out);
    return rc;
  }
  out->prism = true;
  out->bottom = def->min[2];
  out->top = def->max[2];
  return 0;
}

void prism_mesh_free(prism_mesh *m) {
  free(m->xy);
  free(m->tri);
  free(m->wall);
  memset(m, 0, sizeof *m);
}

int prism_meshes_build(const sylva_world *w, prism_mesh **out, int *count) {
  int n = sylva_world_obstacle_count(w);
  *out = NULL;
  *count = 0;
  if (n == 0) return 0;
  prism_mesh *m = calloc((size_t)n, sizeof *m);
  if (!m) return SYLVA_ENOMEM;
  for (int i = 0; i < n; i++) {
    sylva_obstacle_def def;
    sylva_world_obstacle_at(w, i, NULL, &def);
    int rc = prism_mesh_build(&def, &m[i]);
    if (rc < 0) {
      prism_meshes_free(m, i);
      return rc;
    }
  }
  *out = m;
  *count = n;
  return 0;
}

void prism_meshes_free(prism_mesh *m, int n) {
  for (int i = 0; m && i < n; i++) prism_mesh_free(&m[i]);
  free(m);
}
