/* The world's private layout, shared by the phase modules. */
#ifndef SYLVA_WORLD_IMPL_H
#define SYLVA_WORLD_IMPL_H

#include "alloc.h"
#include "debug.h"
#include "grid.h"
#include "pool.h"
#include "prism.h"
#include "rng.h"
#include "skeleton.h"
#include "sylva/world.h"

typedef struct sylva__species {
  sylva_species_def def;   /* as the phases use it: for a species with ref_rho, its
                              counts scaled to its rho (docs/model.md, "Species in years") */
  sylva_species_def given; /* as it was added: what queries and snapshots give back */
  double scale;            /* s = ref_rho / rho: nodes per internode of ref_rho (1
                              without ref_rho); weighs each node's shade */
  int bud_every;           /* a node carries a lateral bud when its depth is a multiple */
  char label[SYLVA_LABEL_MAX];
  int t95;             /* first local iteration with X(T) >= 0.95 limit */
  double *age_pow;     /* age^sigma by age, grown on demand */
  int age_pow_n;
  /* The shade of a node by its local birth iteration t (fixed-point b^-q, q =
   * 1..pyramid_depth, and its shape), made when first needed: b varies only between
   * tau and t95, so entry k is t = tau + k, entry 0 every t <= tau and the last
   * (once made) every t >= t95. */
  sylva__pyramid *shades;
  int shades_n;
} sylva__species;

typedef struct sylva__plant {
  char label[SYLVA_LABEL_MAX];
  int species;
  int first_stem, stem_count;
} sylva__plant;

typedef struct sylva__stem {
  int plant, index, species;
  int born;           /* world iteration at which the stem was planted */
  double root[3];
  int32_t root_slot;
  bool finished;
  sylva_stem_stats stats;
  double ext[5]; /* scratch of the stats pass: min x, max x, min y, max y, max z */
  double shed_below; /* scratch of shedding: the stem's threshold of E this iteration */
  double light_next; /* its Q at the next iteration, after shedding and pruning (stats) */
  /* Stands (docs/model.md, "Stands"), kept in snapshots with the STAND flag */
  double clock;      /* its time on its growth equation (its local iteration while
                        every season counts one) */
  double clock_prev; /* the clock before the last season grown */
  double rate;       /* its vigour: the clock's advance per season in full light */
  int32_t low;       /* seasons in a row its vigour was below mortality_light */
} sylva__stem;

/** A node that sprouts this iteration. */
typedef struct sylva__sprout {
  int32_t slot, stem;
  int32_t n;   /* new nodes wanted after the cap */
  double r;    /* resource R_i, orders the shoots of a stem */
  bool apex;
} sylva__sprout;

/** The sprouts one piece of the parallel allocation found. */
typedef struct sylva__piece_sprouts {
  sylva__sprout *data;
  size_t len, cap;
} sylva__piece_sprouts;

/** One node of an axis being ranked by its BH share. */
typedef struct sylva__ranked {
  double rbh;      /* RBH_i, the key of the ranking */
  double weighted; /* RBH_i * w_i, once ranked */
  int32_t pos;     /* position along the axis, base = 0 */
} sylva__ranked;

/** A node that collects light in a pass under a site sky, with the age it collects
 *  at (sylva__light_collect). */
typedef struct sylva__lit {
  int32_t slot;
  int32_t age;
} sylva__lit;

/** A box in metres. */
typedef struct sylva__box {
  double min[3], max[3];
} sylva__box;

/** A stem entered a zone: first is the iteration one of its nodes was first seen
 *  inside. Kept sorted by (stem, zone) and stored in snapshots. */
typedef struct sylva__entered {
  int32_t stem, zone, first;
} sylva__entered;

/** An obstacle near a stem (conflicts.c): its slot, and what the pass found. */
typedef struct sylva__candidate {
  int32_t stem, slot;
  int64_t count; /* zone: the stem's nodes inside */
  double dist2;  /* solid: the least squared distance from the stem's nodes */
} sylva__candidate;

/** Where a step or a new plant started from. Until the point after which it cannot
 *  fail, such a call only appends nodes (casting their shade), draws from the
 *  generator and plants stems; a failure takes all of it back to the mark, so the
 *  call changes nothing. */
typedef struct sylva__mark {
  int iteration;
  sylva__rng rng;
  size_t count;    /* skeleton slots at the mark: the call's nodes are above */
  size_t shaded;   /* the call's nodes below this slot have cast their shade */
  int32_t next_id;
  int stem_count;
} sylva__mark;

/** Growable scratch array of one element type. */
#define SYLVA__VEC(T)   \
  struct {              \
    T *data;            \
    size_t len, cap;    \
  }

struct sylva_world {
  sylva_world_def def;
  sylva__pool *pool; /* NULL: the caller's thread alone */
  sylva_threads *shared; /* the threads pool is, when shared: not the world's to stop */
  sylva__grid grid;
  sylva__skeleton nodes;
  sylva__rng rng;
  int iteration;
  int status; /* sticky failure of a step past the point where it cannot fail (never
                 expected: everything it needs is reserved before), 0 when healthy */
  sylva__mark mark; /* the step or plant being made */

  sylva__species *species;
  int species_count, species_cap;
  sylva__plant *plants;
  int plant_count, plant_cap;
  int32_t *plant_index;  /* open-addressing hash of plant labels -> plant, -1 empty */
  size_t plant_index_cap; /* a power of two, at least twice the plants */
  sylva__stem *stems;
  int stem_count, stem_cap;
  /* Conflicts (conflicts.c): the zones each stem entered (state, in snapshots), the
   * pruning schedules (state), and the zone lines and clearances now (as after the
   * last step or edit). */
  SYLVA__VEC(sylva__entered) entered;
  SYLVA__VEC(sylva_prune_def) prunes;
  SYLVA__VEC(sylva_zone_stat) zone_stats;
  SYLVA__VEC(sylva_clearance_stat) clear_stats;
  bool reports;  /* has held a zone, a schedule or pruned a node (sticky, in snapshots) */

  /* Per-step scratch, reused across steps. Each buffer has one meaning, named by the
   * phase that fills it; none is reused by a later phase for something else. */
  /* by slot, sized to the skeleton's capacity (sylva__reserve_scratch). light's
   * block (a double, or two int32s, a slot) is free once allocation has read it, so
   * the scratch of the later phases, which never overlap, are views of it: sap
   * (radii), leaves and the crown lift's path (shedding: the block's two halves),
   * canopy (stats) and remap (compaction). 24 bytes a slot instead of 52
   * (docs/performance.md, "Memory"). */
  double *light;         /* light: L_i of the pass at T, read by allocation (owns the block) */
  double *q;             /* light: Q_i, the light of the node and its subtree, of the
                            last light pass (T for allocation, T + 1 after shoots); L_i
                            while light_at is the iteration of a pass kept */
  int light_at;          /* the iteration whose light pass q holds as L_i, kept after
                            shedding for that iteration's light phase; 0: none */
  double *pipe;          /* radii: sum over the node's children of r^v */
  double *sap;           /* radii: the functional pipes of the node's tips, sum of r_tip^v
                            (light's block) */
  int32_t *leaves;       /* shedding: leaf-bearing nodes of the node's subtree (light's
                            block, its first half) */
  int32_t *remap;        /* compaction: each old slot's new slot, -1 if dropped (light's
                            block) */
  int32_t *canopy;       /* canopy: leaf-bearing slots grouped by stem, then (from
                            scratch_cap) the same in slot order (2 x scratch_cap int32s:
                            light's block) */
  size_t scratch_cap;
  SYLVA__VEC(sylva__lit) lit; /* light: the lit slots of a pass under a site sky, in slot
                                 order (room: the skeleton's capacity with a sky) */
  /* by stem */
  SYLVA__VEC(double) clock_next;  /* allocation: each stem's clock after this season,
                                     committed once the step cannot fail */
  SYLVA__VEC(int32_t) stem_high;  /* allocation: each stem's highest node (-1: none) */
  SYLVA__VEC(int32_t) finishing;  /* stop: the stems whose equation stops at this step;
                                     they grow nothing and are marked finished once the
                                     step can no longer fail */
  SYLVA__VEC(int32_t) caps;       /* allocation: c(T) of each stem that grows, else 0; then
                                   * the laterals' caps (stem_count + k) */
  SYLVA__VEC(int32_t) stem_first; /* allocation: the stems' live nodes summed (each piece's
                                     room), then each stem's first sprout, stem_count + 1 */
  SYLVA__VEC(int32_t) stem_top;   /* shedding: each stem's highest live node; canopy: its
                                     leaf-bearing nodes, rows and counts by band
                                     (sylva__canopy_room, kept reserved) */
  SYLVA__VEC(double) crown_bins;  /* stats: the lowest and highest leaves of each height
                                     bin of one stem, one stem per piece of the pool's
                                     loop (SYLVA__STATS_PIECES, from creation) */
  /* the rest as the phases need them */
  SYLVA__VEC(sylva__sprout) sprouts;
  SYLVA__VEC(int32_t) order;
  /* allocation, one list and one stretch of scratch for each piece of stems
   * (allocate.c, axis_scratch) */
  SYLVA__VEC(sylva__piece_sprouts) piece_sprouts;
  SYLVA__VEC(int32_t) axis;      /* nodes of one axis */
  SYLVA__VEC(sylva__ranked) ranked; /* ranking of one axis */
  SYLVA__VEC(int32_t) work;      /* pending (slot) stack for axes */
  SYLVA__VEC(double) work_r;     /* resource for pending axes */
  SYLVA__VEC(double) work_light; /* light of each bud's stretch of one axis */
  SYLVA__VEC(int32_t) shoot;     /* slots grown by the current shoot */
  SYLVA__VEC(sylva__box) stem_box;        /* conflicts: each stem's nodes' box */
  SYLVA__VEC(int32_t) stem_nodes;         /* radii, conflicts: live slots grouped by stem
                                             (room: scratch_cap, sylva__reserve_scratch) */
  SYLVA__VEC(int32_t) stem_nodes_first;   /* each stem's first, stem_count + 1 (room: the
                                             same) */
  SYLVA__VEC(sylva__candidate) candidates; /* conflicts: obstacles near each stem */
  int conflicts_from;                      /* conflicts: the first stem of the reserve */
  SYLVA__VEC(int32_t) pruned_ids;          /* sylva_world_prune: the subtrees' roots */
  SYLVA__VEC(sylva_node_info) added;
  SYLVA__VEC(sylva_leaf_change) leaf_changes;
  SYLVA__VEC(sylva_radius_change) radii;
  SYLVA__VEC(int32_t) shed;
  SYLVA__VEC(sylva_stem_stats) stats;
  SYLVA__VEC(int32_t) cells;        /* removal: the doomed slots, chunk by chunk */
  SYLVA__VEC(int32_t) cell_start;   /* removal: where each chunk's start in cells (the
                                       grid's chunks + 1) */
  SYLVA__VEC(sylva__stamp) stamps;  /* their shade, in that order */
  SYLVA__VEC(size_t) stamp_lists;   /* the stamps each thread takes (sylva__grid_stamp_scratch) */
  SYLVA__VEC(int32_t) cell_first;    /* competition index: first item of each cell */
  SYLVA__VEC(int32_t) cell_items;    /* sprout indices, cell by cell */
  SYLVA__VEC(float) cell_pos;        /* their positions, x y z */
  SYLVA__VEC(int32_t) cell_of;       /* cell of each sprout while building */
  sylva_journal journal;

  /* Canopy (stats.c, docs/model.md "Canopy cover"): the floor's cells, the voxel's
   * squares (or squares of col_edge when the floor has more than
   * SYLVA__CANOPY_MAX_COLS of them), from creation. cols[c] is the stamp of the last
   * stem pass that counted cell c; foot marks the cells under a solid obstacle that
   * stands on the floor, rebuilt when foot_dirty. */
  uint32_t *cols;
  uint8_t *foot;
  int col_n[2];
  double col_edge;
  uint32_t col_stamp;
  int64_t open_cols;
  bool foot_dirty;
  double canopy_cover;
  sylva_stand_stats stand; /* the stand's figures (stand.c), as after the last change */
  double stand_area;       /* stand.c: the area of the stand_stems first stems' roots */
  int stand_stems;         /* stems when stand_area was found, -1 before */
  bool stand_fresh;        /* w->stand is the stand as it is now */
};

/** The stand's figures into w->stand, from the stems' measures (docs/model.md,
 *  "Stands"). */
void sylva__stand(sylva_world *w);
/** Marks w->stand out of date (a planting): sylva_world_stand() finds the figures
 *  itself until the next sylva__stand(). */
void sylva__stand_stale(sylva_world *w);

/** Most cells of the canopy's floor grid. */
#define SYLVA__CANOPY_MAX_COLS (1 << 22)
/** The room in w->stem_top (int32s) the canopy pass needs for this many stems. */
size_t sylva__canopy_room(int stems);
/** Sets up the canopy's floor grid of a new world; 0 or SYLVA_ENOMEM. */
int sylva__canopy_init(sylva_world *w);
/** Every stem's crown_area and the world's canopy cover, from the leaf-bearing nodes
 *  as the next iteration counts them (as the stats do). */
void sylva__canopy(sylva_world *w);
/** A stem's carbon measures from its wood_volume, dbh and height; co2_sequestered
 *  against prev_co2, the co2 it had before (NaN: none). */
void sylva__stats_carbon(sylva_world *w, int stem, double prev_co2);
/** The measures an image does not hold, of a world just read from one: every stem's
 *  wood and carbon (co2_sequestered as the image gave it) and the canopy. */
void sylva__stats_loaded(sylva_world *w);

/** Grows a scratch vector to hold n elements; 0 or SYLVA_ENOMEM. */
int sylva__vec_reserve(void **data, size_t *cap, size_t n, size_t elem);
#define SYLVA__VEC_RESERVE(v, n) \
  sylva__vec_reserve((void **)&(v).data, &(v).cap, (n), sizeof *(v).data)

/** Local iteration of a stem at world iteration T (1 for its first). */
static inline int sylva__stem_local(const sylva__stem *s, int world_iteration) {
  return world_iteration - s->born;
}

/** c(T) of a stem's species at local iteration T (docs/model.md, "Cap" and "Species
 *  in years"). */
int sylva__species_cap(const sylva__species *sp, int local);
/* The cap of f times the leader's path: a shoot off the trunk with the reach f
 *  (allocate.c); f = 1 is c(T). */
int sylva__scaled_cap(const sylva__species *sp, int local, double f);
/** The cap of f times the leader's path over a season that takes the stem's clock
 *  from t0 to t1 (docs/model.md, "Stands"); with t1 = t0 + 1 = local, it is
 *  sylva__scaled_cap(sp, local, f). */
int sylva__clock_cap(const sylva__species *sp, double t0, double t1, double f);
/** Is the stem dead (docs/model.md, "Stands")? */
static inline bool sylva__stem_dead(const sylva__stem *st) { return st->stats.died >= 0; }
/** Does a stem of this species stop growing at local iteration T ("Stop")? */
bool sylva__species_stops(const sylva__species *sp, int local);
/** Height bins of the crown base's measure for a world of this height (stats.c). */
size_t sylva__crown_bins(double height);
/** Most pieces of the stats' parallel loop over stems, each with its crown bins. */
#define SYLVA__STATS_PIECES 64
/** Does the node at this depth carry a lateral bud? */
static inline bool sylva__has_bud(const sylva__species *sp, int32_t depth) {
  return depth % sp->bud_every == 0;
}

/** The age whose light node i's leaves collect at iteration T, or -1 when it bears
 *  none: its own age for its first leaf_age iterations; for a species in years, an
 *  axis's tip that has outlived those flushes anew each season, as a short shoot
 *  does (docs/model.md, "Species in years"). */
static inline int sylva__leaf_age(const sylva__skeleton *s, const sylva_species_def *d, size_t i,
                                  int T) {
  if (s->flags[i] & SYLVA__NODE_BARE) return -1; /* a dead stem's */
  int age = T - s->birth[i];
  if (age <= d->leaf_age) return age;
  return d->years && s->axis_child[i] < 0 ? 1 : -1;
}

/** The leaves node i carries now (sylva_node_info.leaves): its species' leaf_density
 *  while it bears leaves as the next iteration counts them, else 0. */
static inline int sylva__node_leaves(const sylva_world *w, size_t i) {
  const sylva_species_def *d = &w->species[w->stems[w->nodes.stem[i]].species].def;
  return sylva__leaf_age(&w->nodes, d, i, w->iteration + 1) >= 0 ? d->leaf_density : 0;
}

/** The one-sided leaf area one leaf-bearing node of species d carries, m^2. */
static inline double sylva__node_leaf_area(const sylva_species_def *d) {
  return (double)d->leaf_density * SYLVA_LEAF_FILL * d->leaf_size * d->leaf_size;
}

/** Does a node born at world iteration birth bear leaves at iteration T? It does
 *  for its first leaf_age iterations (docs/model.md, "Light"): only then does it
 *  collect light, and only then may its lateral bud sprout. */
static inline bool sylva__bears_leaves(const sylva_species_def *d, int32_t birth, int T) {
  return T - birth <= d->leaf_age;
}

/** Shade base b of a node born at a stem's local iteration t. */
double sylva__species_b(const sylva__species *sp, int t);
/** The shade cast by a node born at local iteration t, its table made up to t
 *  (sylva__species_shade_reserve); NULL when the table could not grow. Never NULL
 *  for a node whose shade was cast already: the table never shrinks, so taking a
 *  shade away needs no memory. */
const sylva__pyramid *sylva__species_shade(sylva__species *sp, int t);
/** age^sigma, cached. NaN on allocation failure is avoided by computing directly. */
double sylva__species_age_pow(sylva__species *sp, int age);
/** Makes the shade of local birth iterations up to t (one thread at a time);
 *  SYLVA_ENOMEM when the table could not grow. */
int sylva__species_shade_reserve(sylva__species *sp, int t);
/** The shade of local birth iteration t, made already (sylva__species_shade_reserve):
 *  safe on several threads at once. */
const sylva__pyramid *sylva__species_shade_at(const sylva__species *sp, int t);
/** The half-width of the widest (deepest) layer of each of the species' pyramids. */
int sylva__species_shade_reach(const sylva__species *sp);

/** Rounds p to the stored float position f and finds its voxel; false if outside. */
bool sylva__voxel_of(const sylva_world *w, const double p[3], float f[3], int v[3]);
/** Voxel of a slot's node (always inside the grid). */
void sylva__node_voxel(const sylva_world *w, int32_t slot, int v[3]);

/** The plant with this label, or -1. */
int sylva__find_plant(const sylva_world *w, const char *label);
/** Files plant p under its label; 0 or SYLVA_ENOMEM. */
int sylva__index_plant(sylva_world *w, int p);

/** Sizes the per-slot scratch arrays to the skeleton's capacity. */
int sylva__reserve_scratch(sylva_world *w);

/** Boundaries at which debug builds check the world's invariants. */
typedef enum sylva__boundary {
  SYLVA__BETWEEN_STEPS,    /* after a step, a failed step, a new plant or a load */
  SYLVA__AFTER_LIGHT,      /* phase 1 */
  SYLVA__AFTER_ALLOCATION, /* phases 2-3: the sprouts */
  SYLVA__AFTER_SHOOTS,     /* phase 4 and the room for the rest of the step */
  SYLVA__AFTER_RADII,      /* phase 5 */
  SYLVA__AFTER_SHEDDING    /* phase 6 */
} sylva__boundary;

/** Checks, in O(nodes + stems + plants), what must hold at a boundary: skeleton
 *  slots in order (parent below child) with links both ways, live counts, roots,
 *  occupancy, scratch sizes and the sprouts; aborts on the first broken one. */
void sylva__check_world(const sylva_world *w, sylva__boundary at);
#ifdef NDEBUG
#define SYLVA__CHECK_WORLD(w, at) ((void)0)
#else
#define SYLVA__CHECK_WORLD(w, at) sylva__check_world((w), (at))
#endif

/* Phases (one module each). */
/** Light pass: L by slot (if light != NULL) and Q of every node, at iteration T. */
void sylva__light_collect(sylva_world *w, int iteration, double *light);
/** Light pass at iteration T kept for T's light phase (sylva__light_kept): each node's
 *  L in q (light's block holds the sums, and each stem's light_next its Q, until the
 *  next phase that uses the block). Anything that changes the world's light before
 *  T's step sets light_at to 0 (docs/performance.md, "The light kept"). */
void sylva__light_keep(sylva_world *w, int iteration);
/** The light phase at T from the pass kept for it: L into w->light and Q into q, the
 *  values sylva__light_collect(w, T, w->light) gives; false (nothing done) when none
 *  is kept for T. */
bool sylva__light_kept(sylva_world *w, int iteration);
/** Each stem's light_next from Q by slot. */
void sylva__stems_light(sylva_world *w, const double *q);
/** Phases 2-3: fills w->sprouts for stems that grow at iteration T. */
int sylva__allocate(sylva_world *w, int iteration);
/** Phases 4-5: grows the sprouts stem by stem in w->order, shading after each shoot. */
int sylva__shoots(sylva_world *w, int iteration);
/** Adds (sign +1) or removes (-1) the shade of one node. Adding may fail
 *  (SYLVA_ENOMEM, the shade as it was); removing the shade a node cast never does. */
int sylva__shade_node(sylva_world *w, int32_t slot, int sign);
/** Pipe-model radii; records changes of nodes born before T. */
int sylva__radii(sylva_world *w, int iteration);
/** Shedding of dark lateral branches (needs a fresh light pass in q). */
int sylva__shed(sylva_world *w, int iteration);
/** Room for sylva__remove_doomed to remove every live node: its order (cells), their
 *  shade (stamps) and the lists of each thread's stamps on the world's pool. Made
 *  before the point after which a call cannot fail (reserve_rest, a prune, a new
 *  trunk's cuts); the skeleton and the pool must not grow before the removal. */
int sylva__reserve_removal(sylva_world *w);
/** Removes the doomed nodes: their shade on the world's threads,
 *  at once, then their voxels and slots, each counted in its stem's stats.pruned or
 *  stats.shed. Never fails: its room was reserved (sylva__reserve_removal). */
void sylva__remove_doomed(sylva_world *w, bool pruned);
/** Groups the live slots by stem, in slot order, into stem_nodes (stem k's from
 *  stem_nodes_first[k] to [k + 1]); room for both was reserved. */
void sylva__group_by_stem(sylva_world *w);
/** Per-stem measures into stems[].stats. */
void sylva__stats(sylva_world *w, int iteration);
/** Measures of a stem just planted (its vertical initial trunk), without a pass
 *  over the other stems' nodes. */
void sylva__stats_planted(sylva_world *w, int stem);
/** Every stem's leaf_area from its leaf-bearing nodes now, and every node's leaves as
 *  the last journal reported them (a world read from an image, which holds neither). */
void sylva__stats_leaf_area(sylva_world *w);
/** Adds a node: occupancy and skeleton; returns slot or a negative status. */
int32_t sylva__add_node(sylva_world *w, int32_t parent, bool lateral, const double p[3],
                        int32_t stem, int iteration);
#endif
