/* sylva server: the fixed pool of worker threads that every run's work shares
 * (iterations, edits, light slices, snapshots, loading at start). Tasks run in
 * the order they were submitted; a run has at most one task queued or running,
 * and submits its next one when the last is done, so the runs take turns
 * (round-robin) and none starves another. A task's done callback runs on the
 * loop thread. The exports and regrows of clients use libuv's own threadpool
 * (capped apart, see jobs in daemon.h), so they never hold up growing. The
 * workers, and the jobs that grow, run at a lower priority (nice) than the loop,
 * so that the loop's fan-out of a delta never waits behind the next iteration's
 * growth; a world's threads, made by them, inherit it. */
#ifndef SYLVA_SERVER_POOL_H
#define SYLVA_SERVER_POOL_H

#include <pthread.h>
#include <stdbool.h>
#include <uv.h>

#include "sylva/world.h"

typedef struct pool_task pool_task;

/** One piece of work: work runs on a worker, done on the loop (cancelled true
 *  when the pool dropped it unrun at shutdown). A task that has results before it
 *  is done reports them (pool_report): progress then runs on the loop, before
 *  done. */
struct pool_task {
  void (*work)(pool_task *t);
  void (*done)(pool_task *t, bool cancelled);
  void (*progress)(pool_task *t); /**< may be NULL when the task never reports */
  pool_task *next;
  pool_task *next_report;
  bool reported; /**< in the pool's report list (pool lock) */
};

typedef struct pool {
  pthread_t *threads;
  int count;
  pthread_mutex_t lock;
  pthread_cond_t wake;
  pool_task *queue, *queue_tail; /**< waiting, in order */
  pool_task *finished;           /**< done on a worker, waiting for the loop */
  pool_task *reports;            /**< running tasks with progress for the loop */
  int running;                   /**< tasks on workers now */
  bool stopping;
  int nice;                      /**< the workers' steps of niceness below the loop */
  uv_async_t async;              /**< wakes the loop for finished tasks */
} pool;

/** Starts count workers on the loop's side, each `nice` steps of niceness below the
 *  loop (pool_thread_nice); 0 or a negative errno (then nothing is left to stop or
 *  close). */
int pool_init(pool *p, uv_loop_t *loop, int count, int nice);
/** Sets the calling thread's niceness `steps` (0 to 19) above the main thread's, the
 *  loop's, at most 19: its own alone (Linux keeps one per thread, and the threads it
 *  starts inherit it). A system that refuses leaves it as it was: the same results,
 *  served less promptly. */
void pool_thread_nice(int steps);
/** The threads every run's world shares (sylva_threads_create, count of them), made
 *  by a thread `nice` steps below the loop, so that they run there too; NULL when the
 *  system gave none (every world then grows on its caller's thread: the same worlds). */
sylva_threads *pool_world_threads(int count, int nice);
/** Queues a task (loop thread). */
void pool_submit(pool *p, pool_task *t);
/** From the task's work, on its worker: has its progress callback run on the
 *  loop soon (once for any number of reports made before it runs). */
void pool_report(pool *p, pool_task *t);
/** Drops the queued tasks (their done gets cancelled = true, on the loop) and
 *  lets the running ones finish; the workers then exit. */
void pool_stop(pool *p);
/** Whether no task is running or waiting to be reported. */
bool pool_idle(pool *p);
/** Joins the workers and closes the handle (after pool_stop, once idle). */
void pool_close(pool *p);

#endif
