/* sylva server: stored runs for the command line: opening a store, creating a
 * run, and restoring a run's world at any stored iteration. Each prints its own
 * error ("sylva: ...") and returns an exit status (options.h). */
#ifndef SYLVA_SERVER_STORED_H
#define SYLVA_SERVER_STORED_H

#include <stdbool.h>
#include <stdint.h>

#include "grow.h"
#include "store.h"
#include "sylva/scenario.h"

/** Prints a store's warning (a damaged snapshot passed over) on stderr. */
void cli_store_warn(const char *msg);

/** Opens a store (create: a new file may be made). */
int cli_store_open(const char *path, bool create, store **out);

/** Opens (creating) the store at db, creates run `name` for scenario s with the
 *  job's planted world as iteration 0, and points job->st and job->run at it. */
int cli_store_new_run(const char *db, const char *name, const sylva_scenario *s, int limit,
                      grow_job *job);

/** For a command given --db and --name: checks both were given, opens the store
 *  (not creating it) and finds the run. On failure nothing stays open. */
int cli_open_run(const char *command, const char *db, const char *name, store **st,
                 store_run *out);

/** Finds run `name`; exit status 2 with a message when there is none. */
int cli_store_find(store *st, const char *db, const char *name, store_run *out);

/** The iteration of run r a command was asked for: `iteration` when given,
 *  otherwise the last stored one. Exit status 2 with a message naming the stored
 *  range when the run has no such iteration. */
int cli_stored_iteration(const char *db, const store_run *r, bool given, uint64_t iteration,
                         int *at);

/** The world of a stored run at iteration `at`: the newest good snapshot at or
 *  before it, regrown to `at`, each regrown iteration checked against the stored
 *  world hash. */
int cli_store_world_at(store *st, const store_run *r, int at, sylva_world **out);

#endif
