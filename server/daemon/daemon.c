/* The daemon: the loop, libwebsockets on it (HTTP routes: http.c), WebSocket sessions,
 * signals and an orderly shutdown. */
#include "daemon.h"

#include <errno.h>
#include <malloc.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include <cairo.h>
#include <fontconfig/fontconfig.h>

#include "client.h"
#include "handlers.h"
#include "http.h"
#include "files.h"
#include "runs.h"
#include "sylva/json_check.h"
#include "sylva/protocol.h"

static void log_line(const char *run_name, const char *msg) {
  if (run_name)
    fprintf(stderr, "sylva: [run %s] %s\n", run_name, msg);
  else
    fprintf(stderr, "sylva: %s\n", msg);
}

static void vlog(const char *run_name, const char *fmt, va_list ap) {
  char msg[1024];
  vsnprintf(msg, sizeof msg, fmt, ap);
  log_line(run_name, msg);
}

void server_log(const char *run_name, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vlog(run_name, fmt, ap);
  va_end(ap);
}

/* The window of server_log_limited: the second it began and its lines. */
static time_t limited_second;
static int limited_lines, limited_dropped;

void server_log_limited(const char *run_name, const char *fmt, ...) {
  time_t now = time(NULL);
  if (now != limited_second) {
    if (limited_dropped) fprintf(stderr, "sylva: (%d lines left out)\n", limited_dropped);
    limited_second = now;
    limited_lines = limited_dropped = 0;
  }
  if (++limited_lines > 10) {
    limited_dropped++;
    return;
  }
  va_list ap;
  va_start(ap, fmt);
  vlog(run_name, fmt, ap);
  va_end(ap);
}

/* libwebsockets' own errors (an accept failing with EMFILE, say) through the
 * same limit, so that a flood cannot fill the log. */
static void lws_log(int level, const char *line) {
  (void)level;
  size_t n = strlen(line);
  while (n && (line[n - 1] == '\n' || line[n - 1] == '\r')) n--;
  server_log_limited(NULL, "libwebsockets: %.*s", (int)n, line);
}

sylva_auth server_auth(const server *d) {
  if (!d->opt.token) return SYLVA_AUTH_NONE;
  return d->opt.public_read ? SYLVA_AUTH_CHANGES : SYLVA_AUTH_ALL;
}

/* ---- WebSocket sessions --------------------------------------------------------- */

/* A close frame's payload: none, or a code a peer may send (1000-1003, 1007-1014,
 * 3000-4999) and a reason. */
static bool close_payload_ok(const void *in, size_t len) {
  if (len == 0) return true;
  if (len == 1) return false;
  const unsigned char *p = in;
  unsigned code = (unsigned)p[0] << 8 | p[1];
  bool known = (code >= 1000 && code <= 1003) || (code >= 1007 && code <= 1014) ||
               (code >= 3000 && code <= 4999);
  return known && sylva_utf8_check((const char *)p + 2, len - 2, NULL, 0) == 0;
}

static int ws_callback(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in,
                       size_t len) {
  client *c = user;
  server *d = lws_context_user(lws_get_context(wsi));
  switch (reason) {
  case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION: {
    /* an upgrade: only /ws, from a Host and an Origin that name this daemon */
    char uri[64];
    const char *why = NULL;
    if (lws_hdr_copy(wsi, uri, sizeof uri, WSI_TOKEN_GET_URI) < 0 || strcmp(uri, "/ws") != 0)
      why = "WebSockets are served on /ws with the subprotocol sylva.v1";
    else if (d->stopping)
      why = "the daemon is stopping";
    else if (!access_host_ok(&d->access, wsi) || !access_origin_ok(&d->access, wsi))
      why = "the Host or the Origin is not this daemon's (see --allow-host)";
    else if (!client_set_has_room(&d->clients))
      why = "too many clients (--max-clients)";
    if (!why) return 0;
    if (!d->stopping) server_log_limited(NULL, "refused a WebSocket upgrade: %s", why);
    bool unavailable = d->stopping || !client_set_has_room(&d->clients);
    lws_return_http_status(wsi, unavailable ? HTTP_STATUS_SERVICE_UNAVAILABLE : HTTP_STATUS_FORBIDDEN,
                           why);
    return 1;
  }
  case LWS_CALLBACK_ESTABLISHED:
    client_open(&d->clients, c, wsi, d, d->opt.token == NULL);
    client_send_text(c, sylva_msg_welcome(SYLVA_VERSION_TEXT, server_auth(d), NULL));
    break;
  case LWS_CALLBACK_CLOSED:
    if (!c || !c->set) break;
    runs_forget_client(d, c->serial);
    client_closed(c);
    break;
  case LWS_CALLBACK_RECEIVE:
    if (!c || !c->set || c->close_code) break;
    if (client_receive(c, in, len)) {
      if (c->rx_len >= DAEMON_PARSE_INLINE) {
        handle_message_later(c);
      } else {
        handle_message(c, c->rx, c->rx_len);
        if (c->set) client_handled(c);
      }
    }
    break;
  case LWS_CALLBACK_WS_PEER_INITIATED_CLOSE:
    /* RFC 6455 7.4: a close payload is empty or a valid code and a UTF-8 reason;
     * anything else is a protocol error */
    if (!close_payload_ok(in, len)) {
      lws_close_reason(wsi, LWS_CLOSE_STATUS_PROTOCOL_ERR, (unsigned char *)"invalid close frame",
                       19);
      return -1;
    }
    break;
  case LWS_CALLBACK_SERVER_WRITEABLE:
    if (!c || !c->set) break;
    return client_writable(c);
  default: break;
  }
  return 0;
}

static struct lws_protocols protocols[] = {
    {"http", http_callback, sizeof(http_pss), 0, 0, NULL, 0},
    {"sylva.v1", ws_callback, sizeof(client), 65536, 0, NULL, 0},
    {NULL, NULL, 0, 0, 0, NULL, 0},
};

static const struct lws_protocol_vhost_options mime_wasm = {NULL, NULL, ".wasm",
                                                            "application/wasm"};
static const struct lws_protocol_vhost_options mime_map = {&mime_wasm, NULL, ".map",
                                                           "application/json"};
static const struct lws_protocol_vhost_options mime_mjs = {&mime_map, NULL, ".mjs",
                                                           "text/javascript"};

/* ---- start and stop ------------------------------------------------------------ */

/* `--run SCENARIO.json`: grow it, unless a run of its name is already held.
 * Returns SERVER_OK or a server_error. */
static int start_scenario(server *d, const char *path) {
  sylva_scenario *s;
  char err[1200];
  /* plants not required: an empty site, as with create */
  int rc = files_load_scenario(path, 0, &s, err, sizeof err);
  if (rc) {
    server_log(NULL, "%s", err);
    return rc;
  }
  run *r = run_find_name(d, s->name, strlen(s->name));
  if (r) {
    server_log(r->name, "already held (%s); not created again", sylva_run_status_name(r->status));
    sylva_scenario_free(s);
    return SERVER_OK;
  }
  /* built and stored off the loop; a failure then is logged */
  const char *refused = run_create(d, NULL, &s, s->name, true, NULL, err, sizeof err);
  sylva_scenario_free(s);
  if (refused) {
    server_log(NULL, "%s: %s", path, err);
    return SERVER_EINPUT;
  }
  return SERVER_OK;
}

static void stop(server *d) {
  if (d->stopping) return;
  d->stopping = true;
  d->stop_at = uv_now(&d->loop);
  server_log(NULL, "stopping: closing clients, finishing the iterations in flight");
  client_set_close_all(&d->clients, LWS_CLOSE_STATUS_GOINGAWAY, "server shutting down");
  pool_stop(&d->pool); /* iterations not started are dropped; the running ones end */
  runs_halt(d);
  uv_signal_stop(&d->sigint);
  uv_signal_stop(&d->sigterm);
}

static void on_signal(uv_signal_t *h, int signum) {
  (void)signum;
  stop(h->data);
}

static uv_timer_t shutdown_timer;

static void on_shutdown_tick(uv_timer_t *t) {
  server *d = t->data;
  /* close frames need a moment on the wire before the context goes */
  bool busy = runs_busy(d) || !pool_idle(&d->pool);
  uint64_t since = uv_now(&d->loop) - d->stop_at;
  /* wait for the iterations in flight, and give the close frames time to leave
   * (up to two seconds for clients that do not answer). An export in flight is not
   * waited for: its connection closes with the context, and the loop, drained
   * below, finishes the job and frees its result. */
  if (!d->stopping || busy || since < 100 || (d->clients.head && since < 2000)) return;
  uv_timer_stop(t);
  uv_close((uv_handle_t *)t, NULL);
  client_set_close(&d->clients);
  pool_close(&d->pool);
  uv_close((uv_handle_t *)&d->sigint, NULL);
  uv_close((uv_handle_t *)&d->sigterm, NULL);
  lws_context_destroy(d->ctx);
}

int server_main(const server_options *opt) {
  server *d = calloc(1, sizeof *d);
  if (!d) return 1;
  d->opt = *opt;
  d->fd_ceiling = 1L << 30;
#ifdef M_MMAP_THRESHOLD
  /* large buffers (messages being received, encoded snapshots) get pages of their
   * own and give them back when freed, so memory falls again after a burst; glibc
   * would otherwise raise the threshold after the first such free */
  mallopt(M_MMAP_THRESHOLD, 256 << 10);
#endif
  /* every client and connection takes a file descriptor: the soft limit goes up
   * to the hard one, and the client cap stays below it, so that accepting never
   * fails for lack of descriptors (which libwebsockets would retry at once) */
  struct rlimit nofile;
  if (getrlimit(RLIMIT_NOFILE, &nofile) == 0) {
    if (nofile.rlim_cur < nofile.rlim_max) {
      nofile.rlim_cur = nofile.rlim_max;
      setrlimit(RLIMIT_NOFILE, &nofile);
      getrlimit(RLIMIT_NOFILE, &nofile);
    }
    rlim_t room = nofile.rlim_cur > 192 ? nofile.rlim_cur - 128 : 64;
    d->fd_ceiling = (long)(nofile.rlim_cur > 96 ? nofile.rlim_cur - 64 : nofile.rlim_cur);
    if ((rlim_t)d->opt.clients.max_clients > room / 2) {
      d->opt.clients.max_clients = (int)(room / 2);
      server_log(NULL, "at most %d clients: the limit of open files is %llu",
                 d->opt.clients.max_clients, (unsigned long long)nofile.rlim_cur);
    }
  }
  if (uv_loop_init(&d->loop)) {
    free(d);
    return 1;
  }
  if (store_open(opt->db, true, &d->st) || store_open(opt->db, false, &d->reader)) {
    server_log(NULL, "%s", store_open_error());
    store_close(d->st);
    uv_loop_close(&d->loop);
    free(d);
    return 2;
  }
  /* Every world the daemon grows (created, loaded, resumed, forked, regrown for a
   * job) shares one set of --threads threads, below the loop as its workers are:
   * a daemon of many runs keeps --threads - 1 of them, not that many per run. */
  d->threads = pool_world_threads(opt->threads, opt->work_nice);
  if (!d->threads && opt->threads > 1)
    server_log(NULL, "cannot start %d threads for the worlds: they grow on one each",
               opt->threads);
  store_share_threads(d->reader, d->threads);
  lws_set_log_level(LLL_ERR, lws_log);
  struct lws_http_mount static_mount = {
      .mountpoint = "/", .origin = opt->web, .def = "index.html",
      .origin_protocol = LWSMPRO_FILE, .mountpoint_len = 1, .extra_mimetypes = &mime_mjs};
  struct lws_http_mount api = {.mount_next = opt->web ? &static_mount : NULL,
                               .mountpoint = "/api", .protocol = "http",
                               .origin_protocol = LWSMPRO_CALLBACK, .mountpoint_len = 4};
  struct lws_http_mount metrics = {.mount_next = &api, .mountpoint = "/metrics",
                                   .protocol = "http", .origin_protocol = LWSMPRO_CALLBACK,
                                   .mountpoint_len = 8};
  struct lws_http_mount healthz = {.mount_next = &metrics, .mountpoint = "/healthz",
                                   .protocol = "http", .origin_protocol = LWSMPRO_CALLBACK,
                                   .mountpoint_len = 8};
  void *foreign[1] = {&d->loop};
  struct lws_context_creation_info info;
  memset(&info, 0, sizeof info);
  info.port = opt->port;
  info.iface = opt->host;
  info.protocols = protocols;
  info.mounts = &healthz;
  /* no LWS_SERVER_OPTION_VALIDATE_UTF8: lws would check every byte of every
   * fragment on the loop, also of messages that never end; a complete text
   * message is checked instead (handlers.c), off the loop when it is large */
  info.options = LWS_SERVER_OPTION_LIBUV | LWS_SERVER_OPTION_DISABLE_IPV6;
  info.foreign_loops = foreign;
  info.pcontext = &d->ctx;
  info.user = d;
  d->access = (access_rules){.listen_host = opt->host, .host_count = opt->host_count,
                             .origins = d->opt.origins, .origin_count = opt->origin_count,
                             .token = opt->token, .public_read = opt->public_read};
  for (int i = 0; i < opt->host_count; i++) d->access.hosts[i] = opt->hosts[i];
  info.timeout_secs = HTTP_TIMEOUT_SECS;
  d->ctx = lws_create_context(&info);
  int rc = 0;
  if (!d->ctx || !lws_get_vhost_by_name(d->ctx, "default")) {
    server_log(NULL, "cannot listen on %s:%d (in use, or not an address of this machine)",
               opt->host, opt->port);
    rc = 1;
  }
  bool pool_up = false;
  if (!rc && !(pool_up = pool_init(&d->pool, &d->loop, opt->workers, opt->work_nice) == 0)) {
    server_log(NULL, "cannot start %d worker threads", opt->workers);
    rc = 1;
  }
  if (!rc && runs_load(d)) rc = 1;
  if (!rc && opt->start_scenario) rc = server_exit_status(start_scenario(d, opt->start_scenario));
  if (!rc) {
    uv_signal_init(&d->loop, &d->sigint);
    uv_signal_init(&d->loop, &d->sigterm);
    d->sigint.data = d->sigterm.data = d;
    uv_signal_start(&d->sigint, on_signal, SIGINT);
    uv_signal_start(&d->sigterm, on_signal, SIGTERM);
    client_set_init(&d->clients, &d->loop, &d->opt.clients);
    uv_timer_init(&d->loop, &shutdown_timer);
    shutdown_timer.data = d;
    uv_timer_start(&shutdown_timer, on_shutdown_tick, 100, 100);
    server_log(NULL, "listening on http://%s:%d/ (WebSocket /ws, protocol sylva.v1), store %s",
               opt->host, opt->port, opt->db);
    if (opt->web) server_log(NULL, "viewer: http://%s:%d/", opt->host, opt->port);
    uv_run(&d->loop, UV_RUN_DEFAULT);
  } else {
    if (pool_up) {
      pool_stop(&d->pool);
      pool_close(&d->pool);
    }
    if (d->ctx) lws_context_destroy(d->ctx);
    uv_run(&d->loop, UV_RUN_DEFAULT);
  }
  /* lws needs a second destroy after its handles drained on the loop */
  if (d->ctx) lws_context_destroy(d->ctx);
  uv_run(&d->loop, UV_RUN_DEFAULT);
  runs_free(d);
  store_close(d->reader);
  store_close(d->st);
  if (uv_loop_close(&d->loop)) server_log(NULL, "the loop still had handles at exit");
  sylva_threads_destroy(d->threads); /* every world is gone with the runs and jobs */
  free(d);
  /* the reports' pictures and plots (http.c) drew text: cairo's font caches and
   * fontconfig's hold memory until the process ends; every job is done (the loop
   * drained), so free them, as `sylva report` does, that leak checkers see none */
  cairo_debug_reset_static_data();
  FcFini();
  if (!rc) server_log(NULL, "stopped");
  return rc;
}
