/* sylva server: the runs the daemon holds: loading them from the store, creating
 * and forking them, growing them off the loop thread (one iteration in flight per
 * run), and sending each delta, encoded once, to every subscriber. */
#ifndef SYLVA_SERVER_RUNS_H
#define SYLVA_SERVER_RUNS_H

#include "client.h"
#include "daemon.h"
#include "sylva/protocol.h"
#include "sylva/scenario.h"

/** Loads every stored run; runs that were running continue. 0 or -1 (logged). */
int runs_load(server *d);
/** Frees every run (the loop must have no work in flight). */
void runs_free(server *d);
/** The run with this id, or NULL. */
run *run_find(server *d, int64_t id);
/** Creates a run from a parsed scenario; on failure err says why (and *code is a
 *  protocol error code). */
run *run_create(server *d, const sylva_scenario *s, const char *name, bool start,
                const char **code, char *err, size_t errlen);
/** Starts the next iteration if the run wants one and none is in flight. */
void run_schedule(run *r);
/** Sends the client what a new subscription needs: a snapshot, or the deltas after
 *  `since` when they are all still held. */
void run_subscribe(run *r, client *c, bool has_since, int64_t since, const char *ref);
/** Sets status (running, paused, finished) and tells the subscribers. */
void run_set_status(run *r, sylva_run_status status);
/** Sends a status message to every subscriber of the run. */
void run_broadcast_status(run *r);
/** Applies an edit between iterations (now, or after the iteration in flight):
 *  takes the parsed message (m is emptied); the store logs it in the command log's
 *  own format. */
void run_edit(run *r, client *c, sylva_msg *m);
/** Forks run r at its stored iteration into a new paused run named `name`, off the
 *  loop; the client gets `created` (or an error). */
void run_fork(run *r, client *c, int iteration, const char *name, const char *ref);
/** Sends the client the light slice at height z of the run's world: now, or when
 *  the iteration in flight is done. */
void run_light(run *r, client *c, double z, const char *ref);
/** Sends the client a snapshot of stored iteration `iteration`, off the loop. */
void run_get(run *r, client *c, int iteration, const char *ref);
/** The run's current summary for `list` and /api/runs. */
void run_summary(const run *r, int64_t *nodes, int *iteration, int *stems);
#endif
