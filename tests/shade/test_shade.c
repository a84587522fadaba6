/* The shade library (server/shade) against computations of its own: the shadow of a
 * box from libnova's sun, called here directly, as a polygon on the ground; faces
 * turned from the sun; the sun through a uniform layer of leaves against
 * exp(-k LAI / sin(elevation)). */
#include <libnova/julian_day.h>
#include <libnova/rise_set.h>
#include <libnova/solar.h>
#include <libnova/transform.h>

#include "../check.h"
#include "shade.h"
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
  static const check_test tests[] = {CHECK_TEST(parse), CHECK_TEST(shadow), CHECK_TEST(faces),
                                     CHECK_TEST(transmission)};
  check_run_tests(argc, argv, 1, tests, sizeof tests / sizeof tests[0]);
  printf("%d passed, %d failed\n", check_passed, check_failed);
  return check_failed ? 1 : 0;
}
