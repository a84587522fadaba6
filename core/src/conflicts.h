/* Zones entered, clearances and pruning (conflicts.c). */
#ifndef SYLVA_CONFLICTS_H
#define SYLVA_CONFLICTS_H

#include "world_impl.h"

/** True when the world reports conflicts (sylva_world_reports_conflicts) and has
 *  anything to report: obstacles, or zones entered before. */
bool sylva__conflicts_any(const sylva_world *w);
/** Finds, for stems from first_stem on, the obstacles near them, and makes room for
 *  their conflicts (zone lines, clearances, zones entered). 0 or SYLVA_ENOMEM, which
 *  changes nothing that sylva__conflicts reads until the next reserve. */
int sylva__conflicts_reserve(sylva_world *w, int first_stem);
/** The conflicts of the stems of the last reserve, at iteration T; never fails. The
 *  nodes may only have been removed since the reserve. */
void sylva__conflicts(sylva_world *w, int T);
/** Reserve, then conflicts at the current iteration. */
int sylva__conflicts_update(sylva_world *w, int first_stem);
/** Appends a (stem, zone, first) pair read from a snapshot, in order; SYLVA_EINVAL
 *  out of order, SYLVA_ENOMEM. */
int sylva__entered_add(sylva_world *w, int32_t stem, int32_t zone, int32_t first);
/** Removes every node inside box (a box [min, max], or a zone's prism) and its subtree
 *  (roots stay), counting them in the stems' stats.pruned. The subtrees' root ids go
 *  to roots (room for every node); with announced_only, those born at T are left out.
 *  Returns the nodes removed; their slots stay dead until compaction. Never fails. */
size_t sylva__prune(sylva_world *w, const sylva__obstacle *box, int T, bool announced_only,
                    int32_t *roots, size_t *root_count);
/** Removes every node (not a root) whose voxel is one of voxels[0..n) and its subtree,
 *  as sylva__prune does. */
size_t sylva__cut_voxels(sylva_world *w, int (*voxels)[3], size_t n, int T, int32_t *roots,
                         size_t *root_count);
/** Does a schedule prune at iteration T? */
bool sylva__prune_due(const sylva_prune_def *d, int T);
#endif
