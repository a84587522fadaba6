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

#include "store.h"
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
/** Most origins given with --allow-origin. */
#define DAEMON_MAX_ORIGINS 16

/** Options of `sylva serve`. */
typedef struct server_options {
  const char *db;        /**< the store */
  const char *host;      /**< listen address */
  int port;              /**< listen port */
  const char *web;       /**< the viewer's files, or NULL */
  const char *scenarios; /**< ready scenarios offered to clients, or NULL */
  const char *token;     /**< required for changing messages, or NULL */
  const char *start_scenario; /**< a scenario to grow at start unless its run exists */
  const char *origins[DAEMON_MAX_ORIGINS];
  int origin_count;
  size_t max_message;
  int rate_limit;
  size_t max_pending;
} server_options;

/** A message encoded once and shared by every client it goes to. */
typedef struct msgbuf {
  int refs;
  size_t len;
  unsigned char data[]; /* LWS_PRE bytes of headroom, then len bytes */
} msgbuf;

/** Wraps text (len bytes) in a new shared buffer with one reference. */
msgbuf *msgbuf_new(const char *text, size_t len);
/** Takes and drops references. */
msgbuf *msgbuf_ref(msgbuf *m);
void msgbuf_unref(msgbuf *m);

typedef struct server server;
typedef struct client client;
typedef struct run run;

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
  struct pending_edit *edits; /**< edits waiting for the iteration in flight */
  struct pending_light *lights; /**< light requests waiting for the iteration in flight */
  msgbuf *snapshot;          /**< the snapshot of seq `snapshot_seq`, shared by subscribers */
  int64_t snapshot_seq;
  run *next;
};

/** The daemon. */
struct server {
  server_options opt;
  uv_loop_t loop;
  uv_signal_t sigint, sigterm;
  uv_timer_t closer;     /**< runs the closes clients asked for, outside lws callbacks */
  struct lws_context *ctx;
  store *st;
  uv_mutex_t store_lock; /**< one transaction at a time on the one connection */
  run *runs;
  client *clients;
  bool stopping;
  uint64_t stop_at;
  int64_t clients_now, iterations_total, bytes_sent, messages_received;
  double iteration_ms_total;
  char origin_self[2][128]; /**< http://HOST:PORT forms the daemon accepts as its own */
};

/** Makes the loop apply pending client closes soon (from outside lws callbacks). */
void server_schedule_closes(server *d);
/** Milliseconds of the loop's clock. */
uint64_t server_now_ms(server *d);
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
