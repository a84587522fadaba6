/* sylva: the sky of a site as a set of weighted directions, for the site light of
 * a scenario (the `light` key with "sky": "site"). The direct part follows the
 * sun's path (sun.h) over the growing season, each position weighted by the sine
 * of its elevation (the sunlight a level surface gets); the diffuse part is the
 * CIE standard overcast sky, whose luminance at elevation g is (1 + 2 sin g) / 3 of
 * the zenith's, weighted the same way. The weights of the directions add up to 1:
 * `diffuse` for the sky's, 1 - diffuse for the sun's. */
#ifndef SYLVA_SKY_H
#define SYLVA_SKY_H

#include "sylva/sylva.h" /* sylva_sky_dir */

/** What a site sky is made from. */
typedef struct sylva_sky_def {
  double latitude;   /**< degrees, north positive, -90 to 90 */
  double north[2];   /**< the direction of north in the x-y plane (not zero) */
  int first_day;     /**< the growing season: days of the year, 1 to 365, */
  int last_day;      /**< first_day <= last_day */
  double diffuse;    /**< the overcast sky's share of the light, 0 to 1 */
  int samples;       /**< directions in all, 2 to 4096 */
} sylva_sky_def;

/** Fills out[0 .. def->samples) (the caller's array): the sun's directions first
 *  (half of them, rounded down, and none when diffuse is 1), then the sky's.
 *  Directions of zero weight (a season whose sun never rises) are kept with
 *  weight 0. The same definition gives the same bytes. */
void sylva_sky_build(const sylva_sky_def *def, sylva_sky_dir *out);

#endif
