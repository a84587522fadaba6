/* sylva server: a stored run's world at any of its iterations, for the command
 * line and the daemon alike: the newest good snapshot at or before it, regrown
 * with the run's command log replayed, each regrown iteration checked against the
 * stored world hash. */
#ifndef SYLVA_SERVER_REPLAY_H
#define SYLVA_SERVER_REPLAY_H

#include "store.h"
#include "sylva/world.h"

/** Prints a store's warning (a damaged snapshot passed over) on stderr. */
void store_warn_stderr(const char *msg);

/** The world of run r at iteration `at`, warnings on stderr. On failure prints
 *  "sylva: run \"NAME\": why" and returns SERVER_EFAIL; SERVER_OK and *out on
 *  success. */
int store_world_at_logged(store *st, const store_run *r, int at, sylva_world **out);

#endif
