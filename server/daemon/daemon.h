/* sylva server: the daemon. One libuv loop; libwebsockets runs on it and serves
 * the viewer's files, the WebSocket protocol (/ws, sylva.v1) and a few HTTP
 * routes; runs grow off the loop thread, one iteration in flight per run.
 *
 * Ownership (libuv style): handles live inside these structs, back-links go
 * through handle->data, and memory is freed only in close callbacks. */
#ifndef SYLVA_SERVER_DAEMON_H
#define SYLVA_SERVER_DAEMON_H

#include <libwebsockets.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <uv.h>

#include "access.h"
#include "client.h"
#include "pool.h"
#include "store.h"
#include "sylva/protocol.h"
#include "sylva/world.h"

#ifdef SYLVA_VERSION
/** The version the daemon reports in its welcome. */
#define SYLVA_VERSION_TEXT SYLVA_VERSION
#else
#define SYLVA_VERSION_TEXT "unknown"
#endif

/** Largest client message, bytes (default). */
#define DAEMON_MAX_MESSAGE (1u << 20)
/** Most messages a client may send per second (default). */
#define DAEMON_RATE_LIMIT 50
/** Light slices that may wait for one run's world; more are refused busy. */
#define DAEMON_MAX_LIGHTS 16
/** Messages of this many bytes or more are parsed on a libuv thread, not the loop
 *  (a create of 70,000 stems, 755 KB, took the loop 70 ms to parse). */
#define DAEMON_PARSE_INLINE (64u << 10)
/** Most bytes waiting to be sent to one client before it is closed (default). */
#define DAEMON_MAX_PENDING (64u << 20)
/** Deltas kept per run for clients that resubscribe with "since". */
#define DAEMON_DELTA_HISTORY 64
/** Most bytes of deltas kept per run for resubscribers (older ones are dropped). */
#define DAEMON_HISTORY_BYTES (64u << 20)
/** Most cells of a light slice (its message is about 1.34 bytes a cell). */
#define DAEMON_MAX_SLICE (16ll << 20)
/** Threads of the run pool (default). */
#define DAEMON_WORKERS 2
/** The growth's and the exports' steps of niceness below the loop (default; pool.h):
 *  the loop's fan-out of a delta goes before the next iteration (docs/performance.md,
 *  "The live view"). */
#define DAEMON_WORK_NICE 10
/** Runs held, forks included (default). */
#define DAEMON_MAX_RUNS 64
/** Stems per world (default). */
#define DAEMON_MAX_STEMS 2000
/** Obstacles per world (default); an edit adds at most SYLVA_MSG_MAX_EDIT. */
#define DAEMON_MAX_OBSTACLES 10000
/** WebSocket clients at once (default; kept below the file-descriptor limit). */
#define DAEMON_MAX_CLIENTS 1000
/** Exports, history snapshots and forks at once (default). */
#define DAEMON_MAX_JOBS 2
/** Bytes of unfinished messages of all clients together (default). */
#define DAEMON_MAX_INPUT (64u << 20)
/** Milliseconds a message may take to arrive (default). */
#define DAEMON_MESSAGE_MS 10000
/** Memory budget of the runs' worlds, MiB (default). */
#define DAEMON_MEMORY_BUDGET_MIB 4096
/** Estimated memory of one full-grown stem: its shade and occupancy voxels and
 *  its nodes (measured: a stand of five trees of Table 2 peaks at 68 MiB). */
#define DAEMON_BYTES_PER_STEM (16u << 20)
/** Most origins given with --allow-origin. */
#define DAEMON_MAX_ORIGINS 16

/** Options of `sylva serve`. */
typedef struct server_options {
  const char *db;        /**< the store */
  const char *host;      /**< listen address */
  int port;              /**< listen port */
  const char *web;       /**< the viewer's files, or NULL */
  const char *scenarios; /**< ready scenarios offered to clients, or NULL */
  const char *token;     /**< required for every message and route but /healthz and
                              the static files (changing ones only with public_read),
                              or NULL */
  const char *start_scenario; /**< a scenario to grow at start unless its run exists */
  const char *origins[DAEMON_MAX_ORIGINS];
  int origin_count;
  const char *hosts[ACCESS_MAX_HOSTS]; /**< --allow-host names */
  int host_count;
  bool public_read;      /**< with a token, reading needs none */
  client_limits clients; /**< message size and rate, backlog, clients, input */
  int workers;           /**< threads of the run pool */
  int threads;           /**< threads every run's world grows on (0 or 1: one) */
  int work_nice;         /**< the growth's and the jobs' steps of niceness below the
                              loop (pool.h) */
  int max_runs;          /**< runs held (forks count) */
  int max_stems;         /**< stems per world */
  int max_obstacles;     /**< obstacles per world */
  int max_jobs;          /**< exports, histories and forks at once */
  size_t memory_budget;  /**< bytes the runs' worlds may take, by estimate */
  FILE *trace;           /**< --trace-iterations: a line per grown iteration, or NULL */
} server_options;


typedef struct run run;

/** The daemon. */
struct server {
  server_options opt;
  uv_loop_t loop;
  uv_signal_t sigint, sigterm;
  struct lws_context *ctx;
  store *st;
  run *runs;
  client_set clients;
  pool pool;             /**< the workers every run's tasks share */
  sylva_threads *threads; /**< the threads every world the daemon grows shares
                               (--threads), or NULL: each on its caller's */
  bool stopping;
  uint64_t stop_at;
  int64_t iterations_total;
  int64_t pruned_total; /* nodes pruned by schedules while growing */
  int jobs;              /**< exports, histories and forks running */
  size_t memory_reserved; /**< estimated memory of the runs held and being forked */
  int runs_pending;      /**< forks on their way */
  long fd_ceiling;       /**< connections on higher descriptors are refused */
  store *reader;         /**< a second connection, for the regrowing of jobs (WAL lets
                              it read while the first one writes) */
  double iteration_ms_total;
  access_rules access;   /**< Host, Origin and token checks */
};

/** What the daemon wants its token for (the welcome says it). */
sylva_auth server_auth(const server *d);

/** A log line that a flood could repeat (refused connections, accept errors): at
 *  most 10 a second get through, and the count of the others follows. */
void server_log_limited(const char *run_name, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/** One log line on stderr: "sylva: [run NAME] message". */
void server_log(const char *run_name, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/** Runs `sylva serve` with these options until SIGINT or SIGTERM; returns the
 *  exit status. */
int server_main(const server_options *opt);

#endif
