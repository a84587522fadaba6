/* The voxel environment: sparse 16^3 chunks holding fixed-point shade and (where
 * a node lies) stem occupancy, per-column block sums for the shade columns below pyramids, and
 * obstacles as voxel boxes, listed under each chunk column they overlap and indexed
 * by label and id. Memory is spent only on chunks and columns something touched. */
#ifndef SYLVA_GRID_H
#define SYLVA_GRID_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "pool.h"
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
  /* Shade as differences along x within each chunk row, stored with y fastest
   * (index y + 16 x + 256 z): a voxel's value is the sum of its row from x = 0 up to
   * itself, and a square layer is two contiguous runs of writes. It holds the
   * pyramids and the part of each shade column inside the chunk where the column
   * starts (one run per row and layer at and below the column's top). */
  int64_t shade[SYLVA__CHUNK_VOXELS];
} sylva__chunk;

/** A chunk's occupied voxels: open addressing with linear probing over cap (a power
 *  of two, at least 4/3 count) slots, each 0 or (local index + 1) << 32 | the
 *  voxel's occupancy word. A crown's chunk holds nodes in a few hundred of its 4,096
 *  voxels: a few kilobytes instead of 16. */
typedef struct sylva__occ {
  uint32_t cap, count;
  uint64_t slot[];
} sylva__occ;

typedef struct sylva__obstacle {
  int id;
  bool live; /* false: removed, a slot waiting for the next compaction */
  bool zone; /* a clearance zone: listed, never in a column; it blocks nothing */
  char label[SYLVA_LABEL_MAX];
  double min[3], max[3]; /* a prism's: its footprint's bounds and its z range */
  int lo[3], hi[3]; /* voxel box [lo, hi), clipped to the grid */
  /* A prism's footprint, owned (freed when the obstacle is removed); NULL for a box.
   * Its voxel rectangles, each over lo[2]..hi[2], are what the columns list. */
  struct sylva__footprint *fp;
} sylva__obstacle;

/** An obstacle's voxel box (a box's one, or one of a prism's rectangles) in the list
 *  of a chunk column it overlaps. */
typedef struct sylva__obstacle_box {
  int32_t lo[3], hi[3];
  int32_t id;
} sylva__obstacle_box;

/** The obstacles whose voxel box overlaps one chunk column's x/y footprint, in no
 *  particular order. */
typedef struct sylva__obstacle_list {
  int32_t count, cap;
  sylva__obstacle_box box[];
} sylva__obstacle_list;

/** Chunks are made in slabs of a growing number of them (up to 128, 4 MB), in
 *  ordinary 4 KB pages touched only when written (huge pages were tried: a new one
 *  cost more than the page faults they saved, docs/performance.md, "4 KB pages"). */
typedef struct sylva__slab {
  struct sylva__slab *next;
  size_t count, used;
  sylva__chunk *chunk; /* inside the same block, at a page boundary */
} sylva__slab;

typedef struct sylva__grid {
  int n[3];            /* voxels per axis */
  int c[3];            /* chunks per axis */
  double min[3], max[3], voxel, inv_voxel;
  sylva__chunk **chunks; /* c0*c1*c2, NULL where no shade is */
  sylva__slab *slabs;     /* where the chunks live, the newest first */
  /* Per chunk (c0*c1*c2): the stem occupancy of the voxels that hold a node; NULL
   * while none does (the chunks below the crowns hold shade alone, the crowns' tops
   * occupancy alone): made when a node enters, freed when the last leaves. */
  struct sylva__occ **occ;
  /* Per chunk (c0*c1*c2, the block): NULL or the shade of the columns whose top lies
   * in the block, which applies to every voxel of the blocks strictly below it; held
   * as a chunk's layer is, as differences along x, so a column's footprint is two
   * runs per row. colsum_top, per chunk column (c0*c1): the highest block any column
   * started in (0: none above the ground block), where a read stops. */
  int64_t **colsum;
  int32_t *colsum_top;
  size_t chunk_count, colsum_count, occ_count;
  size_t occ_bytes; /* the occupancy tables */
  /* Obstacles in the order they were added, so by increasing id (found by binary
   * search): obstacle_slots slots, obstacle_count of them live. A removed obstacle
   * leaves a dead slot; once the dead outnumber the live the slots are compacted. */
  sylva__obstacle *obstacles;
  int obstacle_count, obstacle_slots, obstacle_cap, next_obstacle_id;
  /* Fenwick tree of the live slots (1-based, obstacle_cap + 1 entries): the i-th
   * live obstacle while dead slots exist. */
  int32_t *obstacle_rank;
  /* Labels: open addressing with linear probing, label_cap (a power of two, at
   * least twice the live count) entries of a slot or -1. */
  int32_t *label_slot;
  int label_cap;
  /* Per chunk column (c0*c1, allocated with the first obstacle that overlaps the
   * grid): NULL or the boxes of the obstacles over that column. */
  sylva__obstacle_list **obstacle_cols;
  size_t obstacle_list_bytes; /* the lists, headers and capacity */
  size_t footprint_bytes;     /* the prisms' footprints */
  /* A site's sky (site.h): none in the zenith model. A voxel's factor is computed
   * when first read and kept (per chunk), and forgotten when an obstacle comes or
   * goes. */
  sylva_sky_dir *sky;
  int sky_count;
  double sky_top; /* the highest obstacle top, voxel units */
  struct sylva__site_cache *site;
} sylva__grid;

/** A voxel's site factor, -1 until computed. Threads reading the light at once may
 *  compute the same voxel's factor: they store the same value, atomically. */
typedef _Atomic float sylva__site_factor_t;

/** The site factors read so far: c0*c1*c2 entries, NULL or 4096
 *  factors in the chunk's voxel order. */
typedef struct sylva__site_cache {
  sylva__site_factor_t **chunk;
  size_t count;
} sylva__site_cache;

int sylva__grid_init(sylva__grid *g, const double min[3], const double max[3], double voxel);
/** Gives the grid a site's sky (copied); its light then is the site factor times
 *  the light under the plants' shade. SYLVA_ENOMEM leaves it as it was. */
int sylva__grid_set_sky(sylva__grid *g, const sylva_sky_dir *dirs, int count);
/** The site factor of voxel v (1 without a sky; cached per chunk). Safe on several
 *  threads at once only for voxels whose chunk has its cache (sylva__grid_site_reserve);
 *  elsewhere it allocates. */
double sylva__grid_site_factor(const sylva__grid *g, const int v[3]);
/** Makes the cache of voxel v's chunk (one thread at a time), so that readers on
 *  several threads may then fill it; false when there was no memory for it (the
 *  factors are then computed each time, unkept, by every reader). */
bool sylva__grid_site_reserve(const sylva__grid *g, const int v[3]);
/** The light of voxel v as sylva__grid_light, never allocating: safe on several
 *  threads at once while nothing writes the grid. */
double sylva__grid_light_shared(const sylva__grid *g, const int v[3]);
void sylva__grid_free(sylva__grid *g);
/** Bytes of the site factors cached so far (part of sylva__grid_bytes). */
size_t sylva__grid_site_bytes(const sylva__grid *g);
size_t sylva__grid_bytes(const sylva__grid *g);

/** Voxel of a point; false when outside the grid. */
bool sylva__grid_voxel(const sylva__grid *g, double x, double y, double z, int v[3]);
/** The index of chunk (cx, cy, cz) in the grid's per-chunk arrays: z, then y, then x. */
static inline size_t sylva__grid_chunk_index(const sylva__grid *g, int cx, int cy, int cz) {
  return ((size_t)cz * (size_t)g->c[1] + (size_t)cy) * (size_t)g->c[0] + (size_t)cx;
}
/** The index of voxel v's chunk. */
static inline size_t sylva__grid_chunk_of(const sylva__grid *g, const int v[3]) {
  return sylva__grid_chunk_index(g, v[0] >> SYLVA__CHUNK_BITS, v[1] >> SYLVA__CHUNK_BITS,
                                 v[2] >> SYLVA__CHUNK_BITS);
}
/** True when voxel v is inside a live obstacle. */
bool sylva__grid_blocked(const sylva__grid *g, const int v[3]);
/** True when some live obstacle is at or above voxel v in its column (full shadow). */
bool sylva__grid_under_obstacle(const sylva__grid *g, const int v[3]);
/** Shade S (fixed point) of voxel v, pyramids and columns, without obstacles. */
int64_t sylva__grid_shade_raw(const sylva__grid *g, const int v[3]);
/** Light max(0, 1 - S) of voxel v, 0 under or in an obstacle. */
double sylva__grid_light(const sylva__grid *g, const int v[3]);
/** Asks memory for what sylva__grid_free_light(v) will read in its chunk (its
 *  occupancy slot and its row of shade), so that a caller with several voxels to read
 *  waits once for all of them. Changes nothing. */
void sylva__grid_prefetch(const sylva__grid *g, const int v[3]);
/** Light of voxel v if no stem occupies it, else -1 (one chunk lookup for both). */
double sylva__grid_free_light(const sylva__grid *g, const int v[3]);
/** Voxel v's occupancy word ((stem + 1) << 12 | its nodes there), 0 when free. */
uint32_t sylva__grid_occ_word(const sylva__grid *g, const int v[3]);
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

/** One node's shade in a batch: its voxel and its pyramid. */
typedef struct sylva__stamp {
  int v[3];
  const sylva__pyramid *p;
} sylva__stamp;

/** The entries of scratch that sylva__grid_stamp_many() needs for these n items on
 *  this pool: the lists of the items each thread's columns take; 0 on one thread. */
size_t sylva__grid_stamp_scratch(const sylva__grid *g, const sylva__pool *pool,
                                 const sylva__stamp *items, size_t n);
/** The most entries sylva__grid_stamp_scratch() can ask for n items whose pyramids'
 *  widest layers are at most half voxels wide on either side, wherever they are. */
size_t sylva__grid_stamp_scratch_max(const sylva__grid *g, const sylva__pool *pool, size_t n,
                                     int half);
/** Adds (+1) or removes (-1) the shade of n nodes on the pool's threads (NULL: the
 *  caller's alone). Each thread writes the chunk columns of its own range of x, and
 *  the sums are exact integers, so the grid is the one the stamps give one by one in
 *  any order, on any number of threads. scratch holds sylva__grid_stamp_scratch()
 *  entries (NULL for none), made by the caller, so that this allocates nothing but
 *  chunks. Adding makes every chunk first, on the caller's thread: SYLVA_ENOMEM
 *  leaves the shade as it was. Removing never fails: the chunks of a stamp added
 *  before exist (chunks live as long as the grid). */
int sylva__grid_stamp_many(sylva__grid *g, sylva__pool *pool, const sylva__stamp *items,
                           size_t n, int sign, size_t *scratch);

/** Adds a solid box with the next id; returns the id, SYLVA_EINVAL for a bad box or
 *  label or a label in use, SYLVA_ENOMEM leaving the grid as it was. */
int sylva__grid_add_obstacle(sylva__grid *g, const char *label, const double min[3],
                             const double max[3]);
/** Adds the obstacle of def (a box or a prism, solid or a clearance zone, which is
 *  kept with its id and label but neither blocks, nor darkens, nor hides sky) with a
 *  given id, above every id given so far (a snapshot's obstacles; SYLVA_EINVAL for an
 *  id at or below one, or a def sylva_world_add_obstacle() refuses). */
int sylva__grid_add_obstacle_def(sylva__grid *g, int id, const sylva_obstacle_def *def);
/** Removes the obstacle of this id (never allocates); SYLVA_ENOTFOUND if none. */
int sylva__grid_remove_obstacle(sylva__grid *g, int id);
/** Slot of the live obstacle with this id, or -1. */
int sylva__grid_obstacle_slot(const sylva__grid *g, int id);
/** Id of the obstacle with this label, or SYLVA_ENOTFOUND. */
int sylva__grid_find_obstacle(const sylva__grid *g, const char *label);
/** The i-th live obstacle in the order they were added, 0 <= i < obstacle_count. */
const sylva__obstacle *sylva__grid_obstacle_at(const sylva__grid *g, int i);
#endif
