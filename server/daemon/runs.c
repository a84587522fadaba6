#include "runs.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "edit.h"
#include "sweep_store.h"
#include "sylva/protocol.h"
#include "sylva/status.h"

/** An edit waiting for its task. */
typedef struct pending_edit {
  sylva_msg msg;
  uint64_t client;
  struct pending_edit *next;
} pending_edit;

/** A light request waiting for its task. */
typedef struct pending_light {
  uint64_t client;
  double z;
  char *ref;
  struct pending_light *next;
} pending_light;


static run_conflicts conflicts_of(const sylva_world *w) {
  run_conflicts out = {.reported = sylva_world_reports_conflicts(w)};
  sylva_conflicts c = sylva_world_conflicts(w);
  for (size_t i = 0; i < c.zone_count; i++) out.zone_nodes += c.zones[i].nodes;
  out.entered = (int64_t)c.zone_count;
  return out;
}

/* Caches what the loop may report while a worker has the world. */
static void run_note(run *r) {
  r->conflicts = conflicts_of(r->w);
  r->nodes = (int64_t)sylva_world_node_count(r->w);
  r->iteration = sylva_world_iteration(r->w);
  r->stems = sylva_world_stem_count(r->w);
  r->finished = sylva_world_finished(r->w);
  r->obstacles = sylva_world_obstacle_count(r->w);
}

/* ---- limits ------------------------------------------------------------------------ */

/** Bytes of one grid chunk of 16^3 voxels at most (shade, occupancy, a column). */
#define BYTES_PER_CHUNK (80u << 10)

/* The estimate of a world of dims voxels (see runs_estimate). */
static size_t estimate_dims(const int dims[3], int stems) {
  size_t chunks = 1;
  for (int a = 0; a < 3; a++) chunks *= (size_t)(dims[a] + 15) / 16;
  size_t box = chunks * BYTES_PER_CHUNK, grown = (size_t)stems * DAEMON_BYTES_PER_STEM;
  return (grown < box ? grown : box) + (1u << 20);
}

size_t runs_estimate(const sylva_world *w, int stems) {
  int dims[3];
  sylva_world_dims(w, dims);
  return estimate_dims(dims, stems);
}

size_t runs_estimate_scenario(const sylva_scenario *s) {
  int dims[3];
  for (int a = 0; a < 3; a++) { /* as the grid counts its cells (core/src/grid.c) */
    double cells = ceil((s->world_max[a] - s->world_min[a]) / s->voxel - 1e-9);
    dims[a] = cells >= 1.0 && cells < (double)(1 << 24) ? (int)cells : 1 << 24;
  }
  return estimate_dims(dims, s->stem_count);
}

/* What a run not in memory will take once loaded: its stored stems' share, as
 * runs_estimate without the box's bound (the box is not known before loading). */
static size_t estimate_unloaded(const run *r) {
  return (size_t)r->stems * DAEMON_BYTES_PER_STEM + (1u << 20);
}

static bool run_loaded(const run *r) { return r->w != NULL; }

static bool run_watched(const run *r) {
  for (client *c = r->d->clients.head; c; c = c->next)
    if (client_subscription(c, r->id)) return true;
  return false;
}

/* A run in memory that nothing needs there: no task, no waiting work, not growing,
 * nobody subscribed. Its world may go back to the store. */
static bool run_idle(const run *r) {
  return run_loaded(r) && !r->busy && !r->edits && !r->lights && r->steps == 0 &&
         r->status != SYLVA_RUN_RUNNING && !run_watched(r);
}

/* Frees an idle run's world (and what was encoded from it); it stays listed and
 * loads again when a client needs it. */
static void run_unload(run *r) {
  server *d = r->d;
  d->memory_reserved -= r->estimate;
  r->estimate = 0;
  sylva_world_destroy(r->w);
  r->w = NULL;
  for (int i = 0; i < DAEMON_DELTA_HISTORY; i++) {
    msgbuf_unref(r->history[i]);
    r->history[i] = NULL;
  }
  for (int k = 0; k < SYLVA_DETAIL_COUNT; k++) {
    msgbuf_unref(r->snapshot[k]);
    r->snapshot[k] = NULL;
  }
  server_log(r->name, "unloaded (memory budget)");
}

/* Unloads idle runs, the least recently used first, until `bytes` more fit in the
 * memory budget; whether they do. */
static bool runs_free_memory(server *d, size_t bytes, const run *keep) {
  while (d->memory_reserved + bytes > d->opt.memory_budget) {
    run *oldest = NULL;
    for (run *r = d->runs; r; r = r->next)
      if (r != keep && run_idle(r) && (!oldest || r->used < oldest->used)) oldest = r;
    if (!oldest) return false;
    run_unload(oldest);
  }
  return true;
}

static int runs_held(server *d) {
  int n = d->runs_pending;
  for (run *r = d->runs; r; r = r->next) n++;
  return n;
}

/* Unloads idle runs until estimate more bytes fit in the budget: NULL, or why not
 * in buf ("<what> would need about N MiB; M of the B MiB budget are taken<by> ..."). */
static const char *budget_room(server *d, size_t estimate, const char *what, const char *by,
                               char *buf, size_t size) {
  if (runs_free_memory(d, estimate, NULL)) return NULL;
  snprintf(buf, size, "%s would need about %zu MiB; %zu of the %zu MiB budget are taken%s "
           "(--memory-budget)", what, estimate >> 20, d->memory_reserved >> 20,
           d->opt.memory_budget >> 20, by);
  return buf;
}

const char *runs_room(server *d, size_t estimate, char *buf, size_t size) {
  if (runs_held(d) >= d->opt.max_runs) {
    snprintf(buf, size, "the daemon holds %d runs, its limit (--max-runs)", d->opt.max_runs);
    return buf;
  }
  return budget_room(d, estimate, "the run", "", buf, size);
}

const char *runs_job_room(server *d) {
  return d->jobs < d->opt.max_jobs
             ? NULL
             : "the daemon is busy with other exports, histories and forks (--max-jobs); "
               "try again soon";
}

static bool run_wants_step(const run *r) {
  if (r->loading) return false;
  if (r->status != SYLVA_RUN_RUNNING && !(r->status == SYLVA_RUN_PAUSED && r->steps > 0))
    return false;
  return !r->finished && r->iteration < r->limit;
}

static void persist_status(run *r, const char *reason) {
  server *d = r->d;
  int failed = store_set_status(d->st, r->id, r->status, reason, r->limit);
  if (failed) server_log(r->name, "%s", store_error(d->st));
}

void run_broadcast_status(run *r) {
  char *text = sylva_msg_status(r->id, r->status, r->iteration, r->start_year, NULL);
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
  if (status == SYLVA_RUN_FINISHED) reason = r->finished ? "finished" : "limit";
  persist_status(r, reason);
  server_log(r->name, "%s at iteration %d", sylva_run_status_name(status), r->iteration);
  run_broadcast_status(r);
}

const char *run_control(run *r, sylva_control_action action, int count) {
  switch (action) {
  case SYLVA_CONTROL_START:
    if (sylva_run_status_over(r->status)) return "/action: the run has ended; fork it to go on";
    run_set_status(r, SYLVA_RUN_RUNNING);
    break;
  case SYLVA_CONTROL_PAUSE:
    if (r->status == SYLVA_RUN_RUNNING) run_set_status(r, SYLVA_RUN_PAUSED);
    r->steps = 0;
    break;
  case SYLVA_CONTROL_STEP:
    if (sylva_run_status_over(r->status)) return "/action: the run has ended; fork it to go on";
    if (r->status == SYLVA_RUN_RUNNING) run_set_status(r, SYLVA_RUN_PAUSED);
    r->steps += count;
    break;
  case SYLVA_CONTROL_STOP:
    r->steps = 0;
    if (r->busy)
      r->stop_after = true; /* ends when the task in flight is done */
    else
      run_set_status(r, SYLVA_RUN_FINISHED);
    break;
  }
  run_schedule(r);
  return NULL;
}

static double mono_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

/* ---- the tasks, on a worker ----------------------------------------------------- */

static void load_warning(const char *msg) { server_log(NULL, "warning: %s", msg); }

static void work_load(run *r) {
  server *d = r->d;
  if (store_world_at(d->reader, r->id, r->iteration, load_warning, &r->task_world) ||
      store_command_count(d->reader, r->id, &r->task_edits)) {
    r->task_status = SYLVA_EINVAL;
    snprintf(r->task_error, sizeof r->task_error, "%s", store_error(d->reader));
  }
}

/* One iteration, stored and encoded, into res; whether it went well. */
static bool step_once(run *r, int64_t seq, step_result *res) {
  server *d = r->d;
  const sylva_journal *j;
  *res = (step_result){.status = SYLVA_OK};
  double t0 = mono_ms();
  res->status = sylva_world_step(r->w, &j);
  res->at_ms[0] = mono_ms();
  res->ms = res->at_ms[0] - t0;
  if (res->status != SYLVA_OK) {
    snprintf(res->error, sizeof res->error, "iteration %d: %s", sylva_world_iteration(r->w) + 1,
             sylva_strerror(res->status));
    return false;
  }
  /* the iteration's row first: it is stored, and can be regrown, before its delta
   * goes out; its snapshot, when due, is added after (work_step), so that viewers do
   * not wait for the image of the whole world (docs/protocol.md) */
  res->snapshot_due = store_step_snapshot(r->w, j, r->snapshot_every, r->limit);
  if (store_save_iteration(d->st, r->id, r->w, j, false)) {
    snprintf(res->error, sizeof res->error, "%s", store_error(d->st));
    res->status = SYLVA_EINVAL;
    return false;
  }
  res->at_ms[1] = mono_ms();
  for (int k = 0; k < SYLVA_DETAIL_COUNT; k++)
    if (atomic_load(&r->want[k]))
      res->text[k] = sylva_msg_delta_detail(r->id, seq, r->w, j, r->start_year, (sylva_detail)k);
  res->at_ms[2] = mono_ms();
  res->iteration = sylva_world_iteration(r->w);
  res->stems = sylva_world_stem_count(r->w);
  res->obstacles = sylva_world_obstacle_count(r->w);
  res->nodes = (int64_t)sylva_world_node_count(r->w);
  res->finished = sylva_world_finished(r->w);
  res->conflicts = conflicts_of(r->w);
  for (size_t k = 0; k < j->stem_count; k++) res->pruned += j->stats[k].pruned;
  return true;
}

/* Up to batch_max iterations, each handed to the loop when made. */
static void work_step(run *r) {
  double t0 = mono_ms();
  r->snapshot_error[0] = '\0';
  for (int k = 0; k < r->batch_max; k++) {
    bool ok = step_once(r, r->batch_seq + k + 1, &r->results[k]);
    bool snapshot = ok && r->results[k].snapshot_due;
    pthread_mutex_lock(&r->lock);
    r->made = k + 1;
    pthread_mutex_unlock(&r->lock);
    pool_report(&r->d->pool, &r->task);
    /* the loop sends the delta meanwhile; a snapshot that cannot be stored fails the
     * run once the task is done (task_done), its row kept */
    if (snapshot && store_save_snapshot(r->d->st, r->id, r->w)) {
      snprintf(r->snapshot_error, sizeof r->snapshot_error, "%s", store_error(r->d->st));
      break;
    }
    if (!ok || r->results[k].finished || atomic_load(&r->yield) ||
        mono_ms() - t0 >= RUN_SLICE_MS)
      break;
  }
}

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
    eo->kind = o->kind;
    sylva_obstacle_def def = sylva_scenario_obstacle_def(o);
    if (!(eo->id = strdup(o->id)) || edit_obstacle_footprint(eo, &def.footprint)) return SYLVA_ENOMEM;
  }
  if (m->prune) {
    e->prune.set = true;
    memcpy(e->prune.min, m->prune_min, sizeof e->prune.min);
    memcpy(e->prune.max, m->prune_max, sizeof e->prune.max);
    if (m->prune_zone[0] && !(e->prune.zone = strdup(m->prune_zone))) return SYLVA_ENOMEM;
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
    ep->age = p->age;
  }
  return SYLVA_OK;
}

static void work_edit(run *r) {
  server *d = r->d;
  const sylva_msg *m = &r->edits->msg;
  edit e;
  r->task_code = "internal";
  snprintf(r->task_error, sizeof r->task_error, "out of memory");
  int rc = edit_from_msg(m, &e);
  if (rc == SYLVA_OK) rc = edit_apply(r->w, &e, &r->task_world, r->task_error, sizeof r->task_error);
  if (rc != SYLVA_OK) {
    if (rc != SYLVA_ENOMEM) r->task_code = "bad_request";
  } else if (store_apply_edit(d->st, r->id, r->task_world, &e)) {
    snprintf(r->task_error, sizeof r->task_error, "%s", store_error(d->st));
    sylva_world_destroy(r->task_world);
    r->task_world = NULL;
    rc = SYLVA_EINVAL;
  }
  edit_free(&e);
  r->task_status = rc;
}

static void task_work(pool_task *t) {
  run *r = (run *)((char *)t - offsetof(run, task));
  r->task_status = SYLVA_OK;
  r->task_error[0] = 0;
  switch (r->kind) {
  case RUN_TASK_LOAD: work_load(r); break;
  case RUN_TASK_STEP: work_step(r); break;
  case RUN_TASK_EDIT: work_edit(r); break;
  case RUN_TASK_LIGHT:
    r->task_text = sylva_msg_light_slice(r->id, r->w, r->lights->z, r->lights->ref);
    break;
  case RUN_TASK_SNAPSHOT:
    for (int k = 0; k < SYLVA_DETAIL_COUNT; k++)
      if (r->task_details[k])
        r->task_snapshots[k] =
            sylva_msg_snapshot_detail(r->id, r->seq, r->w, r->start_year, (sylva_detail)k, NULL);
    break;
  case RUN_TASK_NONE: break;
  }
}

/* ---- the tasks' results, on the loop -------------------------------------------- */

/* Sends the cached snapshot of its detail to every subscriber waiting for one at
 * one of the details `which`. */
static void send_waiting_snapshots(run *r, const bool which[SYLVA_DETAIL_COUNT]) {
  for (client *c = r->d->clients.head; c; c = c->next) {
    subscription *s = client_subscription(c, r->id);
    if (!s || !s->need_snapshot || !which[s->detail]) continue;
    msgbuf *snapshot = r->snapshot[s->detail];
    s->need_snapshot = false;
    if (!snapshot) {
      client_send_text(c, NULL); /* out of memory: an error */
    } else if (s->ref) {
      msgbuf *m = msgbuf_with_ref(snapshot, s->ref);
      if (m) client_send(c, m);
      else client_send_text(c, NULL);
      msgbuf_unref(m);
    } else {
      client_send(c, snapshot);
    }
    free(s->ref);
    s->ref = NULL;
  }
}

/* Whether a subscriber waits for a snapshot; the details they wait for in `details`. */
static bool snapshot_wanted(run *r, bool details[SYLVA_DETAIL_COUNT]) {
  bool any = false;
  for (int k = 0; k < SYLVA_DETAIL_COUNT; k++) details[k] = false;
  for (client *c = r->d->clients.head; c; c = c->next) {
    subscription *s = client_subscription(c, r->id);
    if (s && s->need_snapshot) any = details[s->detail] = true;
  }
  return any;
}

static bool snapshot_current(const run *r, sylva_detail k) {
  return r->snapshot[k] && r->snapshot_seq[k] == r->seq;
}

/* Counts the details of the run's subscribers, whose deltas its iterations encode
 * (r->want). The nodes delta is also encoded while nobody is subscribed, so that a
 * viewer that comes back with `since` finds the deltas it missed held. */
static void note_wanted(run *r) {
  bool want[SYLVA_DETAIL_COUNT] = {false}, any = false;
  for (client *c = r->d->clients.head; c; c = c->next) {
    subscription *s = client_subscription(c, r->id);
    if (s) any = want[s->detail] = true;
  }
  if (!any) want[SYLVA_DETAIL_NODES] = true;
  for (int k = 0; k < SYLVA_DETAIL_COUNT; k++) atomic_store(&r->want[k], want[k]);
}

static void done_snapshot(run *r) {
  for (int k = 0; k < SYLVA_DETAIL_COUNT; k++) {
    if (!r->task_details[k]) continue;
    char *text = r->task_snapshots[k];
    msgbuf_unref(r->snapshot[k]);
    r->snapshot[k] = text ? msgbuf_new(text, strlen(text)) : NULL;
    r->snapshot_seq[k] = r->seq;
  }
  send_waiting_snapshots(r, r->task_details);
}

static void done_step(run *r, const step_result *res) {
  server *d = r->d;
  if (res->status != SYLVA_OK) {
    server_log(r->name, "failed: %s", res->error);
    r->status = SYLVA_RUN_FAILED;
    persist_status(r, NULL);
    run_broadcast_status(r);
    return;
  }
  d->iterations_total++;
  d->iteration_ms_total += res->ms;
  d->pruned_total += res->pruned;
  r->conflicts = res->conflicts;
  r->iteration = res->iteration;
  r->stems = res->stems;
  r->obstacles = res->obstacles;
  r->nodes = res->nodes;
  r->finished = res->finished;
  r->seq++;
  msgbuf *m[SYLVA_DETAIL_COUNT];
  for (int k = 0; k < SYLVA_DETAIL_COUNT; k++)
    m[k] = res->text[k] ? msgbuf_new(res->text[k], strlen(res->text[k])) : NULL;
  /* the nodes deltas are held for `since` (a stems subscriber gets a snapshot) */
  msgbuf **slot = &r->history[r->seq % DAEMON_DELTA_HISTORY];
  msgbuf_unref(*slot);
  *slot = m[SYLVA_DETAIL_NODES];
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
  /* a subscriber waiting for a snapshot gets the next one (the next task) instead, and
   * so does one whose delta is missing (out of memory, or it subscribed at a detail
   * nobody had wanted when the iteration began) */
  for (client *c = d->clients.head; c; c = c->next) {
    subscription *s = client_subscription(c, r->id);
    if (!s) continue;
    if (!m[s->detail]) s->need_snapshot = true;
    if (!s->need_snapshot) client_send(c, m[s->detail]);
  }
  msgbuf_unref(m[SYLVA_DETAIL_STEMS]);
  note_wanted(r); /* subscribers may have gone */
  if (d->opt.trace) /* the step returned, stored, its delta encoded, handed out */
    fprintf(d->opt.trace, "%lld %d %.6f %.6f %.6f %.6f\n", (long long)r->id, res->iteration,
            res->at_ms[0] / 1e3, res->at_ms[1] / 1e3, res->at_ms[2] / 1e3, mono_ms() / 1e3);
  if (r->steps > 0) r->steps--;
  if (d->stopping) return;
  if (r->stop_after || r->finished || r->iteration >= r->limit) {
    r->stop_after = false;
    /* While the task still stores the last snapshot (work_step), marking the run
     * finished in the store would wait for it on the loop thread, and the delta just
     * handed out with it: the status follows when the task is done. */
    if (r->busy)
      r->finish_pending = true;
    else
      run_set_status(r, SYLVA_RUN_FINISHED);
    return;
  }
  if (r->status == SYLVA_RUN_PAUSED && r->steps == 0) run_broadcast_status(r);
}

/* The iterations of the step task that the loop has not taken yet, in order. */
static void take_steps(run *r) {
  pthread_mutex_lock(&r->lock);
  int made = r->made;
  pthread_mutex_unlock(&r->lock);
  for (; r->taken < made; r->taken++) {
    step_result *res = &r->results[r->taken];
    done_step(r, res);
    for (int k = 0; k < SYLVA_DETAIL_COUNT; k++) {
      free(res->text[k]);
      res->text[k] = NULL;
    }
  }
}

static void task_progress(pool_task *t) {
  run *r = (run *)((char *)t - offsetof(run, task));
  if (r->kind == RUN_TASK_STEP) take_steps(r);
}

static void done_edit(run *r) {
  server *d = r->d;
  pending_edit *e = r->edits;
  r->edits = e->next;
  client *c = client_find(&d->clients, e->client);
  const sylva_msg *m = &e->msg;
  if (r->task_status != SYLVA_OK) {
    if (strcmp(r->task_code, "internal") == 0)
      server_log(r->name, "edit not applied: %s", r->task_error);
    if (c) client_send_text(c, sylva_msg_error(r->task_code, r->task_error, m->ref));
  } else {
    sylva_world_destroy(r->w);
    r->w = r->task_world;
    r->task_world = NULL;
    run_note(r);
    size_t estimate = runs_estimate(r->w, r->stems);
    d->memory_reserved += estimate - r->estimate;
    r->estimate = estimate;
    server_log(r->name, "edited after iteration %d (+%d plants, +%d obstacles, -%d obstacles)",
               r->iteration, m->add_plant_count, m->add_obstacle_count,
               m->remove_obstacle_count);
    /* deltas cannot carry an edit: every subscriber gets a fresh snapshot (the next
     * task), and the deltas held for resubscribers end here */
    r->seq++;
    for (int i = 0; i < DAEMON_DELTA_HISTORY; i++) {
      msgbuf_unref(r->history[i]);
      r->history[i] = NULL;
    }
    for (client *o = d->clients.head; o; o = o->next) {
      subscription *s = client_subscription(o, r->id);
      if (s) s->need_snapshot = true;
    }
    if (c)
      client_send_text(c, sylva_msg_status(r->id, r->status, r->iteration, r->start_year, m->ref));
  }
  sylva_msg_free(&e->msg);
  free(e);
}

static void done_light(run *r) {
  pending_light *l = r->lights;
  r->lights = l->next;
  client *c = client_find(&r->d->clients, l->client);
  if (c) client_send_text(c, r->task_text); /* takes it */
  else free(r->task_text);
  r->task_text = NULL;
  free(l->ref);
  free(l);
}

static void run_remove(run *r);

static void done_load(run *r) {
  if (r->task_status != SYLVA_OK) {
    server_log(r->name, "not loaded: %s", r->task_error);
    run_remove(r);
    return;
  }
  r->w = r->task_world;
  r->task_world = NULL;
  r->loading = false;
  run_note(r);
  size_t estimate = runs_estimate(r->w, r->stems);
  r->d->memory_reserved += estimate - r->estimate;
  r->estimate = estimate;
  /* one seq per delta and per edit since the run was planted, so that the numbers a
   * client holds keep their meaning across restarts of the daemon */
  r->seq = (int64_t)r->iteration + r->task_edits;
  server_log(r->name, "loaded at iteration %d (%s)", r->iteration,
             sylva_run_status_name(r->status));
}

static void task_done(pool_task *t, bool cancelled) {
  run *r = (run *)((char *)t - offsetof(run, task));
  run_task kind = r->kind;
  r->used = uv_now(&r->d->loop);
  r->busy = false;
  r->kind = RUN_TASK_NONE;
  if (!cancelled) {
    switch (kind) {
    case RUN_TASK_LOAD: done_load(r); break;
    case RUN_TASK_STEP:
      take_steps(r); /* the last of them may leave the run to finish (done_step) */
      if (r->snapshot_error[0] && r->status != SYLVA_RUN_FAILED) {
        server_log(r->name, "failed: %s", r->snapshot_error);
        r->status = SYLVA_RUN_FAILED;
        persist_status(r, NULL);
        run_broadcast_status(r);
      } else if (r->finish_pending && !r->d->stopping) {
        run_set_status(r, SYLVA_RUN_FINISHED);
      }
      break;
    case RUN_TASK_EDIT: done_edit(r); break;
    case RUN_TASK_LIGHT: done_light(r); break;
    case RUN_TASK_SNAPSHOT: done_snapshot(r); break;
    case RUN_TASK_NONE: break;
    }
    if (kind == RUN_TASK_LOAD && r->task_status != SYLVA_OK) {
      runs_wake(r->d); /* removed: its reservation is free */
      return;
    }
  }
  r->finish_pending = false;
  free(r->task_text);
  r->task_text = NULL;
  for (int k = 0; k < SYLVA_DETAIL_COUNT; k++) {
    free(r->task_snapshots[k]);
    r->task_snapshots[k] = NULL;
  }
  sylva_world_destroy(r->task_world);
  r->task_world = NULL;
  if (cancelled || r->d->stopping) return;
  if (r->stop_after && kind != RUN_TASK_STEP) {
    r->stop_after = false;
    run_set_status(r, SYLVA_RUN_FINISHED);
  }
  run_schedule(r);
  if (!r->busy) runs_wake(r->d); /* the run may have stopped needing its memory */
}

/* Queues the run's task of this kind on the pool. */
static void submit(run *r, run_task kind) {
  r->busy = true;
  r->kind = kind;
  r->task = (pool_task){.work = task_work, .done = task_done, .progress = task_progress};
  pool_submit(&r->d->pool, &r->task);
}

/* Starts the run's next task: pending edits first, then light slices, then a
 * snapshot for subscribers waiting for one, then an iteration. */
void run_schedule(run *r) {
  /* something new wants the run: a step task stops after its iteration in flight */
  if (r->busy && r->kind == RUN_TASK_STEP) atomic_store(&r->yield, true);
  if (r->busy || r->d->stopping || r->loading) return;
  if (!run_loaded(r)) {
    /* loads when something needs the world; a run that cannot have the memory yet
     * waits (runs_wake tries again when memory is freed) */
    char why[256];
    if (run_wants_step(r) || snapshot_wanted(r, r->task_details) || r->edits || r->lights)
      run_load(r, why, sizeof why);
    return;
  }
  run_task kind = RUN_TASK_NONE;
  if (r->edits)
    kind = RUN_TASK_EDIT;
  else if (r->lights)
    kind = RUN_TASK_LIGHT;
  else if (snapshot_wanted(r, r->task_details)) {
    bool current[SYLVA_DETAIL_COUNT], any = false;
    for (int k = 0; k < SYLVA_DETAIL_COUNT; k++)
      any |= current[k] = r->task_details[k] && snapshot_current(r, (sylva_detail)k);
    if (any) {
      send_waiting_snapshots(r, current); /* the cached ones are current */
      run_schedule(r);
      return;
    }
    kind = RUN_TASK_SNAPSHOT; /* of the details in task_details */
  } else if (run_wants_step(r))
    kind = RUN_TASK_STEP;
  if (kind == RUN_TASK_NONE) return;
  if (kind == RUN_TASK_STEP) {
    int n = r->limit - r->iteration;
    if (r->status != SYLVA_RUN_RUNNING && r->steps < n) n = r->steps;
    r->batch_max = n < RUN_AHEAD ? n : RUN_AHEAD;
    r->batch_seq = r->seq;
    r->made = r->taken = 0;
    atomic_store(&r->yield, false);
    note_wanted(r);
  }
  submit(r, kind);
}

const char *run_load(run *r, char *buf, size_t size) {
  server *d = r->d;
  if (run_loaded(r) || r->loading) return NULL;
  if (d->stopping) { /* the pool takes no more work */
    snprintf(buf, size, "/run: the daemon is stopping");
    return buf;
  }
  size_t estimate = estimate_unloaded(r);
  const char *full = budget_room(d, estimate, "/run: loading the run", " by runs in use", buf, size);
  if (full) return full;
  r->estimate = estimate;
  d->memory_reserved += estimate;
  r->loading = true;
  submit(r, RUN_TASK_LOAD);
  return NULL;
}

const char *run_ready(run *r, char *buf, size_t size) {
  r->used = uv_now(&r->d->loop);
  if (run_loaded(r) && !r->loading) return NULL;
  const char *why = run_load(r, buf, size);
  return why ? why : "/run: the run is loading; ask again in a moment";
}

void runs_wake(server *d) {
  if (d->stopping) return;
  for (run *r = d->runs; r; r = r->next)
    if (!run_loaded(r) && !r->loading && run_wants_step(r)) {
      char why[256];
      if (run_load(r, why, sizeof why)) return; /* the first in line waits */
    }
}

void runs_forget_client(server *d, uint64_t serial) {
  for (run *r = d->runs; r; r = r->next) {
    /* the slice in flight (the head, while a light task runs) stays for its task */
    pending_light **p = &r->lights;
    if (r->kind == RUN_TASK_LIGHT && *p) p = &(*p)->next;
    while (*p) {
      pending_light *l = *p;
      if (l->client != serial) {
        p = &l->next;
        continue;
      }
      *p = l->next;
      free(l->ref);
      free(l);
    }
  }
  runs_wake(d);
}

void runs_halt(server *d) {
  for (run *r = d->runs; r; r = r->next) atomic_store(&r->yield, true);
}

bool runs_busy(server *d) {
  for (run *r = d->runs; r; r = r->next)
    if (r->busy) return true;
  return false;
}

void run_subscribe(run *r, client *c, bool has_since, int64_t since, sylva_detail detail,
                   const char *ref) {
  char why[256];
  r->used = uv_now(&r->d->loop);
  if (!run_loaded(r) && run_load(r, why, sizeof why)) {
    client_send_text(c, sylva_msg_error("busy", why, ref));
    return;
  }
  subscription *s = client_subscribe(c, r->id);
  if (!s) {
    client_send_text(c, sylva_msg_error("internal", "out of memory", ref));
    return;
  }
  s->detail = detail;
  note_wanted(r);
  /* the deltas after `since` can be replayed when every one of them is held (nodes
   * deltas only: a stems subscriber always gets a fresh snapshot) */
  if (detail == SYLVA_DETAIL_NODES && !r->loading && has_since && since >= 0 && since <= r->seq &&
      r->seq - since < DAEMON_DELTA_HISTORY) {
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
  free(s->ref);
  s->ref = ref ? strdup(ref) : NULL;
  s->need_snapshot = true;
  /* now when the cached snapshot is current and no task is in flight, else after */
  bool only[SYLVA_DETAIL_COUNT] = {false};
  only[detail] = true;
  if (!r->busy && !r->loading && snapshot_current(r, detail))
    send_waiting_snapshots(r, only);
  else
    run_schedule(r);
}

static run *run_new(server *d, int64_t id, const char *name, sylva_world *w,
                    sylva_run_status status, int limit, int snapshot_every, int start_year) {
  run *r = calloc(1, sizeof *r);
  if (!r || !(r->name = strdup(name))) {
    free(r);
    return NULL;
  }
  if (pthread_mutex_init(&r->lock, NULL)) {
    free(r->name);
    free(r);
    return NULL;
  }
  r->d = d;
  r->id = id;
  r->w = w;
  r->limit = limit;
  r->snapshot_every = snapshot_every;
  r->start_year = start_year;
  r->status = status;
  if (w) run_note(r);
  r->estimate = w ? runs_estimate(w, r->stems) : 0;
  d->memory_reserved += r->estimate;
  /* append, so that runs stay in creation order */
  run **tail = &d->runs;
  while (*tail) tail = &(*tail)->next;
  *tail = r;
  return r;
}

static void run_free(run *r) {
  r->d->memory_reserved -= r->estimate;
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
  for (int k = 0; k < SYLVA_DETAIL_COUNT; k++) {
    msgbuf_unref(r->snapshot[k]);
    free(r->task_snapshots[k]);
  }
  free(r->task_text);
  sylva_world_destroy(r->task_world);
  sylva_world_destroy(r->w);
  pthread_mutex_destroy(&r->lock);
  free(r->name);
  free(r->sweep);
  free(r->axes);
  free(r);
}

/* Takes an idle run out of the list and frees it. */
static void run_remove(run *r) {
  for (run **p = &r->d->runs; *p; p = &(*p)->next)
    if (*p == r) {
      *p = r->next;
      break;
    }
  run_free(r);
}

/* store_each_sweep_run's callback: gives the listed run its place in its sweep. */
static int note_sweep_run(const store_sweep_run *sr, void *ctx) {
  run *r = run_find(ctx, sr->run);
  if (!r) return 0;
  free(r->sweep);
  free(r->axes);
  r->sweep = strdup(sr->sweep ? sr->sweep : "");
  r->axes = sr->axes ? strdup(sr->axes) : NULL;
  r->position = sr->position;
  /* out of memory: the run is listed as of no sweep, rather than with half a place */
  if (!r->sweep || (sr->axes && !r->axes)) {
    free(r->sweep);
    free(r->axes);
    r->sweep = r->axes = NULL;
  }
  return 0;
}

int runs_load(server *d) {
  store_run *stored;
  size_t n;
  if (store_list_runs(d->st, &stored, &n)) {
    server_log(NULL, "%s", store_error(d->st));
    return SERVER_EFAIL;
  }
  for (size_t i = 0; i < n; i++) {
    store_run *sr = &stored[i];
    run *r = run_new(d, sr->id, sr->name, NULL, sr->status, sr->iterations, sr->snapshot_every,
                     sr->start_year);
    if (!r) {
      store_runs_free(stored, n);
      return SERVER_ENOMEM;
    }
    r->iteration = sr->last_iteration;
    r->nodes = sr->nodes;
    r->stems = sr->stems;
    r->conflicts = (run_conflicts){sr->reports_conflicts, sr->zone_nodes, sr->zone_pairs};
  }
  store_runs_free(stored, n);
  /* the runs of sweeps carry their place in the run list; without it they are still
   * runs like any other, so a failure to read it is logged and not fatal */
  if (store_each_sweep_run(d->st, NULL, note_sweep_run, d))
    server_log(NULL, "the runs' places in their sweeps: %s", store_error(d->st));
  /* the growing runs load now, as many as the budget holds; the others when a client
   * needs them */
  char why[256];
  for (run *r = d->runs; r; r = r->next)
    if (run_wants_step(r) && run_load(r, why, sizeof why))
      server_log(r->name, "waits for memory to grow: %s", why + strlen("/run: "));
  return SERVER_OK;
}

void runs_free(server *d) {
  run *r = d->runs;
  while (r) {
    run *next = r->next;
    run_free(r);
    r = next;
  }
  d->runs = NULL;
}

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
                                  .stems = r->stems, .loading = r->loading,
                                  .sweep = r->sweep, .position = r->position,
                                  .axes = r->axes};
  char *text = message ? sylva_msg_runs(list, n, ref) : sylva_runs_json(list, n);
  free(list);
  return text;
}

static void start_create(server *d, client *c, sylva_scenario *s, const char *name, bool start,
                         const char *ref, size_t estimate);

const char *run_create(server *d, client *c, sylva_scenario **sp, const char *name, bool start,
                       const char *ref, char *err, size_t errlen) {
  const sylva_scenario *s = *sp;
  if (s->stem_count > d->opt.max_stems) {
    snprintf(err, errlen, "/scenario/plants: %d stems; at most %d in one world (--max-stems)",
             s->stem_count, d->opt.max_stems);
    return "too_large";
  }
  if (s->obstacle_count > d->opt.max_obstacles) {
    snprintf(err, errlen,
             "/scenario/obstacles: %d obstacles; at most %d in one world (--max-obstacles)",
             s->obstacle_count, d->opt.max_obstacles);
    return "too_large";
  }
  if (run_find_name(d, name, strlen(name))) {
    snprintf(err, errlen, "/name: a run named \"%.64s\" exists already", name);
    return "bad_request";
  }
  size_t estimate = runs_estimate_scenario(s);
  if (runs_room(d, estimate, err, errlen)) return "busy";
  start_create(d, c, *sp, name, start, ref, estimate);
  *sp = NULL; /* the job owns it */
  return NULL;
}

/* ---- edits, light slices, forks, history ----------------------------------------- */

/* NULL when the edit keeps the world within the stem and obstacle caps and the
 * memory budget, else why not and *code. The edits still waiting (or being applied)
 * are not in the run's counts yet: their plants and obstacles count as added (their
 * removals do not, as a waiting edit may fail), so that a burst of edits cannot pass
 * a cap that each one alone keeps. */
static const char *edit_room(run *r, const sylva_msg *m, const char **code, char *buf,
                             size_t size) {
  server *d = r->d;
  int stems = r->stems, obstacles = r->obstacles;
  for (const pending_edit *e = r->edits; e; e = e->next) {
    for (int i = 0; i < e->msg.add_plant_count; i++) stems += e->msg.add_plants[i].root_count;
    obstacles += e->msg.add_obstacle_count;
  }
  for (int i = 0; i < m->add_plant_count; i++) stems += m->add_plants[i].root_count;
  *code = "too_large";
  if (stems > d->opt.max_stems) {
    snprintf(buf, size, "/add_plants: the world would have %d stems; at most %d (--max-stems)",
             stems, d->opt.max_stems);
    return buf;
  }
  obstacles += m->add_obstacle_count - m->remove_obstacle_count;
  if (obstacles > d->opt.max_obstacles) {
    snprintf(buf, size,
             "/add_obstacles: the world would have %d obstacles; at most %d (--max-obstacles)",
             obstacles, d->opt.max_obstacles);
    return buf;
  }
  *code = "busy";
  size_t more = stems > r->stems && r->w ? runs_estimate(r->w, stems) : r->estimate;
  if (more > r->estimate && !runs_free_memory(d, more - r->estimate, r)) {
    snprintf(buf, size, "the plants would need about %zu MiB more than the budget has free "
             "(--memory-budget)", (more - r->estimate) >> 20);
    return buf;
  }
  return NULL;
}

void run_edit(run *r, client *c, sylva_msg *m) {
  const char *code;
  char why[256];
  if (edit_room(r, m, &code, why, sizeof why)) {
    client_send_text(c, sylva_msg_error(code, why, m->ref));
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
  run_schedule(r);
}

void run_light(run *r, client *c, double z, const char *ref) {
  int waiting = 0;
  for (const pending_light *o = r->lights; o; o = o->next) waiting++;
  if (waiting >= DAEMON_MAX_LIGHTS) {
    char why[128];
    snprintf(why, sizeof why, "/run: %d light slices of this run are waiting; ask again later",
             waiting);
    client_send_text(c, sylva_msg_error("busy", why, ref));
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
  run_schedule(r);
}

/* A create, a fork or a history snapshot, made off the loop. */
typedef enum job_kind { JOB_GET, JOB_FORK, JOB_CREATE } job_kind;

typedef struct job {
  uv_work_t work;
  server *d;
  job_kind kind;
  uint64_t client;   /**< who asked (0: the daemon itself, --run) */
  int64_t run;
  int iteration, limit, snapshot_every;
  int start_year;    /**< a get's or fork's run's (a create's is its scenario's) */
  bool start;        /**< a create: running at once */
  sylva_scenario *scenario; /**< a create's (owned) */
  char *name, *ref, *text;
  sylva_world *w;
  int64_t new_id;
  size_t estimate;   /**< a create's or fork's share of the budget, held while it is made */
  char err[512];
  const char *code;
} job;

static void job_free(job *j) {
  sylva_scenario_free(j->scenario);
  free(j->name);
  free(j->ref);
  free(j->text);
  sylva_world_destroy(j->w);
  free(j);
}

/* A create: the world built and stored, paused or running. */
static void create_work(job *j) {
  server *d = j->d;
  const sylva_scenario *s = j->scenario;
  char why[400];
  if (sylva_scenario_build(s, &j->w, why, sizeof why) < 0) {
    j->w = NULL;
    j->code = "bad_request";
    snprintf(j->err, sizeof j->err, "/scenario%s%s", why[0] == '/' ? "" : ": ", why);
    return;
  }
  sylva_world_share_threads(j->w, d->threads);
  char *json = sylva_scenario_json(s);
  if (!json) {
    j->code = "internal";
    snprintf(j->err, sizeof j->err, "out of memory");
    return;
  }
  sylva_run_status status = j->start ? SYLVA_RUN_RUNNING : SYLVA_RUN_PAUSED;
  if (store_create_run(d->st, j->name, json, s->seed, s->iterations, STORE_SNAPSHOT_EVERY, j->w,
                       &j->new_id) ||
      store_set_status(d->st, j->new_id, status, NULL, 0)) {
    snprintf(j->err, sizeof j->err, "%s", store_error(d->st));
    j->code = strstr(j->err, "exists already") ? "bad_request" : "internal";
  }
  free(json);
}

static void job_work(uv_work_t *req) {
  job *j = req->data;
  server *d = j->d;
  pool_thread_nice(d->opt.work_nice); /* the world's threads it makes inherit it */
  j->code = NULL;
  if (j->kind == JOB_CREATE) {
    create_work(j);
    return;
  }
  bool fork = j->kind == JOB_FORK;
  int failed = store_world_at(d->reader, j->run, j->iteration, NULL, &j->w);
  if (failed) snprintf(j->err, sizeof j->err, "%s", store_error(d->reader));
  char *scenario = NULL;
  if (!failed && fork) {
    failed = store_run_scenario(d->st, j->run, &scenario) ||
             store_create_run(d->st, j->name, scenario, sylva_world_get_def(j->w)->seed, j->limit,
                              j->snapshot_every, j->w, &j->new_id);
    if (!failed) failed = store_set_status(d->st, j->new_id, SYLVA_RUN_PAUSED, NULL, 0);
  }
  if (failed) {
    if (j->w) snprintf(j->err, sizeof j->err, "%s", store_error(d->st));
    j->code = strstr(j->err, "exists already") ? "bad_request" : "internal";
  }
  free(scenario);
  if (!failed && !fork) {
    j->text = sylva_msg_snapshot(j->run, 0, j->w, j->start_year, j->ref);
    if (!j->text) {
      j->code = "internal";
      snprintf(j->err, sizeof j->err, "out of memory");
    }
  }
}

static void job_done(uv_work_t *req, int status) {
  job *j = req->data;
  server *d = j->d;
  (void)status;
  d->jobs -= j->kind != JOB_CREATE;
  d->runs_pending -= j->kind != JOB_GET;
  d->memory_reserved -= j->estimate;
  client *c = j->client ? client_find(&d->clients, j->client) : NULL;
  if (j->code) {
    if (c) client_send_text(c, sylva_msg_error(j->code, j->err, j->ref));
    if (!j->client) server_log(NULL, "%s: %s", j->name, j->err);
  } else if (j->kind == JOB_CREATE) {
    sylva_run_status status = j->start ? SYLVA_RUN_RUNNING : SYLVA_RUN_PAUSED;
    run *nr = run_new(d, j->new_id, j->name, j->w, status, j->scenario->iterations,
                      STORE_SNAPSHOT_EVERY, j->scenario->start_year);
    if (nr) {
      j->w = NULL; /* the run owns it */
      server_log(nr->name, "created (%s)", sylva_run_status_name(nr->status));
      if (c) client_send_text(c, sylva_msg_created(nr->id, nr->name, j->ref));
      run_schedule(nr);
    } else if (c) {
      client_send_text(c, sylva_msg_error("internal", "out of memory", j->ref));
    }
  } else if (j->kind == JOB_FORK) {
    run *nr = run_new(j->d, j->new_id, j->name, j->w, SYLVA_RUN_PAUSED, j->limit, j->snapshot_every,
                      j->start_year);
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
  runs_wake(d);
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
  const char *busy = runs_job_room(r->d);
  char why[256];
  if (!busy && name) {
    j->estimate = run_loaded(r) ? r->estimate : estimate_unloaded(r);
    busy = runs_room(r->d, j->estimate, why, sizeof why);
  }
  if (busy) {
    client_send_text(c, sylva_msg_error("busy", busy, ref));
    job_free(j);
    return;
  }
  j->d = r->d;
  j->client = c->serial;
  j->run = r->id;
  j->iteration = iteration;
  j->kind = name ? JOB_FORK : JOB_GET;
  j->limit = r->limit;
  j->snapshot_every = r->snapshot_every;
  j->start_year = r->start_year;
  j->work.data = j;
  if (uv_queue_work(&r->d->loop, &j->work, job_work, job_done) != 0) {
    client_send_text(c, sylva_msg_error("internal", "cannot queue the work", ref));
    job_free(j);
    return;
  }
  r->d->jobs++;
  r->d->runs_pending += j->kind == JOB_FORK;
  r->d->memory_reserved += j->estimate;
}

static void start_create(server *d, client *c, sylva_scenario *s, const char *name, bool start,
                         const char *ref, size_t estimate) {
  job *j = calloc(1, sizeof *j);
  if (!j || !(j->name = strdup(name)) || (ref && !(j->ref = strdup(ref)))) {
    if (j) job_free(j);
    sylva_scenario_free(s);
    if (c) client_send_text(c, sylva_msg_error("internal", "out of memory", ref));
    return;
  }
  j->d = d;
  j->kind = JOB_CREATE;
  j->client = c ? c->serial : 0;
  j->scenario = s;
  j->start = start;
  j->estimate = estimate;
  j->work.data = j;
  if (uv_queue_work(&d->loop, &j->work, job_work, job_done) != 0) {
    if (c) client_send_text(c, sylva_msg_error("internal", "cannot queue the work", ref));
    job_free(j);
    return;
  }
  d->runs_pending++;
  d->memory_reserved += estimate;
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
