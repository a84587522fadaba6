/* The site factor (core/src/site.c) against hand-worked cases and a brute force:
 * open ground gets every direction; a voxel under a wide board keeps the low
 * directions that pass under its edge; beside an east-west wall the sun from the
 * south reaches the south side and not the north one; and on random boxes and rays
 * the walk over the chunk columns finds exactly the boxes a test of every obstacle
 * finds. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../check.h"
#include "grid.h"
#include "rng.h"
#include "site.h"
#include "sylva/sylva.h"

#define DEG (3.14159265358979323846 / 180.0)

/* The direction at elevation el (degrees) towards azimuth az, measured from +y
 * (north here) clockwise, so +x is east. */
static sylva_sky_dir toward(double el, double az, double weight) {
  return (sylva_sky_dir){.d = {cos(el * DEG) * sin(az * DEG), cos(el * DEG) * cos(az * DEG),
                               sin(el * DEG)},
                         .weight = weight};
}

/* The voxel holding point p (metres). */
static void voxel_of(const sylva__grid *g, const double p[3], int v[3]) {
  for (int a = 0; a < 3; a++) v[a] = (int)floor((p[a] - g->min[a]) / g->voxel);
}

static double factor_at(const sylva__grid *g, const sylva_sky_dir *dirs, int n, double x, double y,
                        double z) {
  double p[3] = {x, y, z};
  int v[3];
  voxel_of(g, p, v);
  return sylva__site_factor(g, dirs, n, sylva__site_top(g), v);
}

static void test_open_ground(void) {
  sylva__grid g;
  double mn[3] = {-5, -5, 0}, mx[3] = {5, 5, 8};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.1), 0);
  sylva_sky_dir dirs[] = {toward(90, 0, 0.25), toward(30, 180, 0.25), toward(5, 90, 0.25),
                          toward(60, 300, 0.25)};
  CHECK_NEAR(factor_at(&g, dirs, 4, 0.05, 0.05, 0.05), 1.0, 1e-12);
  /* an obstacle elsewhere changes nothing here */
  double bmn[3] = {3, 3, 0}, bmx[3] = {4, 4, 1};
  CHECK(sylva__grid_add_obstacle(&g, "box", bmn, bmx) >= 0);
  CHECK_NEAR(factor_at(&g, dirs, 4, 0.05, 0.05, 0.05), 1.0, 1e-12);
  sylva__grid_free(&g);
}

/* A board 4 x 4 m at 1 m over a voxel at 0.5 m: the zenith and 40 degrees are
 * blocked; 5 degrees rises 0.17 m over the 2 m to the board's edge and passes. */
static void test_board(void) {
  sylva__grid g;
  double mn[3] = {-10, -10, 0}, mx[3] = {10, 10, 6};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.1), 0);
  double bmn[3] = {-2, -2, 1.0}, bmx[3] = {2, 2, 1.2};
  CHECK(sylva__grid_add_obstacle(&g, "board", bmn, bmx) >= 0);
  sylva_sky_dir dirs[] = {toward(90, 0, 0.4), toward(40, 135, 0.3), toward(5, 90, 0.2),
                          toward(5, 225, 0.1)};
  CHECK_NEAR(factor_at(&g, dirs, 4, 0.05, 0.05, 0.55), 0.3, 1e-12);
  /* on the board everything is open; inside it nothing */
  CHECK_NEAR(factor_at(&g, dirs, 4, 0.05, 0.05, 1.25), 1.0, 1e-12);
  CHECK_NEAR(factor_at(&g, dirs, 4, 0.05, 0.05, 1.05), 0.0, 1e-12);
  sylva__grid_free(&g);
}

/* An east-west wall 6 m high: the sun from the south at 40 degrees rises 0.84 m on
 * the metre to the wall from the north side, so the north side is in its shadow. */
static void test_wall(void) {
  sylva__grid g;
  double mn[3] = {-10, -10, 0}, mx[3] = {10, 10, 8};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.1), 0);
  double wmn[3] = {-8, 0, 0}, wmx[3] = {8, 0.2, 6};
  CHECK(sylva__grid_add_obstacle(&g, "wall", wmn, wmx) >= 0);
  sylva_sky_dir sun[] = {toward(40, 180, 1.0)};
  CHECK_NEAR(factor_at(&g, sun, 1, 0.05, 1.25, 0.55), 0.0, 1e-12);
  CHECK_NEAR(factor_at(&g, sun, 1, 0.05, -1.05, 0.55), 1.0, 1e-12);
  /* high enough, the north side sees over it: 7 m up, 1 m away */
  CHECK_NEAR(factor_at(&g, sun, 1, 0.05, 1.25, 7.05), 1.0, 1e-12);
  /* beyond the wall's end, nothing is in the way */
  CHECK_NEAR(factor_at(&g, sun, 1, 9.05, 1.25, 0.55), 1.0, 1e-12);
  sylva__grid_free(&g);
}

/* The definition: every live obstacle tested. */
static bool brute_blocked(const sylva__grid *g, const double p[3], const double d[3]) {
  for (int s = 0; s < g->obstacle_slots; s++) {
    const sylva__obstacle *o = &g->obstacles[s];
    if (!o->live) continue;
    double near = 0.0, far = INFINITY;
    bool miss = false;
    for (int a = 0; a < 3 && !miss; a++) {
      if (d[a] == 0.0) {
        miss = p[a] < o->lo[a] || p[a] >= o->hi[a];
        continue;
      }
      double t0 = (o->lo[a] - p[a]) / d[a], t1 = (o->hi[a] - p[a]) / d[a];
      near = fmax(near, fmin(t0, t1));
      far = fmin(far, fmax(t0, t1));
      miss = near >= far;
    }
    if (!miss && far > 0.0) return true;
  }
  return false;
}

static void test_against_brute_force(void) {
  sylva__grid g;
  double mn[3] = {-4, -4, 0}, mx[3] = {4.3, 4, 4};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.1), 0);
  sylva__rng r;
  sylva__rng_seed(&r, 11);
  for (int i = 0; i < 60; i++) {
    double bmn[3], bmx[3];
    for (int a = 0; a < 3; a++) {
      double lo = mn[a] + sylva__rng_unit(&r) * (mx[a] - mn[a]);
      bmn[a] = lo;
      bmx[a] = lo + 0.1 + sylva__rng_unit(&r) * (a == 2 ? 1.0 : 2.5);
    }
    char label[16];
    snprintf(label, sizeof label, "b%d", i);
    CHECK(sylva__grid_add_obstacle(&g, label, bmn, bmx) >= 0);
  }
  CHECK_INT(sylva__grid_remove_obstacle(&g, 7), SYLVA_OK); /* a dead slot is not an obstacle */
  double top = sylva__site_top(&g);
  int blocked = 0, agree = 0, n = 20000;
  for (int i = 0; i < n; i++) {
    double p[3], d[3];
    for (int a = 0; a < 3; a++) p[a] = sylva__rng_unit(&r) * g.n[a];
    double el = sylva__rng_unit(&r) * 90.0, az = sylva__rng_unit(&r) * 360.0;
    if (i % 50 == 0) el = 90.0;        /* straight up */
    if (i % 50 == 1) az = 90.0 * (i % 4); /* along an axis */
    d[0] = cos(el * DEG) * sin(az * DEG);
    d[1] = cos(el * DEG) * cos(az * DEG);
    d[2] = sin(el * DEG);
    if (el == 90.0) d[0] = d[1] = 0.0;
    bool fast = sylva__site_blocked(&g, p, d, top), slow = brute_blocked(&g, p, d);
    agree += fast == slow;
    blocked += slow;
  }
  CHECK_INT(agree, n);
  CHECK(blocked > n / 10 && blocked < n - n / 10); /* both answers were put to the test */
  sylva__grid_free(&g);
}

/* ---- a world with a sky ---- */

/* A world of one tree, with the given sky (NULL: zenith) and optionally a board
 * over it at 3 m. */
static sylva_world *tree_world(const sylva_sky_dir *sky, int sky_count, bool board) {
  sylva_world_def wd = sylva_default_world_def();
  wd.sky = sky;
  wd.sky_count = sky_count;
  sylva_world *w = NULL;
  if (sylva_world_create(&wd, &w)) return NULL;
  sylva_species_def sp = sylva_default_species_def();
  int s = sylva_world_add_species(w, &sp, "oak");
  double roots[1][3] = {{0, 0, 0}};
  sylva_plant_def pd = {s, "tree", (const double(*)[3])roots, 1, 0, NULL, 0};
  sylva_obstacle_def roof = {"board", {-1, -1, 3.0}, {1, 1, 3.2}, SYLVA_OBSTACLE_SOLID, {0}};
  if (s < 0 || sylva_world_add_plant(w, &pd, NULL) < 0 ||
      (board && sylva_world_add_obstacle(w, &roof) < 0)) {
    sylva_world_destroy(w);
    return NULL;
  }
  return w;
}

/* With every direction reaching it (weights adding up to exactly 1, no obstacle)
 * a site's tree grows as the zenith model's does, to the bit. */
static void test_open_sky_is_zenith(void) {
  sylva_sky_dir sky[] = {toward(90, 0, 0.5), toward(30, 200, 0.25), toward(10, 45, 0.25)};
  sylva_world *a = tree_world(NULL, 0, false), *b = tree_world(sky, 3, false);
  CHECK(a && b);
  if (!a || !b) return;
  for (int i = 0; i < 12; i++) {
    CHECK_INT(sylva_world_step(a, NULL), 0);
    CHECK_INT(sylva_world_step(b, NULL), 0);
  }
  CHECK(sylva_world_hash(a) == sylva_world_hash(b));
  sylva_world_destroy(a);
  sylva_world_destroy(b);
}

/* Under a board the zenith model has no light; a site's sky still sends the low
 * directions under its edge; adding and removing obstacles updates the factors. */
static void test_board_light(void) {
  sylva_sky_dir sky[] = {toward(90, 0, 0.6), toward(8, 90, 0.4)};
  sylva_world *z = tree_world(NULL, 0, true), *s = tree_world(sky, 2, true);
  CHECK(z && s);
  if (!z || !s) return;
  double under[3] = {0.02, 0.02, 2.0};
  CHECK_NEAR(sylva_world_light_at(z, under), 0.0, 0.0);
  CHECK_NEAR(sylva_world_light_at(s, under), 0.4, 1e-6);
  /* a wall to the east takes the low direction too */
  sylva_obstacle_def wall = {"wall", {2, -3, 0}, {2.2, 3, 4}, SYLVA_OBSTACLE_SOLID, {0}};
  int id = sylva_world_add_obstacle(s, &wall);
  CHECK(id >= 0);
  CHECK_NEAR(sylva_world_light_at(s, under), 0.0, 1e-6);
  CHECK_INT(sylva_world_remove_obstacle(s, id), SYLVA_OK);
  CHECK_NEAR(sylva_world_light_at(s, under), 0.4, 1e-6);
  /* a clearance zone where the wall stood hides no sky */
  sylva_obstacle_def zone = {"lane", {2, -3, 0}, {2.2, 3, 4}, SYLVA_OBSTACLE_ZONE, {0}};
  CHECK(sylva_world_add_obstacle(s, &zone) >= 0);
  CHECK_NEAR(sylva_world_light_at(s, under), 0.4, 1e-6);
  sylva_world_destroy(z);
  sylva_world_destroy(s);
}

/* A snapshot keeps the sky: saved, loaded and saved again, the same bytes, and the
 * same light; a world without a sky keeps the flags word 0 (the old bytes). */
static void test_snapshot(void) {
  sylva_sky_dir sky[] = {toward(90, 0, 0.6), toward(8, 90, 0.4)};
  sylva_world *s = tree_world(sky, 2, true), *z = tree_world(NULL, 0, true);
  CHECK(s && z);
  if (!s || !z) return;
  CHECK_INT(sylva_world_step(s, NULL), 0);
  uint8_t *a = NULL, *b = NULL, *c = NULL;
  size_t na = 0, nb = 0, nc = 0;
  CHECK_INT(sylva_snapshot_save(s, &a, &na), 0);
  sylva_world *back = NULL;
  CHECK_INT(sylva_snapshot_load(a, na, &back), 0);
  if (back) {
    CHECK_INT(sylva_snapshot_save(back, &b, &nb), 0);
    CHECK(na == nb && memcmp(a, b, na) == 0);
    double under[3] = {0.02, 0.02, 2.0};
    CHECK_NEAR(sylva_world_light_at(back, under), sylva_world_light_at(s, under), 0.0);
    CHECK_INT(sylva_world_step(back, NULL), 0);
    CHECK_INT(sylva_world_step(s, NULL), 0);
    CHECK(sylva_world_hash(back) == sylva_world_hash(s));
  }
  CHECK(a && a[12] == 1 && a[13] == 0);
  CHECK_INT(sylva_snapshot_save(z, &c, &nc), 0);
  CHECK(c && c[12] == 0 && c[13] == 0 && c[14] == 0 && c[15] == 0);
  free(a);
  free(b);
  free(c);
  sylva_world_destroy(back);
  sylva_world_destroy(s);
  sylva_world_destroy(z);
}

/* A sky must be unit vectors pointing up with weights >= 0, 1 to 4096 of them. */
static void test_bad_sky(void) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w = NULL;
  sylva_sky_dir down[] = {toward(-10, 0, 1.0)}, longer[] = {{{0, 0, 2}, 1.0}},
                negative[] = {toward(45, 0, -0.1)};
  const sylva_sky_dir *bad[] = {down, longer, negative};
  for (int i = 0; i < 3; i++) {
    wd.sky = bad[i];
    wd.sky_count = 1;
    CHECK_INT(sylva_world_create(&wd, &w), SYLVA_EINVAL);
  }
  wd.sky = NULL;
  CHECK_INT(sylva_world_create(&wd, &w), SYLVA_EINVAL);
  wd.sky = down;
  wd.sky_count = SYLVA_MAX_SKY + 1;
  CHECK_INT(sylva_world_create(&wd, &w), SYLVA_EINVAL);
  CHECK(w == NULL);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {
      CHECK_TEST(open_ground),         CHECK_TEST(board),      CHECK_TEST(wall),
      CHECK_TEST(against_brute_force), CHECK_TEST(open_sky_is_zenith), CHECK_TEST(board_light),
      CHECK_TEST(snapshot),            CHECK_TEST(bad_sky)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("site");
}
