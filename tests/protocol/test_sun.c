/* The sun's positions from libnova (proto/src/sun.c) against published values:
 * solar noon elevation is 90 - |latitude - declination|, with the declination
 * +23.44 degrees at the June solstice, -23.44 at the December one and about 0 at
 * the equinoxes (NOAA's solar calculator gives the same to 0.01 degree). */
#include "../check.h"
#include "sylva/sun.h"

enum { MARCH_20 = 79, JUNE_21 = 172, DECEMBER_21 = 355 };

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

int main(int argc, char **argv) {
  static const check_test tests[] = {CHECK_TEST(noon_50n_june), CHECK_TEST(noon_50n_december),
                                     CHECK_TEST(equator_equinox), CHECK_TEST(equator_june),
                                     CHECK_TEST(south), CHECK_TEST(symmetry), CHECK_TEST(polar)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("sun");
}
