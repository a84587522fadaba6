/* Mesh export (server/mesh.c): a small world with a tree, a two-root shrub and a
 * wall, grown a few iterations, written as OBJ and PLY with several options. The
 * files are parsed back and checked against counts derived here from the nodes
 * (sylva_mesh_count must agree), against each other (same layout), for the same
 * bytes on a second write, and for geometry: finite vertices, rings of the node's
 * radius perpendicular to its internode, frames carried by parallel transport,
 * outward faces. Write errors and bad options are checked too. The prisms of
 * prism_world.h (an L-shaped building with a courtyard at 30 degrees, a prism equal
 * to a box, the box, a zone) as closed meshes of their footprints' volume.
 *
 * Usage: test_mesh [OUTDIR|- [TEST]]; TEST runs one test alone. With OUTDIR (not -),
 * the files are also written there with a manifest expected.tsv for assimp_check.py:
 *   file <TAB> NAME <TAB> obj|ply <TAB> VERTICES <TAB> FACES
 *   object <TAB> NAME <TAB> OBJECT <TAB> FACES <TAB> VERTICES   (OBJ, one per object) */
#include <errno.h>
#include <stdint.h>
#include <string.h>

#include "../check.h"
#include "export_world.h"
#include "mesh.h"
#include "prism_world.h"
#include "sylva/sylva.h"

/* ---- the world and what the export of it must hold ---- */

/* The world: the tree and the shrub beside a wall. */
static sylva_world *make_world(int iterations) {
  static const sylva_obstacle_def wall = {
      "wall", {-0.2, -3.0, 0.0}, {0.2, 3.0, 2.5}, SYLVA_OBSTACLE_SOLID, {0}};
  return export_world(0x4a7f35, 0x4a7f35, &wall, 1, iterations);
}

/* The nodes of a world with their topology, and the ring layout of mesh.h. */
typedef struct model {
  size_t n;
  sylva_node_info *node;
  int32_t *parent;   /* node index or -1 */
  int32_t *first;    /* first child's node index or -1 */
  int *children;
  int *stem;         /* global stem index */
  int stems;
  size_t *layout;    /* node indices with a ring, in layout order */
  size_t rings, internodes, tips, roots;
  size_t *stem_internodes, *stem_caps, *stem_rings;
  int boxes;
} model;

static int32_t index_of(const model *m, size_t count, int32_t id) {
  size_t lo = 0, hi = count;
  while (lo < hi) {
    size_t mid = (lo + hi) / 2;
    if (m->node[mid].id < id) lo = mid + 1;
    else hi = mid;
  }
  return lo < count && m->node[lo].id == id ? (int32_t)lo : -1;
}

static void model_build(model *m, const sylva_world *w) {
  memset(m, 0, sizeof *m);
  m->n = sylva_world_node_count(w);
  m->stems = sylva_world_stem_count(w);
  m->boxes = sylva_world_obstacle_count(w);
  size_t n = m->n + 1, s = (size_t)m->stems + 1;
  m->node = calloc(n, sizeof *m->node);
  m->parent = calloc(n, sizeof *m->parent);
  m->first = calloc(n, sizeof *m->first);
  m->children = calloc(n, sizeof *m->children);
  m->stem = calloc(n, sizeof *m->stem);
  m->layout = calloc(n, sizeof *m->layout);
  m->stem_internodes = calloc(s, sizeof(size_t));
  m->stem_caps = calloc(s, sizeof(size_t));
  m->stem_rings = calloc(s, sizeof(size_t));
  if (!m->node || !m->parent || !m->first || !m->children || !m->stem || !m->layout ||
      !m->stem_internodes || !m->stem_caps || !m->stem_rings) {
    fprintf(stderr, "out of memory\n");
    exit(1);
  }
  for (size_t i = 0; i < m->n; i++) {
    sylva_world_node_at(w, i, &m->node[i]);
    m->first[i] = -1;
    m->parent[i] = m->node[i].parent < 0 ? -1 : index_of(m, i, m->node[i].parent);
    if (m->node[i].parent >= 0) CHECK(m->parent[i] >= 0);
    if (m->parent[i] >= 0) {
      m->children[m->parent[i]]++;
      if (m->first[m->parent[i]] < 0) m->first[m->parent[i]] = (int32_t)i;
    }
    m->stem[i] = sylva_world_stem_index(w, m->node[i].plant, m->node[i].stem);
  }
  for (int st = 0; st < m->stems; st++) {
    for (size_t i = 0; i < m->n; i++) {
      if (m->stem[i] != st || (m->parent[i] < 0 && m->children[i] == 0)) continue;
      m->layout[m->rings++] = i;
      m->stem_rings[st]++;
      if (m->parent[i] >= 0) m->internodes++, m->stem_internodes[st]++;
      if (m->parent[i] >= 0 && m->children[i] == 0) m->tips++, m->stem_caps[st]++;
      if (m->parent[i] < 0) m->roots++, m->stem_caps[st]++;
    }
  }
}

static void model_free(model *m) {
  free(m->node);
  free(m->parent);
  free(m->first);
  free(m->children);
  free(m->stem);
  free(m->layout);
  free(m->stem_internodes);
  free(m->stem_caps);
  free(m->stem_rings);
}

static void expected_counts(const model *m, int sides, bool boxes, size_t *v, size_t *f) {
  size_t b = boxes ? (size_t)m->boxes : 0, k = (size_t)sides;
  *v = k * (m->internodes + m->roots) + 8 * b;
  *f = 2 * k * m->internodes + (k - 2) * (m->tips + m->roots) + 12 * b;
}

/* ---- writing into memory ---- */

static blob write_blob(const sylva_world *w, sylva_mesh_format format,
                       const sylva_mesh_options *opt) {
  blob b;
  FILE *f = blob_open(&b);
  b.rc = sylva_mesh_write(f, w, format, opt);
  fclose(f);
  return b;
}

/* ---- reading back ---- */

typedef struct parsed {
  bool ok;                 /* every line as the format says */
  size_t nv, nf;           /* vertex and face lines */
  size_t header_v, header_f;
  double (*v)[3];
  size_t (*f)[3];          /* 0-based */
  int *face_tag;           /* PLY: the stem property; OBJ: the object index */
  size_t nobj;
  char (*obj_name)[96];
  size_t *obj_faces;
} parsed;

static void parsed_free(parsed *p) {
  free(p->v);
  free(p->f);
  free(p->face_tag);
  free(p->obj_name);
  free(p->obj_faces);
}

/* Returns the next line (NUL-terminated in place) or NULL at the end. */
static char *next_line(char **cursor, char *end) {
  if (*cursor >= end) return NULL;
  char *line = *cursor, *nl = memchr(line, '\n', (size_t)(end - line));
  if (!nl) {
    *cursor = end;
    return NULL; /* every line must end with a newline */
  }
  *nl = '\0';
  *cursor = nl + 1;
  return line;
}

static bool read_doubles(const char *s, double out[3]) {
  char *e;
  for (int a = 0; a < 3; a++) {
    out[a] = strtod(s, &e);
    if (e == s) return false;
    s = e;
  }
  return *s == '\0';
}

static void parsed_alloc(parsed *p, size_t lines) {
  p->v = calloc(lines + 1, sizeof *p->v);
  p->f = calloc(lines + 1, sizeof *p->f);
  p->face_tag = calloc(lines + 1, sizeof *p->face_tag);
  p->obj_name = calloc(lines + 1, sizeof *p->obj_name);
  p->obj_faces = calloc(lines + 1, sizeof *p->obj_faces);
  if (!p->v || !p->f || !p->face_tag || !p->obj_name || !p->obj_faces) {
    fprintf(stderr, "out of memory\n");
    exit(1);
  }
}

static size_t count_lines(const blob *b) {
  size_t lines = 0;
  for (size_t i = 0; i < b->size; i++) lines += b->data[i] == '\n';
  return lines;
}

static parsed parse_obj(const blob *b) {
  parsed p = {.ok = true};
  parsed_alloc(&p, count_lines(b));
  char *text = malloc(b->size + 1), *cur = text, *end = text + b->size, *line;
  if (!text) exit(1);
  memcpy(text, b->data, b->size);
  long object = -1;
  while ((line = next_line(&cur, end))) {
    if (line[0] == '#') continue;
    if (strncmp(line, "o ", 2) == 0) {
      object = (long)p.nobj++;
      snprintf(p.obj_name[object], sizeof p.obj_name[object], "%s", line + 2);
      if (strchr(line + 2, ' ') || strchr(line + 2, '\t')) p.ok = false;
    } else if (strncmp(line, "v ", 2) == 0) {
      if (!read_doubles(line + 2, p.v[p.nv++])) p.ok = false;
    } else if (strncmp(line, "f ", 2) == 0) {
      size_t a, c, d;
      int used = 0;
      if (sscanf(line + 2, "%zu %zu %zu%n", &a, &c, &d, &used) != 3 || line[2 + used] != '\0' ||
          object < 0 || a < 1 || c < 1 || d < 1) {
        p.ok = false;
        continue;
      }
      p.f[p.nf][0] = a - 1, p.f[p.nf][1] = c - 1, p.f[p.nf][2] = d - 1;
      p.face_tag[p.nf++] = (int)object;
      p.obj_faces[object]++;
    } else {
      p.ok = false;
    }
  }
  if (cur != end) p.ok = false;
  for (size_t i = 0; i < p.nf; i++)
    for (int k = 0; k < 3; k++)
      if (p.f[i][k] >= p.nv) p.ok = false;
  free(text);
  return p;
}

static parsed parse_ply(const blob *b) {
  parsed p = {.ok = true};
  parsed_alloc(&p, count_lines(b));
  char *text = malloc(b->size + 1), *cur = text, *end = text + b->size, *line;
  if (!text) exit(1);
  memcpy(text, b->data, b->size);
  static const char *const props[] = {
      "property float x", "property float y", "property float z",
      "property list uchar int vertex_indices", "property int stem"};
  size_t prop = 0;
  bool head = false;
  line = next_line(&cur, end);
  if (!line || strcmp(line, "ply") != 0) p.ok = false;
  line = next_line(&cur, end);
  if (!line || strcmp(line, "format ascii 1.0") != 0) p.ok = false;
  while ((line = next_line(&cur, end))) {
    if (strcmp(line, "end_header") == 0) {
      head = true;
      break;
    }
    if (strncmp(line, "comment ", 8) == 0) continue;
    if (sscanf(line, "element vertex %zu", &p.header_v) == 1) continue;
    if (sscanf(line, "element face %zu", &p.header_f) == 1) continue;
    if (prop < 5 && strcmp(line, props[prop]) == 0) prop++;
    else p.ok = false;
  }
  if (!head || prop != 5) p.ok = false;
  for (size_t i = 0; p.ok && i < p.header_v; i++) {
    line = next_line(&cur, end);
    if (!line || !read_doubles(line, p.v[p.nv++])) p.ok = false;
  }
  for (size_t i = 0; p.ok && i < p.header_f; i++) {
    line = next_line(&cur, end);
    size_t a, c, d;
    int tag, used = 0;
    if (!line || sscanf(line, "3 %zu %zu %zu %d%n", &a, &c, &d, &tag, &used) != 4 ||
        line[used] != '\0' || a >= p.header_v || c >= p.header_v || d >= p.header_v) {
      p.ok = false;
      break;
    }
    p.f[p.nf][0] = a, p.f[p.nf][1] = c, p.f[p.nf][2] = d;
    p.face_tag[p.nf++] = tag;
  }
  if (cur != end) p.ok = false;
  free(text);
  return p;
}

/* ---- geometry ---- */

static void sub3(const double a[3], const double b[3], double out[3]) {
  for (int k = 0; k < 3; k++) out[k] = a[k] - b[k];
}
static double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static void cross3(const double a[3], const double b[3], double out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}
static double norm3(const double a[3]) { return sqrt(dot3(a, a)); }
static void unit3(double a[3]) {
  double l = norm3(a);
  for (int k = 0; k < 3; k++) a[k] /= l;
}
static void pos_of(const sylva_node_info *n, double out[3]) {
  out[0] = n->x, out[1] = n->y, out[2] = n->z;
}

/* The direction a node's ring faces: its internode, a root's towards its first child. */
static void tangent(const model *m, size_t i, double t[3]) {
  double a[3], b[3];
  if (m->parent[i] >= 0) {
    pos_of(&m->node[m->parent[i]], a);
    pos_of(&m->node[i], b);
  } else {
    pos_of(&m->node[i], a);
    pos_of(&m->node[m->first[i]], b);
  }
  sub3(b, a, t);
  unit3(t);
}

/* Rodrigues rotation taking unit t0 to unit t1, applied to v. */
static void rotate(const double t0[3], const double t1[3], const double v[3], double out[3]) {
  double a[3], axv[3], c = dot3(t0, t1);
  cross3(t0, t1, a);
  cross3(a, v, axv);
  double k = dot3(a, v) / (1 + c);
  for (int q = 0; q < 3; q++) out[q] = c * v[q] + axv[q] + k * a[q];
}

static void face_normal(const parsed *p, size_t f, double n[3], double centroid[3]) {
  const double *a = p->v[p->f[f][0]], *b = p->v[p->f[f][1]], *c = p->v[p->f[f][2]];
  double e1[3], e2[3];
  sub3(b, a, e1);
  sub3(c, a, e2);
  cross3(e1, e2, n);
  for (int k = 0; k < 3; k++) centroid[k] = (a[k] + b[k] + c[k]) / 3;
}
/* The rings of a parsed file against the model: finite vertices, each ring of its
 * node's radius in the plane across its internode, frames carried along by parallel
 * transport. */
static void check_rings(const model *m, const parsed *p, int sides) {
  size_t bad_finite = 0, bad_radius = 0, bad_plane = 0, bad_frame = 0;
  for (size_t i = 0; i < p->nv; i++)
    for (int k = 0; k < 3; k++)
      if (!isfinite(p->v[i][k])) bad_finite++;
  size_t k = (size_t)sides;
  double (*u)[3] = calloc(m->n + 1, sizeof *u); /* u per node, from vertex 0 of its ring */
  if (!u) exit(1);
  for (size_t r = 0; r < m->rings; r++) {
    size_t i = m->layout[r];
    double c[3], t[3], d[3], rad = m->node[i].radius;
    pos_of(&m->node[i], c);
    tangent(m, i, t);
    for (size_t j = 0; j < k; j++) {
      sub3(p->v[r * k + j], c, d);
      /* "%.5f" rounds each coordinate by up to 5e-6 m */
      if (fabs(norm3(d) - rad) > 1e-5 + 1e-6 * rad) bad_radius++;
      if (fabs(dot3(d, t)) > 1e-5) bad_plane++;
    }
    sub3(p->v[r * k], c, u[i]);
    unit3(u[i]);
    if (m->parent[i] >= 0) {
      double tp[3], expect[3], diff[3];
      size_t q = (size_t)m->parent[i];
      tangent(m, q, tp);
      rotate(tp, t, u[q], expect);
      sub3(u[i], expect, diff);
      /* one side of twist at 64 sides is 0.098; rounding of a 3 mm ring about 0.006 */
      if (norm3(diff) > 0.03) bad_frame++;
    }
  }
  CHECK_INT(bad_finite, 0);
  CHECK_INT(bad_radius, 0);
  CHECK_INT(bad_plane, 0);
  CHECK_INT(bad_frame, 0);
  free(u);
}

/* Counts the side triangles of node i's internode (ring r, its parent's ring pr)
 * that face inwards or use another ring; *f is the first, and is moved past them. */
static size_t bad_side_faces(const model *m, const parsed *p, size_t k, size_t r, size_t pr,
                             bool sharp, size_t *f) {
  size_t i = m->layout[r], bad = 0;
  double a[3], c[3], axis[3];
  pos_of(&m->node[m->parent[i]], a);
  pos_of(&m->node[i], c);
  sub3(c, a, axis);
  double len2 = dot3(axis, axis);
  for (size_t j = 0; j < 2 * k; j++, ++*f) {
    double n[3], g[3], ga[3], out[3];
    face_normal(p, *f, n, g);
    /* outwards: away from the nearest point of the internode's axis */
    sub3(g, a, ga);
    double s = len2 > 0 ? dot3(ga, axis) / len2 : 0;
    s = s < 0 ? 0 : s > 1 ? 1 : s;
    for (int q = 0; q < 3; q++) out[q] = g[q] - (a[q] + s * axis[q]);
    if (!(dot3(n, out) > 0) && !sharp) bad++;
    /* each side triangle uses the parent's ring and the node's */
    for (int q = 0; q < 3; q++) {
      size_t ring = p->f[*f][q] / k;
      if (ring != r && ring != pr) bad++;
    }
  }
  return bad;
}

/* The branch faces of a parsed file, in layout order: per node its internode's
 * 2 * sides facing outwards, then its cap (a tip's facing along its internode, a
 * root's against it); then 12 per box. */
static void check_branch_faces(const model *m, const parsed *p, int sides, bool boxes) {
  size_t k = (size_t)sides, f = 0, bad_side = 0, bad_cap = 0, sharp_bends = 0;
  size_t *ring_of = calloc(m->n + 1, sizeof *ring_of);
  if (!ring_of) exit(1);
  for (size_t r = 0; r < m->rings; r++) ring_of[m->layout[r]] = r;
  for (size_t r = 0; r < m->rings; r++) {
    size_t i = m->layout[r];
    double t[3];
    tangent(m, i, t);
    if (m->parent[i] >= 0) {
      /* at a bend near a right angle the parent's ring, shared with the bent child,
       * is seen edge-on from the child's internode, and some of its side triangles
       * face inwards: orientation is checked up to 60 degrees of bend */
      double tp[3];
      tangent(m, (size_t)m->parent[i], tp);
      bool sharp = dot3(tp, t) < 0.5;
      sharp_bends += sharp;
      bad_side += bad_side_faces(m, p, k, r, ring_of[m->parent[i]], sharp, &f);
    }
    bool tip = m->parent[i] >= 0 && m->children[i] == 0, root = m->parent[i] < 0;
    if (tip || root) {
      for (size_t j = 0; j + 2 < k; j++, f++) {
        double n[3], g[3];
        face_normal(p, f, n, g);
        if (!(dot3(n, t) * (tip ? 1 : -1) > 0)) bad_cap++;
        for (int q = 0; q < 3; q++)
          if (p->f[f][q] / k != r) bad_cap++;
      }
    }
  }
  CHECK_INT(f + (boxes ? 12 * (size_t)m->boxes : 0), p->nf);
  /* most internodes bend less than 60 degrees, so the orientation check has teeth */
  CHECK(sharp_bends * 4 < m->internodes);
  CHECK_INT(bad_side, 0);
  CHECK_INT(bad_cap, 0);
  free(ring_of);
}

/* The boxes' faces after the branches': 12 per box facing outwards, each on the
 * box's own 8 vertices at its corners. */
static void check_box_faces(const model *m, const parsed *p, int sides, bool boxes,
                            const sylva_world *w) {
  size_t k = (size_t)sides, bad_box = 0, v, f;
  expected_counts(m, sides, false, &v, &f); /* the branches' faces come first */
  for (int b = 0; boxes && b < m->boxes; b++) {
    sylva_obstacle_def o;
    sylva_world_obstacle_at(w, b, NULL, &o);
    double mid[3];
    for (int q = 0; q < 3; q++) mid[q] = (o.min[q] + o.max[q]) / 2;
    for (int j = 0; j < 12 && f < p->nf; j++, f++) {
      double n[3], g[3], out[3];
      face_normal(p, f, n, g);
      sub3(g, mid, out);
      if (!(dot3(n, out) > 0)) bad_box++;
      for (int q = 0; q < 3; q++) {
        size_t vi = p->f[f][q];
        if (vi < m->rings * k + 8 * (size_t)b || vi >= m->rings * k + 8 * (size_t)b + 8)
          bad_box++;
        else
          for (int a = 0; a < 3; a++)
            if (fabs(p->v[vi][a] - o.max[a]) > 1e-5 && fabs(p->v[vi][a] - o.min[a]) > 1e-5)
              bad_box++;
      }
    }
  }
  CHECK_INT(bad_box, 0);
}

/* ---- the cases ---- */

/* The world every test exports (made once): a tree, a two-root shrub and a wall,
 * grown six iterations; and its model. */
static sylva_world *world;
static model world_model;

static const sylva_world *the_world(void) {
  if (!world) {
    world = make_world(6);
    CHECK(world != NULL);
    if (!world) exit(check_summary("export-mesh"));
    model_build(&world_model, world);
  }
  return world;
}

/* An export of the world with a number of sides, with or without its boxes: the
 * counts derived from the model, the OBJ and PLY files written and parsed back. */
typedef struct mesh_case {
  int sides;
  bool boxes;
  sylva_mesh_options opt;
  size_t ev, ef; /* the vertices and faces expected */
  blob obj, ply;
  parsed po, pp;
} mesh_case;

enum { CASES = 6 };
static mesh_case cases[CASES];
static bool cases_made;

/* The six cases: 3, 8 and 64 sides, each without and with the boxes (made once). */
static mesh_case *mesh_cases(void) {
  if (cases_made) return cases;
  const sylva_world *w = the_world();
  static const int sides[] = {3, 8, 64};
  for (int c = 0; c < CASES; c++) {
    mesh_case *k = &cases[c];
    k->sides = sides[c / 2];
    k->boxes = c % 2;
    k->opt = sylva_mesh_default_options();
    k->opt.sides = k->sides;
    k->opt.obstacles = k->boxes;
    expected_counts(&world_model, k->sides, k->boxes, &k->ev, &k->ef);
    k->obj = write_blob(w, SYLVA_MESH_OBJ, &k->opt);
    k->ply = write_blob(w, SYLVA_MESH_PLY, &k->opt);
    k->po = parse_obj(&k->obj);
    k->pp = parse_ply(&k->ply);
  }
  cases_made = true;
  return cases;
}

/* Whether a case's OBJ parsed with the expected counts (its geometry can be checked). */
static bool parsed_as_expected(const mesh_case *k) {
  return k->po.ok && k->po.nv == k->ev && k->po.nf == k->ef;
}

/* The world has what the export must handle: three stems, branching, tips. */
static void test_world(void) {
  the_world();
  const model *m = &world_model;
  CHECK_INT(m->stems, 3);
  CHECK_INT(m->roots, 3);
  size_t branching = 0;
  for (size_t i = 0; i < m->n; i++) branching += m->children[i] > 1;
  CHECK(branching > 0);
  CHECK(m->tips > 3);
  printf("world: %zu nodes, %zu internodes, %zu tips, %zu branching nodes\n", m->n, m->internodes,
         m->tips, branching);
}

/* sylva_mesh_count gives the counts derived from the nodes, for both formats. */
static void test_counts(void) {
  const mesh_case *k = mesh_cases();
  for (int c = 0; c < CASES; c++, k++) {
    size_t cv = 1, cf = 1;
    CHECK_INT(sylva_mesh_count(world, SYLVA_MESH_OBJ, &k->opt, &cv, &cf), 0);
    CHECK_INT(cv, k->ev);
    CHECK_INT(cf, k->ef);
    CHECK_INT(sylva_mesh_count(world, SYLVA_MESH_PLY, &k->opt, &cv, &cf), 0);
    CHECK_INT(cv, k->ev);
    CHECK_INT(cf, k->ef);
  }
}

/* Both formats are written, and the same world gives the same bytes again. */
static void test_deterministic(void) {
  const mesh_case *k = mesh_cases();
  for (int c = 0; c < CASES; c++, k++) {
    blob obj2 = write_blob(world, SYLVA_MESH_OBJ, &k->opt);
    blob ply2 = write_blob(world, SYLVA_MESH_PLY, &k->opt);
    CHECK_INT(k->obj.rc, 0);
    CHECK_INT(k->ply.rc, 0);
    CHECK(k->obj.size == obj2.size && memcmp(k->obj.data, obj2.data, obj2.size) == 0);
    CHECK(k->ply.size == ply2.size && memcmp(k->ply.data, ply2.data, ply2.size) == 0);
    free(obj2.data);
    free(ply2.data);
  }
}

/* Both files parse back, with the counts derived from the nodes. */
static void test_parse_back(void) {
  const mesh_case *k = mesh_cases();
  for (int c = 0; c < CASES; c++, k++) {
    CHECK(k->po.ok);
    CHECK(k->pp.ok);
    CHECK_INT(k->po.nv, k->ev);
    CHECK_INT(k->po.nf, k->ef);
    CHECK_INT(k->pp.header_v, k->ev);
    CHECK_INT(k->pp.header_f, k->ef);
    CHECK_INT(k->pp.nv, k->ev);
    CHECK_INT(k->pp.nf, k->ef);
  }
}

/* One layout: the same vertices and faces in both formats. */
static void test_same_layout(void) {
  const mesh_case *k = mesh_cases();
  for (int c = 0; c < CASES; c++, k++) {
    const parsed *po = &k->po, *pp = &k->pp;
    bool same = po->nv == pp->nv && po->nf == pp->nf;
    for (size_t i = 0; same && i < po->nv; i++)
      same = memcmp(po->v[i], pp->v[i], sizeof po->v[i]) == 0;
    for (size_t i = 0; same && i < po->nf; i++)
      same = memcmp(po->f[i], pp->f[i], sizeof po->f[i]) == 0;
    CHECK(same);
  }
}

static void stem_name(const sylva_world *w, int s, char *buf, size_t size) {
  for (int pl = 0; pl < sylva_world_plant_count(w); pl++)
    for (int st = 0; st < sylva_world_plant_stem_count(w, pl); st++)
      if (sylva_world_stem_index(w, pl, st) == s) {
        char label[SYLVA_LABEL_MAX];
        snprintf(label, sizeof label, "%s", sylva_world_plant_label(w, pl));
        for (char *c = label; *c; c++)
          if (*c == ' ') *c = '_';
        snprintf(buf, size, "%s_%d", label, st);
      }
}


/* The faces of OBJ object o all have PLY stem tag `tag`: the mismatches. */
static size_t tag_mismatches(const mesh_case *k, size_t o, int tag) {
  size_t mismatched = 0;
  for (size_t f = 0; f < k->po.nf && f < k->pp.nf; f++)
    if ((size_t)k->po.face_tag[f] == o && k->pp.face_tag[f] != tag) mismatched++;
  return mismatched;
}

/* OBJ objects: each stem with geometry, then each box; PLY's stem tags name the same. */
static void test_objects(void) {
  /* the PLY stem property is the stem's index, or -1 - i for box i */
  const mesh_case *k = mesh_cases();
  const model *m = &world_model;
  for (int c = 0; c < CASES; c++, k++) {
    size_t expect_obj = 0;
    for (int s = 0; s < m->stems; s++) expect_obj += m->stem_rings[s] > 0;
    CHECK_INT(k->po.nobj, expect_obj + (k->boxes ? (size_t)m->boxes : 0));
    size_t o = 0;
    for (int s = 0; s < m->stems && o < k->po.nobj; s++) {
      if (!m->stem_rings[s]) continue;
      char name[96];
      stem_name(world, s, name, sizeof name);
      CHECK(strcmp(k->po.obj_name[o], name) == 0);
      CHECK_INT(k->po.obj_faces[o], 2 * (size_t)k->sides * m->stem_internodes[s] +
                                        (size_t)(k->sides - 2) * m->stem_caps[s]);
      CHECK_INT(tag_mismatches(k, o, s), 0);
      o++;
    }
    for (int b = 0; k->boxes && b < m->boxes && o < k->po.nobj; b++, o++) {
      sylva_obstacle_def od;
      sylva_world_obstacle_at(world, b, NULL, &od);
      char name[96];
      snprintf(name, sizeof name, "obstacle_%s", od.label);
      CHECK(strcmp(k->po.obj_name[o], name) == 0);
      CHECK_INT(k->po.obj_faces[o], 12);
      CHECK_INT(tag_mismatches(k, o, -1 - b), 0);
    }
  }
}

/* Rings of the node's radius across its internode, frames by parallel transport. */
static void test_rings(void) {
  const mesh_case *k = mesh_cases();
  for (int c = 0; c < CASES; c++, k++)
    if (parsed_as_expected(k)) check_rings(&world_model, &k->po, k->sides);
}

/* Side and cap triangles in layout order, facing outwards. */
static void test_branch_faces(void) {
  const mesh_case *k = mesh_cases();
  for (int c = 0; c < CASES; c++, k++)
    if (parsed_as_expected(k)) check_branch_faces(&world_model, &k->po, k->sides, k->boxes);
}

/* The boxes' triangles at their corners, facing outwards. */
static void test_box_faces(void) {
  const mesh_case *k = mesh_cases();
  for (int c = 0; c < CASES; c++, k++)
    if (parsed_as_expected(k)) check_box_faces(&world_model, &k->po, k->sides, k->boxes, world);
}

/* ---- prisms ---- */

/* Per obstacle of prism_world: its vertices, faces and wall triangles. The house
 * and the yard: 10 points, 10 walls and 10 cap triangles (a footprint of n points
 * and h holes, its rings crossing nowhere: n + 2h - 2); the slab as the block. */
static const size_t prism_vertices[PRISMS] = {20, 8, 20};
static const size_t prism_faces[PRISMS] = {40, 12, 40};
static const size_t prism_walls[PRISMS] = {20, 8, 20};
static const char *const prism_objects[PRISMS] = {"obstacle_house", "obstacle_slab",
                                                  "zone_yard"};

/* Copies the faces of obstacle i of a parsed file (OBJ: object i, the world having
 * no stems; PLY: stem tag -1 - i) into out; returns their number, and in *foreign
 * the corners on vertices outside [first, first + vertices). */
static size_t obstacle_faces(const parsed *p, bool ply, int i, size_t first, size_t vertices,
                             size_t (*out)[3], size_t *foreign) {
  size_t n = 0;
  *foreign = 0;
  for (size_t f = 0; f < p->nf; f++) {
    if (p->face_tag[f] != (ply ? -1 - i : i)) continue;
    for (int c = 0; c < 3; c++) {
      out[n][c] = p->f[f][c];
      if (out[n][c] < first || out[n][c] >= first + vertices) ++*foreign;
    }
    n++;
  }
  return n;
}

/* One obstacle's faces of a parsed file: closed, of its footprint's volume and cap
 * areas, walls facing out (into the courtyard for a hole), its bounds; returns its
 * measures. */
static mesh_measure check_prism(const sylva_world *w, const parsed *p, bool ply, int i,
                                size_t first, size_t (*f)[3]) {
  sylva_obstacle_def o;
  sylva_world_obstacle_at(w, i, NULL, &o);
  size_t foreign, n = obstacle_faces(p, ply, i, first, prism_vertices[i], f, &foreign);
  CHECK_INT(n, prism_faces[i]);
  CHECK_INT(foreign, 0);
  mesh_measure m = measure_mesh((const double(*)[3])p->v, (const size_t(*)[3])f, n, &o);
  check_measures(&m, &o, prism_walls[i]);
  return m;
}

/* The prisms written as OBJ and PLY: each a closed mesh of its own vertices, of its
 * footprint's volume (polygon area x height) and cap areas (the L's less its
 * courtyard), walls facing out; the slab's mesh has the volume and bounds of the
 * box of its corners (block_world). */
static void test_prisms(void) {
  sylva_world *w = prism_world();
  CHECK(w != NULL);
  if (!w) return;
  sylva_obstacle_def house;
  sylva_world_obstacle_at(w, 0, NULL, &house);
  /* the L of 36 m2 less the courtyard's 1, as snapped */
  CHECK_NEAR(footprint_area(&house), 35.0, 0.05);
  sylva_mesh_options opt = sylva_mesh_default_options();
  opt.obstacles = true;
  size_t cv = 0, cf = 0, ev = 0, ef = 0;
  for (int i = 0; i < PRISMS; i++) ev += prism_vertices[i], ef += prism_faces[i];
  CHECK_INT(sylva_mesh_count(w, SYLVA_MESH_PLY, &opt, &cv, &cf), 0);
  CHECK_INT(cv, ev);
  CHECK_INT(cf, ef);
  for (int fmt = 0; fmt < 2; fmt++) {
    bool ply = fmt == 1;
    blob b = write_blob(w, ply ? SYLVA_MESH_PLY : SYLVA_MESH_OBJ, &opt);
    parsed p = ply ? parse_ply(&b) : parse_obj(&b);
    CHECK(b.rc == 0 && p.ok);
    CHECK_INT(p.nv, ev);
    CHECK_INT(p.nf, ef);
    size_t(*f)[3] = malloc((p.nf + 1) * sizeof *f);
    if (!f) exit(1);
    mesh_measure m[PRISMS];
    for (int i = 0, first = 0; p.ok && i < PRISMS; first += (int)prism_vertices[i++])
      m[i] = check_prism(w, &p, ply, i, (size_t)first, f);
    if (p.ok) {
      /* a prism on a rectangle is its box */
      sylva_world *bw = block_world();
      blob bb = write_blob(bw, ply ? SYLVA_MESH_PLY : SYLVA_MESH_OBJ, &opt);
      parsed bp = ply ? parse_ply(&bb) : parse_obj(&bb);
      CHECK(bw && bb.rc == 0 && bp.ok && bp.nf == 12);
      if (bp.ok && bp.nf == 12) {
        sylva_obstacle_def o;
        sylva_world_obstacle_at(bw, 0, NULL, &o);
        mesh_measure box =
            measure_mesh((const double(*)[3])bp.v, (const size_t(*)[3])bp.f, 12, &o);
        CHECK(box.closed);
        CHECK_NEAR(box.volume, 6.0, 1e-12);
        CHECK_NEAR(m[1].volume, box.volume, 1e-12);
        for (int d = 0; d < 3; d++) CHECK(m[1].lo[d] == box.lo[d] && m[1].hi[d] == box.hi[d]);
      }
      parsed_free(&bp);
      free(bb.data);
      sylva_world_destroy(bw);
    }
    if (!ply && p.nobj == PRISMS)
      for (int i = 0; i < PRISMS; i++) CHECK(strcmp(p.obj_name[i], prism_objects[i]) == 0);
    if (ply) {
      CHECK(strstr(b.data, "comment obstacle 0 house\n") != NULL);
      CHECK(strstr(b.data, "comment zone 2 yard\n") != NULL);
    }
    free(f);
    parsed_free(&p);
    free(b.data);
  }
  sylva_world_destroy(w);
}

/* A footprint of a ring that crosses itself at (1.5, 1.5) (a bow-tie of triangles
 * of 4.5 and 0.5 m2) and a separate square of 1 m2, read even-odd: cut at the
 * crossing, which becomes a point of its own (9 points, 10 walls, 4 cap
 * triangles), of volume 6 m2 x its height, its walls facing out. At the crossing
 * four walls meet, so its vertical edge is in four triangles: no closedness here. */
static void test_crossing(void) {
  static const double points[8][2] = {{0, 0}, {2, 2}, {2, 0}, {0, 6},
                                      {5, 0}, {6, 0}, {6, 1}, {5, 1}};
  static const int rings[2] = {4, 4};
  const sylva_obstacle_def def = {"bow", {0, 0, 0}, {0, 0, 2}, SYLVA_OBSTACLE_SOLID,
                                  {points, 8, rings, 2}};
  sylva_world *w = obstacles_world(&def, 1);
  CHECK(w != NULL);
  if (!w) return;
  sylva_mesh_options opt = sylva_mesh_default_options();
  opt.obstacles = true;
  blob b = write_blob(w, SYLVA_MESH_OBJ, &opt);
  parsed p = parse_obj(&b);
  CHECK(b.rc == 0 && p.ok);
  CHECK_INT(p.nv, 18);
  CHECK_INT(p.nf, 28);
  if (p.ok) {
    sylva_obstacle_def o;
    sylva_world_obstacle_at(w, 0, NULL, &o);
    mesh_measure m = measure_mesh((const double(*)[3])p.v, (const size_t(*)[3])p.f, p.nf, &o);
    CHECK_NEAR(m.volume, 6.0 * 2.0, 1e-12);
    CHECK_NEAR(m.top, 6.0, 1e-12);
    CHECK_NEAR(m.bottom, 6.0, 1e-12);
    CHECK_INT(m.walls, 20);
    CHECK_INT(m.bad_walls, 0);
  }
  parsed_free(&p);
  free(b.data);
  sylva_world_destroy(w);
}

static FILE *manifest;
static const char *outdir;

static void save(const char *name, const blob *b) {
  char path[4096];
  snprintf(path, sizeof path, "%s/%s", outdir, name);
  FILE *f = fopen(path, "wb");
  CHECK(f != NULL);
  if (!f) return;
  CHECK_INT(fwrite(b->data, 1, b->size, f), b->size);
  CHECK_INT(fclose(f), 0);
}

/* With OUTDIR: every case's files written there and listed in expected.tsv. */
static void test_files(void) {
  if (!outdir) return;
  const mesh_case *k = mesh_cases();
  const model *m = &world_model;
  for (int c = 0; c < CASES; c++, k++) {
    char name[64];
    snprintf(name, sizeof name, "mesh_s%d%s.obj", k->sides, k->boxes ? "_obstacles" : "");
    save(name, &k->obj);
    fprintf(manifest, "file\t%s\tobj\t%zu\t%zu\n", name, k->ev, k->ef);
    size_t i = 0;
    for (int st = 0; st < m->stems && i < k->po.nobj; st++) {
      if (!m->stem_rings[st]) continue;
      fprintf(manifest, "object\t%s\t%s\t%zu\t%zu\n", name, k->po.obj_name[i],
              k->po.obj_faces[i], (size_t)k->sides * m->stem_rings[st]);
      i++;
    }
    for (; i < k->po.nobj; i++)
      fprintf(manifest, "object\t%s\t%s\t%zu\t8\n", name, k->po.obj_name[i], k->po.obj_faces[i]);
    snprintf(name, sizeof name, "mesh_s%d%s.ply", k->sides, k->boxes ? "_obstacles" : "");
    save(name, &k->ply);
    fprintf(manifest, "file\t%s\tply\t%zu\t%zu\n", name, k->ev, k->ef);
  }
  /* the prisms, one object each */
  sylva_world *w = prism_world();
  CHECK(w != NULL);
  if (!w) return;
  sylva_mesh_options opt = sylva_mesh_default_options();
  opt.obstacles = true;
  size_t ev = 0, ef = 0;
  for (int i = 0; i < PRISMS; i++) ev += prism_vertices[i], ef += prism_faces[i];
  for (int fmt = 0; fmt < 2; fmt++) {
    const char *name = fmt ? "prisms.ply" : "prisms.obj";
    blob b = write_blob(w, fmt ? SYLVA_MESH_PLY : SYLVA_MESH_OBJ, &opt);
    save(name, &b);
    fprintf(manifest, "file\t%s\t%s\t%zu\t%zu\n", name, fmt ? "ply" : "obj", ev, ef);
    for (int i = 0; !fmt && i < PRISMS; i++)
      fprintf(manifest, "object\t%s\t%s\t%zu\t%zu\n", name, prism_objects[i], prism_faces[i],
              prism_vertices[i]);
    free(b.data);
  }
  sylva_world_destroy(w);
}

static void mesh_cases_free(void) {
  for (int c = 0; cases_made && c < CASES; c++) {
    parsed_free(&cases[c].po);
    parsed_free(&cases[c].pp);
    free(cases[c].obj.data);
    free(cases[c].ply.data);
  }
  if (world) {
    model_free(&world_model);
    sylva_world_destroy(world);
  }
}

/* Options: 3 to 64 sides (else nothing written), a known format, NULL as the defaults. */
static void test_options(void) {
  const sylva_world *w = the_world();
  sylva_mesh_options d = sylva_mesh_default_options();
  CHECK_INT(d.sides, 8);
  CHECK(!d.obstacles);
  size_t v = 1, f = 1;
  static const int sides[] = {-1, 0, 2, 3, 64, 65};
  for (size_t i = 0; i < sizeof sides / sizeof *sides; i++) {
    sylva_mesh_options o = d;
    o.sides = sides[i];
    int want = sides[i] >= 3 && sides[i] <= 64 ? 0 : SYLVA_EINVAL;
    CHECK_INT(sylva_mesh_count(w, SYLVA_MESH_PLY, &o, &v, &f), want);
    if (want) CHECK(v == 0 && f == 0);
    blob b = write_blob(w, SYLVA_MESH_OBJ, &o);
    CHECK_INT(b.rc, want);
    if (want) CHECK_INT(b.size, 0); /* nothing written */
    free(b.data);
  }
  blob bad = write_blob(w, (sylva_mesh_format)7, &d);
  CHECK_INT(bad.rc, SYLVA_EINVAL);
  CHECK_INT(bad.size, 0);
  free(bad.data);
  CHECK_INT(sylva_mesh_count(w, (sylva_mesh_format)7, &d, &v, &f), SYLVA_EINVAL);
  /* NULL options are the defaults */
  blob a = write_blob(w, SYLVA_MESH_PLY, NULL), b = write_blob(w, SYLVA_MESH_PLY, &d);
  CHECK(a.rc == 0 && b.rc == 0 && a.size == b.size && memcmp(a.data, b.data, a.size) == 0);
  free(a.data);
  free(b.data);
}

static int write_obj(FILE *f, const void *w) { return sylva_mesh_write(f, w, SYLVA_MESH_OBJ, NULL); }

/* A failed write is SYLVA_MESH_EWRITE with errno kept. */
static void test_write_error(void) {
  int err;
  CHECK_INT(write_to_full(write_obj, the_world(), &err), SYLVA_MESH_EWRITE);
  CHECK_INT(err, ENOSPC);
}

/* An empty world exports nothing; with a box, the box alone. */
static void test_empty(void) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w;
  CHECK_INT(sylva_world_create(&wd, &w), 0);
  sylva_mesh_options opt = sylva_mesh_default_options();
  size_t v = 1, f = 1;
  CHECK_INT(sylva_mesh_count(w, SYLVA_MESH_OBJ, &opt, &v, &f), 0);
  CHECK(v == 0 && f == 0);
  blob ply = write_blob(w, SYLVA_MESH_PLY, &opt);
  CHECK_INT(ply.rc, 0);
  parsed p = parse_ply(&ply);
  CHECK(p.ok && p.header_v == 0 && p.header_f == 0);
  parsed_free(&p);
  free(ply.data);
  sylva_obstacle_def box = {"a box", {1, 1, 1}, {2, 3, 4}, SYLVA_OBSTACLE_SOLID, {0}};
  CHECK(sylva_world_add_obstacle(w, &box) >= 0);
  opt.obstacles = true;
  CHECK_INT(sylva_mesh_count(w, SYLVA_MESH_OBJ, &opt, &v, &f), 0);
  CHECK(v == 8 && f == 12);
  blob obj = write_blob(w, SYLVA_MESH_OBJ, &opt);
  CHECK_INT(obj.rc, 0);
  p = parse_obj(&obj);
  CHECK(p.ok && p.nv == 8 && p.nf == 12 && p.nobj == 1);
  if (p.nobj == 1) CHECK(strcmp(p.obj_name[0], "obstacle_a_box") == 0);
  parsed_free(&p);
  free(obj.data);
  /* a clearance zone is a box too, named a zone */
  sylva_obstacle_def zone = {"road", {0, 0, 0}, {1, 1, 1}, SYLVA_OBSTACLE_ZONE, {0}};
  CHECK(sylva_world_add_obstacle(w, &zone) >= 0);
  obj = write_blob(w, SYLVA_MESH_OBJ, &opt);
  p = parse_obj(&obj);
  CHECK(p.ok && p.nv == 16 && p.nf == 24 && p.nobj == 2);
  if (p.nobj == 2) CHECK(strcmp(p.obj_name[1], "zone_road") == 0);
  parsed_free(&p);
  free(obj.data);
  ply = write_blob(w, SYLVA_MESH_PLY, &opt);
  CHECK(ply.rc == 0 && ply.data && strstr((const char *)ply.data, "comment obstacle 0 a_box\n") &&
        strstr((const char *)ply.data, "comment zone 1 road\n"));
  free(ply.data);
  sylva_world_destroy(w);
}


int main(int argc, char **argv) {
  if (argc > 3) {
    fprintf(stderr, "usage: %s [OUTDIR|- [TEST]]\n", argv[0]);
    return 2;
  }
  if (argc >= 2 && strcmp(argv[1], "-") != 0) {
    outdir = argv[1];
    char path[4096];
    snprintf(path, sizeof path, "%s/expected.tsv", outdir);
    manifest = fopen(path, "w");
    if (!manifest) {
      fprintf(stderr, "%s: %s\n", path, strerror(errno));
      return 1;
    }
  }
  static const check_test tests[] = {
      CHECK_TEST(world), CHECK_TEST(counts), CHECK_TEST(deterministic), CHECK_TEST(parse_back),
      CHECK_TEST(same_layout), CHECK_TEST(objects), CHECK_TEST(rings), CHECK_TEST(branch_faces),
      CHECK_TEST(box_faces), CHECK_TEST(prisms), CHECK_TEST(crossing), CHECK_TEST(files),
      CHECK_TEST(options),
      CHECK_TEST(write_error), CHECK_TEST(empty)};
  CHECK_RUN(argc, argv, 2, tests);
  if (manifest) CHECK_INT(fclose(manifest), 0);
  mesh_cases_free();
  return check_summary("export-mesh");
}
