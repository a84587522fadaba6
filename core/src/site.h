/* The site factor of a voxel: the share of a site's light (a sky of weighted
 * directions, proto's sky.c) that reaches it unblocked by the obstacles. Each
 * direction's ray leaves the voxel's centre; it walks the chunk columns of the
 * obstacle index under its path and tests the boxes listed there, until it is
 * above every obstacle or out of the world's footprint. */
#ifndef SYLVA_SITE_H
#define SYLVA_SITE_H

#include "grid.h"
#include "sylva/world.h"

/** Whether the ray from voxel coordinates p (voxel units, the grid's origin at 0)
 *  along d meets an obstacle; top is the highest obstacle top (voxel units). */
bool sylva__site_blocked(const sylva__grid *g, const double p[3], const double d[3], double top);

/** The highest top of the live obstacles in voxel units (0 when there are none). */
double sylva__site_top(const sylva__grid *g);

/** The sum of the weights of the directions whose ray from voxel v's centre is not
 *  blocked. */
double sylva__site_factor(const sylva__grid *g, const sylva_sky_dir *dirs, int count, double top,
                          const int v[3]);

#endif
