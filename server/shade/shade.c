/* The site's sun hours (shade.h; docs/model.md, "Shade on the site"): cells, the
 * sun's samples, rays past the boxes and prisms and through the leaves' voxels. */
#include "shade.h"

#include <libnova/julian_day.h>
#include <libnova/sidereal_time.h>
#include <libnova/solar.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "foliage.h"
#include "server_error.h"
#include "sylva/sun.h"

#define DEG (3.14159265358979323846 / 180.0)

static const char *const face_names[SHADE_FACE_COUNT] = {"+x", "-x", "+y", "-y"};
static const int month_days[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};

const char *shade_face_name(shade_face f) {
  return f >= 0 && f < SHADE_FACE_COUNT ? face_names[f] : "?";
}

shade_day shade_default_day(void) {
  return (shade_day){.month = 1, .day = 1, .year = 2025, .from = 0, .to = SHADE_DAY_MINUTES,
                     .step = 10};
}

int shade_day_of_year(int month, int day) {
  if (month < 1 || month > 12 || day < 1 || day > month_days[month - 1]) return 0;
  int doy = day;
  for (int m = 0; m < month - 1; m++) doy += month_days[m];
  return doy;
}

/* Reads exactly `digits` decimal digits. */
static int read_digits(const char *s, int digits, int *out) {
  int v = 0;
  for (int i = 0; i < digits; i++) {
    if (s[i] < '0' || s[i] > '9') return -1;
    v = v * 10 + (s[i] - '0');
  }
  *out = v;
  return 0;
}

int shade_parse_date(const char *text, int *month, int *day, char *err, size_t errlen) {
  int m = 0, d = 0;
  if (!text || strlen(text) != 5 || text[2] != '-' || read_digits(text, 2, &m) ||
      read_digits(text + 3, 2, &d))
    return server_fail(err, errlen, SERVER_EINPUT, "expected MM-DD (e.g. 06-21), got '%s'",
                       text ? text : "");
  if (!shade_day_of_year(m, d))
    return server_fail(err, errlen, SERVER_EINPUT,
                       "'%s' is not a date (of a common year: no 02-29)", text);
  *month = m;
  *day = d;
  return SERVER_OK;
}

int shade_parse_time(const char *text, int *minutes, char *err, size_t errlen) {
  int h = 0, m = 0;
  if (!text || strlen(text) != 5 || text[2] != ':' || read_digits(text, 2, &h) ||
      read_digits(text + 3, 2, &m) || h > 24 || m > 59 || (h == 24 && m != 0))
    return server_fail(err, errlen, SERVER_EINPUT,
                       "expected HH:MM from 00:00 to 24:00 (e.g. 09:30), got '%s'",
                       text ? text : "");
  *minutes = h * 60 + m;
  return SERVER_OK;
}

int shade_parse_surface(const sylva_world *w, const char *text, shade_filter *out, char *err,
                        size_t errlen) {
  if (strcmp(text, "ground") == 0) {
    *out = (shade_filter){.ground = true, .faces = false, .obstacle = -1, .face = -1};
    return SERVER_OK;
  }
  const char *colon = strrchr(text, ':');
  if (!colon || colon == text)
    return server_fail(err, errlen, SERVER_EINPUT,
                       "expected 'ground' or OBSTACLE_ID:FACE (FACE +x, -x, +y or -y of a box, "
                       "e0, e1, ... of a prism), got '%s'",
                       text);
  char id[SYLVA_LABEL_MAX];
  size_t len = (size_t)(colon - text);
  int obstacle = SYLVA_ENOTFOUND;
  if (len < sizeof id) {
    memcpy(id, text, len);
    id[len] = '\0';
    obstacle = sylva_world_find_obstacle(w, id);
  }
  sylva_obstacle_def def;
  if (obstacle < 0 || sylva_world_obstacle(w, obstacle, &def) != 0)
    return server_fail(err, errlen, SERVER_EINPUT, "'%s': the world has no obstacle '%.*s'",
                       text, (int)len, text);
  if (def.kind != SYLVA_OBSTACLE_SOLID)
    return server_fail(err, errlen, SERVER_EINPUT,
                       "'%s': obstacle '%s' is a zone, which has no faces (only solid boxes and "
                       "prisms do)",
                       text, def.label);
  const char *name = colon + 1;
  int face = -1;
  if (def.footprint.ring_count > 0) {
    /* "e" and the edge's number in decimal, without sign or leading zeros */
    int edges = def.footprint.point_count;
    if (name[0] == 'e' && name[1] >= '0' && name[1] <= '9' && (name[1] != '0' || !name[2])) {
      long n = 0;
      const char *q = name + 1;
      while (*q >= '0' && *q <= '9' && n < edges) n = n * 10 + (*q++ - '0');
      if (!*q && n < edges) face = (int)n;
    }
    if (face < 0)
      return server_fail(err, errlen, SERVER_EINPUT,
                         "'%s': unknown face '%s' (prism '%s' has a wall on each edge of its "
                         "footprint, e0 to e%d)",
                         text, name, def.label, edges - 1);
  } else {
    for (int f = 0; f < SHADE_FACE_COUNT; f++)
      if (strcmp(name, face_names[f]) == 0) face = f;
    if (face < 0)
      return server_fail(err, errlen, SERVER_EINPUT,
                         "'%s': unknown face '%s' (a box's vertical faces are +x, -x, +y and -y)",
                         text, name);
  }
  *out = (shade_filter){.ground = false, .faces = true, .obstacle = obstacle, .face = face};
  return SERVER_OK;
}

int shade_check(const shade_site *site, const shade_day *day, char *err, size_t errlen) {
  if (!(site->latitude >= -90.0 && site->latitude <= 90.0))
    return server_fail(err, errlen, SERVER_EINPUT, "latitude must be from -90 to 90, got %g",
                       site->latitude);
  if (!(hypot(site->north[0], site->north[1]) > 1e-9))
    return server_fail(err, errlen, SERVER_EINPUT, "the direction of north has no length");
  if (site->clock && !(site->longitude >= -180.0 && site->longitude <= 180.0 &&
                       site->utc_offset >= -14.0 && site->utc_offset <= 14.0))
    return server_fail(err, errlen, SERVER_EINPUT,
                       "longitude must be from -180 to 180 and utc_offset from -14 to 14");
  if (!shade_day_of_year(day->month, day->day))
    return server_fail(err, errlen, SERVER_EINPUT, "%02d-%02d is not a date (of a common year)",
                       day->month, day->day);
  if (day->from < 0 || day->to > SHADE_DAY_MINUTES || day->from >= day->to)
    return server_fail(err, errlen, SERVER_EINPUT,
                       "the times must run forwards within the day: from %02d:%02d to %02d:%02d",
                       day->from / 60, day->from % 60, day->to / 60, day->to % 60);
  if (day->step < 1 || day->step > SHADE_DAY_MINUTES)
    return server_fail(err, errlen, SERVER_EINPUT, "the step must be 1 to %d minutes, got %d",
                       SHADE_DAY_MINUTES, day->step);
  return SERVER_OK;
}

/* The equation of time (apparent minus mean solar time) in hours on day `doy` of
 * proto's year: the sun's hour angle at Greenwich at 12:00 UT, from libnova's
 * sidereal time and apparent right ascension. */
static double equation_of_time(int doy) {
  struct ln_date date = {.years = 2025, .months = 1, .days = 1, .hours = 12};
  double jd = ln_get_julian_day(&date) + (double)(doy - 1);
  struct ln_equ_posn sun;
  ln_get_solar_equ_coords(jd, &sun);
  double h = fmod(ln_get_apparent_sidereal_time(jd) * 15.0 - sun.ra, 360.0);
  if (h > 180.0) h -= 360.0;
  if (h <= -180.0) h += 360.0;
  return h / 15.0;
}

/* The leaves' density as a dense grid over the box of the voxels that hold leaves:
 * k times the leaf area density, m^-1, so that a path's optical depth is the sum of
 * kd * length. */
typedef struct leaf_grid {
  int lo[3], n[3];   /* first voxel (world indices) and voxels per axis */
  double bmin[3], bmax[3];
  double *kd;        /* n[0] * n[1] * n[2], x fastest; NULL without leaves */
  int nb[3];         /* blocks of SHADE_BLOCK^3 voxels per axis */
  unsigned char *full; /* nb[0] * nb[1] * nb[2]: 1 where a block holds leaves */
  double area;
} leaf_grid;

/* Voxels per edge of the blocks the rays skip when empty. */
#define SHADE_BLOCK 4

/* One leaf card's centre as a world voxel, clamped into the world so that every
 * leaf the world reports is counted. */
static void leaf_voxel(const sylva_world_def *def, const int dims[3], const double c[3],
                       int v[3]) {
  for (int a = 0; a < 3; a++) {
    double f = floor((c[a] - def->min[a]) / def->voxel);
    v[a] = f < 0 ? 0 : f >= dims[a] ? dims[a] - 1 : (int)f;
  }
}

/* Visits every leaf of w: pass 0 finds the box of their voxels, pass 1 adds their
 * areas into g->kd. */
static void leaf_pass(const sylva_world *w, const sylva_node_info *nodes, size_t count, int pass,
                      leaf_grid *g) {
  const sylva_world_def *def = sylva_world_get_def(w);
  int dims[3];
  sylva_world_dims(w, dims);
  double vol = def->voxel * def->voxel * def->voxel;
  for (size_t i = 0; i < count; i++) {
    const sylva_node_info *nd = &nodes[i];
    if (nd->leaves <= 0) continue;
    const sylva_species_def *sp =
        sylva_world_species(w, sylva_world_plant_species(w, nd->plant));
    if (!sp) continue;
    double q[3] = {nd->x, nd->y, nd->z}, p[3] = {0, 0, 0};
    int64_t parent = nd->parent >= 0 ? sylva_world_node_index(w, nd->parent) : -1;
    if (parent >= 0) {
      p[0] = nodes[parent].x;
      p[1] = nodes[parent].y;
      p[2] = nodes[parent].z;
    }
    double area = SYLVA_LEAF_FILL * sp->leaf_size * sp->leaf_size;
    for (int k = 0; k < nd->leaves; k++) {
      foliage_leaf leaf;
      foliage_place(parent >= 0 ? p : NULL, q, k, nd->leaves, sp->leaf_size, &leaf);
      int v[3];
      leaf_voxel(def, dims, leaf.centre, v);
      if (pass == 0) {
        for (int a = 0; a < 3; a++) {
          if (g->n[a] == 0 || v[a] < g->lo[a]) {
            int hi = g->n[a] ? g->lo[a] + g->n[a] - 1 : v[a];
            g->lo[a] = v[a];
            g->n[a] = hi - v[a] + 1;
          } else if (v[a] >= g->lo[a] + g->n[a]) {
            g->n[a] = v[a] - g->lo[a] + 1;
          }
        }
        g->area += area;
      } else {
        size_t at = (size_t)(v[0] - g->lo[0]) +
                    (size_t)g->n[0] * ((size_t)(v[1] - g->lo[1]) +
                                       (size_t)g->n[1] * (size_t)(v[2] - g->lo[2]));
        g->kd[at] += SHADE_K * area / vol;
      }
    }
  }
}

/* The blocks that hold leaves. */
static int mark_blocks(leaf_grid *g, char *err, size_t errlen) {
  for (int a = 0; a < 3; a++) g->nb[a] = (g->n[a] + SHADE_BLOCK - 1) / SHADE_BLOCK;
  g->full = calloc((size_t)g->nb[0] * (size_t)g->nb[1] * (size_t)g->nb[2], 1);
  if (!g->full) return server_fail(err, errlen, SERVER_ENOMEM, "out of memory for leaf blocks");
  size_t at = 0;
  for (int z = 0; z < g->n[2]; z++)
    for (int y = 0; y < g->n[1]; y++)
      for (int x = 0; x < g->n[0]; x++, at++)
        if (g->kd[at] != 0.0)
          g->full[(size_t)(x / SHADE_BLOCK) +
                  (size_t)g->nb[0] * ((size_t)(y / SHADE_BLOCK) +
                                      (size_t)g->nb[1] * (size_t)(z / SHADE_BLOCK))] = 1;
  return SERVER_OK;
}

static int leaf_grid_build(const sylva_world *w, leaf_grid *g, char *err, size_t errlen) {
  *g = (leaf_grid){.kd = NULL};
  size_t count = sylva_world_node_count(w);
  if (count == 0) return SERVER_OK;
  sylva_node_info *nodes = malloc(count * sizeof *nodes);
  if (!nodes) return server_fail(err, errlen, SERVER_ENOMEM, "out of memory for %zu nodes", count);
  for (size_t i = 0; i < count; i++) sylva_world_node_at(w, i, &nodes[i]);
  leaf_pass(w, nodes, count, 0, g);
  int rc = SERVER_OK;
  if (g->n[0] > 0) {
    size_t cells = (size_t)g->n[0] * (size_t)g->n[1] * (size_t)g->n[2];
    g->kd = calloc(cells, sizeof *g->kd);
    if (!g->kd) {
      rc = server_fail(err, errlen, SERVER_ENOMEM, "out of memory for %zu leaf voxels", cells);
    } else {
      leaf_pass(w, nodes, count, 1, g);
      rc = mark_blocks(g, err, errlen);
      const sylva_world_def *def = sylva_world_get_def(w);
      for (int a = 0; a < 3; a++) {
        g->bmin[a] = def->min[a] + g->lo[a] * def->voxel;
        g->bmax[a] = def->min[a] + (g->lo[a] + g->n[a]) * def->voxel;
      }
    }
  }
  free(nodes);
  return rc;
}

/* The entry and exit of the ray o + t d (t > 0) through the box [lo, hi]: true when
 * it crosses its inside (t0 < t1). */
static bool ray_box(const double o[3], const double d[3], const double lo[3],
                    const double hi[3], double *t0, double *t1) {
  double a = 0.0, b = INFINITY;
  for (int k = 0; k < 3; k++) {
    if (d[k] == 0.0) {
      if (o[k] <= lo[k] || o[k] >= hi[k]) return false;
      continue;
    }
    double ta = (lo[k] - o[k]) / d[k], tb = (hi[k] - o[k]) / d[k];
    if (ta > tb) {
      double s = ta;
      ta = tb;
      tb = s;
    }
    if (ta > a) a = ta;
    if (tb < b) b = tb;
    if (a >= b) return false;
  }
  *t0 = a;
  *t1 = b;
  return true;
}

/* The walk of the ray o + t d from t0 to t1 through the cells lo .. hi (indices,
 * inclusive) of a grid of edge `edge` starting at `base`, exact (Amanatides and
 * Woo 1987): each cell crossed is visited with the length of its part of the
 * path. The cell the walk starts in is where o + t0 d lies, clamped into lo .. hi. */
typedef struct walk {
  int idx[3], step[3];
  double tmax[3], tdelta[3];
} walk;

static void walk_start(walk *k, const double base[3], double edge, const int lo[3],
                       const int hi[3], const double o[3], const double d[3], double t0) {
  for (int a = 0; a < 3; a++) {
    int i = (int)floor((o[a] + d[a] * t0 - base[a]) / edge);
    if (i < lo[a]) i = lo[a];
    if (i > hi[a]) i = hi[a];
    k->idx[a] = i;
    if (d[a] > 0.0) {
      k->step[a] = 1;
      k->tmax[a] = (base[a] + (i + 1) * edge - o[a]) / d[a];
      k->tdelta[a] = edge / d[a];
    } else if (d[a] < 0.0) {
      k->step[a] = -1;
      k->tmax[a] = (base[a] + i * edge - o[a]) / d[a];
      k->tdelta[a] = -edge / d[a];
    } else {
      k->step[a] = 0;
      k->tmax[a] = INFINITY;
      k->tdelta[a] = INFINITY;
    }
  }
}

/* The axis whose boundary the walk meets first. */
static int walk_axis(const walk *k) {
  return k->tmax[0] < k->tmax[1] ? (k->tmax[0] < k->tmax[2] ? 0 : 2)
                                 : (k->tmax[1] < k->tmax[2] ? 1 : 2);
}

/* Sum of kd * length over the leaf voxels of one block crossed from t0 to t1. */
static double block_depth(const leaf_grid *g, double voxel, const int lo[3], const int hi[3],
                          const double o[3], const double d[3], double t0, double t1) {
  walk k;
  walk_start(&k, g->bmin, voxel, lo, hi, o, d, t0);
  size_t sy = (size_t)g->n[0], sz = (size_t)g->n[0] * (size_t)g->n[1];
  double depth = 0.0, t = t0;
  for (;;) {
    int a = walk_axis(&k);
    double next = k.tmax[a] < t1 ? k.tmax[a] : t1;
    double v = g->kd[(size_t)k.idx[0] + (size_t)k.idx[1] * sy + (size_t)k.idx[2] * sz];
    if (v != 0.0) depth += v * (next - t);
    if (k.tmax[a] >= t1) break;
    t = next;
    k.idx[a] += k.step[a];
    if (k.idx[a] < lo[a] || k.idx[a] > hi[a]) break;
    k.tmax[a] += k.tdelta[a];
  }
  return depth;
}

/* An optical depth past which the leaves pass none of the sun: exp(-30) is 9e-14,
 * below the last printed digit of a day's hours however many samples it takes. */
#define SHADE_OPAQUE 30.0

/* The share of the sun the leaves pass along o + t d: exp(-sum of kd * length)
 * over the voxels the ray crosses, inside the leaves' box only (0 past an optical
 * depth of SHADE_OPAQUE). The walk goes
 * through blocks of SHADE_BLOCK^3 voxels and into the voxels of those that hold
 * leaves: the same voxels and lengths, without stepping through empty air. */
static double transmission(const leaf_grid *g, double voxel, const double o[3],
                           const double d[3]) {
  double t0, t1;
  if (!g->kd || !ray_box(o, d, g->bmin, g->bmax, &t0, &t1)) return 1.0;
  int zero[3] = {0, 0, 0}, top[3];
  for (int a = 0; a < 3; a++) top[a] = g->nb[a] - 1;
  walk k;
  walk_start(&k, g->bmin, voxel * SHADE_BLOCK, zero, top, o, d, t0);
  double depth = 0.0, t = t0;
  for (;;) {
    int a = walk_axis(&k);
    double next = k.tmax[a] < t1 ? k.tmax[a] : t1;
    if (g->full[(size_t)k.idx[0] + (size_t)g->nb[0] * ((size_t)k.idx[1] +
                                                        (size_t)g->nb[1] * (size_t)k.idx[2])]) {
      int lo[3], hi[3];
      for (int b = 0; b < 3; b++) {
        lo[b] = k.idx[b] * SHADE_BLOCK;
        hi[b] = lo[b] + SHADE_BLOCK - 1 < g->n[b] - 1 ? lo[b] + SHADE_BLOCK - 1 : g->n[b] - 1;
      }
      depth += block_depth(g, voxel, lo, hi, o, d, t, next);
      if (depth > SHADE_OPAQUE) return 0.0; /* nothing passes: the rest is not walked */
    }
    if (k.tmax[a] >= t1) break;
    t = next;
    k.idx[a] += k.step[a];
    if (k.idx[a] < 0 || k.idx[a] > top[a]) break;
    k.tmax[a] += k.tdelta[a];
  }
  return exp(-depth);
}

/* A solid obstacle of the world, with its id: a box, or a prism (its bounds and z
 * range in min, max, and its footprint, pointing into the world). */
typedef struct shade_box {
  int id;
  double min[3], max[3];
  sylva_footprint fp; /* ring_count 0 for a box */
} shade_box;

/* The end of edge i of a footprint whose ring starts at point `first` and has n
 * points: the next point of the ring. */
static const double *edge_end(const sylva_footprint *f, int first, int n, int i) {
  return f->points[i + 1 < first + n ? i + 1 : first];
}

/* Does the ray o + t d, t0 < t < t1 (its part inside a prism's bounds and z range),
 * pass inside the footprint? Where it crosses an edge it is inside on one side of
 * it; crossing none, it is inside all along or nowhere, as its middle is (even-odd:
 * a half-line from it crosses the rings an odd number of times). */
static bool ray_footprint(const sylva_footprint *f, const double o[3], const double d[3],
                          double t0, double t1) {
  double ax = o[0] + t0 * d[0], ay = o[1] + t0 * d[1];
  double dx = (t1 - t0) * d[0], dy = (t1 - t0) * d[1];
  double mx = ax + 0.5 * dx, my = ay + 0.5 * dy;
  bool in = false;
  for (int r = 0, first = 0; r < f->ring_count; first += f->ring_sizes[r++])
    for (int i = first; i < first + f->ring_sizes[r]; i++) {
      const double *p = f->points[i], *q = edge_end(f, first, f->ring_sizes[r], i);
      double ex = q[0] - p[0], ey = q[1] - p[1], den = dx * ey - dy * ex;
      if (den != 0.0) {
        /* a + s (dx, dy) = p + u (ex, ey) */
        double wx = p[0] - ax, wy = p[1] - ay;
        double s = (wx * ey - wy * ex) / den, u = (wx * dy - wy * dx) / den;
        if (s > 0.0 && s < 1.0 && u >= 0.0 && u <= 1.0) return true;
      }
      if ((p[1] > my) != (q[1] > my) && mx < p[0] + (my - p[1]) * ex / ey) in = !in;
    }
  return in;
}

/* Is the ray from o towards d stopped by a solid obstacle other than `own`? A
 * prism's bounds first, its footprint's edges only for a ray that meets them. */
static bool blocked(const shade_box *boxes, int count, int own, const double o[3],
                    const double d[3]) {
  for (int b = 0; b < count; b++) {
    if (boxes[b].id == own) continue;
    double t0, t1;
    if (ray_box(o, d, boxes[b].min, boxes[b].max, &t0, &t1) &&
        (boxes[b].fp.ring_count == 0 || ray_footprint(&boxes[b].fp, o, d, t0, t1)))
      return true;
  }
  return false;
}

/* How far a prism wall's cells send their rays from outside the wall, metres: off
 * the edge (a ray from on it could count its own wall), far below any cell's size. */
#define SHADE_WALL_OFFSET 1e-6

/* How the cells of one surface meet the sun: their outward normal, the obstacle
 * their rays pass through (a box's own: a box cannot shade its own face; -1 for
 * the ground and for a prism, whose courtyard walls its other walls shade), and how
 * far out along the normal the rays start. */
typedef struct cell_work {
  double n[3];
  int own;
  double offset;
} cell_work;

/* Grows r->cells to hold `more` more. */
static int reserve_cells(shade_result *r, size_t *cap, size_t more) {
  if (r->cell_count + more <= *cap) return SERVER_OK;
  size_t want = *cap ? *cap : 1024;
  while (want < r->cell_count + more) want *= 2;
  shade_cell *c = realloc(r->cells, want * sizeof *c);
  if (!c) return SERVER_ENOMEM;
  r->cells = c;
  *cap = want;
  return SERVER_OK;
}

/* A new surface, its cells to come; face_name NULL for the ground. */
static shade_surface *add_surface(shade_result *r, const char *label, int obstacle, int face,
                                  const char *face_name) {
  shade_surface *s = realloc(r->surfaces, (size_t)(r->surface_count + 1) * sizeof *s);
  if (!s) return NULL;
  r->surfaces = s;
  shade_surface *n = &s[r->surface_count++];
  *n = (shade_surface){.obstacle = obstacle, .face = face, .first = r->cell_count};
  if (!face_name) {
    snprintf(n->name, sizeof n->name, "%s", label);
  } else {
    snprintf(n->face_name, sizeof n->face_name, "%s", face_name);
    snprintf(n->name, sizeof n->name, "%s:%s", label, face_name);
  }
  return n;
}

/* The first voxel centre index along an axis at or above x (centres at min +
 * (i + 0.5) v), and the last at or below y, clamped to the world's voxels. */
static void centre_range(double min, double voxel, int dim, double x, double y, int *first,
                         int *last) {
  double a = ceil((x - min) / voxel - 0.5), b = floor((y - min) / voxel - 0.5);
  *first = a < 0 ? 0 : a > dim ? dim : (int)a;
  *last = b >= dim ? dim - 1 : b < -1 ? -1 : (int)b;
}

/* The point u cells along a face: origin + (u + 0.5) step, on each axis of x, y
 * (the origin itself where the step is 0). */
static double face_at(const double origin[2], const double step[2], int u, int a) {
  return step[a] != 0.0 ? origin[a] + (u + 0.5) * step[a] : origin[a];
}

/* The cells u0 .. u1 along the last surface of r (face_at), by the world's voxels
 * in z whose centres [zlo, zhi] holds, along it fastest. */
static int face_cells(shade_result *r, size_t *cap, const sylva_world_def *def,
                      const int dims[3], double zlo, double zhi, int u0, int u1,
                      const double origin[2], const double step[2]) {
  int z0, z1;
  centre_range(def->min[2], def->voxel, dims[2], zlo, zhi, &z0, &z1);
  if (u1 < u0 || z1 < z0) return SERVER_OK;
  size_t n = (size_t)(u1 - u0 + 1) * (size_t)(z1 - z0 + 1);
  if (reserve_cells(r, cap, n)) return SERVER_ENOMEM;
  for (int k = z0; k <= z1; k++)
    for (int u = u0; u <= u1; u++)
      r->cells[r->cell_count++] =
          (shade_cell){.p = {face_at(origin, step, u, 0), face_at(origin, step, u, 1),
                             def->min[2] + (k + 0.5) * def->voxel},
                       .surface = r->surface_count - 1};
  r->surfaces[r->surface_count - 1].count = n;
  return SERVER_OK;
}

/* The cells of one face of box o, in the world's voxel grid. */
static int add_face(shade_result *r, size_t *cap, const sylva_world_def *def,
                    const int dims[3], const sylva_obstacle_def *o, int id, int face) {
  int axis = face < 2 ? 0 : 1, across = 1 - axis;
  double plane = face % 2 == 0 ? o->max[axis] : o->min[axis];
  shade_surface *sf = add_surface(r, o->label, id, face, face_names[face]);
  if (!sf) return SERVER_ENOMEM;
  sf->normal[axis] = face % 2 == 0 ? 1.0 : -1.0;
  sf->along[across] = 1.0;
  sf->width = def->voxel;
  if (plane < def->min[axis] || plane > def->max[axis]) return SERVER_OK;
  int u0, u1;
  centre_range(def->min[across], def->voxel, dims[across], o->min[across], o->max[across], &u0,
               &u1);
  double origin[2], step[2];
  origin[axis] = plane;
  step[axis] = 0.0;
  origin[across] = def->min[across];
  step[across] = def->voxel;
  return face_cells(r, cap, def, dims, o->min[2], o->max[2], u0, u1, origin, step);
}

/* Is the left of footprint edge k (from p to q, of the ring starting at `first` with
 * n points) inside the footprint? The parity of the crossings of the half-line from
 * the edge's middle to its left with the other edges (a crossing where an end lies
 * on the half-line's line counted once: that end as if to the right of it). */
static bool left_inside(const sylva_footprint *f, const double p[2], const double q[2], int k) {
  double mx = 0.5 * (p[0] + q[0]), my = 0.5 * (p[1] + q[1]);
  double lx = p[1] - q[1], ly = q[0] - p[0]; /* the left normal, unscaled */
  bool in = false;
  for (int r = 0, first = 0; r < f->ring_count; first += f->ring_sizes[r++])
    for (int i = first; i < first + f->ring_sizes[r]; i++) {
      if (i == k) continue;
      const double *a = f->points[i], *b = edge_end(f, first, f->ring_sizes[r], i);
      double sa = lx * (a[1] - my) - ly * (a[0] - mx), sb = lx * (b[1] - my) - ly * (b[0] - mx);
      if ((sa > 0.0) == (sb > 0.0)) continue;
      double ta = lx * (a[0] - mx) + ly * (a[1] - my), tb = lx * (b[0] - mx) + ly * (b[1] - my);
      if (ta + (tb - ta) * sa / (sa - sb) > 0.0) in = !in;
    }
  return in;
}

_Static_assert(SYLVA_FOOTPRINT_MAX_POINTS <= 100000, "an edge's name, e99999, fits its field");

/* The cells of the wall on edge k (from p to q) of prism o: round(length / voxel)
 * cells along it (at least one), centred, by the world's voxels in z that its z
 * range holds; those whose centres lie inside the world's box. */
static int add_wall(shade_result *r, size_t *cap, const sylva_world_def *def,
                    const int dims[3], const sylva_obstacle_def *o, int id, int k,
                    const double p[2], const double q[2]) {
  char name[SHADE_FACE_NAME_MAX]; /* k < SYLVA_FOOTPRINT_MAX_POINTS, 100000 */
  snprintf(name, sizeof name, "e%u", (unsigned)k % 100000u);
  shade_surface *sf = add_surface(r, o->label, id, k, name);
  if (!sf) return SERVER_ENOMEM;
  double ex = q[0] - p[0], ey = q[1] - p[1], len = hypot(ex, ey);
  if (!(len > 0.0)) return SERVER_OK; /* a repeated point: a wall of no width */
  double side = left_inside(&o->footprint, p, q, k) ? -1.0 : 1.0;
  sf->normal[0] = -side * ey / len;
  sf->normal[1] = side * ex / len;
  sf->along[0] = ex / len;
  sf->along[1] = ey / len;
  long cells = lround(len / def->voxel);
  int nu = cells < 1 ? 1 : cells > INT_MAX / 2 ? INT_MAX / 2 : (int)cells;
  sf->width = len / nu;
  double step[2] = {ex / nu, ey / nu};
  int u0 = nu, u1 = -1;
  for (int u = 0; u < nu; u++) {
    double x = face_at(p, step, u, 0), y = face_at(p, step, u, 1);
    if (x < def->min[0] || x > def->max[0] || y < def->min[1] || y > def->max[1]) continue;
    if (u < u0) u0 = u;
    u1 = u; /* the world's box is convex: the cells inside it are a run */
  }
  return face_cells(r, cap, def, dims, o->min[2], o->max[2], u0, u1, p, step);
}

/* The walls of prism o that the filter asks for (face: one edge, or -1). */
static int add_walls(shade_result *r, size_t *cap, const sylva_world_def *def,
                     const int dims[3], const sylva_obstacle_def *o, int id, int face) {
  const sylva_footprint *f = &o->footprint;
  for (int ring = 0, first = 0; ring < f->ring_count; first += f->ring_sizes[ring++])
    for (int i = first; i < first + f->ring_sizes[ring]; i++) {
      if (face >= 0 && i != face) continue;
      int rc = add_wall(r, cap, def, dims, o, id, i, f->points[i],
                        edge_end(f, first, f->ring_sizes[ring], i));
      if (rc) return rc;
    }
  return SERVER_OK;
}

/* The cells the filter asks for, the ground's first. */
static int make_cells(const sylva_world *w, const shade_filter *f, shade_result *r) {
  const sylva_world_def *def = sylva_world_get_def(w);
  int dims[3];
  sylva_world_dims(w, dims);
  size_t cap = 0;
  if (f->ground) {
    shade_surface *g = add_surface(r, "ground", -1, -1, NULL);
    if (!g) return SERVER_ENOMEM;
    g->normal[2] = 1.0;
    size_t n = (size_t)dims[0] * (size_t)dims[1];
    if (reserve_cells(r, &cap, n)) return SERVER_ENOMEM;
    for (int j = 0; j < dims[1]; j++)
      for (int i = 0; i < dims[0]; i++) {
        shade_cell *c = &r->cells[r->cell_count++];
        *c = (shade_cell){.p = {def->min[0] + (i + 0.5) * def->voxel,
                                def->min[1] + (j + 0.5) * def->voxel, def->min[2]},
                          .surface = 0};
      }
    r->surfaces[0].count = n;
    r->nx = dims[0];
    r->ny = dims[1];
  }
  if (!f->faces) return SERVER_OK;
  int count = sylva_world_obstacle_count(w);
  for (int i = 0; i < count; i++) {
    int id;
    sylva_obstacle_def o;
    if (sylva_world_obstacle_at(w, i, &id, &o) != 0 || o.kind != SYLVA_OBSTACLE_SOLID) continue;
    if (f->obstacle >= 0 && id != f->obstacle) continue;
    if (o.footprint.ring_count > 0) {
      int rc = add_walls(r, &cap, def, dims, &o, id, f->face);
      if (rc) return rc;
      continue;
    }
    for (int face = 0; face < SHADE_FACE_COUNT; face++) {
      if (f->face >= 0 && face != f->face) continue;
      int rc = add_face(r, &cap, def, dims, &o, id, face);
      if (rc) return rc;
    }
  }
  return SERVER_OK;
}

/* How each surface of r meets the sun (one cell_work per surface, into work). */
static void surface_work(const shade_result *r, const shade_box *boxes, int box_count,
                         cell_work *work) {
  for (int s = 0; s < r->surface_count; s++) {
    const shade_surface *sf = &r->surfaces[s];
    cell_work *cw = &work[s];
    *cw = (cell_work){.own = sf->obstacle};
    memcpy(cw->n, sf->normal, sizeof cw->n);
    for (int b = 0; b < box_count; b++)
      if (boxes[b].id == sf->obstacle && boxes[b].fp.ring_count > 0) {
        cw->own = -1;
        cw->offset = SHADE_WALL_OFFSET;
      }
  }
}

/* The solid boxes and prisms of w (NULL and 0 when there are none). */
static int collect_boxes(const sylva_world *w, shade_box **out, int *count) {
  int n = sylva_world_obstacle_count(w);
  *out = NULL;
  *count = 0;
  if (n <= 0) return SERVER_OK;
  shade_box *b = malloc((size_t)n * sizeof *b);
  if (!b) return SERVER_ENOMEM;
  for (int i = 0; i < n; i++) {
    int id;
    sylva_obstacle_def o;
    if (sylva_world_obstacle_at(w, i, &id, &o) != 0 || o.kind != SYLVA_OBSTACLE_SOLID) continue;
    shade_box *x = &b[(*count)++];
    x->id = id;
    memcpy(x->min, o.min, sizeof x->min);
    memcpy(x->max, o.max, sizeof x->max);
    x->fp = o.footprint;
  }
  *out = b;
  return SERVER_OK;
}

/* The unit vector towards elevation el and azimuth az (degrees clockwise from
 * north) with north along n (unit) and east (n.y, -n.x), as proto's sky maps its
 * sun (proto/src/sky.c). */
static void sun_direction(const double n[2], double el, double az, double d[3]) {
  double h = cos(el * DEG), c = cos(az * DEG), s = sin(az * DEG);
  d[0] = h * (c * n[0] + s * n[1]);
  d[1] = h * (c * n[1] - s * n[0]);
  d[2] = sin(el * DEG);
}

/* The means of cells[first .. first + count) into s. */
static void summarise(const shade_cell *cells, size_t first, size_t count, shade_surface *s) {
  double open = 0.0, with = 0.0;
  size_t dim = 0;
  for (size_t i = first; i < first + count; i++) {
    open += cells[i].open;
    with += cells[i].with;
    if (cells[i].with < SHADE_DIM_HOURS) dim++;
  }
  s->count = count;
  s->mean_open = count ? open / (double)count : 0.0;
  s->mean_with = count ? with / (double)count : 0.0;
  s->mean_added = s->mean_open - s->mean_with;
  s->share_dim = count ? (double)dim / (double)count : 0.0;
}

void shade_obstacle_summary(const shade_result *r, int obstacle, shade_surface *out) {
  *out = (shade_surface){.obstacle = obstacle, .face = -1};
  double open = 0.0, with = 0.0, dim = 0.0;
  size_t n = 0;
  for (int s = 0; s < r->surface_count; s++) {
    const shade_surface *x = &r->surfaces[s];
    if (x->obstacle != obstacle || x->face < 0) continue;
    if (!out->name[0]) snprintf(out->name, sizeof out->name, "%.*s",
                                (int)(strrchr(x->name, ':') - x->name), x->name);
    open += x->mean_open * (double)x->count;
    with += x->mean_with * (double)x->count;
    dim += x->share_dim * (double)x->count;
    n += x->count;
  }
  out->count = n;
  out->mean_open = n ? open / (double)n : 0.0;
  out->mean_with = n ? with / (double)n : 0.0;
  out->mean_added = out->mean_open - out->mean_with;
  out->share_dim = n ? dim / (double)n : 0.0;
}

/* The cells [from, to) of a day: each cell's hours summed over the samples in their
 * order, whatever the cells the other threads take, so the sums are the same bits
 * for any number of threads. */
typedef struct shade_job {
  const shade_result *r;
  shade_cell *cells;
  const leaf_grid *g;
  double voxel, dt;
  const shade_box *boxes;
  int box_count;
  const cell_work *work; /* per surface */
  const double (*dirs)[3]; /* the sun's directions of the samples with the sun up */
  int dir_count;
  size_t from, to;
} shade_job;

static void shade_cells(const shade_job *j) {
  for (int i = 0; i < j->dir_count; i++) {
    const double *d = j->dirs[i];
    for (int s = 0; s < j->r->surface_count; s++) {
      const shade_surface *sf = &j->r->surfaces[s];
      const cell_work *cw = &j->work[s];
      if (!(cw->n[0] * d[0] + cw->n[1] * d[1] + cw->n[2] * d[2] > 0.0)) continue;
      size_t lo = sf->first > j->from ? sf->first : j->from;
      size_t hi = sf->first + sf->count < j->to ? sf->first + sf->count : j->to;
      for (size_t c = lo; c < hi; c++) {
        shade_cell *cell = &j->cells[c];
        double moved[3];
        const double *o = cell->p;
        if (cw->offset > 0.0) {
          for (int a = 0; a < 3; a++) moved[a] = cell->p[a] + cw->offset * cw->n[a];
          o = moved;
        }
        if (blocked(j->boxes, j->box_count, cw->own, o, d)) continue;
        cell->open += j->dt;
        cell->with += j->dt * transmission(j->g, j->voxel, cell->p, d); /* as a box's */
      }
    }
  }
}

static void *shade_thread(void *arg) {
  shade_cells(arg);
  return NULL;
}

/* Runs the job on `threads` threads, each a run of cells; a thread that cannot be
 * started leaves its cells to the caller's. */
static void shade_run(shade_job job, int threads) {
  enum { MAX_THREADS = 64 };
  if (threads <= 0) {
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    threads = n > 0 ? (int)n : 1;
  }
  if (threads > MAX_THREADS) threads = MAX_THREADS;
  size_t n = job.to - job.from;
  if ((size_t)threads > n / 1024 + 1) threads = (int)(n / 1024 + 1); /* not for a few cells */
  pthread_t tid[MAX_THREADS];
  shade_job part[MAX_THREADS];
  bool started[MAX_THREADS] = {false};
  for (int t = 0; t < threads; t++) {
    part[t] = job;
    part[t].from = job.from + n * (size_t)t / (size_t)threads;
    part[t].to = job.from + n * (size_t)(t + 1) / (size_t)threads;
    if (t > 0) started[t] = pthread_create(&tid[t], NULL, shade_thread, &part[t]) == 0;
  }
  shade_cells(&part[0]);
  for (int t = 1; t < threads; t++) {
    if (started[t])
      pthread_join(tid[t], NULL);
    else
      shade_cells(&part[t]);
  }
}

int shade_compute(const sylva_world *w, const shade_site *site, const shade_day *day,
                  const shade_filter *filter, shade_result *out, char *err, size_t errlen) {
  return shade_compute_threads(w, site, day, filter, 1, out, err, errlen);
}

int shade_compute_threads(const sylva_world *w, const shade_site *site, const shade_day *day,
                          const shade_filter *filter, int threads, shade_result *out, char *err,
                          size_t errlen) {
  const sylva_world_def *def = sylva_world_get_def(w);
  *out = (shade_result){.voxel = def->voxel, .site = *site, .day = *day};
  memcpy(out->min, def->min, sizeof out->min);
  memcpy(out->max, def->max, sizeof out->max);
  int rc = shade_check(site, day, err, errlen);
  if (rc) return rc;
  shade_filter all = {.ground = true, .faces = true, .obstacle = -1, .face = -1};
  if (make_cells(w, filter ? filter : &all, out))
    return server_fail(err, errlen, SERVER_ENOMEM, "out of memory for the cells");

  /* the sun's samples, as hours after its transit */
  int doy = shade_day_of_year(day->month, day->day);
  int count = (day->to - day->from + day->step - 1) / day->step;
  double transit = 12.0;
  if (site->clock) transit = 12.0 - site->longitude / 15.0 + site->utc_offset - equation_of_time(doy);
  double *hours = malloc((size_t)count * sizeof *hours);
  sylva_sun *sun = malloc((size_t)count * sizeof *sun);
  shade_box *boxes = NULL;
  int box_count = 0;
  double(*dirs)[3] = NULL;
  cell_work *work = NULL;
  leaf_grid g = {.kd = NULL, .full = NULL};
  if (!hours || !sun || collect_boxes(w, &boxes, &box_count)) {
    rc = server_fail(err, errlen, SERVER_ENOMEM, "out of memory for the sun's samples");
    goto done;
  }
  for (int i = 0; i < count; i++) hours[i] = (day->from + i * day->step) / 60.0 - transit;
  sylva_sun_day(site->latitude, doy, hours, count, sun);
  out->samples = count;
  rc = leaf_grid_build(w, &g, err, errlen);
  if (rc) goto done;
  out->leaf_area = g.area;

  double len = hypot(site->north[0], site->north[1]);
  double north[2] = {site->north[0] / len, site->north[1] / len};
  dirs = malloc((size_t)count * sizeof *dirs);
  work = malloc((size_t)(out->surface_count > 0 ? out->surface_count : 1) * sizeof *work);
  if (!dirs || !work) {
    rc = server_fail(err, errlen, SERVER_ENOMEM, "out of memory for the sun's samples");
    goto done;
  }
  surface_work(out, boxes, box_count, work);
  int lit = 0;
  for (int i = 0; i < count; i++)
    if (sun[i].elevation > 0.0) sun_direction(north, sun[i].elevation, sun[i].azimuth, dirs[lit++]);
  shade_run((shade_job){.r = out, .cells = out->cells, .g = &g, .voxel = def->voxel,
                        .dt = day->step / 60.0, .boxes = boxes, .box_count = box_count,
                        .work = work, .dirs = (const double(*)[3])dirs, .dir_count = lit, .from = 0,
                        .to = out->cell_count},
            threads);
  for (int s = 0; s < out->surface_count; s++)
    summarise(out->cells, out->surfaces[s].first, out->surfaces[s].count, &out->surfaces[s]);
done:
  free(hours);
  free(dirs);
  free(work);
  free(sun);
  free(boxes);
  free(g.kd);
  free(g.full);
  return rc;
}

void shade_result_free(shade_result *r) {
  free(r->cells);
  free(r->surfaces);
  *r = (shade_result){.cells = NULL};
}

int shade_ground_added(const shade_result *r, double *out) {
  if (r->surface_count < 1 || r->surfaces[0].face >= 0 || r->nx <= 0) return SERVER_EINPUT;
  size_t n = (size_t)r->nx * (size_t)r->ny;
  for (size_t i = 0; i < n; i++) out[i] = r->cells[i].open - r->cells[i].with;
  return SERVER_OK;
}

bool shade_site_of(const sylva_scenario *s, shade_site *site) {
  if (!s->light.site) return false;
  *site = (shade_site){.latitude = s->light.sky.latitude,
                       .north = {s->light.sky.north[0], s->light.sky.north[1]},
                       .clock = s->light.clock,
                       .longitude = s->light.longitude,
                       .utc_offset = s->light.utc_offset};
  return true;
}
