/* The voxel environment: sparse 16^3 chunks holding fixed-point shade and stem
 * occupancy, per-column block sums for the shade columns below pyramids, and
 * obstacles as voxel boxes. Memory is spent only on chunks something touched. */
#ifndef SYLVA_GRID_H
#define SYLVA_GRID_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "sylva/world.h"

#define SYLVA__CHUNK_BITS 4
#define SYLVA__CHUNK 16
#define SYLVA__CHUNK_VOXELS 4096
/** Shade fixed point: S = raw / 2^32. Integer sums make add/remove exact. */
#define SYLVA__SHADE_ONE 4294967296.0
/** Occupancy word: (stem + 1) << 12 | count of that stem's nodes in the voxel. */
#define SYLVA__OCC_COUNT_BITS 12
#define SYLVA__OCC_COUNT_MAX 4095u

typedef struct sylva__chunk {
  /* Pyramid shade as differences along x within each chunk row, stored with y
   * fastest (index y + 16 x + 256 z): a voxel's value is the sum of its row from
   * x = 0 up to itself, and a square layer is two contiguous runs of writes. */
  int64_t shade[SYLVA__CHUNK_VOXELS];
  uint32_t occ[SYLVA__CHUNK_VOXELS];
  /* Columns that start in this chunk, same index: the shade of the columns whose
   * top voxel it is; a voxel sums the entries at or above it in the chunk. NULL
   * until a column starts here. */
  int64_t *column;
} sylva__chunk;

typedef struct sylva__obstacle {
  int id;
  char label[SYLVA_LABEL_MAX];
  double min[3], max[3];
  int lo[3], hi[3]; /* voxel box [lo, hi), clipped to the grid */
} sylva__obstacle;

typedef struct sylva__grid {
  int n[3];            /* voxels per axis */
  int c[3];            /* chunks per axis */
  double min[3], max[3], voxel, inv_voxel;
  sylva__chunk **chunks; /* c0*c1*c2, NULL where nothing is */
  /* Per chunk column (c0*c1): NULL or c2 blocks x 256 columns of shade that applies
   * to every voxel of blocks strictly below. */
  int64_t **colsum;
  size_t chunk_count, colsum_count, column_count;
  sylva__obstacle *obstacles;
  int obstacle_count, obstacle_cap, next_obstacle_id;
  /* Per-column obstacle top: (x, y) -> highest hi[2] of live obstacles covering it,
   * rebuilt lazily; 0 where none. Kept sparse by storing only the obstacle list. */
} sylva__grid;

int sylva__grid_init(sylva__grid *g, const double min[3], const double max[3], double voxel);
void sylva__grid_free(sylva__grid *g);
size_t sylva__grid_bytes(const sylva__grid *g);

/** Voxel of a point; false when outside the grid. */
bool sylva__grid_voxel(const sylva__grid *g, double x, double y, double z, int v[3]);
/** True when voxel v is inside a live obstacle. */
bool sylva__grid_blocked(const sylva__grid *g, const int v[3]);
/** True when some live obstacle is at or above voxel v in its column (full shadow). */
bool sylva__grid_under_obstacle(const sylva__grid *g, const int v[3]);
/** Shade S (fixed point) of voxel v, pyramids and columns, without obstacles. */
int64_t sylva__grid_shade_raw(const sylva__grid *g, const int v[3]);
/** Light max(0, 1 - S) of voxel v, 0 under or in an obstacle. */
double sylva__grid_light(const sylva__grid *g, const int v[3]);
/** Light of voxel v if no stem occupies it, else -1 (one chunk lookup for both). */
double sylva__grid_free_light(const sylva__grid *g, const int v[3]);
/** Stem occupying voxel v, or -1. */
int32_t sylva__grid_occupant(const sylva__grid *g, const int v[3]);
/** Adds one node of stem to voxel v. SYLVA_EOCCUPIED if another stem holds it or
 *  the count is full. */
int sylva__grid_occupy(sylva__grid *g, const int v[3], int32_t stem);
/** Removes one node of stem from voxel v. */
void sylva__grid_vacate(sylva__grid *g, const int v[3]);

/** The shade one node casts (docs/model.md, "Shade"): at q = 1..depth voxels below
 *  it, w[q-1] on every voxel within horizontal Chebyshev distance half[q-1]; below
 *  the base, column on every voxel of the base's footprint down to the ground.
 *  half must not decrease with q. */
typedef struct sylva__pyramid {
  int depth;
  int64_t w[64];
  int half[64];
  int64_t column;
} sylva__pyramid;

/** Adds (sign +1) or removes (-1) the shade of one node at voxel v. SYLVA_ENOMEM
 *  leaves the shade as it was. */
int sylva__grid_stamp(sylva__grid *g, const int v[3], const sylva__pyramid *p, int sign);

int sylva__grid_add_obstacle(sylva__grid *g, const char *label, const double min[3],
                             const double max[3]);
int sylva__grid_remove_obstacle(sylva__grid *g, int id);
int sylva__grid_find_obstacle(const sylva__grid *g, const char *label);
#endif
