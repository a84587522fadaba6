#include "sylva/sky.h"

#include <math.h>
#include <string.h>

#include "sylva/sun.h"

#define DEG (3.14159265358979323846 / 180.0)
/* The sun's path is followed on at most this many days of the season, every
 * quarter of an hour. */
#define SKY_DAYS 32
#define SKY_STEPS 96

/* The unit vector towards elevation el and azimuth az (degrees clockwise from
 * north) in the scenario's axes: north n (unit), east (n.y, -n.x), z up. */
static void direction(const double n[2], double el, double az, double d[3]) {
  double h = cos(el * DEG), c = cos(az * DEG), s = sin(az * DEG);
  d[0] = h * (c * n[0] + s * n[1]);
  d[1] = h * (c * n[1] - s * n[0]);
  d[2] = sin(el * DEG);
}

/* The largest divisor of n not above target (at least 1). */
static int divisor_below(int n, int target) {
  for (int k = target < n ? target : n; k > 1; k--)
    if (n % k == 0) return k;
  return 1;
}

/* The sun's part: a grid of day slots by hour slots over the season, each slot the
 * weighted mean direction of the positions in it, with their summed weight. */
static void sun_part(const sylva_sky_def *def, const double n[2], int count, sylva_sky_dir *out) {
  int target = (int)lround(sqrt(count / 8.0));
  int slots_d = divisor_below(count, target < 1 ? 1 : target), slots_h = count / slots_d;
  for (int i = 0; i < count; i++) out[i] = (sylva_sky_dir){.d = {0.0, 0.0, 0.0}, .weight = 0.0};
  int span = def->last_day - def->first_day;
  int days = span + 1 < SKY_DAYS ? span + 1 : SKY_DAYS;
  double hours[SKY_STEPS];
  for (int k = 0; k < SKY_STEPS; k++) hours[k] = -12.0 + 24.0 * (k + 0.5) / SKY_STEPS;
  double total = 0.0;
  for (int k = 0; k < days; k++) {
    int day = def->first_day + (days > 1 ? (int)lround((double)k * span / (days - 1)) : 0);
    sylva_sun path[SKY_STEPS];
    sylva_sun_day(def->latitude, day, hours, SKY_STEPS, path);
    int slot_d = k * slots_d / days;
    /* the day's hours of sunshine share the hour slots */
    int first = 0, last = SKY_STEPS - 1;
    while (first < SKY_STEPS && path[first].elevation <= 0.0) first++;
    while (last >= first && path[last].elevation <= 0.0) last--;
    for (int j = first; j <= last; j++) {
      if (path[j].elevation <= 0.0) continue;
      double w = sin(path[j].elevation * DEG), d[3];
      direction(n, path[j].elevation, path[j].azimuth, d);
      sylva_sky_dir *cell = &out[slot_d * slots_h + (j - first) * slots_h / (last - first + 1)];
      for (int a = 0; a < 3; a++) cell->d[a] += w * d[a];
      cell->weight += w;
      total += w;
    }
  }
  for (int i = 0; i < count; i++) {
    sylva_sky_dir *cell = &out[i];
    double len = sqrt(cell->d[0] * cell->d[0] + cell->d[1] * cell->d[1] + cell->d[2] * cell->d[2]);
    if (cell->weight > 0.0 && len > 0.0) {
      for (int a = 0; a < 3; a++) cell->d[a] /= len;
      cell->weight *= (1.0 - def->diffuse) / total;
    } else {
      cell->d[2] = 1.0; /* the sun never stands there: no light */
      cell->weight = 0.0;
    }
  }
}

/* The overcast sky's part: directions of equal solid angle over the hemisphere (a
 * golden-angle spiral, heights evenly spaced), each weighted by the CIE overcast
 * luminance (1 + 2 sin g) / 3 times sin g. */
static void sky_part(double diffuse, int count, sylva_sky_dir *out) {
  const double golden = 3.14159265358979323846 * (3.0 - sqrt(5.0));
  double total = 0.0;
  for (int i = 0; i < count; i++) {
    double z = 1.0 - (i + 0.5) / count, r = sqrt(1.0 - z * z), phi = golden * i;
    out[i] = (sylva_sky_dir){.d = {r * cos(phi), r * sin(phi), z},
                             .weight = (1.0 + 2.0 * z) / 3.0 * z};
    total += out[i].weight;
  }
  for (int i = 0; i < count; i++) out[i].weight *= diffuse / total;
}

void sylva_sky_build(const sylva_sky_def *def, sylva_sky_dir *out) {
  double len = hypot(def->north[0], def->north[1]);
  double n[2] = {def->north[0] / len, def->north[1] / len};
  int suns = def->diffuse >= 1.0 ? 0 : def->samples / 2;
  if (suns > 0) sun_part(def, n, suns, out);
  sky_part(def->diffuse, def->samples - suns, out + suns);
}
