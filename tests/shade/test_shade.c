/* The shade library (server/shade) against computations of its own: the shadow of a
 * box from libnova's sun, called here directly, as a polygon on the ground; faces
 * turned from the sun; the sun through a uniform layer of leaves against
 * exp(-k LAI / sin(elevation)). Prisms: one equal to a box shades as the box does,
 * a building at 30 degrees casts the shadow polygon of its corners cell by cell,
 * a courtyard's walls and ground get the sun its walls leave them. */
#include <libnova/julian_day.h>
#include <libnova/rise_set.h>
#include <libnova/solar.h>
#include <libnova/transform.h>

#include "../check.h"
#include "shade.h"
#include "sylva/sun.h"
#include "sylva/world.h"

#define DEG (3.14159265358979323846 / 180.0)

/* The sun's unit direction (north +y, east +x) from libnova at lat on 2025-MM-DD,
 * `minutes` of local solar time (12:00 the transit at longitude 0). */
static double sun_at(double lat, int month, int day, int minutes, double d[3]) {
  struct ln_date date = {.years = 2025, .months = month, .days = day, .hours = 0};
  struct ln_lnlat_posn site = {.lng = 0.0, .lat = lat};
  struct ln_rst_time rst;
  ln_get_solar_rst(ln_get_julian_day(&date), &site, &rst);
  double jd = rst.transit + (minutes / 60.0 - 12.0) / 24.0;
  struct ln_equ_posn equ;
  struct ln_hrz_posn hrz;
  ln_get_solar_equ_coords(jd, &equ);
  ln_get_hrz_from_equ(&equ, &site, jd, &hrz);
  double az = hrz.az + 180.0; /* libnova: from the south, westwards */
  d[0] = cos(hrz.alt * DEG) * sin(az * DEG);
  d[1] = cos(hrz.alt * DEG) * cos(az * DEG);
  d[2] = sin(hrz.alt * DEG);
  return hrz.alt;
}

/* Is (x, y) inside the convex hull of the points pts[0 .. n)? (Gift wrapping, then
 * the point on the inner side of every edge.) */
static bool in_hull(const double (*pts)[2], int n, double x, double y) {
  int hull[16], h = 0, start = 0;
  for (int i = 1; i < n; i++)
    if (pts[i][0] < pts[start][0] || (pts[i][0] == pts[start][0] && pts[i][1] < pts[start][1]))
      start = i;
  int p = start;
  do {
    hull[h++] = p;
    int q = (p + 1) % n;
    for (int r = 0; r < n; r++) {
      double cross = (pts[q][0] - pts[p][0]) * (pts[r][1] - pts[p][1]) -
                     (pts[q][1] - pts[p][1]) * (pts[r][0] - pts[p][0]);
      if (cross < 0) q = r;
    }
    p = q;
  } while (p != start && h < 16);
  for (int i = 0; i < h; i++) {
    const double *a = pts[hull[i]], *b = pts[hull[(i + 1) % h]];
    if ((b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]) < 0) return false;
  }
  return true;
}

static sylva_world *box_world(double voxel) {
  sylva_world_def def = sylva_default_world_def();
  def.min[0] = -12; def.min[1] = -12; def.min[2] = 0;
  def.max[0] = 12; def.max[1] = 12; def.max[2] = 8;
  def.voxel = voxel;
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&def, &w), 0);
  sylva_obstacle_def box = {.label = "tower", .min = {-1, -1, 0}, .max = {1, 1, 6},
                            .kind = SYLVA_OBSTACLE_SOLID};
  CHECK(sylva_world_add_obstacle(w, &box) >= 0);
  return w;
}

/* Every ground cell's open hours against the box's shadow polygon, each 10 minutes
 * from 06:00 to 18:00 at 40 N on 06-21: within one step. */
static void test_shadow(void) {
  sylva_world *w = box_world(0.25);
  shade_site site = {.latitude = 40, .north = {0, 1}};
  shade_day day = {.month = 6, .day = 21, .year = 2025, .from = 360, .to = 1080, .step = 10};
  shade_filter ground = {.ground = true, .faces = false, .obstacle = -1, .face = -1};
  shade_result r;
  char err[256];
  CHECK_INT(shade_compute(w, &site, &day, &ground, &r, err, sizeof err), 0);
  CHECK_INT(r.nx * r.ny, (int)r.cell_count);
  double *expect = calloc(r.cell_count, sizeof *expect);
  for (int t = day.from; t < day.to; t += day.step) {
    double d[3];
    if (sun_at(40, 6, 21, t, d) <= 0) continue;
    double corners[8][2];
    for (int k = 0; k < 8; k++) {
      double c[3] = {k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 6 : 0};
      corners[k][0] = c[0] - d[0] / d[2] * c[2];
      corners[k][1] = c[1] - d[1] / d[2] * c[2];
    }
    for (size_t i = 0; i < r.cell_count; i++)
      if (!in_hull((const double (*)[2])corners, 8, r.cells[i].p[0], r.cells[i].p[1]))
        expect[i] += day.step / 60.0;
  }
  int off = 0, shaded = 0;
  for (size_t i = 0; i < r.cell_count; i++) {
    if (fabs(r.cells[i].open - expect[i]) > day.step / 60.0 + 1e-9) off++;
    if (r.cells[i].open < 11.9) shaded++;
    CHECK_NEAR(r.cells[i].open, r.cells[i].with, 1e-12); /* no plants */
  }
  CHECK_INT(off, 0);
  CHECK(shaded > 100); /* the shadow is there */
  free(expect);
  shade_result_free(&r);
  sylva_world_destroy(w);
}

/* At 50 N on 12-21 the north face (+y) gets no sun; the east face (+x) none after
 * the transit, and some before it. */
static void test_faces(void) {
  sylva_world *w = box_world(0.5);
  shade_site site = {.latitude = 50, .north = {0, 1}};
  shade_day day = {.month = 12, .day = 21, .year = 2025, .from = 0, .to = 1440, .step = 10};
  char err[256];
  shade_filter north;
  CHECK_INT(shade_parse_surface(w, "tower:+y", &north, err, sizeof err), 0);
  shade_result r;
  CHECK_INT(shade_compute(w, &site, &day, &north, &r, err, sizeof err), 0);
  CHECK(r.cell_count > 0);
  for (size_t i = 0; i < r.cell_count; i++) CHECK_NEAR(r.cells[i].open, 0.0, 0.0);
  shade_result_free(&r);

  shade_filter east;
  CHECK_INT(shade_parse_surface(w, "tower:+x", &east, err, sizeof err), 0);
  day.from = 721; /* just after the transit (at it the sun is due south: grazing) */
  CHECK_INT(shade_compute(w, &site, &day, &east, &r, err, sizeof err), 0);
  for (size_t i = 0; i < r.cell_count; i++) CHECK_NEAR(r.cells[i].open, 0.0, 0.0);
  shade_result_free(&r);
  day.from = 0;
  day.to = 720;
  CHECK_INT(shade_compute(w, &site, &day, &east, &r, err, sizeof err), 0);
  CHECK(r.surfaces[0].mean_open > 1.0);
  shade_result_free(&r);

  CHECK_INT(shade_parse_surface(w, "awning:+z", &east, err, sizeof err), SERVER_EINPUT);
  CHECK_INT(shade_parse_surface(w, "tower:+z", &east, err, sizeof err), SERVER_EINPUT);
  CHECK_INT(shade_parse_surface(w, "awning:+x", &east, err, sizeof err), SERVER_EINPUT);
  sylva_world_destroy(w);
}

/* A 4 m x 4 m layer of leaves, every voxel column alike: the sun at the transit
 * reaches the ground below its centre through exp(-k LAI / sin(elevation)). */
static void test_transmission(void) {
  sylva_world_def def = sylva_default_world_def();
  def.min[0] = -6; def.min[1] = -6; def.min[2] = 0;
  def.max[0] = 6; def.max[1] = 6; def.max[2] = 4;
  def.voxel = 0.1;
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&def, &w), 0);
  sylva_species_def sp = sylva_default_species_def();
  sp.leaf_size = 0.01;
  sp.leaf_density = 4;
  int species = sylva_world_add_species(w, &sp, "leafy");
  CHECK(species >= 0);
  enum { SIDE = 40, LEVELS = 11 };
  for (int i = 0; i < SIDE; i++)
    for (int j = 0; j < SIDE; j++) {
      sylva_plant_node nodes[LEVELS];
      for (int k = 0; k < LEVELS; k++)
        nodes[k] = (sylva_plant_node){.p = {-2 + (i + 0.5) * 0.1, -2 + (j + 0.5) * 0.1,
                                            1.0 + 0.1 * k},
                                      .radius = 0.001, .parent = k - 1, .birth = 0};
      char label[32];
      snprintf(label, sizeof label, "column-%d-%d", i, j);
      sylva_plant_def plant = {.species = species, .label = label, .nodes = nodes,
                               .node_count = LEVELS};
      int bad = -1; /* given: the core writes it for a measured plant */
      CHECK(sylva_world_add_plant(w, &plant, &bad) >= 0);
    }
  double area = 0.0;
  size_t count = sylva_world_node_count(w);
  for (size_t i = 0; i < count; i++) {
    sylva_node_info info;
    sylva_world_node_at(w, i, &info);
    area += info.leaves * SYLVA_LEAF_FILL * sp.leaf_size * sp.leaf_size;
  }
  CHECK(area > 0.0);
  shade_site site = {.latitude = 30, .north = {0, 1}};
  shade_day day = {.month = 6, .day = 21, .year = 2025, .from = 720, .to = 730, .step = 10};
  shade_filter ground = {.ground = true, .faces = false, .obstacle = -1, .face = -1};
  shade_result r;
  char err[256];
  CHECK_INT(shade_compute(w, &site, &day, &ground, &r, err, sizeof err), 0);
  CHECK_NEAR(r.leaf_area, area, 1e-9 * area);
  double d[3];
  double el = sun_at(30, 6, 21, 720, d);
  double expect = exp(-SHADE_K * area / 16.0 / sin(el * DEG));
  CHECK(expect > 0.05 && expect < 0.95); /* a test that can tell */
  /* the cell whose centre is (0.05, 0.05): its ray leaves the layer's top about
   * 0.4 m from it, inside the layer */
  size_t at = (size_t)(60 + r.nx * 60);
  CHECK_NEAR(r.cells[at].p[0], 0.05, 1e-9);
  CHECK_NEAR(r.cells[at].open, 10.0 / 60.0, 1e-12);
  CHECK_NEAR(r.cells[at].with / r.cells[at].open, expect, 0.01 * expect);
  /* far from the layer the sun is whole */
  CHECK_NEAR(r.cells[0].with, r.cells[0].open, 1e-12);
  double *added = malloc((size_t)r.nx * (size_t)r.ny * sizeof *added);
  CHECK_INT(shade_ground_added(&r, added), 0);
  CHECK_NEAR(added[at], r.cells[at].open - r.cells[at].with, 0.0);
  free(added);
  /* on 1, 2 and 3 threads, the whole day: the same bits in every cell */
  shade_day whole = {.month = 6, .day = 21, .year = 2025, .from = 0, .to = 1440, .step = 10};
  shade_result one, more;
  CHECK_INT(shade_compute_threads(w, &site, &whole, NULL, 1, &one, err, sizeof err), 0);
  for (int threads = 2; threads <= 3; threads++) {
    CHECK_INT(shade_compute_threads(w, &site, &whole, NULL, threads, &more, err, sizeof err), 0);
    bool same = more.cell_count == one.cell_count && one.cell_count > 0;
    for (size_t c = 0; same && c < one.cell_count; c++)
      same = memcmp(&more.cells[c].open, &one.cells[c].open, sizeof one.cells[c].open) == 0 &&
             memcmp(&more.cells[c].with, &one.cells[c].with, sizeof one.cells[c].with) == 0;
    CHECK(same);
    shade_result_free(&more);
  }
  shade_result_free(&one);
  shade_result_free(&r);
  sylva_world_destroy(w);
}

/* The direction of the sun that shade_compute takes for a sample at `minutes` of
 * local solar time at lat on day doy, north +y: proto's sun, mapped to the plan with
 * the same operations, so the same bits. */
static double sun_sample(double lat, int doy, int minutes, double d[3]) {
  double hours = minutes / 60.0 - 12.0;
  sylva_sun sun;
  sylva_sun_day(lat, doy, &hours, 1, &sun);
  double h = cos(sun.elevation * DEG), c = cos(sun.azimuth * DEG), s = sin(sun.azimuth * DEG);
  d[0] = h * (c * 0.0 + s * 1.0);
  d[1] = h * (c * 1.0 - s * 0.0);
  d[2] = sin(sun.elevation * DEG);
  return sun.elevation;
}

/* Even-odd: is (x, y) inside the rings (sizes[0 .. rings)) of pts? */
static bool in_rings(const double (*pts)[2], const int *sizes, int rings, double x, double y) {
  bool in = false;
  for (int r = 0, first = 0; r < rings; first += sizes[r++])
    for (int i = 0; i < sizes[r]; i++) {
      const double *a = pts[first + i], *b = pts[first + (i + 1) % sizes[r]];
      if ((a[1] > y) != (b[1] > y) && x < a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1]))
        in = !in;
    }
  return in;
}

/* A world of voxel `voxel` over [lo, hi]^2 x [0, top]. */
static sylva_world *open_world(double lo, double hi, double top, double voxel) {
  sylva_world_def def = sylva_default_world_def();
  def.min[0] = lo; def.min[1] = lo; def.min[2] = 0;
  def.max[0] = hi; def.max[1] = hi; def.max[2] = top;
  def.voxel = voxel;
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&def, &w), 0);
  return w;
}

/* Adds a solid prism of rings (sizes[0 .. rings)) of pts from z0 to z1. */
static void add_prism(sylva_world *w, const char *label, const double (*pts)[2], const int *sizes,
                      int rings, double z0, double z1) {
  int n = 0;
  for (int r = 0; r < rings; r++) n += sizes[r];
  sylva_obstacle_def o = {.label = label, .min = {0, 0, z0}, .max = {0, 0, z1},
                          .kind = SYLVA_OBSTACLE_SOLID,
                          .footprint = {pts, n, sizes, rings}};
  CHECK(sylva_world_add_obstacle(w, &o) >= 0);
}

/* The surface of r named `name`, or NULL. */
static const shade_surface *surface_named(const shade_result *r, const char *name) {
  for (int s = 0; s < r->surface_count; s++)
    if (strcmp(r->surfaces[s].name, name) == 0) return &r->surfaces[s];
  return NULL;
}

/* The surface of r for wall e of obstacle `label` (checked to be there), or NULL. */
static const shade_surface *wall_of(const shade_result *r, const char *label, int e) {
  char name[SYLVA_LABEL_MAX + SHADE_FACE_NAME_MAX];
  snprintf(name, sizeof name, "%s:e%d", label, e);
  const shade_surface *sf = surface_named(r, name);
  CHECK(sf != NULL);
  return sf;
}

/* A prism whose footprint is the box's rectangle, wound either way, beside a wall
 * that it shades and that shades it, over a whole day: the same bits on every
 * ground cell and every cell of the wall, and each box face's cells on the edge
 * with its normal (-y e0, +x e1, +y e2, -x e3 wound anticlockwise), at the same
 * centres with the same bits. */
static void test_prism_box(void) {
  static const double ccw[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  static const double cw[4][2] = {{-1, -1}, {-1, 1}, {1, 1}, {1, -1}};
  static const int four[1] = {4};
  static const char *const ccw_face[4] = {"-y", "+x", "+y", "-x"};
  sylva_obstacle_def wall = {.label = "wall", .min = {2.2, -4, 0}, .max = {2.7, 3, 4},
                             .kind = SYLVA_OBSTACLE_SOLID};
  sylva_obstacle_def tower = {.label = "tower", .min = {-1, -1, 0}, .max = {1, 1, 6},
                              .kind = SYLVA_OBSTACLE_SOLID};
  sylva_world *box = open_world(-12, 12, 8, 0.25);
  CHECK(sylva_world_add_obstacle(box, &tower) >= 0);
  CHECK(sylva_world_add_obstacle(box, &wall) >= 0);
  shade_site site = {.latitude = 40, .north = {0, 1}};
  shade_day day = {.month = 6, .day = 21, .year = 2025, .from = 0, .to = 1440, .step = 10};
  char err[256];
  shade_result rb;
  CHECK_INT(shade_compute(box, &site, &day, NULL, &rb, err, sizeof err), 0);
  for (int wind = 0; wind < 2; wind++) {
    sylva_world *w = open_world(-12, 12, 8, 0.25);
    add_prism(w, "tower", wind ? cw : ccw, four, 1, 0, 6);
    CHECK(sylva_world_add_obstacle(w, &wall) >= 0);
    shade_result rp;
    CHECK_INT(shade_compute(w, &site, &day, NULL, &rp, err, sizeof err), 0);
    CHECK_INT(rp.surface_count, rb.surface_count);
    CHECK_INT(rp.cell_count, rb.cell_count);
    /* the ground and the wall's faces: in the same order, the same bits */
    size_t same = 0, compared = 0;
    for (int s = 0; s < rb.surface_count && s < rp.surface_count; s++) {
      if (strncmp(rb.surfaces[s].name, "tower:", 6) == 0) continue;
      CHECK(strcmp(rb.surfaces[s].name, rp.surfaces[s].name) == 0);
      for (size_t c = rb.surfaces[s].first; c < rb.surfaces[s].first + rb.surfaces[s].count; c++) {
        compared++;
        same += memcmp(&rb.cells[c].open, &rp.cells[c].open, sizeof(double)) == 0 &&
                memcmp(rb.cells[c].p, rp.cells[c].p, sizeof rb.cells[c].p) == 0;
      }
    }
    CHECK(compared > (size_t)rb.nx * (size_t)rb.ny);
    CHECK_INT(same, compared);
    /* the tower's faces: each box face's cells on the edge facing its way */
    int matched = 0;
    for (int e = 0; e < 4; e++) {
      const shade_surface *pe = wall_of(&rp, "tower", e);
      if (!pe) continue;
      char name[32];
      snprintf(name, sizeof name, "e%d", e);
      CHECK(strcmp(pe->face_name, name) == 0);
      CHECK_INT(pe->face, e);
      CHECK_NEAR(pe->width, 0.25, 1e-12);
      int f = e; /* the clockwise ring's edge e runs against the anticlockwise's edge 3 - e */
      if (wind) f = 3 - e;
      snprintf(name, sizeof name, "tower:%s", ccw_face[f]);
      const shade_surface *bf = surface_named(&rb, name);
      CHECK(bf != NULL);
      if (!bf) continue;
      for (int a = 0; a < 3; a++) CHECK_NEAR(pe->normal[a], bf->normal[a], 1e-15);
      CHECK_INT(pe->count, bf->count);
      CHECK(bf->count > 0);
      size_t found = 0;
      for (size_t i = bf->first; i < bf->first + bf->count; i++)
        for (size_t j = pe->first; j < pe->first + pe->count; j++) {
          const shade_cell *a = &rb.cells[i], *b = &rp.cells[j];
          if (fabs(a->p[0] - b->p[0]) < 1e-9 && fabs(a->p[1] - b->p[1]) < 1e-9 &&
              a->p[2] == b->p[2]) {
            found += memcmp(&a->open, &b->open, sizeof a->open) == 0;
            break;
          }
        }
      CHECK_INT(found, bf->count);
      matched++;
    }
    CHECK_INT(matched, 4);
    /* some cells in sun, some in the wall's shade: the comparison can tell */
    const shade_surface *east = surface_named(&rb, "tower:+x");
    CHECK(east && east->mean_open > 0.5 && east->mean_open < 5.9);
    shade_result_free(&rp);
    sylva_world_destroy(w);
  }
  shade_result_free(&rb);
  sylva_world_destroy(box);
}

/* A building 10 m x 5 m turned 30 degrees, 9 m high: at five fixed suns, each ground
 * cell is in shade exactly where its centre lies inside the convex hull of the
 * footprint's corners and their shadows at its roof (footprint + h cot(elevation)
 * towards the sun's antipode); over the day, the cells whose centres the footprint
 * holds get no sun and those only inside its bounds do; its four walls face out. */
static void test_prism_turned(void) {
  double pts[4][2], cx = 1.3, cy = -0.7, a = 30 * DEG, hx = 5, hy = 2.5, top = 9;
  static const int four[1] = {4};
  for (int k = 0; k < 4; k++) {
    double u = (k == 1 || k == 2) ? hx : -hx, v = k >= 2 ? hy : -hy;
    pts[k][0] = cx + u * cos(a) - v * sin(a);
    pts[k][1] = cy + u * sin(a) + v * cos(a);
  }
  sylva_world *w = open_world(-20, 20, 12, 0.25);
  add_prism(w, "office", (const double (*)[2])pts, four, 1, 0, top);
  shade_site site = {.latitude = 40, .north = {0, 1}};
  shade_filter ground = {.ground = true, .faces = false, .obstacle = -1, .face = -1};
  char err[256];
  static const int times[5] = {8 * 60, 10 * 60 + 30, 12 * 60, 15 * 60 + 20, 18 * 60};
  for (int t = 0; t < 5; t++) {
    shade_day day = {.month = 6, .day = 21, .year = 2025, .from = times[t],
                     .to = times[t] + 10, .step = 10};
    double d[3];
    CHECK(sun_sample(40, shade_day_of_year(6, 21), times[t], d) > 5);
    double corners[8][2];
    for (int k = 0; k < 8; k++) {
      double h = k < 4 ? 0 : top;
      corners[k][0] = pts[k % 4][0] - d[0] / d[2] * h;
      corners[k][1] = pts[k % 4][1] - d[1] / d[2] * h;
    }
    shade_result r;
    CHECK_INT(shade_compute(w, &site, &day, &ground, &r, err, sizeof err), 0);
    int wrong = 0, shaded = 0;
    for (size_t i = 0; i < r.cell_count; i++) {
      bool dark = in_hull((const double (*)[2])corners, 8, r.cells[i].p[0], r.cells[i].p[1]);
      shaded += dark;
      wrong += dark != (r.cells[i].open == 0.0);
    }
    CHECK_INT(wrong, 0);
    CHECK(shaded > 1000);
    shade_result_free(&r);
  }
  shade_day whole = {.month = 6, .day = 21, .year = 2025, .from = 0, .to = 1440, .step = 10};
  shade_result r;
  CHECK_INT(shade_compute(w, &site, &whole, NULL, &r, err, sizeof err), 0);
  int inside = 0, dark_inside = 0, bounds_only = 0, lit_bounds_only = 0;
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (int k = 0; k < 4; k++)
    for (int c = 0; c < 2; c++) {
      lo[c] = fmin(lo[c], pts[k][c]);
      hi[c] = fmax(hi[c], pts[k][c]);
    }
  for (size_t i = 0; i < (size_t)r.nx * (size_t)r.ny; i++) {
    double x = r.cells[i].p[0], y = r.cells[i].p[1];
    if (in_rings((const double (*)[2])pts, four, 1, x, y)) {
      inside++;
      dark_inside += r.cells[i].open == 0.0;
    } else if (x > lo[0] && x < hi[0] && y > lo[1] && y < hi[1]) {
      bounds_only++;
      lit_bounds_only += r.cells[i].open > 0.0;
    }
  }
  CHECK_INT(dark_inside, inside);
  CHECK(inside > 700); /* 50 m^2 of 1/16 m^2 cells */
  CHECK(lit_bounds_only > bounds_only / 4);
  for (int e = 0; e < 4; e++) {
    const shade_surface *sf = wall_of(&r, "office", e);
    if (!sf) continue;
    const double *p = pts[e], *q = pts[(e + 1) % 4];
    double len = hypot(q[0] - p[0], q[1] - p[1]);
    double mx = 0.5 * (p[0] + q[0]) - cx, my = 0.5 * (p[1] + q[1]) - cy;
    CHECK_NEAR(hypot(sf->normal[0], sf->normal[1]), 1.0, 1e-12);
    CHECK_NEAR(sf->normal[0] * (q[0] - p[0]) + sf->normal[1] * (q[1] - p[1]), 0.0, 1e-9);
    CHECK(sf->normal[0] * mx + sf->normal[1] * my > 0); /* away from the middle */
    CHECK_NEAR(sf->along[0], (q[0] - p[0]) / len, 1e-12);
    int nu = (int)lround(len / 0.25);
    CHECK_NEAR(sf->width, len / nu, 1e-12);
    CHECK_INT(sf->count, (size_t)nu * 36); /* 9 m of 0.25 m voxels */
    const shade_cell *c0 = &r.cells[sf->first];
    CHECK_NEAR(c0->p[0], p[0] + (q[0] - p[0]) * 0.5 / nu, 1e-9);
    CHECK_NEAR(c0->p[2], 0.125, 1e-12);
    CHECK(sf->mean_open > 0.5); /* at 40 N on 06-21 every wall sees the sun a while */
  }
  shade_result_free(&r);
  sylva_world_destroy(w);
}

/* An L of two 8 m arms, 6 m high, with a 4 m courtyard in its corner: the
 * courtyard's walls face into it; its south-facing wall (e8) gets less sun than the
 * outline's south wall (e0) and the courtyard's north-facing wall less than the
 * L's outer north wall (e4); at noon on 06-21 at 48 N the courtyard's ground is lit
 * beyond the south wall's shadow (6 m cot(elevation)) and dark within it. */
static void test_prism_courtyard(void) {
  static const double pts[10][2] = {{0, 0}, {20, 0}, {20, 8}, {8, 8}, {8, 20}, {0, 20},
                                    {2, 2}, {6, 2}, {6, 6}, {2, 6}};
  static const int sizes[2] = {6, 4};
  sylva_world *w = open_world(-2, 24, 8, 0.25);
  add_prism(w, "block", pts, sizes, 2, 0, 6);
  shade_site site = {.latitude = 48, .north = {0, 1}};
  shade_day day = {.month = 6, .day = 21, .year = 2025, .from = 0, .to = 1440, .step = 10};
  char err[256];
  shade_result r;
  CHECK_INT(shade_compute(w, &site, &day, NULL, &r, err, sizeof err), 0);
  /* the hole's edges, e6 to e9, face into the courtyard */
  static const double into[4][2] = {{0, 1}, {-1, 0}, {0, -1}, {1, 0}};
  for (int e = 6; e < 10; e++) {
    const shade_surface *sf = wall_of(&r, "block", e);
    if (!sf) continue;
    CHECK_NEAR(sf->normal[0], into[e - 6][0], 1e-15);
    CHECK_NEAR(sf->normal[1], into[e - 6][1], 1e-15);
    CHECK_INT(sf->count, 16 * 24);
  }
  const shade_surface *yard_south = wall_of(&r, "block", 8), *outer_south = wall_of(&r, "block", 0),
                      *yard_north = wall_of(&r, "block", 6), *outer_north = wall_of(&r, "block", 4);
  if (yard_south && outer_south && yard_north && outer_north) {
    CHECK_NEAR(outer_south->normal[1], -1.0, 0.0);
    CHECK_NEAR(outer_north->normal[1], 1.0, 0.0);
    CHECK(yard_south->mean_open < outer_south->mean_open - 1.0);
    CHECK(yard_north->mean_open < outer_north->mean_open);
    /* the yard's south-facing wall: its top row sees over the wall opposite at noon,
     * its bottom row is in that wall's shade, and the outer wall's cells all see it */
    CHECK(r.cells[yard_south->first].open < r.cells[yard_south->first + yard_south->count - 1].open);
  }
  shade_result_free(&r);

  day.from = 720;
  day.to = 730;
  shade_filter ground = {.ground = true, .faces = false, .obstacle = -1, .face = -1};
  CHECK_INT(shade_compute(w, &site, &day, &ground, &r, err, sizeof err), 0);
  double d[3];
  double el = sun_sample(48, shade_day_of_year(6, 21), 720, d);
  double reach = 6.0 / tan(el * DEG); /* the south wall's shadow, about 2.73 m */
  CHECK(reach > 2.0 && reach < 3.5);
  int lit = 0, dark = 0, yard = 0;
  for (size_t i = 0; i < r.cell_count; i++) {
    double x = r.cells[i].p[0], y = r.cells[i].p[1];
    if (!(x > 2 && x < 6 && y > 2 && y < 6)) continue;
    yard++;
    if (y - 2 > reach + 0.05) lit += r.cells[i].open > 0.0;
    else if (y - 2 < reach - 0.05) dark += r.cells[i].open == 0.0;
  }
  CHECK_INT(yard, 256);
  CHECK_INT(lit, 16 * 5);  /* rows at 4.875 to 5.875 */
  CHECK_INT(dark, 16 * 11);
  shade_result_free(&r);
  sylva_world_destroy(w);
}

/* Face names: a box's by normal, a prism's by edge. */
static void test_prism_names(void) {
  static const double tri[3][2] = {{0, 0}, {4, 0}, {0, 3}};
  static const int three[1] = {3};
  sylva_world *w = open_world(-6, 6, 4, 0.5);
  add_prism(w, "kiosk", tri, three, 1, 0, 3);
  sylva_obstacle_def shed = {.label = "shed", .min = {-5, -5, 0}, .max = {-4, -4, 2},
                             .kind = SYLVA_OBSTACLE_SOLID};
  int shed_id = sylva_world_add_obstacle(w, &shed);
  CHECK(shed_id >= 0);
  char err[256];
  shade_filter f;
  CHECK_INT(shade_parse_surface(w, "kiosk:e2", &f, err, sizeof err), 0);
  CHECK_INT(f.face, 2);
  CHECK(f.faces && !f.ground);
  CHECK_INT(shade_parse_surface(w, "kiosk:e0", &f, err, sizeof err), 0);
  CHECK_INT(f.face, 0);
  const char *bad[] = {"kiosk:e3", "kiosk:+x", "kiosk:e", "kiosk:e02", "kiosk:e-1", "kiosk:e1x",
                       "kiosk:E1", "shed:e0"};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
    CHECK_INT(shade_parse_surface(w, bad[i], &f, err, sizeof err), SERVER_EINPUT);
  CHECK(strstr(err, "+x") != NULL); /* a box's names, for the box */
  CHECK_INT(shade_parse_surface(w, "kiosk:+y", &f, err, sizeof err), SERVER_EINPUT);
  CHECK(strstr(err, "e0 to e2") != NULL);
  shade_site site = {.latitude = 40, .north = {0, 1}};
  shade_day day = {.month = 3, .day = 21, .year = 2025, .from = 360, .to = 1080, .step = 30};
  CHECK_INT(shade_parse_surface(w, "kiosk:e1", &f, err, sizeof err), 0);
  shade_result r;
  CHECK_INT(shade_compute(w, &site, &day, &f, &r, err, sizeof err), 0);
  CHECK_INT(r.surface_count, 1);
  CHECK(strcmp(r.surfaces[0].name, "kiosk:e1") == 0);
  /* the hypotenuse from (4, 0) to (0, 3): 5 m, 10 cells, facing out (+x, +y) */
  CHECK_INT(r.surfaces[0].count, 10 * 6);
  CHECK_NEAR(r.surfaces[0].normal[0], 0.6, 1e-12);
  CHECK_NEAR(r.surfaces[0].normal[1], 0.8, 1e-12);
  shade_result_free(&r);
  sylva_world_destroy(w);
}

/* Dates, times and the checks of a day. */
static void test_parse(void) {
  char err[256];
  int m, d, t;
  CHECK_INT(shade_parse_date("02-30", &m, &d, err, sizeof err), SERVER_EINPUT);
  CHECK_INT(shade_parse_date("02-29", &m, &d, err, sizeof err), SERVER_EINPUT);
  CHECK_INT(shade_parse_date("12-31", &m, &d, err, sizeof err), 0);
  CHECK_INT(shade_day_of_year(m, d), 365);
  CHECK_INT(shade_parse_time("24:00", &t, err, sizeof err), 0);
  CHECK_INT(t, 1440);
  CHECK_INT(shade_parse_time("24:01", &t, err, sizeof err), SERVER_EINPUT);
  CHECK_INT(shade_parse_time("9:30", &t, err, sizeof err), SERVER_EINPUT);
  shade_site site = {.latitude = 40, .north = {0, 1}};
  shade_day day = shade_default_day();
  CHECK_INT(shade_check(&site, &day, err, sizeof err), 0);
  day.step = 0;
  CHECK_INT(shade_check(&site, &day, err, sizeof err), SERVER_EINPUT);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {CHECK_TEST(parse),         CHECK_TEST(shadow),
                                     CHECK_TEST(faces),         CHECK_TEST(transmission),
                                     CHECK_TEST(prism_box),     CHECK_TEST(prism_turned),
                                     CHECK_TEST(prism_courtyard), CHECK_TEST(prism_names)};
  check_run_tests(argc, argv, 1, tests, sizeof tests / sizeof tests[0]);
  printf("%d passed, %d failed\n", check_passed, check_failed);
  return check_failed ? 1 : 0;
}
