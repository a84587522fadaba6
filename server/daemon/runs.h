/* sylva server: the runs the daemon holds: loading them from the store, creating
 * and forking them, growing them off the loop thread (one iteration in flight per
 * run), and sending each delta, encoded once, to every subscriber. */
#ifndef SYLVA_SERVER_RUNS_H
#define SYLVA_SERVER_RUNS_H

#include "client.h"
#include "daemon.h"
#include "sylva/protocol.h"
#include "sylva/scenario.h"

/** A run the daemon holds. */
struct run {
  server *d;
  int64_t id;       /**< the store's run id, also the protocol's "run" */
  char *name;
  sylva_world *w;   /**< owned; touched by the worker while busy */
  sylva_run_status status;
  int limit;        /**< iteration limit */
  int snapshot_every;
  int steps;        /**< iterations still wanted while paused (control step) */
  int64_t seq;      /**< sequence number of the last delta */
  int iteration, stems; /**< summary as of the last finished iteration (the */
  int64_t nodes;        /**< world may be mid-step on a worker) */
  bool busy;        /**< an iteration is in flight */
  bool stop_after;  /**< stop requested while busy */
  uv_work_t work;
  /* result of the worker */
  int work_status;
  char work_error[512];
  char *work_delta;  /**< encoded delta (malloc'd) */
  double work_ms;
  msgbuf *history[DAEMON_DELTA_HISTORY]; /**< the last deltas, by seq % size */
  struct pending_edit *edits;   /**< edits waiting for the iteration in flight (runs.c) */
  struct pending_light *lights; /**< light requests waiting for it (runs.c) */
  msgbuf *snapshot;          /**< the snapshot of seq `snapshot_seq`, shared by subscribers */
  int64_t snapshot_seq;
  run *next;
};

/** Loads every stored run; runs that were running continue. SERVER_OK, or a
 *  server_error (logged). */
int runs_load(server *d);
/** Frees every run (the loop must have no work in flight). */
void runs_free(server *d);
/** The run with this id, or NULL. */
run *run_find(server *d, int64_t id);
/** The run named by the len bytes at name, or NULL. */
run *run_find_name(server *d, const char *name, size_t len);
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
/** The JSON of every run: a `runs` message (message true, with ref) or the array
 *  of GET /api/runs; malloc'd, NULL when memory ran out. */
char *runs_json(server *d, bool message, const char *ref);
#endif
