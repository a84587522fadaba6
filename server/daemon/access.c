#include "access.h"

#include <string.h>
#include <strings.h>

/* The host name of a Host header value or an origin's authority, without the
 * port: "a.b:80" -> "a.b", "[::1]:8080" -> "[::1]". */
static void host_name(const char *in, char *out, size_t size) {
  size_t n = strlen(in);
  if (in[0] == '[') {
    const char *close = strchr(in, ']');
    n = close ? (size_t)(close - in) + 1 : n;
  } else {
    const char *colon = strchr(in, ':');
    if (colon) n = (size_t)(colon - in);
  }
  if (n >= size) n = size - 1;
  memcpy(out, in, n);
  out[n] = 0;
}

static bool name_allowed(const access_rules *a, const char *name) {
  static const char *const local[] = {"localhost", "127.0.0.1", "[::1]"};
  if (!name[0]) return false;
  for (size_t i = 0; i < sizeof local / sizeof local[0]; i++)
    if (strcasecmp(name, local[i]) == 0) return true;
  if (a->listen_host && strcasecmp(name, a->listen_host) == 0) return true;
  for (int i = 0; i < a->host_count; i++)
    if (strcasecmp(name, a->hosts[i]) == 0) return true;
  return false;
}

bool access_host_ok(const access_rules *a, struct lws *wsi) {
  char host[256], name[256];
  int n = lws_hdr_total_length(wsi, WSI_TOKEN_HOST);
  if (n <= 0 || n >= (int)sizeof host || lws_hdr_copy(wsi, host, sizeof host, WSI_TOKEN_HOST) < 0)
    return false;
  host_name(host, name, sizeof name);
  return name_allowed(a, name);
}

bool access_origin_ok(const access_rules *a, struct lws *wsi) {
  char origin[256], name[256];
  int n = lws_hdr_total_length(wsi, WSI_TOKEN_ORIGIN);
  if (n <= 0) return true; /* not a browser */
  if (n >= (int)sizeof origin || lws_hdr_copy(wsi, origin, sizeof origin, WSI_TOKEN_ORIGIN) < 0)
    return false;
  for (int i = 0; i < a->origin_count; i++)
    if (strcmp(origin, a->origins[i]) == 0) return true;
  const char *rest = strncmp(origin, "http://", 7) == 0    ? origin + 7
                     : strncmp(origin, "https://", 8) == 0 ? origin + 8
                                                           : NULL;
  if (!rest || strchr(rest, '/')) return false;
  host_name(rest, name, sizeof name);
  return name_allowed(a, name);
}

/* Equal strings, in a time that depends only on the secret's length. */
static bool same_secret(const char *given, const char *secret) {
  size_t lg = strlen(given), ls = strlen(secret);
  unsigned diff = lg != ls;
  for (size_t i = 0; i < ls; i++)
    diff |= (unsigned char)(i < lg ? given[i] : 0) ^ (unsigned char)secret[i];
  return diff == 0;
}

access_verdict access_check_token(access_rules *a, const char *given, uint64_t now_ms) {
  if (!a->token) return ACCESS_OK;
  if (now_ms - a->window_start >= 1000) {
    a->window_start = now_ms;
    a->window_failures = 0;
  }
  if (a->window_failures >= ACCESS_FAILURES_PER_SECOND) return ACCESS_THROTTLED;
  if (given && same_secret(given, a->token)) return ACCESS_OK;
  a->window_failures++;
  return ACCESS_WRONG;
}

const char *access_bearer(struct lws *wsi, char *buf, size_t size) {
  int n = lws_hdr_total_length(wsi, WSI_TOKEN_HTTP_AUTHORIZATION);
  if (n <= 0 || n >= (int)size || lws_hdr_copy(wsi, buf, (int)size, WSI_TOKEN_HTTP_AUTHORIZATION) < 0)
    return NULL;
  if (strncasecmp(buf, "Bearer ", 7) != 0) return NULL;
  const char *t = buf + 7;
  while (*t == ' ') t++;
  return t;
}
