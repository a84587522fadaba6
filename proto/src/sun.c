#include "sylva/sun.h"

#include <libnova/julian_day.h>
#include <libnova/sidereal_time.h>
#include <libnova/solar.h>
#include <libnova/transform.h>
#include <math.h>

/* The sun's hour angle at JD seen from longitude 0, degrees in (-180, 180]. */
static double hour_angle(double jd, const struct ln_equ_posn *sun) {
  double h = fmod(ln_get_apparent_sidereal_time(jd) * 15.0 - sun->ra, 360.0);
  if (h > 180.0) h -= 360.0;
  if (h <= -180.0) h += 360.0;
  return h;
}

/* The Julian day of the sun's transit (at longitude 0) on day `day` of 2025: where
 * its hour angle is 0. It moves about 360 degrees of hour angle a day; three
 * steps bring it within a fraction of a second. */
static double transit(int day) {
  struct ln_date date = {.years = 2025, .months = 1, .days = 1, .hours = 12};
  double jd = ln_get_julian_day(&date) + (double)(day - 1);
  struct ln_equ_posn sun;
  for (int k = 0; k < 3; k++) {
    ln_get_solar_equ_coords(jd, &sun);
    jd -= hour_angle(jd, &sun) / 360.0;
  }
  return jd;
}

static sylva_sun sun_at_jd(double latitude, double jd) {
  struct ln_equ_posn sun;
  ln_get_solar_equ_coords(jd, &sun);
  struct ln_lnlat_posn site = {.lng = 0.0, .lat = latitude};
  struct ln_hrz_posn at;
  ln_get_hrz_from_equ(&sun, &site, jd, &at);
  /* libnova counts azimuth from the south, westwards */
  return (sylva_sun){.elevation = at.alt, .azimuth = fmod(at.az + 180.0, 360.0)};
}

sylva_sun sylva_sun_at(double latitude, int day, double hours) {
  return sun_at_jd(latitude, transit(day) + hours / 24.0);
}

void sylva_sun_day(double latitude, int day, const double *hours, int count, sylva_sun *out) {
  double noon = transit(day);
  /* The sun's right ascension and declination half a day either side of the
   * transit, and between them a straight line: they move about 1 and at most 0.4
   * degrees a day, so the line strays from libnova's curve by thousandths of a
   * degree, for two of its series instead of one per hour. */
  struct ln_equ_posn a, b;
  ln_get_solar_equ_coords(noon - 0.5, &a);
  ln_get_solar_equ_coords(noon + 0.5, &b);
  double dra = b.ra - a.ra;
  if (dra < -180.0) dra += 360.0; /* across 0 h of right ascension */
  struct ln_lnlat_posn site = {.lng = 0.0, .lat = latitude};
  for (int i = 0; i < count; i++) {
    double f = 0.5 + hours[i] / 24.0;
    struct ln_equ_posn sun = {.ra = fmod(a.ra + f * dra + 360.0, 360.0),
                              .dec = a.dec + f * (b.dec - a.dec)};
    struct ln_hrz_posn at;
    ln_get_hrz_from_equ(&sun, &site, noon + hours[i] / 24.0, &at);
    out[i] = (sylva_sun){.elevation = at.alt, .azimuth = fmod(at.az + 180.0, 360.0)};
  }
}
