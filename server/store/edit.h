/* sylva server: an edit of a run's world between iterations (add plants, add and
 * remove obstacles), as the store keeps it: the daemon makes one from a protocol
 * `edit` message, the command log (command_log.h) stores and reads it back. An
 * edit is applied all or nothing. */
#ifndef SYLVA_SERVER_EDIT_H
#define SYLVA_SERVER_EDIT_H

#include <stdbool.h>
#include <stddef.h>

#include "sylva/world.h"

/** A plant to add: its label, its species' label, its roots and its age. */
typedef struct edit_plant {
  char *id, *species;
  double (*roots)[3];
  int root_count;
  int age; /**< years at planting (0 to SYLVA_MAX_AGE); above 0 only for a
                species with years */
} edit_plant;

/** An obstacle to add: solid or a clearance zone, a box or a prism (its footprint's
 *  points and ring sizes owned, ring_count 0 for a box; sylva_obstacle_def). */
typedef struct edit_obstacle {
  char *id;
  double min[3], max[3];
  sylva_obstacle_kind kind;
  double (*points)[2];
  int *ring_sizes;
  int point_count, ring_count;
} edit_obstacle;

/** Copies a prism's footprint into o (SYLVA_ENOMEM or 0; nothing for a box). */
int edit_obstacle_footprint(edit_obstacle *o, const sylva_footprint *f);

/** Pruning now: of a zone (zone set) or of a box (zone NULL). */
typedef struct edit_prune {
  bool set;
  char *zone;
  double min[3], max[3];
} edit_prune;

/** One edit; every string and array is owned (edit_free). Applied in this order:
 *  removals, then obstacles, then plants, then the prune. */
typedef struct edit {
  char **removals; /**< ids of obstacles to remove */
  int removal_count;
  edit_obstacle *obstacles;
  int obstacle_count;
  edit_plant *plants;
  int plant_count;
  edit_prune prune;
} edit;

/** Sizes the arrays of a zeroed edit (their elements zeroed); SYLVA_ENOMEM or 0.
 *  On failure what was allocated stays for edit_free. */
int edit_reserve(edit *e, int removals, int obstacles, int plants);
/** Frees what an edit owns and zeroes it. */
void edit_free(edit *e);

/** Makes *out, a copy of w with the edit applied, on the threads of w, and returns
 *  0. On failure w is untouched, err names what and where
 *  ("/add_plants/1/roots/0: root inside an obstacle") and the status is negative
 *  (SYLVA_ENOMEM when memory ran out, SYLVA_EINVAL for an edit that does not fit
 *  the world). */
int edit_apply(const sylva_world *w, const edit *e, sylva_world **out, char *err,
               size_t errlen);
#endif
