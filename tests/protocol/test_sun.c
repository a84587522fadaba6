/* The sun's positions from libnova (proto/src/sun.c) against published values,
 * and the site sky built on them (proto/src/sky.c).
 *
 * The sun:
 * solar noon elevation is 90 - |latitude - declination|, with the declination
 * +23.44 degrees at the June solstice, -23.44 at the December one and about 0 at
 * the equinoxes (NOAA's solar calculator gives the same to 0.01 degree). */
#include "../check.h"
#include "sylva/sky.h"
#include "sylva/sun.h"
#include "sylva/sylva.h"

enum { MARCH_20 = 79, JUNE_21 = 172, DECEMBER_21 = 355 };
#define DEG (3.14159265358979323846 / 180.0)

/* How far azimuth a is from b, degrees (0 to 180, across north too). */
static double azimuth_off(double a, double b) {
  return fabs(fmod(a - b + 540.0, 360.0) - 180.0);
}

/* 50 N, June solstice: 63.4 degrees, due south. */
static void test_noon_50n_june(void) {
  sylva_sun s = sylva_sun_at(50.0, JUNE_21, 0.0);
  CHECK_NEAR(s.elevation, 63.44, 0.05);
  CHECK_NEAR(s.azimuth, 180.0, 0.05);
}

/* 50 N, December solstice: 16.6 degrees. */
static void test_noon_50n_december(void) {
  CHECK_NEAR(sylva_sun_at(50.0, DECEMBER_21, 0.0).elevation, 16.56, 0.05);
}

/* The equator at the March equinox: straight overhead at noon (the equinox of
 * 2025 was at 09:01 UT on March 20: the declination at noon is 0.05 degrees). */
static void test_equator_equinox(void) {
  sylva_sun s = sylva_sun_at(0.0, MARCH_20, 0.0);
  CHECK(s.elevation > 89.8);
  /* six hours before noon it rises in the east */
  sylva_sun rise = sylva_sun_at(0.0, MARCH_20, -6.0);
  CHECK_NEAR(rise.elevation, 0.0, 0.5);
  CHECK_NEAR(rise.azimuth, 90.0, 0.5);
}

/* The equator at the June solstice: the sun stands in the north at noon. */
static void test_equator_june(void) {
  sylva_sun s = sylva_sun_at(0.0, JUNE_21, 0.0);
  CHECK_NEAR(s.elevation, 66.56, 0.05);
  CHECK_NEAR(azimuth_off(s.azimuth, 0.0), 0.0, 0.05);
}

/* The southern hemisphere mirrors the northern one. */
static void test_south(void) {
  CHECK_NEAR(sylva_sun_at(-50.0, DECEMBER_21, 0.0).elevation, 63.44, 0.05);
  CHECK_NEAR(azimuth_off(sylva_sun_at(-50.0, DECEMBER_21, 0.0).azimuth, 0.0), 0.0, 0.05);
}

/* Morning and afternoon mirror each other about the meridian. */
static void test_symmetry(void) {
  for (double h = 1.0; h <= 7.0; h += 2.0) {
    sylva_sun am = sylva_sun_at(48.1, JUNE_21, -h), pm = sylva_sun_at(48.1, JUNE_21, h);
    CHECK_NEAR(am.elevation, pm.elevation, 0.1);
    CHECK_NEAR(am.azimuth + pm.azimuth, 360.0, 0.2);
    CHECK(am.azimuth > 0.0 && am.azimuth < 180.0); /* the morning sun is in the east */
  }
}

/* Polar day and night: the midnight sun at 80 N in June, none in December. */
static void test_polar(void) {
  sylva_sun midnight = sylva_sun_at(80.0, JUNE_21, 12.0);
  CHECK_NEAR(midnight.elevation, 23.44 - 10.0, 0.1);
  CHECK_NEAR(azimuth_off(midnight.azimuth, 0.0), 0.0, 0.5);
  CHECK(sylva_sun_at(80.0, DECEMBER_21, 0.0).elevation < 0.0);
}

/* ---- the sky (sky.c) ---- */

/* The weights' sum, the sun's part (the first samples / 2) and the weighted mean
 * direction of the sun's part. */
typedef struct sky_sums {
  double total, sun, mean[3];
} sky_sums;

static sky_sums sums(const sylva_sky_def *def, const sylva_sky_dir *dirs) {
  sky_sums s = {0};
  int suns = def->diffuse >= 1.0 ? 0 : def->samples / 2;
  for (int i = 0; i < def->samples; i++) {
    s.total += dirs[i].weight;
    if (i < suns) {
      s.sun += dirs[i].weight;
      for (int a = 0; a < 3; a++) s.mean[a] += dirs[i].weight * dirs[i].d[a];
    }
  }
  return s;
}

static const sylva_sky_def munich = {.latitude = 48.1, .north = {0, 1}, .first_day = 91,
                                     .last_day = 273, .diffuse = 0.4, .samples = 64};

/* The sums of munich's sky moved to another latitude and season. */
static sky_sums sums_at(double latitude, int first_day, int last_day) {
  sylva_sky_def def = munich;
  def.latitude = latitude;
  def.first_day = first_day;
  def.last_day = last_day;
  sylva_sky_dir dirs[64];
  sylva_sky_build(&def, dirs);
  return sums(&def, dirs);
}

/* The weights add up to 1, the sky's to `diffuse`; every direction is a unit
 * vector above the horizon. */
static void test_sky_weights(void) {
  sylva_sky_dir dirs[64];
  sylva_sky_build(&munich, dirs);
  sky_sums s = sums(&munich, dirs);
  CHECK_NEAR(s.total, 1.0, 1e-12);
  CHECK_NEAR(s.sun, 0.6, 1e-12);
  for (int i = 0; i < 64; i++) {
    double len = sqrt(dirs[i].d[0] * dirs[i].d[0] + dirs[i].d[1] * dirs[i].d[1] + dirs[i].d[2] * dirs[i].d[2]);
    CHECK_NEAR(len, 1.0, 1e-12);
    CHECK(dirs[i].d[2] >= 0.0);
    CHECK(dirs[i].weight >= 0.0);
  }
  /* every sun slot is used at this latitude in summer */
  for (int i = 0; i < 32; i++) CHECK(dirs[i].weight > 0.0);
}

/* In the northern hemisphere the sun stands in the south: with north along +y its
 * light comes from -y, balanced east and west; north along +x turns it to -x. */
static void test_sky_north(void) {
  sylva_sky_dir dirs[64];
  sylva_sky_build(&munich, dirs);
  sky_sums s = sums(&munich, dirs);
  CHECK(s.mean[1] < -0.2 * s.sun);
  CHECK_NEAR(s.mean[0], 0.0, 0.01 * s.sun);
  sylva_sky_def turned = munich;
  turned.north[0] = 2.0; /* not a unit vector: its direction is what counts */
  turned.north[1] = 0.0;
  sylva_sky_build(&turned, dirs);
  sky_sums t = sums(&turned, dirs);
  CHECK_NEAR(t.mean[0], s.mean[1], 1e-9);
  CHECK_NEAR(t.mean[1], -s.mean[0], 1e-9);
  CHECK_NEAR(t.mean[2], s.mean[2], 1e-9);
  CHECK(sums_at(-48.1, 1, 90).mean[1] > 0.2 * s.sun);
}

/* At the equator over the whole year the sun is as much north as south. */
static void test_sky_equator(void) {
  sky_sums s = sums_at(0.0, 1, 365);
  CHECK_NEAR(s.mean[1], 0.0, 0.03 * s.sun);
  CHECK(s.mean[2] > 0.5 * s.sun);
}

/* The overcast sky: CIE luminance (1 + 2 sin g) / 3 times sin g on equal solid
 * angles; all sky with diffuse 1; none of it with 0. */
static void test_sky_overcast(void) {
  sylva_sky_def overcast = munich;
  overcast.diffuse = 1.0;
  overcast.samples = 100;
  sylva_sky_dir dirs[100];
  sylva_sky_build(&overcast, dirs);
  CHECK_NEAR(sums(&overcast, dirs).total, 1.0, 1e-12);
  for (int i = 1; i < 100; i++) {
    double zi = dirs[i].d[2], z0 = dirs[0].d[2];
    CHECK_NEAR(dirs[i].weight / dirs[0].weight, (1 + 2 * zi) * zi / ((1 + 2 * z0) * z0), 1e-9);
  }
  sylva_sky_def clear = munich;
  clear.diffuse = 0.0;
  sylva_sky_dir more[64];
  sylva_sky_build(&clear, more);
  for (int i = 32; i < 64; i++) CHECK(more[i].weight == 0.0);
  CHECK_NEAR(sums(&clear, more).sun, 1.0, 1e-12);
}

/* A polar night: the sun's directions get no weight; the light is the sky's. */
static void test_sky_polar_night(void) {
  sky_sums s = sums_at(80.0, 340, 365);
  CHECK(s.sun == 0.0);
  CHECK_NEAR(s.total, 0.4, 1e-12);
}

/* The same definition gives the same bytes; the largest count is built. */
static void test_sky_deterministic(void) {
  static sylva_sky_dir a[4096], b[4096];
  sylva_sky_def big = munich;
  big.samples = 4096;
  sylva_sky_build(&big, a);
  sylva_sky_build(&big, b);
  CHECK(memcmp(a, b, sizeof a) == 0);
  CHECK_NEAR(sums(&big, a).total, 1.0, 1e-9);
  sylva_sky_def odd = munich;
  odd.samples = 7; /* 3 sun directions, 4 of the sky */
  sylva_sky_dir c[7];
  sylva_sky_build(&odd, c);
  CHECK_NEAR(sums(&odd, c).sun, 0.6, 1e-12);
}

/* A day's positions (interpolated between two of libnova's) stay within 0.01
 * degree of libnova's own at every hour, over the year and the latitudes. */
static void test_day_matches(void) {
  double hours[25];
  for (int k = 0; k < 25; k++) hours[k] = -12.0 + k;
  double worst = 0.0;
  for (int day = 1; day <= 365; day += 13)
    for (double lat = -80.0; lat <= 80.0; lat += 32.0) {
      sylva_sun path[25];
      sylva_sun_day(lat, day, hours, 25, path);
      for (int k = 0; k < 25; k++) {
        sylva_sun one = sylva_sun_at(lat, day, hours[k]);
        double de = fabs(path[k].elevation - one.elevation);
        /* azimuth matters as far as the sun stands off the zenith */
        double da = azimuth_off(path[k].azimuth, one.azimuth) * cos(one.elevation * DEG);
        worst = fmax(worst, fmax(de, da));
      }
    }
  CHECK(worst < 0.01);
  printf("  a day's positions within %.5f degree of libnova's own\n", worst);
}

/* ---- site factors of a real sky (core/src/site.c with proto/src/sky.c) ---- */

/* A 40 x 40 x 12 m world at 10 cm lit by def's sky (256 directions), with one
 * solid box; the factor of a voxel is its light, nothing being planted. */
static sylva_world *site_world(const sylva_sky_def *def, const sylva_obstacle_def *box) {
  static sylva_sky_dir dirs[SYLVA_MAX_SKY];
  sylva_sky_build(def, dirs);
  sylva_world_def wd = sylva_default_world_def();
  wd.min[0] = wd.min[1] = -20, wd.max[0] = wd.max[1] = 20, wd.max[2] = 12;
  wd.voxel = 0.1;
  wd.sky = dirs;
  wd.sky_count = def->samples;
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&wd, &w), 0);
  if (w && box) CHECK(sylva_world_add_obstacle(w, box) >= 0);
  return w;
}

static double factor(const sylva_world *w, double x, double y, double z) {
  double p[3] = {x, y, z};
  return w ? sylva_world_light_at(w, p) : -1;
}

/* Open ground takes the whole sky; under a wide board at 1 m only the low sky
 * past its edges arrives: above 0, below the diffuse share, below the open
 * value. */
static void test_site_open_and_board(void) {
  sylva_sky_def def = munich;
  def.latitude = 50, def.samples = 256;
  sylva_obstacle_def board = {"board", {-6, -6, 1.0}, {6, 6, 1.1}, SYLVA_OBSTACLE_SOLID, {0}};
  sylva_world *w = site_world(&def, &board);
  double open = factor(w, 15.05, 15.05, 0.55), under = factor(w, 0.05, 0.05, 0.55);
  CHECK_NEAR(open, 1.0, 1e-9);
  CHECK(under > 0.0);
  CHECK(under < def.diffuse);
  CHECK(under < open);
  printf("  site factor at 50 N: open %.4f, under a 12 m board at 1 m %.4f (diffuse %.2f)\n", open,
         under, def.diffuse);
  sylva_world_destroy(w);
}

/* 50 N: 1 m north of a 6 m east-west wall (north is +y) gets less than 1 m south
 * of it; at the equator over the whole year the two sides are within 10%. */
static void test_site_wall_sides(void) {
  sylva_obstacle_def wall = {"wall", {-10, -0.1, 0}, {10, 0.1, 6}, SYLVA_OBSTACLE_SOLID, {0}};
  sylva_sky_def def = munich;
  def.latitude = 50, def.samples = 256;
  sylva_world *w = site_world(&def, &wall);
  double north = factor(w, 0.05, 1.15, 0.55), south = factor(w, 0.05, -1.15, 0.55);
  CHECK(north < south);
  CHECK(north > 0.0 && south < 1.0);
  printf("  site factor 1 m from a 6 m east-west wall at 50 N: north %.4f, south %.4f\n", north,
         south);
  sylva_world_destroy(w);
  def.latitude = 0, def.first_day = 1, def.last_day = 365;
  w = site_world(&def, &wall);
  north = factor(w, 0.05, 1.15, 0.55), south = factor(w, 0.05, -1.15, 0.55);
  CHECK(fabs(north - south) <= 0.1 * fmax(north, south));
  printf("  the same at the equator over the year: north %.4f, south %.4f\n", north, south);
  sylva_world_destroy(w);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {CHECK_TEST(noon_50n_june), CHECK_TEST(noon_50n_december),
                                     CHECK_TEST(equator_equinox), CHECK_TEST(equator_june),
                                     CHECK_TEST(south), CHECK_TEST(symmetry), CHECK_TEST(polar),
                                     CHECK_TEST(sky_weights), CHECK_TEST(sky_north),
                                     CHECK_TEST(sky_equator), CHECK_TEST(sky_overcast),
                                     CHECK_TEST(sky_polar_night), CHECK_TEST(sky_deterministic),
                                     CHECK_TEST(site_open_and_board), CHECK_TEST(site_wall_sides),
                                     CHECK_TEST(day_matches)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("sun");
}
