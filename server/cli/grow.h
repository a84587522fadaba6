/* sylva server: the headless growing loop shared by `run` and `resume`: step,
 * print the stats line, store the iteration, show progress, and end with the
 * done line. */
#ifndef SYLVA_SERVER_GROW_H
#define SYLVA_SERVER_GROW_H

#include <stdbool.h>
#include <stdint.h>

#include "store.h"
#include "sylva/world.h"

/** One headless run. */
typedef struct grow_job {
  const char *label;  /**< names the run in messages (a path or a run name) */
  sylva_world *w;
  int threads;        /**< grow w on this many threads (0: as it is) */
  int limit;          /**< the iteration limit */
  bool progress;      /**< show a progress bar on stderr */
  bool silent;        /**< print no stats or done lines on stdout */
  store *st;          /**< NULL: not stored */
  int64_t run;        /**< the stored run */
  int snapshot_every; /**< iterations between full snapshots when stored */
  int start_year;     /**< the scenario's start_year (0: none): the lines' calendar */
  const char *reason; /**< out: "finished" or "limit" when it ended well */
} grow_job;

/** Grows w on `threads` threads (sylva_world_set_threads); when the system gives
 *  fewer, warns on stderr and grows it on one, the same world. */
void grow_set_threads(sylva_world *w, int threads);

/** Grows until every stem finished or the limit, on job->threads threads, printing
 *  one line per iteration and the done line (unless silent); stores every iteration
 *  when job->st is set (a full snapshot every snapshot_every iterations and at the
 *  end). Returns the exit status. */
int grow_run(grow_job *job);

/** Prints a line and a newline to stdout and flushes; false on a write error. */
bool grow_put_line(const char *line);

#endif
