/* sylva: the world: a voxel light environment, obstacles and plants that grow.
 *
 *   sylva_world_def def = sylva_default_world_def();
 *   ... set def.min, def.max, def.seed ...
 *   sylva_world *w; sylva_world_create(&def, &w);
 *   int sp = sylva_world_add_species(w, &species, "broadleaf");
 *   sylva_world_add_plant(w, &plant, NULL);
 *   const sylva_journal *j; while (!sylva_world_finished(w)) sylva_world_step(w, &j);
 *   sylva_world_destroy(w);
 *
 * Plants, stems, species and obstacles are referred to by integer ids. Every
 * function that can fail returns a negative sylva_status and changes nothing; every
 * allocation goes through the allocator of sylva/alloc.h. */
#ifndef SYLVA_WORLD_H
#define SYLVA_WORLD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "alloc.h"
#include "params.h"
#include "status.h"

/** Longest label (plant, species, obstacle id) including the terminating NUL. */
#define SYLVA_LABEL_MAX 64
/** Most stems a world may hold. */
#define SYLVA_MAX_STEMS 1000000
/** Oldest age (years) a plant may be planted at. */
#define SYLVA_MAX_AGE 500
/** Most nodes a measured plant (sylva_plant_def.nodes) may bring. */
#define SYLVA_MAX_MEASURED_NODES 50000000
/** Most voxels a world's box may span (memory is only spent where something is). */
#define SYLVA_MAX_VOXELS 68719476736.0 /* 2^36 */

/** Phases of one iteration, for timing. */
typedef enum sylva_phase {
  SYLVA_PHASE_LIGHT, SYLVA_PHASE_ALLOCATION, SYLVA_PHASE_SHOOTS, SYLVA_PHASE_SHADE,
  SYLVA_PHASE_RADII, SYLVA_PHASE_SHEDDING, SYLVA_PHASE_STATS, SYLVA_PHASE_COUNT
} sylva_phase;

/** How to build a world. */
/** Most directions of a site's sky. */
#define SYLVA_MAX_SKY 4096

/** One direction of a site's sky: d is a unit vector from the ground towards it
 *  (z up), weight its share of the light. */
typedef struct sylva_sky_dir {
  double d[3];
  double weight;
} sylva_sky_dir;

typedef struct sylva_world_def {
  double min[3], max[3]; /**< the box, metres; z is up, the ground is z = min[2] */
  double voxel;          /**< voxel edge, metres (> 0) */
  uint64_t seed;         /**< drives every random choice */
  /** A site's sky (sky_count directions, copied at creation), or none (NULL, 0): the
   *  paper's light from straight above, which obstacles block below themselves.
   *  With a sky, a voxel's light is its site factor (the weights of the directions
   *  that reach it past the obstacles) times 1 - S. */
  const sylva_sky_dir *sky;
  int sky_count;
  /** The stand's area, m^2, for its per-hectare figures (docs/model.md, "Stands");
   *  0: the convex hull of the roots widened by half their mean spacing. */
  double stand_area;
  /** Optional clock (seconds) used only to time phases; never affects results. */
  double (*clock)(void *ctx);
  void *clock_ctx;
  /** Threads that grow the world, the caller's included: 0 or 1 for the caller's
   *  alone, at most SYLVA_MAX_THREADS. Never affects results: every number of
   *  threads grows the same world to the bit (docs/model.md, "Determinism"). */
  int threads;
} sylva_world_def;

/** The most threads a world grows on. */
#define SYLVA_MAX_THREADS 256

/** A plant: one root is a tree, several roots make a shrub (one stem per root). */
/** A node of a measured plant (sylva_plant_def.nodes), parents before children. */
typedef struct sylva_plant_node {
  double p[3];   /**< metres */
  double radius; /**< metres, above 0 */
  int parent;    /**< an earlier node's index, or -1 for a stem's root */
  int lateral;   /**< 1: the node starts a branch off its parent's axis */
  int birth;     /**< the iteration it was born, counted from planting: 0 or below */
} sylva_plant_node;

typedef struct sylva_plant_def {
  int species;              /**< id from sylva_world_add_species */
  const char *label;        /**< the plant's id in scenario and exports */
  const double (*roots)[3]; /**< root positions, metres (not with nodes) */
  int root_count;
  /** Age in years at planting (species with years only; 0 otherwise): the stem is
   *  grown nursery + age seasons in open light before it is placed. With nodes, the
   *  measured tree's age: its stems count nursery + age seasons, grown already. */
  int age;
  /** A measured plant (docs/model.md, "Measured trees"): its nodes as they stand,
   *  one stem per root (parent -1), placed as given with their radii and births
   *  and grown on from their buds. NULL for a plant grown from its roots. */
  const sylva_plant_node *nodes;
  int node_count;
} sylva_plant_def;

/** What an obstacle is. */
typedef enum sylva_obstacle_kind {
  SYLVA_OBSTACLE_SOLID = 0, /**< a box that blocks growth and shades (a wall, a board) */
  SYLVA_OBSTACLE_ZONE = 1   /**< a clearance zone: blocks and shades nothing; the
                                 nodes that grow into it are counted, and pruned */
} sylva_obstacle_kind;

/** Most points of one prism's footprint, all rings together. */
#define SYLVA_FOOTPRINT_MAX_POINTS 100000

/** A prism's footprint in x, y (metres): rings of points, concatenated, each ring
 *  ring_sizes[r] points (at least 3, not closed: the last joins the first). The
 *  first is the outline; the others holes, or more parts. A point is inside where
 *  a ray from it crosses the rings an odd number of times (even-odd), so holes need
 *  no winding of their own. ring_count 0: no footprint (a box). */
typedef struct sylva_footprint {
  const double (*points)[2];
  int point_count;
  const int *ring_sizes;
  int ring_count;
} sylva_footprint;

/** An obstacle, solid or a clearance zone: a box [min, max], or a prism, a footprint
 *  extruded from min[2] to max[2] (docs/model.md, "Obstacles"). A voxel is inside a
 *  prism where its column's centre lies inside the footprint and its z range meets
 *  the prism's, as a voxel is inside a box where its cell meets the box. */
typedef struct sylva_obstacle_def {
  const char *label;
  /** A box's corners; a prism's z range in min[2], max[2] (its x, y given are
   *  ignored: the world gives back the footprint's bounds there). */
  double min[3], max[3];
  sylva_obstacle_kind kind; /**< SOLID when zero-initialised */
  /** A prism's footprint (copied when added; from the world, pointing into it,
   *  valid until the obstacle is removed); ring_count 0 for a box. */
  sylva_footprint footprint;
} sylva_obstacle_def;

/** Farthest a solid obstacle may be from a stem's nodes and still be reported in its
 *  clearance, metres. */
#define SYLVA_CLEARANCE_RANGE 10.0

/** Pruning on a schedule: every `every` iterations from iteration `from` (the first
 *  prune; every 0 prunes once), every node inside the zone goes with its subtree. */
typedef struct sylva_prune_def {
  int zone; /**< obstacle id of a zone */
  int every, from;
} sylva_prune_def;

/** A node as the outside sees it. Ids are unique in a world and never reused. */
typedef struct sylva_node_info {
  int32_t id, parent;  /**< parent -1 for a root */
  int32_t plant, stem; /**< plant id, stem index within the plant */
  int32_t birth;       /**< birth iteration (0 for the initial trunk) */
  float x, y, z, radius;
  int32_t leaves;      /**< leaves it carries: its species' leaf_density when it bears
                            leaves (as the stats count them), else 0 */
} sylva_node_info;

/** A radius that changed in an iteration. */
typedef struct sylva_radius_change {
  int32_t id;
  float radius;
} sylva_radius_change;

/** Per-stem measures (docs/model.md "Measures"); NaN where the measure is null. */
typedef struct sylva_stem_stats {
  int32_t plant, stem;
  double height, dbh, crown_width, crown_base, light;
  double crown_height; /**< height - crown_base (NaN with crown_base) */
  int32_t age;         /**< years since planting (species with years), else -1 */
  double leaf_area;    /**< m^2, one-sided: leaf-bearing nodes x leaf_density x
                            SYLVA_LEAF_FILL x leaf_size^2 (docs/model.md, "Foliage") */
  double crown_area;   /**< m^2: the ground under its leaves, in vertical projection
                            (docs/model.md, "Canopy cover") */
  double wood_volume;  /**< m^3: its internodes' tapered cylinders (docs/model.md,
                            "Wood and carbon") */
  /* Wood and carbon (docs/model.md, "Wood and carbon"); NaN where they do not apply */
  double biomass;         /**< kg above-ground dry weight, by the species' allometry
                               (biomass_form) at its dbh and height; NaN without one or
                               without a dbh */
  double biomass_model;   /**< kg, wood_volume x wood_density; NaN without a density */
  double carbon;          /**< kg C stored, from biomass */
  double co2;             /**< kg CO2-equivalent stored, from carbon */
  double co2_sequestered; /**< kg CO2: co2 now less co2 at the last iteration (0 at
                               planting; a co2 not known then counts as 0) */
  int64_t nodes, shed;
  int64_t pruned; /**< nodes pruned at this iteration (by schedule or edit) */
  int cap;
  bool finished;
  /* Stands (docs/model.md, "Stands") */
  bool alive;      /**< false once it died; a dead stem keeps the measures of its last
                        season alive */
  int32_t died;    /**< the iteration it died, -1 while alive */
  int32_t fallen;  /**< the iteration its snag fell (its nodes gone), -1 while standing */
  double vigour;   /**< its leaves' mean relative light, Q / (alpha N) over its
                        leaf-bearing nodes, as shedding judged it (NaN: none judged) */
} sylva_stem_stats;

/** The stand's figures after a step (docs/model.md, "Stands"): over the stems alive,
 *  per hectare of the stand's area; NaN where a figure is null. */
typedef struct sylva_stand_stats {
  double area;            /**< m^2: the world def's stand_area, or the convex hull of the
                               roots widened by half their mean spacing (NaN: fewer than
                               two roots and no stand_area) */
  int32_t alive;          /**< stems alive */
  int32_t died;           /**< stems that died in this step */
  double stems_per_ha;    /**< alive stems per hectare */
  double basal_area;      /**< m^2/ha: the alive stems' cross-sections at breast height */
  double qmd;             /**< cm: quadratic mean diameter of the stems with a dbh */
  double dominant_height; /**< m: mean height of the 100 thickest stems per hectare (of
                               all the alive stems where there are fewer) */
  double sdi;             /**< Reineke's stand density index: stems_per_ha (qmd / 25)^1.605 */
  double cv_height, cv_dbh; /**< coefficients of variation (population) */
} sylva_stand_stats;

/** A stem in a zone: the nodes inside now, and the iteration a node of the stem was
 *  first seen inside (pruned or not since). One per stem and zone it ever entered. */
typedef struct sylva_zone_stat {
  int32_t stem;     /**< global stem index */
  int32_t obstacle; /**< the zone's obstacle id */
  int64_t nodes;
  int32_t first;
} sylva_zone_stat;

/** A stem's clearance to a solid obstacle: the least distance from its nodes to the
 *  box, metres (0 when a node touches it). One per stem and solid obstacle within
 *  SYLVA_CLEARANCE_RANGE of a node. */
typedef struct sylva_clearance_stat {
  int32_t stem, obstacle;
  double distance;
} sylva_clearance_stat;

/** Conflicts between stems and obstacles, both lists ordered by stem, then obstacle
 *  id. */
typedef struct sylva_conflicts {
  const sylva_zone_stat *zones; size_t zone_count;
  const sylva_clearance_stat *clearances; size_t clearance_count;
} sylva_conflicts;

/** A node whose leaves changed: the leaves it carries now (0: it bears none). */
typedef struct sylva_leaf_change {
  int32_t id;
  int32_t leaves;
} sylva_leaf_change;

/** What one iteration changed; valid until the next step or destroy. */
typedef struct sylva_journal {
  int iteration;
  const sylva_node_info *added; size_t added_count;
  const sylva_radius_change *radii; size_t radii_count;
  const sylva_leaf_change *leaves; size_t leaves_count; /**< live nodes whose leaves
                                                             (sylva_node_info.leaves)
                                                             differ from the last
                                                             journal's, the nodes born
                                                             in this step with leaves
                                                             too; in id order */
  const int32_t *shed; size_t shed_count;        /**< roots of removed subtrees (shed or pruned) */
  const sylva_stem_stats *stats; size_t stem_count;
  const int32_t *order;                           /**< stem order of phase 4 (global stem indices) */
  sylva_conflicts conflicts;                      /**< zones and clearances after the step */
  double canopy_cover;                            /**< sylva_world_canopy_cover() after the step */
  sylva_stand_stats stand;                        /**< sylva_world_stand() after the step */
  double phase_seconds[SYLVA_PHASE_COUNT];        /**< only with def.clock */
} sylva_journal;

/** Memory the world holds, bytes. */
typedef struct sylva_memory {
  size_t voxels, skeleton, other;
  size_t site; /**< of voxels: the site factors cached so far (0 without a site sky) */
} sylva_memory;

typedef struct sylva_world sylva_world;

/** Defaults: a 10 x 10 x 12 m box at 5 cm voxels, seed 1. */
sylva_world_def sylva_default_world_def(void);
/** Checks a world def; SYLVA_ETOOBIG when the box spans more than SYLVA_MAX_VOXELS. */
int sylva_world_def_check(const sylva_world_def *def);
int sylva_world_create(const sylva_world_def *def, sylva_world **out);
void sylva_world_destroy(sylva_world *w);

/** Adds a species; returns its id (>= 0) or a negative status. */
int sylva_world_add_species(sylva_world *w, const sylva_species_def *def, const char *label);
/** Adds a plant with its initial trunks (or a measured plant's nodes); returns its id
 *  or a negative status. On failure *bad_root (if given) is the index of the root
 *  (of a measured plant: the node) at fault, or -1. */
int sylva_world_add_plant(sylva_world *w, const sylva_plant_def *def, int *bad_root);
/** Adds an obstacle; returns its id or a negative status (SYLVA_EINVAL for a
 *  duplicate label, an empty box or z range, an unknown kind, or a footprint with a
 *  ring of under 3 points, ring sizes that do not sum to its point count, more than
 *  SYLVA_FOOTPRINT_MAX_POINTS points, a coordinate that is not finite, or no area). A zone added over nodes counts
 *  them as entering at the current iteration. */
int sylva_world_add_obstacle(sylva_world *w, const sylva_obstacle_def *def);
/** Removes an obstacle by id. */
int sylva_world_remove_obstacle(sylva_world *w, int obstacle);
/** Id of the obstacle with this label, or SYLVA_ENOTFOUND. */
int sylva_world_find_obstacle(const sylva_world *w, const char *label);

/** Adds a pruning schedule (SYLVA_EINVAL when def->zone is not a zone, every < 0
 *  or from < 1). Schedules prune at the end of the iterations they name, after
 *  shedding, in the order they were added. */
int sylva_world_add_prune(sylva_world *w, const sylva_prune_def *def);
/** Number of pruning schedules, and the i-th (0 or SYLVA_ENOTFOUND). */
int sylva_world_prune_count(const sylva_world *w);
int sylva_world_prune_at(const sylva_world *w, int i, sylva_prune_def *out);
/** Prunes now: every node inside the box [min, max] goes with its subtree, as
 *  shedding removes nodes (a stem's root stays). Counted in the stems' `pruned`;
 *  *removed (if given) receives the ids of the subtrees' roots, *removed_count their
 *  number, valid until the next call that changes the world. Returns the nodes
 *  removed, or SYLVA_ENOMEM with the world as it was. */
int64_t sylva_world_prune(sylva_world *w, const double min[3], const double max[3],
                          const int32_t **removed, size_t *removed_count);

/** Sets (or clears, with NULL) the clock that times the phases of each step. */
void sylva_world_set_clock(sylva_world *w, double (*clock)(void *ctx), void *ctx);

/** Grows the world on this many threads from now on (as sylva_world_def.threads; a
 *  loaded snapshot starts on one). SYLVA_EINVAL outside 0..SYLVA_MAX_THREADS;
 *  SYLVA_ENOMEM (memory or threads the system would not give) leaves it on one
 *  thread, which grows the same world. */
int sylva_world_set_threads(sylva_world *w, int threads);
/** The threads the world grows on (1 without a pool), shared ones too. */
int sylva_world_threads(const sylva_world *w);

/** Threads that several worlds share: count - 1 workers that run the parallel loops
 *  of whichever world posts one, beside that world's own thread. A loop posted while
 *  they run another world's runs on its caller alone, so a daemon's many worlds keep
 *  count - 1 threads between them, not each. Never affects results (docs/model.md,
 *  "Determinism"). */
typedef struct sylva_threads sylva_threads;
/** SYLVA_EINVAL outside 1..SYLVA_MAX_THREADS; SYLVA_ENOMEM (memory or threads the
 *  system would not give) leaves *out NULL. The threads start at the caller's
 *  scheduling priority. */
int sylva_threads_create(int count, sylva_threads **out);
/** Threads a loop runs on, the posting world's included. */
int sylva_threads_count(const sylva_threads *t);
/** Stops the threads: only once no world shares them (destroyed, or given others). */
void sylva_threads_destroy(sylva_threads *t);
/** Grows w on t from now on (NULL: on the caller's thread alone); threads of its own
 *  (sylva_world_set_threads) are stopped. Worlds that share t may step on different
 *  threads at once. */
void sylva_world_share_threads(sylva_world *w, sylva_threads *t);
/** The threads w shares, or NULL (its own, or none). */
sylva_threads *sylva_world_shared_threads(const sylva_world *w);

/** Grows one iteration. SYLVA_EFINISHED when every stem has finished. SYLVA_ENOMEM
 *  when memory ran out: the world is as it was before the call (the previous
 *  journal is no longer valid) and may step again. */
int sylva_world_step(sylva_world *w, const sylva_journal **journal);

/* Queries. A bad id or index gets NULL (for a pointer) or SYLVA_ENOTFOUND. */
/** The def the world was created with. */
const sylva_world_def *sylva_world_get_def(const sylva_world *w);
/** Iterations grown so far (0 before the first step). */
int sylva_world_iteration(const sylva_world *w);
/** True when every stem has finished by its growth equation or, dead, has fallen (or
 *  there are none). */
bool sylva_world_finished(const sylva_world *w);
/** Number of species, and a species' parameters and label by id (NULL for a bad id). */
int sylva_world_species_count(const sylva_world *w);
const sylva_species_def *sylva_world_species(const sylva_world *w, int species);
const char *sylva_world_species_label(const sylva_world *w, int species);
/** Number of plants, and a plant's label (NULL for a bad id), species and stem count
 *  by id. */
int sylva_world_plant_count(const sylva_world *w);
const char *sylva_world_plant_label(const sylva_world *w, int plant);
int sylva_world_plant_species(const sylva_world *w, int plant);
int sylva_world_plant_stem_count(const sylva_world *w, int plant);
/** Global index of a plant's stem (stems are numbered in plant order). */
int sylva_world_stem_index(const sylva_world *w, int plant, int stem);
/** Number of stems of all plants. */
int sylva_world_stem_count(const sylva_world *w);
/** Root position of a global stem; 0 or SYLVA_ENOTFOUND (root untouched). */
int sylva_world_stem_root(const sylva_world *w, int stem, double root[3]);
/** Current measures of a global stem (as after the last iteration); 0 or
 *  SYLVA_ENOTFOUND (out untouched). */
int sylva_world_stem_stats(const sylva_world *w, int stem, sylva_stem_stats *out);
/** The share (0..1) of the world's open ground (its floor less the footprints of the
 *  solid obstacles that stand on it) under any stem's leaves, as after the last step,
 *  plant or prune (docs/model.md, "Canopy cover"); 0 when there is no open ground. */
double sylva_world_canopy_cover(const sylva_world *w);
/** The stand's figures as after the last step, plant or prune (docs/model.md,
 *  "Stands"). */
void sylva_world_stand(const sylva_world *w, sylva_stand_stats *out);
/** The edge of the floor's cells, m (docs/model.md, "Canopy cover"). */
double sylva_world_cell_edge(const sylva_world *w);
/** The floor's cells under a stem's leaves, those its crown_area counts (docs/model.md,
 *  "Canopy cover"): cell k is (*cells)[2k] along x and (*cells)[2k + 1] along y, the
 *  square from def.min + (i, j) e to def.min + (i + 1, j + 1) e, e the cell edge; in
 *  order of j, then i. *cells is malloc()ed (NULL when there are none). Returns how
 *  many, or SYLVA_EINVAL (no such stem), SYLVA_ENOMEM. */
int64_t sylva_world_crown_cells(const sylva_world *w, int stem, int32_t **cells);
/** Does the world report conflicts (stems' pruned counts, zones and clearances)?
 *  Once it has held a clearance zone, a pruning schedule or pruned a node; a world
 *  without any reports as worlds did before zones existed. */
bool sylva_world_reports_conflicts(const sylva_world *w);
/** Zones entered and clearances now (as after the last step or edit); valid until
 *  the world changes. */
sylva_conflicts sylva_world_conflicts(const sylva_world *w);
/** The conflicts of one global stem (the parts of sylva_world_conflicts() that are
 *  its own). */
sylva_conflicts sylva_world_stem_conflicts(const sylva_world *w, int stem);
/** Number of obstacles. */
int sylva_world_obstacle_count(const sylva_world *w);
/** The i-th obstacle (0 <= i < count), in the order they were added; the label
 *  points into the world and is valid until the obstacle is removed. 0 or
 *  SYLVA_ENOTFOUND (nothing written). */
int sylva_world_obstacle_at(const sylva_world *w, int i, int *id, sylva_obstacle_def *out);
/** The obstacle with this id (its label points into the world, valid until it is
 *  removed). 0 or SYLVA_ENOTFOUND (nothing written). */
int sylva_world_obstacle(const sylva_world *w, int obstacle, sylva_obstacle_def *out);
/** Number of live nodes. */
size_t sylva_world_node_count(const sylva_world *w);
/** The i-th live node (0 <= i < count), in id order: parents before children. 0 or
 *  SYLVA_ENOTFOUND (out untouched). */
int sylva_world_node_at(const sylva_world *w, size_t i, sylva_node_info *out);
/** The index (for sylva_world_node_at) of the live node with this id, or
 *  SYLVA_ENOTFOUND. */
int64_t sylva_world_node_index(const sylva_world *w, int32_t id);
/** Light (0..1) of the voxel holding point p; 0 outside the world. */
double sylva_world_light_at(const sylva_world *w, const double p[3]);
/** Voxels per axis. */
void sylva_world_dims(const sylva_world *w, int dims[3]);
/** Memory held now: voxels, skeleton and per-step scratch. */
void sylva_world_memory(const sylva_world *w, sylva_memory *out);
/** The newest definition of the world hash, the one new stores keep (docs/store.md,
 *  "The world hash"). */
#define SYLVA_WORLD_HASH_VERSION 2
/** A 64-bit hash of the whole state (skeleton, generator, iteration, stems'
 *  clocks, obstacles) by definition `version` (docs/store.md, "The world hash"):
 *  1, FNV-1a over every live node's fields byte by byte, in id order; 2, the same
 *  except that the live nodes enter as the sum (mod 2^64) of a hash of each node,
 *  which the world's threads share out (equal for every thread count). Two worlds
 *  that grow alike have equal hashes of either version. 0 for an unknown version.
 *  Uses the world's threads: not to be called on one world from two threads at
 *  once. */
uint64_t sylva_world_hash_of(const sylva_world *w, int version);
/** sylva_world_hash_of(w, 1). */
uint64_t sylva_world_hash(const sylva_world *w);

#endif
