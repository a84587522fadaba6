/* libsylva-import: a cylinder model turned into a sylva tree. The cylinders are
 * resampled to internodes of the species' rho, each node given an estimated birth
 * year (the developmental model of docs/model.md, "Measured trees"), so that the
 * tree N years before its measurement is the set of nodes born by then.
 *
 * The rules, in the order sylva_tree_build applies them (docs/cli.md, "import"):
 *
 * - Pieces. Cylinders with parent -1 are roots. The lowest root's start is the
 *   ground; a root whose start is at most 0.5 m above it and inside the horizontal
 *   bounding box of the lowest root's piece (its footprint) is a stem of its own.
 *   Every other root and its cylinders (TreeQSM's disconnected fragments, usually
 *   floating in the crown) is dropped and counted in pieces_dropped.
 * - Axes. A cylinder continues its parent's axis when it is the parent's first
 *   child, in file order, whose branch number equals the parent's; when the file
 *   gives no branch numbers (all 0), the child whose axis is closest in direction
 *   to the parent's. Every other child starts a branch, an axis of its own.
 * - Resampling. Each axis is walked from its first cylinder's start to its last
 *   cylinder's end along the line through its joints (a joint: the midpoint of one
 *   cylinder's end and the next one's start, which in TreeQSM's models are rarely the
 *   same point), a point put every rho of arc length, the remainder carried across
 *   joints; a point takes the radius of the cylinder whose stretch it lies on. The
 *   axis's end is always a node: a point closer than SYLVA_TREE_MERGE to the end is
 *   left out for it. A stem's first axis keeps its start as the stem's root node; a
 *   branch starts at its first point at rho.
 * - Branches. A branch's first node is the lateral child of the node of its parent
 *   axis nearest (in space) to the branch's start, so that the first internode
 *   bridges TreeQSM's gap between a branch's first cylinder and its parent. A node
 *   holds one lateral: when the nearest is taken, the nearest free node of the same
 *   axis is used (laterals_moved); when that axis has none free, the nearest free
 *   node of the stem placed so far (laterals_off_axis). Branches are attached in
 *   axis order: a stem's axes breadth first, each axis's branches from its base up
 *   and siblings in file order.
 * - Births: see sylva_tree_build.
 *
 * Coordinates are the file's, translated so that the first stem's root lands at
 * options->base. */
#ifndef SYLVA_IMPORT_TREE_H
#define SYLVA_IMPORT_TREE_H

#include <stddef.h>

#include "qsm.h"

/** Points of an axis closer than this to its end (m) are merged with the end node. */
#define SYLVA_TREE_MERGE 1e-4
/** A root at most this far above the lowest root's start (m) may be a stem. */
#define SYLVA_TREE_STEM_RISE 0.5
/** Most nodes a tree may have (a rho far below the cylinders' lengths). */
#define SYLVA_TREE_MAX_NODES ((size_t)50000000)

/** One internode's end: a node of the imported tree. Nodes are in parent-before-child
 *  order; parent -1 marks a stem's root (one per stem). A stem's nodes are contiguous,
 *  its root first, stems in the order of their roots in the file. Each node has at
 *  most one axis child (its axis goes on) and at most one lateral child (a branch
 *  starts), as sylva's skeleton holds them. */
typedef struct sylva_tree_node {
  double p[3];   /**< metres, the plant's root at `base` */
  double radius; /**< metres: of the internode that ends here (the root: its cylinder's) */
  int parent;
  int lateral;   /**< 1 when the node starts a branch off its parent's axis */
  int birth;     /**< estimated: years before the measurement, as 0 or a negative number */
} sylva_tree_node;

/** How to build the tree. */
typedef struct sylva_tree_options {
  double rho;     /**< internode length, m (> 0) */
  double base[3]; /**< where the tree's first root is placed */
  /** The species' height over age (m), heights[a] at age a for a = 0..years, never
   *  decreasing, heights[age] > 0. NULL: no curve; every node is born at 0. */
  const double *heights;
  int years;
  /** The tree's age at the measurement, years (0..years with a curve); 0: the first
   *  age a at which heights[a] reaches the tree's height, or `years` if none does. */
  int age;
  double pipe_exponent; /**< for the radii of earlier stages (sylva_tree_stage) */
} sylva_tree_options;

/** An imported tree. Owned: free with sylva_tree_free. */
typedef struct sylva_tree {
  sylva_tree_node *node;
  size_t count;
  int stems;             /**< roots */
  int age;               /**< the tree's age at the measurement, years */
  double base[3];        /**< options->base: the first root's position */
  size_t cylinders;      /**< cylinders of the kept pieces */
  size_t pieces_dropped; /**< disconnected pieces left out (docs/cli.md, "import") */
  size_t cylinders_dropped; /**< their cylinders */
  size_t laterals_moved;    /**< branches moved to a free node of the same axis */
  size_t laterals_off_axis; /**< branches put on a node of another axis (none free) */
  double cylinder_volume;   /**< m^3, sum of pi r^2 l over the kept cylinders */
  /* the summary line of `sylva import` */
  /** m: highest node above the base; m: 2 x the radius of the first stem's main
   *  axis's internode that reaches 1.3 m above the base (NaN if it never does);
   *  m^3: sum of pi r^2 |internode| (r its end node's radius); m: sum of the
   *  internodes' lengths */
  double height, dbh, volume, length;
  int branches;  /**< lateral axes: nodes with lateral = 1 */
  int max_order; /**< deepest branch order (0: a trunk alone) */
} sylva_tree;

/** Frees t's nodes and zeroes it. */
void sylva_tree_free(sylva_tree *t);

/** Builds the tree from a checked q (sylva_qsm_check) by the rules above, then
 *  estimates every node's birth year from the path length to the tips: with d(n) the
 *  longest path from n down its subtree to a tip (0 at a tip), H the tree's height and
 *  the height curve scaled by H / heights[age] so that it reaches H at the tree's age,
 *  a node is born in the first year t (0..age) at which the scaled curve reaches
 *  H - d(n); birth = t - age. Tips are born at 0, the base (and anything below the
 *  scaled curve's start, the planted tree) at -age; births never decrease from parent
 *  to child. Returns 0 with *t filled (any earlier content is not freed), or a
 *  negative status with a message in err: SYLVA_EINVAL for bad options or an empty
 *  model, SYLVA_ETOOBIG for too many nodes, SYLVA_ENOMEM. On failure t is empty. */
int sylva_tree_build(const sylva_qsm *q, const sylva_tree_options *o, sylva_tree *t, char *err,
                     size_t errlen);

/** The stage `years_before` (0..t->age) years before the measurement: the nodes born
 *  by then (birth <= -years_before; a subset closed under parents) in the same order,
 *  their births shifted by years_before so that the stage's own season is 0, its age
 *  t->age - years_before, radii by the pipe model from that stage's tips (each node's
 *  measured radius times (tips then / tips now)^(1 / pipe_exponent)) and the summary
 *  recomputed, so that stage 0 is the tree itself, radii bit for bit. Writes it to out
 *  (freed first; out may not be t). 0, SYLVA_ERANGE for years_before outside
 *  0..t->age or a pipe_exponent not above 0, or SYLVA_ENOMEM (out then empty). */
int sylva_tree_stage(const sylva_tree *t, int years_before, double pipe_exponent,
                     sylva_tree *out);

/** The summary fields (height .. max_order) of t's nodes, recomputed; 0 or
 *  SYLVA_ENOMEM. */
int sylva_tree_summarise(sylva_tree *t);

#endif
