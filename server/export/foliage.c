/* Leaf placement (foliage.h). */
#include "foliage.h"

#include <math.h>

#include "vec3.h"

#define GOLDEN_ANGLE (137.5 * 3.14159265358979323846 / 180.0)
#define SQRT1_2 0.70710678118654752440

void foliage_place(const double p[3], const double q[3], int k, int n, double size,
                   foliage_leaf *out) {
  double base[3], axis[3];
  if (p) {
    for (int a = 0; a < 3; a++) {
      base[a] = p[a];
      axis[a] = q[a] - p[a];
    }
  } else { /* a root: a vertical internode of one leaf's length ending at q */
    base[0] = q[0];
    base[1] = q[1];
    base[2] = q[2] - size;
    axis[0] = axis[1] = 0.0;
    axis[2] = size;
  }
  double length = sqrt(dot3(axis, axis));
  double d[3] = {0.0, 0.0, 1.0};
  if (length > 0.0)
    for (int a = 0; a < 3; a++) d[a] = axis[a] / length;
  /* a frame fixed by the internode alone: e1 the horizontal perpendicular (x for a
   * vertical internode), e2 = d x e1 */
  double up[3] = {0.0, 0.0, 1.0}, e1[3], e2[3];
  cross3(up, d, e1);
  if (dot3(e1, e1) < 1e-12) {
    e1[0] = 1.0;
    e1[1] = e1[2] = 0.0;
  }
  (void)normalize3(e1);
  cross3(d, e1, e2);
  (void)normalize3(e2);
  double phi = GOLDEN_ANGLE * (double)k;
  double c = cos(phi), s = sin(phi);
  double t = ((double)k + 0.5) / (double)(n > 0 ? n : 1);
  double outward[3], along[3], across[3];
  for (int a = 0; a < 3; a++) outward[a] = c * e1[a] + s * e2[a];
  for (int a = 0; a < 3; a++) along[a] = (outward[a] + d[a]) * SQRT1_2;
  cross3(d, outward, across); /* around the internode: the blade's width */
  (void)normalize3(along);
  (void)normalize3(across);
  for (int a = 0; a < 3; a++) {
    out->centre[a] = base[a] + t * axis[a] + 0.5 * size * along[a];
    out->along[a] = along[a];
    out->across[a] = across[a];
  }
  out->edge = size;
}

void foliage_rgb(int colour, double rgb[3]) {
  rgb[0] = (double)((colour >> 16) & 0xff) / 255.0;
  rgb[1] = (double)((colour >> 8) & 0xff) / 255.0;
  rgb[2] = (double)(colour & 0xff) / 255.0;
}
