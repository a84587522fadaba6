/* sylva server: who may use the daemon (docs/protocol.md, "Access"):
 *   - the Host allowlist, on every HTTP request and WebSocket upgrade: the listen
 *     address, localhost, 127.0.0.1, [::1] and the names given with --allow-host
 *     (so that a page of another site cannot reach the daemon through DNS
 *     rebinding);
 *   - the Origin check of WebSocket upgrades against the same names (and the
 *     exact origins given with --allow-origin);
 *   - the token: compared in constant time, with a budget of failures per second
 *     for the whole daemon, so that guessing it is slow. */
#ifndef SYLVA_SERVER_ACCESS_H
#define SYLVA_SERVER_ACCESS_H

#include <libwebsockets.h>
#include <stdbool.h>
#include <stdint.h>

/** Most names given with --allow-host. */
#define ACCESS_MAX_HOSTS 16
/** Most failed token checks per second, daemon-wide; more are refused unchecked. */
#define ACCESS_FAILURES_PER_SECOND 10
/** Failed hellos after which a WebSocket is closed (1008). */
#define ACCESS_FAILURES_PER_CLIENT 3

/** The rules of one daemon. */
typedef struct access_rules {
  const char *listen_host;              /**< the listen address */
  const char *hosts[ACCESS_MAX_HOSTS];  /**< --allow-host names */
  int host_count;
  const char *const *origins;           /**< --allow-origin values, compared exactly */
  int origin_count;
  const char *token;                    /**< NULL: no token */
  bool public_read;                     /**< reading needs no token */
  uint64_t window_start;                /**< the current second of the failure budget (ms) */
  int window_failures;
} access_rules;

/** Whether the request's Host names this daemon. A request without Host fails. */
bool access_host_ok(const access_rules *a, struct lws *wsi);

/** Whether a WebSocket upgrade's Origin is allowed: none (not a browser), one of
 *  the allowed names over http or https (any port), or an --allow-origin value. */
bool access_origin_ok(const access_rules *a, struct lws *wsi);

/** The result of a token check. */
typedef enum access_verdict { ACCESS_OK, ACCESS_WRONG, ACCESS_THROTTLED } access_verdict;

/** Checks a presented token (may be NULL) at time now_ms: ACCESS_OK when it
 *  matches (or the daemon has none), ACCESS_WRONG, or ACCESS_THROTTLED when this
 *  second's budget of failures is spent (the token is then not compared). */
access_verdict access_check_token(access_rules *a, const char *given, uint64_t now_ms);

/** The token of an HTTP request's "Authorization: Bearer T" header, copied into
 *  buf; NULL when there is none. */
const char *access_bearer(struct lws *wsi, char *buf, size_t size);

#endif
