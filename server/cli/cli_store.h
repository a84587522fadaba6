/* sylva server: stored runs for the command line: opening a store, creating a
 * run, finding a run and one of its iterations. Each prints its own error
 * ("sylva: ...") and returns an exit status (options.h). */
#ifndef SYLVA_SERVER_CLI_STORE_H
#define SYLVA_SERVER_CLI_STORE_H

#include <stdbool.h>
#include <stdint.h>

#include "grow.h"
#include "store.h"
#include "sylva/scenario.h"

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

/** The world of run r at iteration `at`, damaged snapshots warned of; on failure
 *  prints "sylva: run \"NAME\": why" and returns CLI_EXIT_FAILURE. */
int cli_store_world_at(store *st, const store_run *r, int at, sylva_world **out);

/** Prints a store's warning (a damaged snapshot passed over): "sylva: warning: ...". */
void cli_store_warn(const char *msg);

#endif
