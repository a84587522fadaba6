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
  size_t max_message;
  int rate_limit;
  size_t max_pending;
  int workers;           /**< threads of the run pool */
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
  bool stopping;
  uint64_t stop_at;
  int64_t iterations_total;
  double iteration_ms_total;
  access_rules access;   /**< Host, Origin and token checks */
};

/** What the daemon wants its token for (the welcome says it). */
sylva_auth server_auth(const server *d);

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
