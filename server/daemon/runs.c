#include "runs.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "edit.h"
#include "sylva/protocol.h"
#include "sylva/status.h"

/** An edit waiting for the iteration in flight. */
typedef struct pending_edit {
  sylva_msg msg;
  uint64_t client;
  struct pending_edit *next;
} pending_edit;

/** A light request waiting for the iteration in flight. */
typedef struct pending_light {
  uint64_t client;
  double z;
  char *ref;
  struct pending_light *next;
} pending_light;

static void apply_pending_edits(run *r);
static void answer_lights(run *r);

run *run_find(server *d, int64_t id) {
  for (run *r = d->runs; r; r = r->next)
    if (r->id == id) return r;
  return NULL;
}

run *run_find_name(server *d, const char *name, size_t len) {
  for (run *r = d->runs; r; r = r->next)
    if (strlen(r->name) == len && memcmp(r->name, name, len) == 0) return r;
  return NULL;
}

char *runs_json(server *d, bool message, const char *ref) {
  size_t n = 0;
  for (run *r = d->runs; r; r = r->next) n++;
  sylva_run_summary *list = calloc(n + 1, sizeof *list);
  if (!list) return NULL;
  size_t i = 0;
  for (run *r = d->runs; r; r = r->next, i++)
    list[i] = (sylva_run_summary){.run = r->id, .name = r->name, .status = r->status,
                                  .nodes = r->nodes, .iteration = r->iteration,
                                  .stems = r->stems};
  char *text = message ? sylva_msg_runs(list, n, ref) : sylva_runs_json(list, n);
  free(list);
  return text;
}

/* Caches the counts the loop may report while a worker steps the world. */
static void run_note(run *r) {
  r->nodes = (int64_t)sylva_world_node_count(r->w);
  r->iteration = sylva_world_iteration(r->w);
  r->stems = sylva_world_stem_count(r->w);
}

static bool run_wants_step(const run *r) {
  if (r->status != SYLVA_RUN_RUNNING && !(r->status == SYLVA_RUN_PAUSED && r->steps > 0))
    return false;
  return !sylva_world_finished(r->w) && sylva_world_iteration(r->w) < r->limit;
}

static void persist_status(run *r, const char *reason) {
  server *d = r->d;
  int failed = store_set_status(d->st, r->id, r->status, reason, r->limit);
  if (failed) server_log(r->name, "%s", store_error(d->st));
}

void run_broadcast_status(run *r) {
  char *text = sylva_msg_status(r->id, r->status, r->iteration, NULL);
  msgbuf *m = text ? msgbuf_new(text, strlen(text)) : NULL;
  free(text);
  if (!m) return;
  for (client *c = r->d->clients.head; c; c = c->next)
    if (client_subscription(c, r->id)) client_send(c, m);
  msgbuf_unref(m);
}

void run_set_status(run *r, sylva_run_status status) {
  if (r->status == status) return;
  r->status = status;
  const char *reason = NULL;
  if (status == SYLVA_RUN_FINISHED) reason = sylva_world_finished(r->w) ? "finished" : "limit";
  persist_status(r, reason);
  server_log(r->name, "%s at iteration %d", sylva_run_status_name(status), r->iteration);
  run_broadcast_status(r);
}

static double mono_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

/* Worker thread: one iteration, stored, and its delta encoded once. */
static void work_cb(uv_work_t *req) {
  run *r = req->data;
  server *d = r->d;
  const sylva_journal *j;
  double t0 = mono_ms();
  r->work_status = sylva_world_step(r->w, &j);
  r->work_ms = mono_ms() - t0;
  r->work_delta = NULL;
  r->work_error[0] = 0;
  if (r->work_status != SYLVA_OK) {
    snprintf(r->work_error, sizeof r->work_error, "iteration %d: %s",
             sylva_world_iteration(r->w) + 1, sylva_strerror(r->work_status));
    return;
  }
  int failed = store_save_step(d->st, r->id, r->w, j, r->snapshot_every, r->limit);
  if (failed) snprintf(r->work_error, sizeof r->work_error, "%s", store_error(d->st));
  if (failed) {
    r->work_status = -1;
    return;
  }
  r->work_delta = sylva_msg_delta(r->id, r->seq + 1, r->w, j);
}

/* The snapshot of the run's current seq, encoded once and shared by every client
 * that needs it (a reply with a ref is encoded for its client alone). */
static void send_snapshot(run *r, client *c, const char *ref) {
  if (ref) {
    client_send_text(c, sylva_msg_snapshot(r->id, r->seq, r->w, ref));
    return;
  }
  if (!r->snapshot || r->snapshot_seq != r->seq) {
    msgbuf_unref(r->snapshot);
    r->snapshot = NULL;
    char *text = sylva_msg_snapshot(r->id, r->seq, r->w, NULL);
    if (text) r->snapshot = msgbuf_new(text, strlen(text));
    free(text);
    r->snapshot_seq = r->seq;
  }
  if (r->snapshot)
    client_send(c, r->snapshot);
  else
    client_send_text(c, NULL); /* out of memory: an error */
}

static void after_cb(uv_work_t *req, int status) {
  run *r = req->data;
  server *d = r->d;
  r->busy = false;
  (void)status;
  answer_lights(r);
  if (r->work_status != SYLVA_OK) {
    server_log(r->name, "failed: %s", r->work_error);
    r->status = SYLVA_RUN_FAILED;
    persist_status(r, NULL);
    run_broadcast_status(r);
    return;
  }
  d->iterations_total++;
  d->iteration_ms_total += r->work_ms;
  run_note(r);
  r->seq++;
  msgbuf *m = r->work_delta ? msgbuf_new(r->work_delta, strlen(r->work_delta)) : NULL;
  free(r->work_delta);
  r->work_delta = NULL;
  msgbuf **slot = &r->history[r->seq % DAEMON_DELTA_HISTORY];
  msgbuf_unref(*slot);
  *slot = m;
  /* keep the newest deltas up to a byte budget: a resubscriber further behind
   * gets a snapshot instead */
  size_t kept = 0;
  for (int64_t k = 0; k < DAEMON_DELTA_HISTORY && k < r->seq; k++) {
    msgbuf **h = &r->history[(r->seq - k) % DAEMON_DELTA_HISTORY];
    if (!*h) continue;
    kept += (*h)->len;
    if (k > 0 && kept > DAEMON_HISTORY_BYTES) {
      msgbuf_unref(*h);
      *h = NULL;
    }
  }
  for (client *c = d->clients.head; c; c = c->next) {
    subscription *s = client_subscription(c, r->id);
    if (!s) continue;
    if (s->need_snapshot || !m) {
      s->need_snapshot = false;
      send_snapshot(r, c, NULL);
    } else {
      client_send(c, m);
    }
  }
  if (r->steps > 0) r->steps--;
  apply_pending_edits(r);
  if (d->stopping) return;
  if (r->stop_after || sylva_world_finished(r->w) || sylva_world_iteration(r->w) >= r->limit) {
    r->stop_after = false;
    run_set_status(r, SYLVA_RUN_FINISHED);
    return;
  }
  if (r->status == SYLVA_RUN_PAUSED && r->steps == 0) run_broadcast_status(r);
  run_schedule(r);
}

void run_schedule(run *r) {
  if (r->busy || r->d->stopping || !run_wants_step(r)) return;
  r->busy = true;
  r->work.data = r;
  if (uv_queue_work(&r->d->loop, &r->work, work_cb, after_cb) != 0) {
    r->busy = false;
    server_log(r->name, "cannot queue an iteration");
  }
}

void run_subscribe(run *r, client *c, bool has_since, int64_t since, const char *ref) {
  subscription *s = client_subscribe(c, r->id);
  if (!s) {
    client_send_text(c, sylva_msg_error("internal", "out of memory", ref));
    return;
  }
  /* the deltas after `since` can be replayed when every one of them is held */
  if (has_since && since >= 0 && since <= r->seq && r->seq - since < DAEMON_DELTA_HISTORY) {
    bool all = true;
    for (int64_t q = since + 1; q <= r->seq; q++)
      if (!r->history[q % DAEMON_DELTA_HISTORY]) all = false;
    if (all) {
      for (int64_t q = since + 1; q <= r->seq; q++)
        client_send(c, r->history[q % DAEMON_DELTA_HISTORY]);
      s->need_snapshot = false;
      return;
    }
  }
  if (r->busy)
    s->need_snapshot = true; /* sent when the iteration in flight is done */
  else
    send_snapshot(r, c, ref);
}

static run *run_new(server *d, int64_t id, const char *name, sylva_world *w,
                    sylva_run_status status,
                    int limit, int snapshot_every) {
  run *r = calloc(1, sizeof *r);
  if (!r || !(r->name = strdup(name))) {
    free(r);
    return NULL;
  }
  r->d = d;
  r->id = id;
  r->w = w;
  r->limit = limit;
  r->snapshot_every = snapshot_every;
  r->status = status;
  run_note(r);
  /* append, so that runs stay in creation order */
  run **tail = &d->runs;
  while (*tail) tail = &(*tail)->next;
  *tail = r;
  return r;
}

static void load_warning(const char *msg) { server_log(NULL, "warning: %s", msg); }

int runs_load(server *d) {
  store_run *stored;
  size_t n;
  if (store_list_runs(d->st, &stored, &n)) {
    server_log(NULL, "%s", store_error(d->st));
    return SERVER_EFAIL;
  }
  for (size_t i = 0; i < n; i++) {
    store_run *sr = &stored[i];
    sylva_world *w;
    if (store_world_at(d->st, sr->id, sr->last_iteration, load_warning, &w)) {
      server_log(sr->name, "not loaded: %s", store_error(d->st));
      continue;
    }
    int64_t edits = 0;
    if (store_command_count(d->st, sr->id, &edits)) {
      server_log(sr->name, "%s", store_error(d->st));
      sylva_world_destroy(w);
      continue;
    }
    run *r = run_new(d, sr->id, sr->name, w, sr->status, sr->iterations, sr->snapshot_every);
    if (!r) {
      sylva_world_destroy(w);
      store_runs_free(stored, n);
      return SERVER_ENOMEM;
    }
    /* one seq per delta and per edit since the run was planted, so that the numbers a
     * client holds keep their meaning across restarts of the daemon */
    r->seq = (int64_t)sr->last_iteration + edits;
    server_log(r->name, "loaded at iteration %d (%s)", sr->last_iteration,
               sylva_run_status_name(sr->status));
    if (r->status == SYLVA_RUN_RUNNING) run_schedule(r);
  }
  store_runs_free(stored, n);
  return 0;
}

void runs_free(server *d) {
  run *r = d->runs;
  while (r) {
    run *next = r->next;
    while (r->edits) {
      pending_edit *e = r->edits;
      r->edits = e->next;
      sylva_msg_free(&e->msg);
      free(e);
    }
    while (r->lights) {
      pending_light *l = r->lights;
      r->lights = l->next;
      free(l->ref);
      free(l);
    }
    for (int i = 0; i < DAEMON_DELTA_HISTORY; i++) msgbuf_unref(r->history[i]);
    msgbuf_unref(r->snapshot);
    free(r->work_delta);
    sylva_world_destroy(r->w);
    free(r->name);
    free(r);
    r = next;
  }
  d->runs = NULL;
}

run *run_create(server *d, const sylva_scenario *s, const char *name, bool start,
                const char **code, char *err, size_t errlen) {
  *code = "bad_request";
  sylva_world *w;
  char why[512];
  if (sylva_scenario_build(s, &w, why, sizeof why) < 0) {
    snprintf(err, errlen, "/scenario%s%s", why[0] == '/' ? "" : ": ", why);
    return NULL;
  }
  char *json = sylva_scenario_json(s);
  if (!json) {
    sylva_world_destroy(w);
    *code = "internal";
    snprintf(err, errlen, "out of memory");
    return NULL;
  }
  int64_t id;
  int failed = store_create_run(d->st, name, json, s->seed, s->iterations, STORE_SNAPSHOT_EVERY,
                                w, &id);
  if (failed) snprintf(err, errlen, "%s", store_error(d->st));
  free(json);
  if (failed) {
    sylva_world_destroy(w);
    if (!strstr(err, "exists already")) *code = "internal";
    return NULL;
  }
  run *r = run_new(d, id, name, w, start ? SYLVA_RUN_RUNNING : SYLVA_RUN_PAUSED, s->iterations,
                   STORE_SNAPSHOT_EVERY);
  if (!r) {
    sylva_world_destroy(w);
    *code = "internal";
    snprintf(err, errlen, "out of memory");
    return NULL;
  }
  store_set_status(d->st, id, r->status, NULL, 0);
  server_log(r->name, "created (%s)", sylva_run_status_name(r->status));
  run_schedule(r);
  return r;
}

/* ---- edits, forks, history ------------------------------------------------------ */

/* The store's edit of a protocol `edit` message (copies; SYLVA_ENOMEM or 0). */
static int edit_from_msg(const sylva_msg *m, edit *e) {
  *e = (edit){0};
  if (edit_reserve(e, m->remove_obstacle_count, m->add_obstacle_count, m->add_plant_count))
    return SYLVA_ENOMEM;
  for (int i = 0; i < m->remove_obstacle_count; i++)
    if (!(e->removals[i] = strdup(m->remove_obstacles[i]))) return SYLVA_ENOMEM;
  for (int i = 0; i < m->add_obstacle_count; i++) {
    const sylva_scenario_obstacle *o = &m->add_obstacles[i];
    edit_obstacle *eo = &e->obstacles[i];
    memcpy(eo->min, o->min, sizeof eo->min);
    memcpy(eo->max, o->max, sizeof eo->max);
    if (!(eo->id = strdup(o->id))) return SYLVA_ENOMEM;
  }
  for (int i = 0; i < m->add_plant_count; i++) {
    const sylva_scenario_plant *p = &m->add_plants[i];
    edit_plant *ep = &e->plants[i];
    size_t roots = (size_t)p->root_count * sizeof *p->roots;
    if (!(ep->id = strdup(p->id)) || !(ep->species = strdup(m->add_plant_species[i])) ||
        !(ep->roots = malloc(roots)))
      return SYLVA_ENOMEM;
    memcpy(ep->roots, p->roots, roots);
    ep->root_count = p->root_count;
  }
  return SYLVA_OK;
}

/* Applies one edit to the idle run; answers the client when it is still there. */
static void edit_now(run *r, client *c, const sylva_msg *m) {
  server *d = r->d;
  char err[512] = "out of memory";
  sylva_world *edited = NULL;
  edit e;
  int rc = edit_from_msg(m, &e);
  if (rc == SYLVA_OK) rc = edit_apply(r->w, &e, &edited, err, sizeof err);
  if (rc != SYLVA_OK) {
    edit_free(&e);
    if (c) client_send_text(c, sylva_msg_error(rc == SYLVA_ENOMEM ? "internal" : "bad_request",
                                               err, m->ref));
    return;
  }
  int failed = store_apply_edit(d->st, r->id, edited, &e);
  if (failed) snprintf(err, sizeof err, "%s", store_error(d->st));
  edit_free(&e);
  if (failed) {
    sylva_world_destroy(edited);
    server_log(r->name, "edit not stored: %s", err);
    if (c) client_send_text(c, sylva_msg_error("internal", err, m->ref));
    return;
  }
  sylva_world_destroy(r->w);
  r->w = edited;
  run_note(r);
  server_log(r->name, "edited after iteration %d (+%d plants, +%d obstacles, -%d obstacles)",
             r->iteration, m->add_plant_count, m->add_obstacle_count, m->remove_obstacle_count);
  /* deltas cannot carry an edit: every subscriber gets a fresh snapshot, and the
   * deltas held for resubscribers end here */
  r->seq++;
  for (int i = 0; i < DAEMON_DELTA_HISTORY; i++) {
    msgbuf_unref(r->history[i]);
    r->history[i] = NULL;
  }
  for (client *o = d->clients.head; o; o = o->next) {
    subscription *s = client_subscription(o, r->id);
    if (!s) continue;
    s->need_snapshot = false;
    send_snapshot(r, o, NULL);
  }
  if (c) client_send_text(c, sylva_msg_status(r->id, r->status, r->iteration, m->ref));
}

static void apply_pending_edits(run *r) {
  while (r->edits) {
    pending_edit *e = r->edits;
    r->edits = e->next;
    if (!r->d->stopping) edit_now(r, client_find(&r->d->clients, e->client), &e->msg);
    sylva_msg_free(&e->msg);
    free(e);
  }
}

void run_edit(run *r, client *c, sylva_msg *m) {
  if (!r->busy) {
    edit_now(r, c, m);
    return;
  }
  pending_edit *e = calloc(1, sizeof *e);
  if (!e) {
    client_send_text(c, sylva_msg_error("internal", "out of memory", m->ref));
    return;
  }
  e->msg = *m;
  memset(m, 0, sizeof *m); /* the queue owns the message now */
  e->client = c->serial;
  pending_edit **tail = &r->edits;
  while (*tail) tail = &(*tail)->next;
  *tail = e;
}

static void answer_lights(run *r) {
  while (r->lights) {
    pending_light *l = r->lights;
    r->lights = l->next;
    client *c = client_find(&r->d->clients, l->client);
    if (c) client_send_text(c, sylva_msg_light_slice(r->id, r->w, l->z, l->ref));
    free(l->ref);
    free(l);
  }
}

void run_light(run *r, client *c, double z, const char *ref) {
  if (!r->busy) {
    client_send_text(c, sylva_msg_light_slice(r->id, r->w, z, ref));
    return;
  }
  pending_light *l = calloc(1, sizeof *l);
  if (!l || (ref && !(l->ref = strdup(ref)))) {
    free(l);
    client_send_text(c, sylva_msg_error("internal", "out of memory", ref));
    return;
  }
  l->client = c->serial;
  l->z = z;
  pending_light **tail = &r->lights;
  while (*tail) tail = &(*tail)->next;
  *tail = l;
}

/* A fork or a history snapshot, computed off the loop. */
typedef struct job {
  uv_work_t work;
  server *d;
  uint64_t client;
  int64_t run;
  int iteration, limit, snapshot_every;
  bool fork;
  char *name, *ref, *text;
  sylva_world *w;
  int64_t new_id;
  char err[512];
  const char *code;
} job;

static void job_free(job *j) {
  free(j->name);
  free(j->ref);
  free(j->text);
  sylva_world_destroy(j->w);
  free(j);
}

static void job_work(uv_work_t *req) {
  job *j = req->data;
  server *d = j->d;
  j->code = NULL;
  int failed = store_world_at(d->st, j->run, j->iteration, NULL, &j->w);
  char *scenario = NULL;
  if (!failed && j->fork) {
    failed = store_run_scenario(d->st, j->run, &scenario) ||
             store_create_run(d->st, j->name, scenario, sylva_world_get_def(j->w)->seed, j->limit,
                              j->snapshot_every, j->w, &j->new_id);
    if (!failed) failed = store_set_status(d->st, j->new_id, SYLVA_RUN_PAUSED, NULL, 0);
  }
  if (failed) {
    snprintf(j->err, sizeof j->err, "%s", store_error(d->st));
    j->code = strstr(j->err, "exists already") ? "bad_request" : "internal";
  }
  free(scenario);
  if (!failed && !j->fork) {
    j->text = sylva_msg_snapshot(j->run, 0, j->w, j->ref);
    if (!j->text) {
      j->code = "internal";
      snprintf(j->err, sizeof j->err, "out of memory");
    }
  }
}

static void job_done(uv_work_t *req, int status) {
  job *j = req->data;
  (void)status;
  client *c = client_find(&j->d->clients, j->client);
  if (j->code) {
    if (c) client_send_text(c, sylva_msg_error(j->code, j->err, j->ref));
  } else if (j->fork) {
    run *nr = run_new(j->d, j->new_id, j->name, j->w, SYLVA_RUN_PAUSED, j->limit, j->snapshot_every);
    if (nr) {
      nr->seq = j->iteration; /* a fork starts with no edits of its own */
      j->w = NULL; /* the run owns it */
      server_log(nr->name, "forked at iteration %d", nr->iteration);
      if (c) client_send_text(c, sylva_msg_created(nr->id, nr->name, j->ref));
    } else if (c) {
      client_send_text(c, sylva_msg_error("internal", "out of memory", j->ref));
    }
  } else if (c) {
    client_send_text(c, j->text);
    j->text = NULL;
  }
  job_free(j);
}

static void start_job(run *r, client *c, int iteration, const char *name, const char *ref) {
  job *j = calloc(1, sizeof *j);
  if (!j || (name && !(j->name = strdup(name))) || (ref && !(j->ref = strdup(ref)))) {
    if (j) job_free(j);
    client_send_text(c, sylva_msg_error("internal", "out of memory", ref));
    return;
  }
  if (iteration > r->iteration) {
    char err[128];
    snprintf(err, sizeof err, "/iteration: run %lld has iterations 0 to %d", (long long)r->id,
             r->iteration);
    client_send_text(c, sylva_msg_error("bad_request", err, ref));
    job_free(j);
    return;
  }
  j->d = r->d;
  j->client = c->serial;
  j->run = r->id;
  j->iteration = iteration;
  j->fork = name != NULL;
  j->limit = r->limit;
  j->snapshot_every = r->snapshot_every;
  j->work.data = j;
  if (uv_queue_work(&r->d->loop, &j->work, job_work, job_done) != 0) {
    client_send_text(c, sylva_msg_error("internal", "cannot queue the work", ref));
    job_free(j);
  }
}

void run_fork(run *r, client *c, int iteration, const char *name, const char *ref) {
  for (run *o = r->d->runs; o; o = o->next)
    if (strcmp(o->name, name) == 0) {
      client_send_text(c, sylva_msg_error("bad_request", "/name: a run with this name exists", ref));
      return;
    }
  start_job(r, c, iteration, name, ref);
}

void run_get(run *r, client *c, int iteration, const char *ref) {
  start_job(r, c, iteration, NULL, ref);
}
