/* sylva server: small vector helpers on double[3], for the export's geometry (mesh,
 * foliage). */
#ifndef SYLVA_SERVER_VEC3_H
#define SYLVA_SERVER_VEC3_H

#include <math.h>
#include <stdbool.h>

static inline double dot3(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void cross3(const double a[3], const double b[3], double out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

/* Scales v to unit length; false (v unchanged) when it is too short to have a direction. */
static inline bool normalize3(double v[3]) {
  double len = sqrt(dot3(v, v));
  if (!(len > 1e-12)) return false;
  for (int a = 0; a < 3; a++) v[a] /= len;
  return true;
}

#endif
