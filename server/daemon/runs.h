/* sylva server: the runs the daemon holds: loading them from the store, creating
 * and forking them, and their work off the loop thread (iterations, edits, light
 * slices, snapshots: one task at a time per run, on the shared pool), and
 * sending each delta and snapshot, encoded once, to every subscriber. */
#ifndef SYLVA_SERVER_RUNS_H
#define SYLVA_SERVER_RUNS_H

#include <pthread.h>
#include <stdatomic.h>

#include "client.h"
#include "daemon.h"
#include "pool.h"
#include "sylva/protocol.h"
#include "sylva/scenario.h"

/** What a run's worker is doing. */
typedef enum run_task {
  RUN_TASK_NONE,
  RUN_TASK_LOAD,     /**< restoring the world from the store (at start) */
  RUN_TASK_STEP,     /**< one iteration, stored, its delta encoded */
  RUN_TASK_EDIT,     /**< the oldest pending edit, applied and stored */
  RUN_TASK_LIGHT,    /**< the oldest pending light slice, encoded */
  RUN_TASK_SNAPSHOT, /**< the snapshot of the current seq, encoded */
} run_task;

/** Iterations one step task may take in a row (RUN_TASK_STEP), and how long it
 *  may go on taking more (ms): each one's delta goes to the loop as soon as it is
 *  made, and the worker goes on without waiting for the loop, unless the loop
 *  asks it to stop (run.yield). The run then goes back to the end of the pool's
 *  queue, behind the other runs' tasks. */
#define RUN_AHEAD 16
#define RUN_SLICE_MS 100.0

/** One iteration of a step task, as the worker made it. */
/** What /metrics shows of a run's conflicts (sylva_world_reports_conflicts). */
typedef struct run_conflicts {
  bool reported;
  int64_t zone_nodes; /**< nodes inside clearance zones now, all stems */
  int64_t entered;    /**< (stem, zone) pairs that ever met */
} run_conflicts;

typedef struct step_result {
  int status;        /**< SYLVA_OK or why it failed */
  char error[256];
  char *text[SYLVA_DETAIL_COUNT]; /**< the encoded delta at each detail that was wanted
                                       (malloc'd; NULL when not wanted or out of memory) */
  bool snapshot_due; /**< its snapshot is to be added to its stored row (work_step) */
  double ms;
  double at_ms[3];   /**< CLOCK_MONOTONIC ms when the step returned, when it was
                          stored and when its delta was encoded (--trace-iterations) */
  /* the world's summary after it */
  int iteration, stems, obstacles;
  int64_t nodes;
  bool finished;
  run_conflicts conflicts;
  int64_t pruned; /**< nodes the iteration's pruning schedules removed */
} step_result;

/** A run the daemon holds. Its world is touched only by its task, one at a time
 *  on the shared pool (pool.h); the loop reads the summary fields. */
struct run {
  server *d;
  int64_t id;       /**< the store's run id, also the protocol's "run" */
  char *name;
  sylva_world *w;   /**< owned; NULL while not in memory (or loading); the worker's
                         while busy */
  sylva_run_status status;
  bool loading;     /**< being restored from the store */
  uint64_t used;    /**< loop time (ms) a client or a task last needed it: the least
                         recently used idle run is unloaded first */
  int limit;        /**< iteration limit */
  int start_year;   /**< the scenario's calendar year of iteration 0; 0: none */
  int snapshot_every;
  int steps;        /**< iterations still wanted while paused (control step) */
  int64_t seq;      /**< sequence number of the last delta or edit */
  /* summary as of the last finished task (the world may be busy on a worker) */
  int iteration, stems, obstacles;
  int64_t nodes;
  bool finished;    /**< the growth equations ended every stem */
  run_conflicts conflicts;
  /* its place in a sweep of the store (sweep_store.h), as of the daemon's start:
   * sweep NULL for a run of no sweep */
  char *sweep;
  int position;
  char *axes;       /**< the store's compact JSON object, axis to value */
  size_t estimate;  /**< its share of the memory budget (runs_estimate) */
  bool busy;        /**< a task is queued or running */
  bool stop_after;  /**< stop requested while busy */
  bool finish_pending; /**< its last iteration is sent; finished once its step task is
                            done (the snapshot stored, runs.c task_done) */
  pool_task task;
  run_task kind;
  /* a step task's iterations: the worker fills results[made++] (under lock); the
   * loop takes them in order (taken) */
  int batch_max;        /**< iterations this task may take (set before it runs) */
  int64_t batch_seq;    /**< seq before its first delta */
  atomic_bool yield;    /**< the loop wants the world: stop after this iteration */
  pthread_mutex_t lock;
  int made, taken;
  step_result results[RUN_AHEAD];
  /* the task's results */
  int task_status;     /**< SYLVA_OK or why it failed */
  char task_error[512];
  char snapshot_error[512]; /**< a step task: why a due snapshot was not stored ("": it was) */
  const char *task_code; /**< the protocol error code of a failed edit */
  char *task_text;     /**< an encoded slice (malloc'd) */
  bool task_details[SYLVA_DETAIL_COUNT]; /**< a snapshot task: the details to encode */
  char *task_snapshots[SYLVA_DETAIL_COUNT]; /**< and their texts (malloc'd) */
  /* the details whose deltas the worker encodes: those of the subscribers, as the
   * loop last counted them (note_wanted, runs.c) */
  atomic_bool want[SYLVA_DETAIL_COUNT];
  sylva_world *task_world; /**< an edited or loaded world */
  int64_t task_edits;  /**< loading: the edits logged since the run began */
  double task_ms;
  msgbuf *history[DAEMON_DELTA_HISTORY]; /**< the last deltas, by seq % size */
  struct pending_edit *edits;   /**< edits waiting for their task (runs.c) */
  struct pending_light *lights; /**< light requests waiting for theirs (runs.c) */
  /* the snapshot of seq `snapshot_seq` at each detail, shared by subscribers */
  msgbuf *snapshot[SYLVA_DETAIL_COUNT];
  int64_t snapshot_seq[SYLVA_DETAIL_COUNT];
  run *next;
};

/** Lists every stored run and restores the worlds of those that were running on
 *  the pool, as many as the memory budget holds (they are listed as loading
 *  meanwhile, and continue once loaded). The other runs stay in the store until a
 *  client needs their world. SERVER_OK, or a server_error (logged) when the store
 *  cannot list them.
 *
 *  A run's world is in memory while it grows, has subscribers or work waiting;
 *  when the budget is needed for another, the least recently used run that needs
 *  none of this goes back to the store (unloaded) and loads again on demand. */
int runs_load(server *d);
/** Queues the loading of a run not in memory, when the budget has room for it
 *  (after unloading idle runs); NULL, or why not (buf). */
const char *run_load(run *r, char *buf, size_t size);
/** NULL when the run's world is in memory and loaded; else starts loading it and
 *  returns what to tell the client (busy: loading, or the budget is full). */
const char *run_ready(run *r, char *buf, size_t size);
/** Loads the runs that wait for memory to grow, as far as the budget now allows. */
void runs_wake(server *d);
/** Frees every run (the loop must have no work in flight). */
void runs_free(server *d);
/** The run with this id, or NULL. */
run *run_find(server *d, int64_t id);
/** The run named by the len bytes at name, or NULL. */
run *run_find_name(server *d, const char *name, size_t len);
/** Creates a run from a parsed scenario, off the loop: checks the caps and the
 *  budget now, and when they allow it takes the scenario (*s becomes NULL) and
 *  returns NULL; the world is built and stored on a libuv thread, and the client
 *  (NULL: the daemon's own --run, logged) gets `created` or an error then (the
 *  run counts against --max-runs and the budget meanwhile). Otherwise returns
 *  the protocol error code, and err says why. */
const char *run_create(server *d, client *c, sylva_scenario **s, const char *name, bool start,
                       const char *ref, char *err, size_t errlen);
/** Starts the next iteration if the run wants one and none is in flight. */
void run_schedule(run *r);
/** Sends the client what a new subscription needs: a snapshot, or the deltas after
 *  `since` when they are all still held. */
void run_subscribe(run *r, client *c, bool has_since, int64_t since, sylva_detail detail,
                   const char *ref);
/** Sets status (running, paused, finished) and tells the subscribers. */
void run_set_status(run *r, sylva_run_status status);
/** A `control` action (count: the steps of SYLVA_CONTROL_STEP); returns NULL or
 *  the message of a refusal. */
const char *run_control(run *r, sylva_control_action action, int count);
/** A client left: its light slices not started yet are dropped (its edits are
 *  still made: they were asked for), and runs waiting for memory may load. */
void runs_forget_client(server *d, uint64_t serial);
/** At stop: every step task ends after its iteration in flight. */
void runs_halt(server *d);
/** Whether a task of some run is running (the daemon waits for them at stop). */
bool runs_busy(server *d);
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
/** The estimated memory of a world of `stems` stems once grown: a full-grown
 *  stem's DAEMON_BYTES_PER_STEM each, at most the grid of the whole world box. */
size_t runs_estimate(const sylva_world *w, int stems);
/** The same estimate for the world a scenario would build. */
size_t runs_estimate_scenario(const sylva_scenario *s);

/** NULL when the daemon may hold another run of this estimate (the run cap, the
 *  memory budget), else why not (the protocol code is then "busy"). */
const char *runs_room(server *d, size_t estimate, char *buf, size_t size);

/** NULL when another export, history snapshot or fork may start now (--max-jobs),
 *  else why not. */
const char *runs_job_room(server *d);

/** The JSON of every run: a `runs` message (message true, with ref) or the array
 *  of GET /api/runs; malloc'd, NULL when memory ran out. */
char *runs_json(server *d, bool message, const char *ref);
#endif
