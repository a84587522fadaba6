#include "client.h"

#include <stdlib.h>
#include <string.h>

#include "sylva/protocol.h"

msgbuf *msgbuf_new(const char *text, size_t len) {
  msgbuf *m = malloc(sizeof *m + LWS_PRE + len);
  if (!m) return NULL;
  m->refs = 1;
  m->len = len;
  memcpy(m->data + LWS_PRE, text, len);
  return m;
}

msgbuf *msgbuf_ref(msgbuf *m) {
  m->refs++;
  return m;
}

void msgbuf_unref(msgbuf *m) {
  if (m && --m->refs == 0) free(m);
}

void client_close(client *c, int code, const char *reason) {
  if (c->close_code) return;
  c->close_code = code;
  snprintf(c->close_reason, sizeof c->close_reason, "%s", reason);
  server_schedule_closes(c->d);
}

void client_send(client *c, msgbuf *m) {
  if (c->close_code) return;
  if (c->pending + m->len > c->d->opt.max_pending) {
    client_close(c, LWS_CLOSE_STATUS_POLICY_VIOLATION, "client too slow: output backlog");
    return;
  }
  if (c->qlen == c->qcap) {
    size_t cap = c->qcap ? 2 * c->qcap : 16;
    msgbuf **q = malloc(cap * sizeof *q);
    if (!q) {
      client_close(c, LWS_CLOSE_STATUS_UNEXPECTED_CONDITION, "out of memory");
      return;
    }
    for (size_t i = 0; i < c->qlen; i++) q[i] = c->queue[(c->qhead + i) % c->qcap];
    free(c->queue);
    c->queue = q;
    c->qcap = cap;
    c->qhead = 0;
  }
  c->queue[(c->qhead + c->qlen++) % c->qcap] = msgbuf_ref(m);
  c->pending += m->len;
  lws_callback_on_writable(c->wsi);
}

void client_send_text(client *c, char *text) {
  if (!text) {
    char *err = sylva_msg_error("internal", "out of memory", NULL);
    if (!err) return;
    text = err;
  }
  msgbuf *m = msgbuf_new(text, strlen(text));
  free(text);
  if (!m) {
    client_close(c, LWS_CLOSE_STATUS_UNEXPECTED_CONDITION, "out of memory");
    return;
  }
  client_send(c, m);
  msgbuf_unref(m);
}

/* Largest fragment written at once: lws copies what the socket does not take, so
 * whole messages of megabytes would sit in its buffers outside the client's cap. */
#define CLIENT_FRAGMENT (128u << 10)

int client_writable(client *c) {
  if (!c->qlen) return 0;
  msgbuf *m = c->queue[c->qhead];
  size_t n = m->len - c->sent;
  if (n > CLIENT_FRAGMENT) n = CLIENT_FRAGMENT;
  bool first = c->sent == 0, last = c->sent + n == m->len;
  int flags = lws_write_ws_flags(LWS_WRITE_TEXT, first, last);
  /* each fragment needs LWS_PRE bytes of headroom in front of it: the shared buffer
   * has them before its start, and later fragments borrow the bytes just sent */
  unsigned char *p = m->data + LWS_PRE + c->sent;
  unsigned char saved[LWS_PRE];
  if (!first) memcpy(saved, p - LWS_PRE, LWS_PRE);
  int w = lws_write(c->wsi, p, n, (enum lws_write_protocol)flags);
  if (!first) memcpy(p - LWS_PRE, saved, LWS_PRE);
  if (w < (int)n) return -1;
  c->sent += n;
  c->d->bytes_sent += (int64_t)n;
  if (last) {
    c->sent = 0;
    c->qhead = (c->qhead + 1) % c->qcap;
    c->qlen--;
    c->pending -= m->len;
    msgbuf_unref(m);
  }
  if (c->qlen) lws_callback_on_writable(c->wsi);
  return 0;
}

subscription *client_subscription(client *c, int64_t run) {
  for (size_t i = 0; i < c->nsubs; i++)
    if (c->subs[i].run == run) return &c->subs[i];
  return NULL;
}

subscription *client_subscribe(client *c, int64_t run) {
  subscription *s = client_subscription(c, run);
  if (s) return s;
  if (c->nsubs == c->subs_cap) {
    size_t cap = c->subs_cap ? 2 * c->subs_cap : 4;
    subscription *p = realloc(c->subs, cap * sizeof *p);
    if (!p) return NULL;
    c->subs = p;
    c->subs_cap = cap;
  }
  s = &c->subs[c->nsubs++];
  s->run = run;
  s->need_snapshot = false;
  return s;
}

void client_unsubscribe(client *c, int64_t run) {
  for (size_t i = 0; i < c->nsubs; i++)
    if (c->subs[i].run == run) {
      c->subs[i] = c->subs[--c->nsubs];
      return;
    }
}

void client_release(client *c) {
  for (size_t i = 0; i < c->qlen; i++) msgbuf_unref(c->queue[(c->qhead + i) % c->qcap]);
  free(c->queue);
  free(c->rx);
  free(c->subs);
  c->queue = NULL;
  c->rx = NULL;
  c->subs = NULL;
  c->qlen = c->nsubs = 0;
}

void clients_close_pending(server *d) {
  for (client *c = d->clients; c; c = c->next) {
    if (c->close_code <= 0) continue;
    lws_close_reason(c->wsi, (enum lws_close_status)c->close_code,
                     (unsigned char *)c->close_reason, strlen(c->close_reason));
    lws_set_timeout(c->wsi, PENDING_TIMEOUT_USER_OK, LWS_TO_KILL_SYNC);
    c->close_code = -1; /* asked; lws reports CLOSED later */
  }
}

client *client_find(server *d, uint64_t serial) {
  for (client *c = d->clients; c; c = c->next)
    if (c->serial == serial) return c;
  return NULL;
}
