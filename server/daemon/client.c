#include "client.h"

#include <stdlib.h>
#include <string.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "sylva/protocol.h"

/* ---- the set ------------------------------------------------------------------- */

/* Closes applied in one turn of the loop: 1,000 clients refused at once (abuse row
 * 8) would otherwise hold the loop for one long turn. */
#define CLIENT_CLOSES_PER_TURN 32

/* close_code of a refused client asked to close: lws sends its close frame in a
 * turn of the loop to come, and the connection is dropped DROP_MS after (RFC 6455
 * 7.1.7: a failed connection's data, a close frame in reply included, is not
 * processed) */
#define CLOSE_DROP (-2)
#define DROP_MS 250

/* Applies the closes asked for; from the set's timer, outside lws callbacks. */
static void on_closer(uv_timer_t *t) {
  client_set *s = t->data;
  uint64_t now = uv_now(t->loop), wait = 0;
  int closed = 0;
  for (client *c = s->head, *next; c; c = next) {
    next = c->next;
    if (c->close_code == CLOSE_DROP) {
      if (now - c->asked_at < DROP_MS) {
        uint64_t left = DROP_MS - (now - c->asked_at);
        if (!wait || left < wait) wait = left;
        continue;
      }
      c->close_code = -1;
      lws_set_timeout(c->wsi, PENDING_TIMEOUT_USER_OK, LWS_TO_KILL_SYNC);
      continue;
    }
    if (c->close_code <= 0) continue;
    if (c->close_after) { /* its messages leave first (client_writable, on_watch) */
      lws_callback_on_writable(c->wsi);
      continue;
    }
    if (closed++ == CLIENT_CLOSES_PER_TURN) { /* the rest in the next turn */
      uv_timer_start(&s->closer, on_closer, 0, 0);
      return;
    }
    lws_close_reason(c->wsi, (enum lws_close_status)c->close_code,
                     (unsigned char *)c->close_reason, strlen(c->close_reason));
    c->close_code = c->refused ? CLOSE_DROP : -1; /* asked; lws reports CLOSED later */
    c->asked_at = now;
    if (c->refused && (!wait || DROP_MS < wait)) wait = DROP_MS;
    lws_set_timeout(c->wsi, PENDING_TIMEOUT_USER_OK, LWS_TO_KILL_SYNC);
  }
  if (wait) uv_timer_start(&s->closer, on_closer, wait, 0);
}

static void closer_soon(client_set *s) {
  if (!uv_is_closing((uv_handle_t *)&s->closer)) uv_timer_start(&s->closer, on_closer, 0, 0);
}

/* A client closed for what it sends is read no more: the rest of its message
 * stays in the kernel's buffers instead of being read, unmasked and dropped on
 * the loop while lws waits for a close frame in reply; the connection is dropped
 * DROP_MS after its own close frame was asked for. */
static void reader_end(client *c);

static void refuse(client *c, int code, const char *reason) {
  if (c->close_code) return;
  lws_rx_flow_control(c->wsi, 0);
  reader_end(c); /* its place goes to the next in the queue */
  c->refused = true;
  client_close(c, code, reason);
}

/* Once a second: a client whose message has been arriving for longer than the
 * limit is closed, so unfinished messages cannot hold memory for ever. */
static void on_watch(uv_timer_t *t) {
  client_set *s = t->data;
  uint64_t now = uv_now(t->loop);
  for (client *c = s->head; c; c = c->next) {
    if (c->rx_start && now - c->rx_start > (uint64_t)s->limits.message_ms)
      refuse(c, LWS_CLOSE_STATUS_POLICY_VIOLATION, "message not finished in time");
    if (c->close_after && now >= c->close_after) { /* its messages did not leave in time */
      c->close_after = 0;
      closer_soon(s);
    }
  }
#ifdef __GLIBC__
  /* glibc keeps freed memory that lies among the loop's other allocations: the
   * large buffers of 1,000 clients' unfinished messages left 100 MiB of RSS behind
   * once they were closed. At most once a second, after such buffers were freed. */
  if (s->trim) {
    s->trim = false;
    malloc_trim(0);
  }
#endif
}

int client_set_init(client_set *s, uv_loop_t *loop, const client_limits *limits) {
  *s = (client_set){.limits = *limits};
  s->closer.data = s;
  s->watch.data = s;
  int rc = uv_timer_init(loop, &s->closer);
  if (!rc) rc = uv_timer_init(loop, &s->watch);
  if (!rc) rc = uv_timer_start(&s->watch, on_watch, 1000, 1000);
  return rc;
}

bool client_set_has_room(const client_set *s) { return s->count < s->limits.max_clients; }

void client_set_close_all(client_set *s, int code, const char *reason) {
  for (client *c = s->head; c; c = c->next) {
    if (c->refused && c->close_code < 0) /* its close is asked; it is read no more */
      lws_set_timeout(c->wsi, PENDING_TIMEOUT_USER_OK, LWS_TO_KILL_ASYNC);
    client_close(c, code, reason);
  }
}

void client_set_close(client_set *s) {
  uv_close((uv_handle_t *)&s->closer, NULL);
  uv_close((uv_handle_t *)&s->watch, NULL);
}

int client_set_waiting(const client_set *s) {
  int n = 0;
  for (const client *w = s->wait_head; w; w = w->wait_next) n++;
  return n;
}

client *client_find(client_set *s, uint64_t serial) {
  for (client *c = s->head; c; c = c->next)
    if (c->serial == serial) return c;
  return NULL;
}

/* ---- one client ----------------------------------------------------------------- */

void client_open(client_set *s, client *c, struct lws *wsi, server *d, bool authed) {
  static uint64_t serial;
  memset(c, 0, sizeof *c);
  c->set = s;
  c->d = d;
  c->wsi = wsi;
  c->serial = ++serial;
  c->authed = authed;
  c->window_start = uv_now(s->closer.loop);
  c->next = s->head;
  if (s->head) s->head->prev = c;
  s->head = c;
  s->count++;
}

/* ---- long messages, CLIENT_READERS at a time -------------------------------------
 * A message that does not arrive in the read that starts it takes a reader's place
 * until it is complete or done with. A client that finds every place taken is read
 * no more, and waits in a queue: a thousand clients sending long messages at once
 * would otherwise all be read, a few KiB each, in every turn of the loop, and make
 * each turn last tens of ms (abuse row 8). Its time limit runs while it waits. */

static void readers_wake(client_set *s) {
  while (s->readers < CLIENT_READERS && s->wait_head) {
    client *w = s->wait_head;
    s->wait_head = w->wait_next;
    if (!s->wait_head) s->wait_tail = NULL;
    w->waiting = false;
    w->wait_next = NULL;
    if (w->close_code) continue; /* refused while it waited: stays unread */
    w->reading = true;
    s->readers++;
    lws_rx_flow_control(w->wsi, 1);
  }
}

static void reader_start(client *c) {
  client_set *s = c->set;
  if (c->reading || c->waiting) return;
  if (s->readers < CLIENT_READERS) {
    c->reading = true;
    s->readers++;
    return;
  }
  c->waiting = true;
  if (s->wait_tail)
    s->wait_tail->wait_next = c;
  else
    s->wait_head = c;
  s->wait_tail = c;
  lws_rx_flow_control(c->wsi, 0);
}

static void reader_end(client *c) {
  client_set *s = c->set;
  if (c->waiting) { /* leaves the queue */
    client *prev = NULL;
    for (client *w = s->wait_head; w; prev = w, w = w->wait_next)
      if (w == c) {
        if (prev)
          prev->wait_next = c->wait_next;
        else
          s->wait_head = c->wait_next;
        if (s->wait_tail == c) s->wait_tail = prev;
        break;
      }
    c->waiting = false;
    c->wait_next = NULL;
  }
  if (!c->reading) return;
  c->reading = false;
  s->readers--;
  readers_wake(s);
}

/* The unfinished message is done with (handled, refused or the client gone). */
static void rx_end(client *c) {
  reader_end(c);
  c->set->input -= c->rx_len;
  c->rx_len = 0;
  c->rx_start = 0;
  if (c->rx_cap > (64u << 10)) { /* a large buffer goes back at once */
    free(c->rx);
    c->rx = NULL;
    c->rx_cap = 0;
    c->set->trim = true;
  }
}

static void release(client *c) {
  rx_end(c);
  for (size_t i = 0; i < c->qlen; i++) msgbuf_unref(c->queue[(c->qhead + i) % c->qcap]);
  free(c->queue);
  free(c->rx);
  for (size_t i = 0; i < c->nsubs; i++) free(c->subs[i].ref);
  free(c->subs);
  c->queue = NULL;
  c->rx = NULL;
  c->subs = NULL;
  c->qlen = c->nsubs = 0;
}

void client_closed(client *c) {
  client_set *s = c->set;
  if (c->prev)
    c->prev->next = c->next;
  else
    s->head = c->next;
  if (c->next) c->next->prev = c->prev;
  s->count--;
  release(c);
  c->set = NULL;
  c->d = NULL;
}

static void rx_append(client *c, const char *in, size_t len) {
  if (c->rx_too_large) return;
  if (c->rx_len + len > c->set->limits.max_message ||
      c->set->input + len > c->set->limits.max_input) {
    c->rx_too_large = true;
    return;
  }
  if (c->rx_len + len + 1 > c->rx_cap) {
    size_t cap = c->rx_cap ? c->rx_cap : 4096;
    while (cap < c->rx_len + len + 1) cap *= 2;
    char *p = realloc(c->rx, cap);
    if (!p) {
      c->rx_too_large = true;
      return;
    }
    c->rx = p;
    c->rx_cap = cap;
  }
  memcpy(c->rx + c->rx_len, in, len);
  c->rx_len += len;
  c->set->input += len;
}

bool client_receive(client *c, const void *in, size_t len) {
  client_set *s = c->set;
  uint64_t now = uv_now(s->closer.loop);
  if (lws_is_first_fragment(c->wsi)) {
    rx_end(c);
    c->rx_too_large = false;
    c->rx_binary = lws_frame_is_binary(c->wsi);
    c->rx_start = now ? now : 1;
  }
  rx_append(c, in, len);
  if (!lws_is_final_fragment(c->wsi) || lws_remaining_packet_payload(c->wsi)) {
    if (c->rx_too_large) {
      rx_end(c);
      refuse(c, LWS_CLOSE_STATUS_MESSAGE_TOO_LARGE, "message too large");
    } else {
      reader_start(c);
    }
    return false;
  }
  reader_end(c);
  c->rx_start = 0;
  s->messages_received++;
  if (now - c->window_start >= 1000) {
    c->window_start = now;
    c->window_count = 0;
  }
  bool ok = false;
  if (++c->window_count > s->limits.rate_limit)
    refuse(c, LWS_CLOSE_STATUS_POLICY_VIOLATION, "rate limit exceeded");
  else if (c->rx_too_large)
    refuse(c, LWS_CLOSE_STATUS_MESSAGE_TOO_LARGE, "message too large");
  else if (c->rx_binary)
    client_send_text(c, sylva_msg_error("bad_request", "binary frames are not accepted", NULL));
  else
    ok = true;
  if (!ok) rx_end(c);
  return ok;
}

void client_handled(client *c) { rx_end(c); }

char *client_take_message(client *c, size_t *len) {
  char *text = c->rx;
  *len = c->rx_len;
  text[c->rx_len] = '\0';
  c->rx = NULL;
  c->rx_len = c->rx_cap = 0;
  c->rx_start = 0;
  lws_rx_flow_control(c->wsi, 0);
  return text;
}

void client_resume(client *c) { lws_rx_flow_control(c->wsi, 1); }

void client_set_input_done(client_set *s, size_t len) {
  s->input -= len;
  s->trim = true;
}

void client_close(client *c, int code, const char *reason) {
  if (c->close_code) return;
  c->close_code = code;
  snprintf(c->close_reason, sizeof c->close_reason, "%s", reason);
  closer_soon(c->set);
}

void client_close_after_sending(client *c, int code, const char *reason) {
  if (c->close_code) return;
  c->close_after = uv_now(c->set->closer.loop) + CLIENT_FLUSH_MS;
  client_close(c, code, reason);
}

void client_send(client *c, msgbuf *m) {
  if (c->close_code) return;
  /* The message going out now does not count: a snapshot (`get`) larger than the
   * cap reaches a client that reads, and what queues behind it is capped. */
  size_t queued = c->qlen ? c->pending - c->queue[c->qhead]->len : 0;
  if (queued + m->len > c->set->limits.max_pending && c->qlen) {
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

/* A close that waited for the queue: the queue is empty, so now. */
static void close_if_sent(client *c) {
  if (!c->close_after) return;
  c->close_after = 0;
  closer_soon(c->set);
}

int client_writable(client *c) {
  if (!c->qlen) {
    close_if_sent(c);
    return 0;
  }
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
  c->set->bytes_sent += (int64_t)n;
  if (last) {
    c->sent = 0;
    c->qhead = (c->qhead + 1) % c->qcap;
    c->qlen--;
    c->pending -= m->len;
    msgbuf_unref(m);
  }
  if (c->qlen)
    lws_callback_on_writable(c->wsi);
  else
    close_if_sent(c);
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
  *s = (subscription){.run = run};
  return s;
}

void client_unsubscribe(client *c, int64_t run) {
  for (size_t i = 0; i < c->nsubs; i++)
    if (c->subs[i].run == run) {
      free(c->subs[i].ref);
      c->subs[i] = c->subs[--c->nsubs];
      return;
    }
}
