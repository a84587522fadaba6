/* Phase 1: light collected by each node, accumulated basipetally. */
#ifndef SYLVA_LIGHT_H
#define SYLVA_LIGHT_H
#include <math.h>
/** L = alpha * l ^ (age ^ sigma); age_pow = age ^ sigma (0 for a newborn node). */
static inline double sylva__collected(double alpha, double l, double age_pow) {
  if (age_pow == 0.0 || l >= 1.0) return alpha;
  return alpha * pow(l, age_pow);
}
#endif
