/* sylva server: the store's sweeps (docs/store.md, "Sweeps"). A sweep is named by
 * its plan; each of its runs is an ordinary run of the store, plus its place in the
 * sweep: its position in the plan's product and its value on every axis. */
#ifndef SYLVA_SERVER_SWEEP_STORE_H
#define SYLVA_SERVER_SWEEP_STORE_H

#include <stdbool.h>
#include <stdint.h>

#include "store.h"

/** One axis of a run's place: "seed", "variant", or "species/KEY". */
typedef struct store_axis {
  const char *axis;
  const char *value; /**< as text: a seed's digits, a variant's name, a preset's name
                          or a species object's compact JSON */
} store_axis;

/** Records (or replaces) run's place in the sweep named `sweep`, in one transaction;
 *  the sweep's plan (canonical JSON) is stored with its first run. */
int store_set_sweep_run(store *st, int64_t run, const char *sweep, const char *plan_json,
                        int position, const store_axis *axes, int n);

/** A swept run, as store_each_sweep_run gives it (valid during the call). */
typedef struct store_sweep_run {
  int64_t run;
  const char *name, *sweep;
  int position;
  bool finished;    /**< its status is finished */
  const char *reason; /**< "finished" (every stem), "limit", or NULL before it ended */
  int iterations;   /**< its iteration limit */
  int last_iteration; /**< its last stored iteration */
  const char *axes; /**< a compact JSON object, axis to value, in the plan's order */
} store_sweep_run;

/** Calls fn for every run of the sweep named `sweep` (NULL: of every sweep), in sweep
 *  then position order; fn returns 0 to go on. The store stays locked meanwhile. */
int store_each_sweep_run(store *st, const char *sweep,
                         int (*fn)(const store_sweep_run *r, void *ctx), void *ctx);

/** The stored plan of a sweep (malloc'd), or *plan NULL when the store has none. */
int store_sweep_plan(store *st, const char *sweep, char **plan);

/** What store_merge did, and whom it tells about the stores and runs it left out. */
typedef struct store_merge_report {
  int copied;     /**< runs copied */
  int kept;       /**< runs the store had already (merged before) */
  int unfinished; /**< runs left out because their task did not finish them */
  int missing;    /**< task stores that could not be read */
  void (*on_missing)(const char *path, const char *why, void *ctx);
  void (*on_unfinished)(const char *path, const char *run, int position, void *ctx);
  void *ctx;
} store_merge_report;

/** Merges the runs of sweep `sweep` from the task stores at paths[0..n) into st, in
 *  one transaction: every finished run st lacks (by name) is copied with its
 *  iterations, stats, commands and place; a run st has already is kept as it is, so
 *  merging twice changes nothing. A task store that cannot be read, and a run that
 *  is not finished, are reported through rep and left out; the rest is merged. */
int store_merge(store *st, const char *sweep, const char *plan_json, const char *const *paths,
                int n, store_merge_report *rep);

#endif
