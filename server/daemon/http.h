/* sylva server: the daemon's HTTP routes: /healthz, /metrics, /api/runs,
 * /api/runs/NAME/stats.csv, /api/runs/NAME/export, /api/runs/NAME/shade,
 * /api/scenarios/NAME and /api/sweeps/NAME/report.(csv|html|pdf).
 *
 * Every reply goes out from LWS_CALLBACK_HTTP_WRITEABLE: the headers in one
 * callback, then the body in chunks, from memory or from a file. An export (and
 * stats.csv, its CSV), a shade layer (shade_json.h) and a sweep's report (which
 * regrow worlds) are written off the loop thread into a tmpfile() by an http_job, on libuv's
 * threadpool under --max-jobs (the store locks itself). The connection waits
 * for it without an lws timeout; a timer closes it when the client leaves. The
 * job may outlive its connection: it is detached when the connection closes
 * (LWS_CALLBACK_HTTP_DROP_PROTOCOL, LWS_CALLBACK_CLOSED_HTTP, also when the
 * daemon stops), and its after-work callback frees its result. */
#ifndef SYLVA_SERVER_HTTP_H
#define SYLVA_SERVER_HTTP_H

#include <libwebsockets.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

/** Seconds a reply may make no progress before lws closes the connection. */
#define HTTP_TIMEOUT_SECS 30

typedef struct http_job http_job;

/** The state of one HTTP transaction (lws allocates it zeroed per transaction). */
typedef struct http_pss {
  unsigned status;     /**< of the reply; 0 while there is none yet */
  const char *type;    /**< its content type */
  char disposition[320]; /**< a Content-Disposition value, or "" */
  bool headers_sent;
  bool challenge;      /**< a 401: send WWW-Authenticate: Bearer */
  char *body;          /**< the body in memory (malloc'd), or NULL */
  FILE *file;          /**< or in a file (an export's or report's tmpfile) */
  size_t len, off;     /**< body length and how much went out */
  http_job *job;       /**< the export or report being written for this transaction */
} http_pss;

/** The callback of the "http" protocol. */
int http_callback(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in,
                  size_t len);

#endif
