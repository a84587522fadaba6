/* Prisms (docs/model.md, "Obstacles"): a footprint's rings as the grid keeps them,
 * whether a point lies inside (even-odd) and how far it is, and the voxel columns
 * whose centres lie inside, as the fewest rows of rectangles that merging equal runs
 * of consecutive rows gives. A footprint equal to a voxel-aligned box gives that
 * box's one rectangle. */
#ifndef SYLVA_PRISM_H
#define SYLVA_PRISM_H

#include <stdbool.h>
#include <stdint.h>

#include "sylva/world.h"

typedef struct sylva__footprint {
  int ring_count, point_count;
  int *ring_size;  /* ring_count */
  double (*pt)[2]; /* point_count, ring after ring */
  /* The voxel columns inside, clipped to the grid: rectangles [x0, x1) x [y0, y1)
   * as {x0, y0, x1, y1}, in order of y0 then x0. */
  int32_t (*rect)[4];
  int rect_count;
  double min[2], max[2]; /* the points' bounds */
} sylva__footprint;

/** Checks and copies a footprint (SYLVA_EINVAL for one sylva_world_add_obstacle()
 *  refuses, SYLVA_ENOMEM); its rectangles are made by sylva__footprint_voxelize(). */
int sylva__footprint_copy(const sylva_footprint *in, sylva__footprint **out);
/** The voxel columns of a grid (origin min, edge voxel, n[0] x n[1] columns) whose
 *  centres lie inside, as rectangles; SYLVA_ENOMEM leaves none. */
int sylva__footprint_voxelize(sylva__footprint *f, const double min[2], double voxel,
                              const int n[2]);
void sylva__footprint_free(sylva__footprint *f);
/** Whether (x, y) lies inside: a ray from it towards +x crosses the rings an odd
 *  number of times. */
bool sylva__footprint_inside(const sylva__footprint *f, double x, double y);
/** Squared distance from (x, y) to the footprint: 0 inside, else to its nearest edge. */
double sylva__footprint_dist2(const sylva__footprint *f, double x, double y);
/** The footprint as the public struct, pointing into f. */
sylva_footprint sylva__footprint_view(const sylva__footprint *f);
/** Bytes held by f. */
size_t sylva__footprint_bytes(const sylva__footprint *f);

#endif
