/* Mesh export (OBJ, PLY) of a world's branches as generalized cylinders; see mesh.h.
 *
 * Two passes over the live nodes. The plan pass maps parent ids to node indices
 * (sylva_world_node_index), marks each node's first child and sorts the nodes by
 * stem (counting sort, stable, so id order holds within a stem). The geometry pass (sylva_mesh_branches,
 * which the glTF export shares) gives ring after ring, stem by stem; it keeps one
 * frame (u, t) per node so children can carry their parent's frame. */
#include "mesh.h"
#include "prism_mesh.h"
#include "vec3.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define MESH_TAU 6.283185307179586476925286766559

/* The nodes of a world, indexed by their position i in id order. */
typedef struct mesh_plan {
  size_t n;              /* live nodes */
  int stems;             /* stems of all plants */
  int32_t *parent;       /* node index of the parent, or -1 */
  int32_t *first_child;  /* node index of the first (lowest id) child, or -1 */
  int32_t *order;        /* node indices sorted by (global stem, id) */
  int32_t *ring;         /* ring number (global, in layout order), or -1 without geometry */
  size_t *stem_start;    /* stems + 1 offsets into order */
  size_t rings, internodes, caps;
} mesh_plan;

static void plan_free(mesh_plan *p) {
  free(p->parent);
  free(p->first_child);
  free(p->order);
  free(p->ring);
  free(p->stem_start);
  memset(p, 0, sizeof *p);
}

static bool has_geometry(const mesh_plan *p, size_t i) {
  return p->parent[i] >= 0 || p->first_child[i] >= 0;
}

static int plan_build(const sylva_world *w, mesh_plan *p) {
  memset(p, 0, sizeof *p);
  size_t n = sylva_world_node_count(w);
  /* node ids are int32, so the indices fit too */
  assert(n <= (size_t)INT32_MAX);
  p->n = n;
  p->stems = sylva_world_stem_count(w);
  size_t m = n ? n : 1;
  p->parent = malloc(m * sizeof *p->parent);
  p->first_child = malloc(m * sizeof *p->first_child);
  p->order = malloc(m * sizeof *p->order);
  p->ring = malloc(m * sizeof *p->ring);
  p->stem_start = calloc((size_t)p->stems + 1, sizeof *p->stem_start);
  if (!p->parent || !p->first_child || !p->order || !p->ring || !p->stem_start) {
    plan_free(p);
    return SYLVA_ENOMEM;
  }
  sylva_node_info info;
  for (size_t i = 0; i < n; i++) {
    sylva_world_node_at(w, i, &info);
    p->first_child[i] = -1;
    p->parent[i] = -1;
    if (info.parent >= 0) {
      int32_t q = (int32_t)sylva_world_node_index(w, info.parent);
      assert(q >= 0); /* a live node's parent is live and comes first */
      p->parent[i] = q;
      if (p->first_child[q] < 0) p->first_child[q] = (int32_t)i;
    }
    int s = sylva_world_stem_index(w, info.plant, info.stem);
    assert(s >= 0 && s < p->stems);
    p->stem_start[s + 1]++;
  }
  for (int s = 0; s < p->stems; s++) p->stem_start[s + 1] += p->stem_start[s];
  /* stem_start[s] is stem s's insertion point while placing and ends at the start of
   * stem s + 1; shifting by one entry restores the starts */
  for (size_t i = 0; i < n; i++) {
    sylva_world_node_at(w, i, &info);
    int s = sylva_world_stem_index(w, info.plant, info.stem);
    p->order[p->stem_start[s]++] = (int32_t)i;
  }
  for (int s = p->stems; s > 0; s--) p->stem_start[s] = p->stem_start[s - 1];
  p->stem_start[0] = 0;
  for (size_t k = 0; k < n; k++) {
    size_t i = (size_t)p->order[k];
    if (!has_geometry(p, i)) {
      p->ring[i] = -1;
      continue;
    }
    p->ring[i] = (int32_t)p->rings++;
    if (p->parent[i] >= 0) p->internodes++;
    /* a tip, or a root with children: both ends of a stem's cylinders are closed */
    if ((p->parent[i] >= 0) != (p->first_child[i] >= 0)) p->caps++;
  }
  return 0;
}

static bool options_ok(sylva_mesh_format format, const sylva_mesh_options *opt) {
  return (format == SYLVA_MESH_OBJ || format == SYLVA_MESH_PLY) &&
         opt->sides >= SYLVA_MESH_MIN_SIDES && opt->sides <= SYLVA_MESH_MAX_SIDES;
}

/* The vertices and faces of an obstacle: a box's 8 and 12, a prism's (mesh.h). */
static void obstacle_counts(const prism_mesh *m, size_t *vertices, size_t *faces) {
  *vertices = m->prism ? 2 * m->points : 8;
  *faces = m->prism ? 2 * m->walls + 2 * m->triangles : 12;
}

/* The counts of the branches and of the n obstacles' meshes. */
static void plan_counts(const mesh_plan *p, const prism_mesh *obstacles, int n,
                        const sylva_mesh_options *opt, size_t *vertices, size_t *faces) {
  size_t sides = (size_t)opt->sides;
  *vertices = sides * p->rings;
  *faces = 2 * sides * p->internodes + (sides - 2) * p->caps;
  for (int i = 0; i < n; i++) {
    size_t v, f;
    obstacle_counts(&obstacles[i], &v, &f);
    *vertices += v;
    *faces += f;
  }
}

/* The meshes of w's obstacles when opt asks for them (*n 0 and *out NULL when not). */
static int plan_obstacles(const sylva_world *w, const sylva_mesh_options *opt, prism_mesh **out,
                          int *n) {
  *out = NULL;
  *n = 0;
  return opt->obstacles ? prism_meshes_build(w, out, n) : 0;
}

sylva_mesh_options sylva_mesh_default_options(void) {
  sylva_mesh_options o = {.sides = 8, .obstacles = false};
  return o;
}

int sylva_mesh_count(const sylva_world *w, sylva_mesh_format format,
                     const sylva_mesh_options *opt, size_t *vertices, size_t *faces) {
  sylva_mesh_options defaults = sylva_mesh_default_options();
  if (!opt) opt = &defaults;
  *vertices = *faces = 0;
  if (!options_ok(format, opt)) return SYLVA_EINVAL;
  prism_mesh *obstacles;
  int n;
  int rc = plan_obstacles(w, opt, &obstacles, &n);
  if (rc < 0) return rc;
  mesh_plan p;
  rc = plan_build(w, &p);
  if (rc == 0) {
    plan_counts(&p, obstacles, n, opt, vertices, faces);
    plan_free(&p);
  }
  prism_meshes_free(obstacles, n);
  return rc;
}


/* A fixed unit vector perpendicular to the unit vector t (+x for t = +z). */
static void first_perpendicular(const double t[3], double u[3]) {
  double e[3] = {0, 0, 0};
  e[fabs(t[0]) < 0.9 ? 0 : 1] = 1;
  double d = dot3(e, t);
  for (int a = 0; a < 3; a++) u[a] = e[a] - d * t[a];
  normalize3(u);
}

/* Parallel transport of the frame vector u0 (perpendicular to t0) to the tangent t1:
 * the smallest rotation that takes t0 to t1, applied to u0 (Rodrigues, with
 * a = t0 x t1 and c = t0 . t1: R v = c v + a x v + a (a . v) / (1 + c)). */
static void transport(const double u0[3], const double t0[3], const double t1[3], double u1[3]) {
  double c = dot3(t0, t1);
  if (1.0 + c < 1e-12) {
    /* a reversal: half a turn about u0 takes t0 to -t0 and keeps u0 */
    memcpy(u1, u0, 3 * sizeof *u1);
  } else {
    double a[3], axu[3];
    cross3(t0, t1, a);
    cross3(a, u0, axu);
    double k = dot3(a, u0) / (1.0 + c);
    for (int i = 0; i < 3; i++) u1[i] = c * u0[i] + axu[i] + k * a[i];
  }
  /* keep the frame orthonormal against rounding drift along long stems */
  double d = dot3(u1, t1);
  for (int i = 0; i < 3; i++) u1[i] -= d * t1[i];
  if (!normalize3(u1)) first_perpendicular(t1, u1);
}

/* ---- the branch geometry, stem by stem (shared by OBJ, PLY and glTF) ---- */

struct sylva_mesh_branches {
  const sylva_world *w;
  mesh_plan p;
  int sides;
  double (*frame)[6]; /* per node: u (0..2), t (3..5) */
  double cosk[SYLVA_MESH_MAX_SIDES], sink[SYLVA_MESH_MAX_SIDES];
};

int sylva_mesh_branches_create(const sylva_world *w, int sides, sylva_mesh_branches **out) {
  *out = NULL;
  if (sides < SYLVA_MESH_MIN_SIDES || sides > SYLVA_MESH_MAX_SIDES) return SYLVA_EINVAL;
  sylva_mesh_branches *b = calloc(1, sizeof *b);
  if (!b) return SYLVA_ENOMEM;
  int rc = plan_build(w, &b->p);
  if (rc < 0) {
    free(b);
    return rc;
  }
  b->frame = malloc((b->p.n ? b->p.n : 1) * sizeof *b->frame);
  if (!b->frame) {
    plan_free(&b->p);
    free(b);
    return SYLVA_ENOMEM;
  }
  b->w = w;
  b->sides = sides;
  for (int j = 0; j < sides; j++) {
    double a = MESH_TAU * j / sides;
    b->cosk[j] = cos(a);
    b->sink[j] = sin(a);
  }
  *out = b;
  return 0;
}

void sylva_mesh_branches_destroy(sylva_mesh_branches *b) {
  if (!b) return;
  free(b->frame);
  plan_free(&b->p);
  free(b);
}

/* The first ring of stem s (rings are numbered in layout order, stem by stem), or
 * the total for a stem without geometry at the end. */
static size_t stem_first_ring(const mesh_plan *p, int s) {
  for (size_t k = p->stem_start[s]; k < p->stem_start[s + 1]; k++) {
    int32_t r = p->ring[p->order[k]];
    if (r >= 0) return (size_t)r;
  }
  return 0;
}

void sylva_mesh_branches_stem(const sylva_mesh_branches *b, int s, size_t *first,
                              size_t *vertices, size_t *triangles) {
  const mesh_plan *p = &b->p;
  size_t n = (size_t)b->sides, rings = 0, internodes = 0, caps = 0;
  for (size_t k = p->stem_start[s]; k < p->stem_start[s + 1]; k++) {
    size_t i = (size_t)p->order[k];
    if (p->ring[i] < 0) continue;
    rings++;
    if (p->parent[i] >= 0) internodes++;
    if ((p->parent[i] >= 0) != (p->first_child[i] >= 0)) caps++;
  }
  *first = rings ? n * stem_first_ring(p, s) : 0;
  *vertices = n * rings;
  *triangles = 2 * n * internodes + (n - 2) * caps;
}

const int32_t *sylva_mesh_branches_stem_nodes(const sylva_mesh_branches *b, int s,
                                              size_t *count) {
  *count = b->p.stem_start[s + 1] - b->p.stem_start[s];
  return b->p.order + b->p.stem_start[s];
}

int32_t sylva_mesh_branches_parent(const sylva_mesh_branches *b, size_t i) {
  assert(i < b->p.n);
  return b->p.parent[i];
}

static void node_position(const sylva_node_info *info, double pos[3]) {
  pos[0] = info->x;
  pos[1] = info->y;
  pos[2] = info->z;
}

/* Computes node i's frame from its parent's (or from scratch for a root). */
static void node_frame(sylva_mesh_branches *b, size_t i, const sylva_node_info *info) {
  const mesh_plan *p = &b->p;
  double *u = b->frame[i], *t = b->frame[i] + 3;
  double pos[3], other[3];
  sylva_node_info o;
  node_position(info, pos);
  if (p->parent[i] < 0) {
    sylva_world_node_at(b->w, (size_t)p->first_child[i], &o);
    node_position(&o, other);
    for (int a = 0; a < 3; a++) t[a] = other[a] - pos[a];
    if (!normalize3(t)) {
      /* no direction to the child: the stem starts upright */
      t[0] = 0;
      t[1] = 0;
      t[2] = 1;
    }
    first_perpendicular(t, u);
    return;
  }
  const double *pu = b->frame[p->parent[i]], *pt = b->frame[p->parent[i]] + 3;
  sylva_world_node_at(b->w, (size_t)p->parent[i], &o);
  node_position(&o, other);
  for (int a = 0; a < 3; a++) t[a] = pos[a] - other[a];
  if (!normalize3(t)) memcpy(t, pt, 3 * sizeof *t); /* a zero-length internode */
  transport(pu, pt, t, u);
}

bool sylva_mesh_branches_vertices(sylva_mesh_branches *b, int s,
                                  bool (*vertex)(void *ctx, const double pos[3],
                                                 const double normal[3]),
                                  void *ctx) {
  const mesh_plan *p = &b->p;
  sylva_node_info info;
  /* a stem's parents come before their children, so every frame is carried from
   * one computed in this same pass */
  for (size_t k = p->stem_start[s]; k < p->stem_start[s + 1]; k++) {
    size_t i = (size_t)p->order[k];
    if (p->ring[i] < 0) continue;
    sylva_world_node_at(b->w, i, &info);
    node_frame(b, i, &info);
    const double *u = b->frame[i], *t = b->frame[i] + 3;
    double v[3], pos[3], r = info.radius;
    cross3(t, u, v);
    node_position(&info, pos);
    for (int j = 0; j < b->sides; j++) {
      double q[3], nrm[3];
      for (int a = 0; a < 3; a++) {
        nrm[a] = b->cosk[j] * u[a] + b->sink[j] * v[a];
        q[a] = pos[a] + r * nrm[a];
      }
      if (!vertex(ctx, q, nrm)) return false;
    }
  }
  return true;
}

bool sylva_mesh_branches_triangles(const sylva_mesh_branches *b, int s,
                                   bool (*triangle)(void *ctx, size_t a, size_t b, size_t c),
                                   void *ctx) {
  const mesh_plan *p = &b->p;
  size_t n = (size_t)b->sides, base = n * stem_first_ring(p, s);
  for (size_t k = p->stem_start[s]; k < p->stem_start[s + 1]; k++) {
    size_t i = (size_t)p->order[k];
    if (p->ring[i] < 0) continue;
    size_t c = (size_t)p->ring[i] * n - base;
    int32_t parent = p->parent[i];
    if (parent >= 0) {
      size_t r = (size_t)p->ring[parent] * n - base;
      for (size_t j = 0; j < n; j++) {
        size_t j1 = (j + 1) % n;
        if (!triangle(ctx, r + j, r + j1, c + j1) || !triangle(ctx, r + j, c + j1, c + j))
          return false;
      }
    }
    if (parent >= 0 && p->first_child[i] < 0) {
      for (size_t j = 1; j + 1 < n; j++)
        if (!triangle(ctx, c, c + j, c + j + 1)) return false;
    } else if (parent < 0) {
      for (size_t j = 1; j + 1 < n; j++)
        if (!triangle(ctx, c, c + j + 1, c + j)) return false;
    }
  }
  return true;
}

/* ---- obstacle boxes ---- */

const int sylva_mesh_box_quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                        {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

void sylva_mesh_box_corner(const sylva_obstacle_def *o, int v, double q[3]) {
  for (int a = 0; a < 3; a++) q[a] = (v >> a) & 1 ? o->max[a] : o->min[a];
}

/* ---- OBJ and PLY ---- */

/* The state of one write. */
typedef struct mesh_writer {
  FILE *out;
  const sylva_world *w;
  sylva_mesh_branches *b;
  sylva_mesh_format format;
  const prism_mesh *obstacles; /* one per obstacle (a box's all zero) */
  int nobstacles;              /* 0 when they are not written */
  size_t obstacle_base;        /* global index of the next obstacle's first vertex */
  size_t base;                 /* global index of the current stem's first vertex */
  int stem;                    /* the current stem: the PLY face property */
} mesh_writer;

static bool stream_ok(const mesh_writer *mw) { return !ferror(mw->out); }

/* Copies a label for a name token: whitespace and control bytes become '_'. */
static void name_token(const char *label, char out[SYLVA_LABEL_MAX]) {
  size_t i = 0;
  for (; label && label[i] && i + 1 < SYLVA_LABEL_MAX; i++) {
    unsigned char c = (unsigned char)label[i];
    out[i] = c <= ' ' || c == 0x7f ? '_' : (char)c;
  }
  out[i] = '\0';
}

static void write_vertex(mesh_writer *mw, const double v[3]) {
  fprintf(mw->out, mw->format == SYLVA_MESH_OBJ ? "v %.5f %.5f %.5f\n" : "%.5f %.5f %.5f\n", v[0],
          v[1], v[2]);
}

/* Global vertex indices (0-based); stem: the PLY face property. */
static void write_face(mesh_writer *mw, size_t a, size_t b, size_t c, int stem) {
  if (mw->format == SYLVA_MESH_OBJ)
    fprintf(mw->out, "f %zu %zu %zu\n", a + 1, b + 1, c + 1);
  else
    fprintf(mw->out, "3 %zu %zu %zu %d\n", a, b, c, stem);
}

static bool stem_vertex(void *ctx, const double pos[3], const double normal[3]) {
  (void)normal;
  mesh_writer *mw = ctx;
  write_vertex(mw, pos);
  return stream_ok(mw);
}

static bool stem_face(void *ctx, size_t a, size_t b, size_t c) {
  mesh_writer *mw = ctx;
  write_face(mw, mw->base + a, mw->base + b, mw->base + c, mw->stem);
  return stream_ok(mw);
}

static bool write_stem_faces(mesh_writer *mw, int s) {
  size_t vertices, triangles;
  sylva_mesh_branches_stem(mw->b, s, &mw->base, &vertices, &triangles);
  mw->stem = s;
  return sylva_mesh_branches_triangles(mw->b, s, stem_face, mw);
}

static void write_obstacle_vertices(mesh_writer *mw, int i) {
  const prism_mesh *m = &mw->obstacles[i];
  if (!m->prism) {
    sylva_obstacle_def o;
    sylva_world_obstacle_at(mw->w, i, NULL, &o);
    for (int v = 0; v < 8; v++) {
      double q[3];
      sylva_mesh_box_corner(&o, v, q);
      write_vertex(mw, q);
    }
    return;
  }
  for (int level = 0; level < 2; level++)
    for (size_t k = 0; k < m->points; k++) {
      double q[3] = {m->xy[k][0], m->xy[k][1], level ? m->top : m->bottom};
      write_vertex(mw, q);
    }
}

/* Obstacle i's faces on its vertices from mw->obstacle_base, which moves past them. */
static void write_obstacle_faces(mesh_writer *mw, int i) {
  const prism_mesh *m = &mw->obstacles[i];
  size_t b = mw->obstacle_base;
  if (!m->prism) {
    /* each side as a quad, counter-clockwise seen from outside */
    for (int f = 0; f < 6; f++) {
      const int *q = sylva_mesh_box_quads[f];
      write_face(mw, b + (size_t)q[0], b + (size_t)q[1], b + (size_t)q[2], -1 - i);
      write_face(mw, b + (size_t)q[0], b + (size_t)q[2], b + (size_t)q[3], -1 - i);
    }
    mw->obstacle_base += 8;
    return;
  }
  /* a wall from its edge's bottom (the solid on its left) up to the top; the
   * bottom cap turned over; the top cap as the tessellator gives it */
  size_t n = m->points;
  for (size_t k = 0; k < m->walls; k++) {
    size_t u = b + m->wall[k][0], v = b + m->wall[k][1];
    write_face(mw, u, v, v + n, -1 - i);
    write_face(mw, u, v + n, u + n, -1 - i);
  }
  for (size_t k = 0; k < m->triangles; k++)
    write_face(mw, b + m->tri[k][0], b + m->tri[k][2], b + m->tri[k][1], -1 - i);
  for (size_t k = 0; k < m->triangles; k++)
    write_face(mw, b + n + m->tri[k][0], b + n + m->tri[k][1], b + n + m->tri[k][2], -1 - i);
  mw->obstacle_base += 2 * n;
}

static int stem_plant(const sylva_world *w, int s, int *stem) {
  int plants = sylva_world_plant_count(w);
  /* stems are numbered in plant order: the last plant whose first stem is <= s */
  int lo = 0, hi = plants - 1;
  while (lo < hi) {
    int mid = lo + (hi - lo + 1) / 2;
    if (sylva_world_stem_index(w, mid, 0) <= s) lo = mid;
    else hi = mid - 1;
  }
  *stem = s - sylva_world_stem_index(w, lo, 0);
  return lo;
}
static void stem_name(const sylva_world *w, int s, char *buf, size_t size) {
  int stem, plant = stem_plant(w, s, &stem);
  char label[SYLVA_LABEL_MAX];
  name_token(sylva_world_plant_label(w, plant), label);
  snprintf(buf, size, "%s_%d", label, stem);
}

static void write_header(mesh_writer *mw, size_t vertices, size_t faces) {
  FILE *out = mw->out;
  const sylva_world *w = mw->w;
  int obstacles = mw->nobstacles;
  char name[SYLVA_LABEL_MAX + 16];
  if (mw->format == SYLVA_MESH_OBJ) {
    fprintf(out,
            "# sylva mesh export: branches as generalized cylinders, one object per stem\n"
            "# iteration %d, %d stems, %d sides, %d obstacles; metres, z up, triangles\n"
            "# vertices %zu, faces %zu\n",
            sylva_world_iteration(w), mw->b->p.stems, mw->b->sides, obstacles, vertices, faces);
    return;
  }
  fprintf(out,
          "ply\n"
          "format ascii 1.0\n"
          "comment sylva mesh export: branches as generalized cylinders\n"
          "comment iteration %d, %d stems, %d sides, %d obstacles; metres, z up\n"
          "comment face property stem: global stem index, or -1 - i for obstacle i\n",
          sylva_world_iteration(w), mw->b->p.stems, mw->b->sides, obstacles);
  for (int s = 0; s < mw->b->p.stems; s++) {
    stem_name(w, s, name, sizeof name);
    fprintf(out, "comment stem %d %s\n", s, name);
  }
  for (int i = 0; i < obstacles; i++) {
    sylva_obstacle_def o;
    sylva_world_obstacle_at(w, i, NULL, &o);
    name_token(o.label, name);
    /* a clearance zone is written as its box or prism too, named for what it is */
    fprintf(out, "comment %s %d %s\n", o.kind == SYLVA_OBSTACLE_ZONE ? "zone" : "obstacle", i, name);
  }
  fprintf(out,
          "element vertex %zu\n"
          "property float x\n"
          "property float y\n"
          "property float z\n"
          "element face %zu\n"
          "property list uchar int vertex_indices\n"
          "property int stem\n"
          "end_header\n",
          vertices, faces);
}

static bool write_body(mesh_writer *mw) {
  int stems = mw->b->p.stems;
  int obstacles = mw->nobstacles;
  char name[SYLVA_LABEL_MAX + 16];
  size_t first, vertices, triangles;
  if (mw->format == SYLVA_MESH_OBJ) {
    for (int s = 0; s < stems; s++) {
      /* a stem of a lone root has no geometry and no object */
      sylva_mesh_branches_stem(mw->b, s, &first, &vertices, &triangles);
      if (!vertices) continue;
      stem_name(mw->w, s, name, sizeof name);
      fprintf(mw->out, "o %s\n", name);
      if (!sylva_mesh_branches_vertices(mw->b, s, stem_vertex, mw) || !write_stem_faces(mw, s))
        return false;
    }
    for (int i = 0; i < obstacles; i++) {
      sylva_obstacle_def o;
      sylva_world_obstacle_at(mw->w, i, NULL, &o);
      name_token(o.label, name);
      fprintf(mw->out, "o %s_%s\n", o.kind == SYLVA_OBSTACLE_ZONE ? "zone" : "obstacle", name);
      write_obstacle_vertices(mw, i);
      write_obstacle_faces(mw, i);
      if (!stream_ok(mw)) return false;
    }
    return true;
  }
  for (int s = 0; s < stems; s++)
    if (!sylva_mesh_branches_vertices(mw->b, s, stem_vertex, mw)) return false;
  for (int i = 0; i < obstacles; i++) write_obstacle_vertices(mw, i);
  for (int s = 0; s < stems; s++)
    if (!write_stem_faces(mw, s)) return false;
  for (int i = 0; i < obstacles; i++) write_obstacle_faces(mw, i);
  return stream_ok(mw);
}

int sylva_mesh_write(FILE *out, const sylva_world *w, sylva_mesh_format format,
                     const sylva_mesh_options *opt) {
  sylva_mesh_options defaults = sylva_mesh_default_options();
  if (!opt) opt = &defaults;
  if (!options_ok(format, opt)) return SYLVA_EINVAL;
  prism_mesh *obstacles;
  int n;
  int rc = plan_obstacles(w, opt, &obstacles, &n);
  if (rc < 0) return rc;
  sylva_mesh_branches *b;
  rc = sylva_mesh_branches_create(w, opt->sides, &b);
  if (rc < 0) {
    prism_meshes_free(obstacles, n);
    return rc;
  }
  size_t vertices, faces;
  plan_counts(&b->p, obstacles, n, opt, &vertices, &faces);
  if (format == SYLVA_MESH_PLY && vertices > (size_t)INT32_MAX) {
    sylva_mesh_branches_destroy(b);
    prism_meshes_free(obstacles, n);
    return SYLVA_ETOOBIG;
  }
  mesh_writer mw = {.out = out, .w = w, .b = b, .format = format, .obstacles = obstacles,
                    .nobstacles = n, .obstacle_base = (size_t)opt->sides * b->p.rings};
  write_header(&mw, vertices, faces);
  bool ok = stream_ok(&mw) && write_body(&mw);
  ok = fflush(out) == 0 && ok;
  int saved = errno;
  sylva_mesh_branches_destroy(b);
  prism_meshes_free(obstacles, n);
  errno = saved;
  return ok ? 0 : SYLVA_MESH_EWRITE;
}
