#include "handlers.h"

#include <stdlib.h>
#include <string.h>

#include "runs.h"
#include "scenarios.h"
#include "sylva/json_check.h"
#include "sylva/protocol.h"
#include "sylva/status.h"

static void reply_error(client *c, const char *code, const char *message, const char *ref) {
  client_send_text(c, sylva_msg_error(code, message, ref));
}

/* Messages that change something need a hello with the token first. */
static bool changes(sylva_msg_type t) {
  return t == SYLVA_MSG_CREATE || t == SYLVA_MSG_CONTROL || t == SYLVA_MSG_EDIT ||
         t == SYLVA_MSG_FORK;
}

static void handle_control(client *c, run *r, const sylva_msg *m) {
  const char *refused = run_control(r, m->action, m->count);
  if (refused)
    reply_error(c, "bad_request", refused, m->ref);
  else
    client_send_text(c, sylva_msg_status(r->id, r->status, r->iteration, r->start_year, m->ref));
}

/* A parsed message (rc and err: how parsing went); frees nothing. */
static void handle_parsed(client *c, sylva_msg *mp, int rc, const char *parse_err) {
  server *d = c->d;
  sylva_msg m = *mp;
  char err[512];
  if (rc != SYLVA_OK) {
    reply_error(c, "bad_request", parse_err, m.ref); /* the id, when it could be read */
    return;
  }
  bool needs_token = m.type != SYLVA_MSG_HELLO && (changes(m.type) || !d->opt.public_read);
  if (needs_token && d->opt.token && !c->authed) {
    reply_error(c, "unauthorized", "send a hello with the token first", m.ref);
    return;
  }
  run *r = NULL;
  if (m.type == SYLVA_MSG_SUBSCRIBE || m.type == SYLVA_MSG_UNSUBSCRIBE ||
      m.type == SYLVA_MSG_CONTROL || m.type == SYLVA_MSG_EDIT || m.type == SYLVA_MSG_FORK ||
      m.type == SYLVA_MSG_GET || m.type == SYLVA_MSG_LIGHT) {
    r = run_find(d, m.run);
    if (!r) {
      snprintf(err, sizeof err, "/run: no run %lld", (long long)m.run);
      reply_error(c, "unknown_run", err, m.ref);
      return;
    }
  }
  switch (m.type) {
  case SYLVA_MSG_HELLO: {
    access_verdict v = access_check_token(&d->access, m.token, uv_now(&d->loop));
    if (v != ACCESS_OK) {
      /* the last failure a socket may have closes it instead of answering */
      if (++c->token_failures >= ACCESS_FAILURES_PER_CLIENT)
        client_close_after_sending(c, LWS_CLOSE_STATUS_POLICY_VIOLATION, "too many wrong tokens");
      else
        reply_error(c, "unauthorized",
                    v == ACCESS_WRONG ? "/token: wrong token"
                                      : "/token: too many wrong tokens; try again in a second",
                    m.ref);
      break;
    }
    c->authed = true;
    client_send_text(c, sylva_msg_welcome(SYLVA_VERSION_TEXT, server_auth(d), m.ref));
    break;
  }
  case SYLVA_MSG_LIST: client_send_text(c, runs_json(d, true, m.ref)); break;
  case SYLVA_MSG_SCENARIOS:
    scenarios_list(&d->loop, &d->clients, c, d->opt.scenarios, m.ref);
    break;
  case SYLVA_MSG_CREATE: {
    const char *name = m.name ? m.name : m.scenario->name;
    const char *code = run_create(d, c, &m.scenario, name, m.start, m.ref, err, sizeof err);
    if (code) reply_error(c, code, err, m.ref);
    break;
  }
  case SYLVA_MSG_SUBSCRIBE: run_subscribe(r, c, m.has_since, m.since, m.detail, m.ref); break;
  case SYLVA_MSG_UNSUBSCRIBE:
    client_unsubscribe(c, r->id);
    runs_wake(d);
    break;
  case SYLVA_MSG_CONTROL: handle_control(c, r, &m); break;
  case SYLVA_MSG_LIGHT: {
    int dims[3];
    const char *waiting = run_ready(r, err, sizeof err);
    if (waiting) {
      reply_error(c, "busy", waiting, m.ref);
      break;
    }
    sylva_world_dims(r->w, dims); /* fixed for the world's life; safe while busy */
    if ((int64_t)dims[0] * dims[1] > DAEMON_MAX_SLICE) {
      snprintf(err, sizeof err, "/z: the slice would have %lld cells; at most %lld are sent",
               (long long)dims[0] * dims[1], (long long)DAEMON_MAX_SLICE);
      reply_error(c, "too_large", err, m.ref);
    } else {
      run_light(r, c, m.z, m.ref);
    }
    break;
  }
  case SYLVA_MSG_EDIT: {
    const char *waiting;
    if (r->status == SYLVA_RUN_FAILED)
      reply_error(c, "bad_request", "/run: the run has failed", m.ref);
    else if ((waiting = run_ready(r, err, sizeof err)))
      reply_error(c, "busy", waiting, m.ref);
    else
      run_edit(r, c, &m);
    break;
  }
  case SYLVA_MSG_FORK: run_fork(r, c, m.iteration, m.name, m.ref); break;
  case SYLVA_MSG_GET: run_get(r, c, m.iteration, m.ref); break;
  }
  *mp = m; /* run_edit may have taken it (and emptied it) */
}

/* RFC 6455 8.1: a text message that is not UTF-8 fails the connection. */
static void refuse_utf8(client *c) {
  client_close(c, LWS_CLOSE_STATUS_INVALID_PAYLOAD, "invalid UTF-8");
}

void handle_message(client *c, const char *text, size_t len) {
  if (sylva_utf8_check(text, len, NULL, 0)) {
    refuse_utf8(c);
    return;
  }
  sylva_msg m;
  char err[512];
  int rc = sylva_msg_parse(text, len, &m, err, sizeof err);
  handle_parsed(c, &m, rc, err);
  sylva_msg_free(&m);
}

/* A large message parsed off the loop. */
typedef struct parse_job {
  uv_work_t work;
  server *d;
  uint64_t client;
  char *text;
  size_t len;
  bool utf8_ok;
  sylva_msg m;
  int rc;
  char err[512];
} parse_job;

static void parse_work(uv_work_t *w) {
  parse_job *j = w->data;
  j->utf8_ok = sylva_utf8_check(j->text, j->len, NULL, 0) == 0;
  if (j->utf8_ok) j->rc = sylva_msg_parse(j->text, j->len, &j->m, j->err, sizeof j->err);
}

static void parse_done(uv_work_t *w, int status) {
  parse_job *j = w->data;
  server *d = j->d;
  client_set_input_done(&d->clients, j->len);
  client *c = client_find(&d->clients, j->client);
  if (c) {
    if (status == 0 && !j->utf8_ok)
      refuse_utf8(c);
    else if (status == 0 && !c->close_code)
      handle_parsed(c, &j->m, j->rc, j->err);
    client_resume(c);
  }
  if (status == 0 && j->utf8_ok) sylva_msg_free(&j->m);
  free(j->text);
  free(j);
}

void handle_message_later(client *c) {
  server *d = c->d;
  parse_job *j = calloc(1, sizeof *j);
  if (!j) {
    handle_message(c, c->rx, c->rx_len);
    client_handled(c);
    return;
  }
  j->d = d;
  j->client = c->serial;
  j->work.data = j;
  j->text = client_take_message(c, &j->len);
  if (uv_queue_work(&d->loop, &j->work, parse_work, parse_done) != 0) {
    handle_message(c, j->text, j->len);
    client_set_input_done(&d->clients, j->len);
    client_resume(c);
    free(j->text);
    free(j);
  }
}
