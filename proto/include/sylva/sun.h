/* sylva: where the sun stands, for a site's light (docs/model.md will describe the
 * site sky built on it). The positions come from libnova (VSOP87, Meeus), for the
 * days of a fixed common year (2025) so that a scenario's light does not depend on
 * when it runs, at the longitude of the site's own solar time: hour 0 is the sun's
 * transit (local apparent noon). */
#ifndef SYLVA_SUN_H
#define SYLVA_SUN_H

/** The sun seen from a site. */
typedef struct sylva_sun {
  double elevation; /**< degrees above the horizon (negative below it) */
  double azimuth;   /**< degrees clockwise from north: 90 east, 180 south */
} sylva_sun;

/** The sun at latitude (degrees, north positive, -90 to 90) on day `day` of the
 *  year (1 to 365), `hours` hours after its transit (negative: before). */
sylva_sun sylva_sun_at(double latitude, int day, double hours);

/** The same for count hours of one day (out[i] at hours[i]): the transit is found
 *  once, and the sun's equatorial position is libnova's half a day either side of
 *  it, interpolated (within 0.01 degree of sylva_sun_at). */
void sylva_sun_day(double latitude, int day, const double *hours, int count, sylva_sun *out);

#endif
