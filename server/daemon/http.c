/* The daemon's HTTP routes; see http.h. */
#include "http.h"

#include "runs.h"
#include "scenarios.h"
#include "shade_json.h"

#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>

#include "daemon.h"
#include "export.h"
#include "files.h"
#include "mesh.h"
#include "report.h"
#include "runs.h"

/* Bytes of a reply's body per lws_write. */
#define HTTP_CHUNK 65536
/* How often a connection waiting for its export is checked for the client leaving. */
#define HTTP_WATCH_USECS 500000

/* What an http_job writes. */
typedef enum job_kind { JOB_EXPORT, JOB_REPORT, JOB_SHADE } job_kind;

/* An export, a sweep's report or a shade layer, written off the loop thread into a
 * tmpfile. */
struct http_job {
  uv_work_t work;
  server *d;
  struct lws *wsi; /* with pss: NULL once the transaction is gone */
  http_pss *pss;
  job_kind kind;
  char *name;      /* the run's name (spec.name), or the sweep's */
  export_spec spec;
  report_format format; /* a report's */
  int years[REPORT_MAX_YEARS], nyears;
  shade_request shade;  /* a shade layer's */
  FILE *file;      /* the result, rewound */
  size_t size;
  int failed;
  char err[512];
};

static const char *const export_types[] = {
    [EXPORT_SKELETON] = "application/json", [EXPORT_OBJ] = "text/plain; charset=utf-8",
    [EXPORT_PLY] = "application/octet-stream", [EXPORT_CSV] = "text/csv",
    [EXPORT_GLB] = "model/gltf-binary"};

/* A report's content type and file extension, by format. */
static const char *const report_types[] = {[REPORT_CSV] = "text/csv",
                                           [REPORT_HTML] = "text/html; charset=utf-8",
                                           [REPORT_PDF] = "application/pdf"};
static const char *const report_extensions[] = {
    [REPORT_CSV] = "csv", [REPORT_HTML] = "html", [REPORT_PDF] = "pdf"};

/* ---- replies ------------------------------------------------------------------ */

/* Frees what the transaction holds. */
static void release(http_pss *pss) {
  free(pss->body);
  pss->body = NULL;
  if (pss->file) fclose(pss->file);
  pss->file = NULL;
}

/* The reply: body (malloc'd; owned from here) of len bytes. */
static void reply(http_pss *pss, unsigned status, const char *type, char *body, size_t len) {
  release(pss);
  pss->status = status;
  pss->type = type;
  pss->body = body;
  pss->len = body ? len : 0;
  pss->off = 0;
}

/* A text/plain reply of one line. */
static void reply_text(http_pss *pss, unsigned status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void reply_text(http_pss *pss, unsigned status, const char *fmt, ...) {
  char line[768];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(line, sizeof line - 1, fmt, ap);
  va_end(ap);
  strcat(line, "\n");
  pss->disposition[0] = '\0';
  reply(pss, status, "text/plain; charset=utf-8", strdup(line), strlen(line));
}

/* Text from the client (or a name) fit to quote in a one-line message: at most 64
 * bytes, control characters as '?'. */
static const char *shown(char *buf, size_t size, const char *s) {
  size_t n = 0;
  for (; *s && n + 1 < size && n < 64; s++)
    buf[n++] = (unsigned char)*s < 0x20 || *s == 0x7F ? '?' : *s;
  buf[n] = '\0';
  return buf;
}

/* ---- /healthz, /metrics --------------------------------------------------------- */

static char *healthz_text(server *d) {
  int64_t runs = 0, loading = 0;
  for (run *r = d->runs; r; r = r->next) {
    runs++;
    loading += r->loading;
  }
  char buf[200];
  snprintf(buf, sizeof buf,
           "{\"ok\": true, \"runs\": %lld, \"loading\": %lld, \"clients\": %lld}\n",
           (long long)runs, (long long)loading, (long long)d->clients.count);
  return strdup(buf);
}

/* A Prometheus label value: backslash and double quote escaped (names hold no line
 * breaks, protocol.md "create"). */
static void label_value(FILE *f, const char *s) {
  for (; *s; s++) {
    if (*s == '\\' || *s == '"') fputc('\\', f);
    fputc(*s, f);
  }
}

/* One age gauge: sylva_plant_age{run="NAME",plant="ID"} AGE. */
typedef struct age_metrics {
  server *d;
  FILE *f;
} age_metrics;

static int age_metric(int64_t id, const char *plant, int age, void *ctx) {
  age_metrics *m = ctx;
  const run *r = run_find(m->d, id);
  if (!r) return 0; /* a run the daemon no longer holds */
  fputs("sylva_plant_age{run=\"", m->f);
  label_value(m->f, r->name);
  fputs("\",plant=\"", m->f);
  label_value(m->f, plant);
  fprintf(m->f, "\"} %d\n", age);
  return 0;
}

static char *metrics_text(server *d) {
  int64_t runs = 0, running = 0;
  for (run *r = d->runs; r; r = r->next) {
    runs++;
    running += r->status == SYLVA_RUN_RUNNING;
  }
  char *text = NULL;
  size_t size = 0;
  FILE *f = open_memstream(&text, &size);
  if (!f) return NULL;
  fprintf(f,
          "# HELP sylva_runs Runs held by the daemon.\n# TYPE sylva_runs gauge\nsylva_runs %lld\n"
          "# HELP sylva_runs_running Runs growing now.\n# TYPE sylva_runs_running gauge\n"
          "sylva_runs_running %lld\n"
          "# HELP sylva_clients Connected WebSocket clients.\n# TYPE sylva_clients gauge\n"
          "sylva_clients %lld\n"
          "# HELP sylva_iterations_total Iterations grown since start.\n"
          "# TYPE sylva_iterations_total counter\nsylva_iterations_total %lld\n"
          "# HELP sylva_iteration_seconds_total Time spent growing iterations.\n"
          "# TYPE sylva_iteration_seconds_total counter\nsylva_iteration_seconds_total %.6f\n"
          "# HELP sylva_messages_received_total Client messages received.\n"
          "# TYPE sylva_messages_received_total counter\nsylva_messages_received_total %lld\n"
          "# HELP sylva_bytes_sent_total WebSocket payload bytes sent.\n"
          "# TYPE sylva_bytes_sent_total counter\nsylva_bytes_sent_total %lld\n",
          (long long)runs, (long long)running, (long long)d->clients.count,
          (long long)d->iterations_total, d->iteration_ms_total / 1e3,
          (long long)d->clients.messages_received, (long long)d->clients.bytes_sent);
  fprintf(f,
          "# HELP sylva_input_bytes Bytes of unfinished client messages held.\n"
          "# TYPE sylva_input_bytes gauge\nsylva_input_bytes %zu\n"
          "# HELP sylva_clients_reading Clients whose long message is being read.\n"
          "# TYPE sylva_clients_reading gauge\nsylva_clients_reading %d\n"
          "# HELP sylva_clients_waiting Clients waiting for their long message to be read.\n"
          "# TYPE sylva_clients_waiting gauge\nsylva_clients_waiting %d\n",
          d->clients.input, d->clients.readers, client_set_waiting(&d->clients));
  fprintf(f, "# HELP sylva_nodes_pruned_total Nodes pruned by management schedules while growing.\n"
             "# TYPE sylva_nodes_pruned_total counter\nsylva_nodes_pruned_total %lld\n",
          (long long)d->pruned_total);
  /* the conflicts of each run that reports them (one with a zone), by name */
  static const char *const conflict_metrics[2][2] = {
      {"sylva_zone_nodes", "Nodes inside clearance zones now, by run."},
      {"sylva_zone_conflicts", "Stem and zone pairs that ever met, by run."}};
  for (int m = 0; m < 2; m++) {
    fprintf(f, "# HELP %s %s\n# TYPE %s gauge\n", conflict_metrics[m][0], conflict_metrics[m][1],
            conflict_metrics[m][0]);
    for (run *r = d->runs; r; r = r->next)
      if (r->conflicts.reported) {
        fprintf(f, "%s{run=\"", conflict_metrics[m][0]);
        label_value(f, r->name);
        fprintf(f, "\"} %lld\n", (long long)(m ? r->conflicts.entered : r->conflicts.zone_nodes));
      }
  }
  /* the calendar of runs with a start year, and the ages of plants of years species
   * as of their runs' last stored iteration */
  fputs("# HELP sylva_run_year The calendar year of the last finished iteration, by run.\n"
        "# TYPE sylva_run_year gauge\n", f);
  for (run *r = d->runs; r; r = r->next)
    if (r->start_year) {
      fputs("sylva_run_year{run=\"", f);
      label_value(f, r->name);
      fprintf(f, "\"} %d\n", r->start_year + r->iteration);
    }
  fputs("# HELP sylva_plant_age Age in years of each plant of a species with years (its age "
        "at planting and the seasons since), by run and plant.\n# TYPE sylva_plant_age gauge\n", f);
  /* one indexed query of the store for every run (in memory or not): the stored
   * stats of each run's last iteration are its current ones */
  age_metrics ages = {d, f};
  if (store_each_age(d->st, age_metric, &ages))
    server_log(NULL, "metrics: %s", store_error(d->st));
  if (fclose(f) != 0) {
    free(text);
    return NULL;
  }
  return text;
}

/* A reply built in memory: 200, or 500 when memory ran out. */
static void reply_built(http_pss *pss, const char *type, char *body) {
  if (body)
    reply(pss, 200, type, body, strlen(body));
  else
    reply_text(pss, 500, "out of memory");
}

/* ---- /api/scenarios/NAME -------------------------------------------------------- */

/* The ready scenario file <--scenarios>/NAME.json, byte for byte. */
static void scenario_file(server *d, http_pss *pss, const char *name) {
  char path[PATH_MAX], q[80];
  struct stat sb;
  if (!d->opt.scenarios || !scenarios_path(d->opt.scenarios, name, path, sizeof path) ||
      stat(path, &sb) != 0 || !S_ISREG(sb.st_mode)) {
    reply_text(pss, 404, "no scenario \"%s\"", shown(q, sizeof q, name));
    return;
  }
  char *data = NULL;
  size_t len = 0;
  int e = sb.st_size > (off_t)SCENARIOS_MAX_FILE
              ? EFBIG
              : files_read(path, SCENARIOS_MAX_FILE, &data, &len);
  if (e) {
    if (e == EFBIG)
      server_log(NULL, "%s: larger than %u bytes; not served", path, SCENARIOS_MAX_FILE);
    else
      server_log(NULL, "%s: %s", path, strerror(e));
    reply_text(pss, 404, "no scenario \"%s\"", shown(q, sizeof q, name));
    return;
  }
  reply(pss, 200, "application/json", data, len);
}

/* ---- exports and reports, off the loop ------------------------------------------ */

static void log_warning(const char *msg) { server_log(NULL, "export: %s", msg); }
static void log_report_warning(const char *msg) { server_log(NULL, "report: %s", msg); }

/* The last part of a path ("runs.db" of "/srv/sylva/runs.db"): a report's title
 * names its store, and a download need not tell where the daemon keeps it. */
static const char *base_name(const char *path) {
  const char *slash = strrchr(path, '/');
  return slash && slash[1] ? slash + 1 : path;
}

/* Worker thread: the sweep's report (report.h), as `sylva report` writes it. A
 * sweep the store does not have is SERVER_EINPUT (a 404). */
static int write_report(http_job *j) {
  report_request q = {.db = base_name(j->d->opt.db), .sweep = j->name, .years = j->years,
                      .nyears = j->nyears};
  report *r = NULL;
  int rc = report_load(j->d->reader, &q, &r, j->err, sizeof j->err);
  if (rc) return rc;
  report_draw_options o = {.view = RENDER_FRONT, .width = 0, .warn = log_report_warning};
  switch (j->format) {
  case REPORT_CSV: rc = report_write_csv(j->file, r, j->err, sizeof j->err); break;
  case REPORT_HTML:
    rc = report_write_html(j->file, j->d->reader, r, &o, j->err, sizeof j->err);
    break;
  default: rc = report_write_pdf(j->file, j->d->reader, r, &o, j->err, sizeof j->err); break;
  }
  report_free(r);
  /* a write error can also show only when the buffer goes out */
  if (!rc && fflush(j->file) != 0) {
    rc = SERVER_EWRITE;
    snprintf(j->err, sizeof j->err, "temporary file: %s", strerror(errno));
  }
  return rc;
}

/* Worker thread: the export or report into a tmpfile. */
static void job_work(uv_work_t *req) {
  http_job *j = req->data;
  pool_thread_nice(j->d->opt.work_nice); /* an export may regrow a world */
  j->file = tmpfile();
  if (!j->file) {
    j->failed = SERVER_EFAIL;
    snprintf(j->err, sizeof j->err, "cannot create a temporary file: %s", strerror(errno));
    return;
  }
  if (j->kind == JOB_REPORT)
    j->failed = write_report(j);
  else if (j->kind == JOB_SHADE)
    j->failed = shade_json_write(j->file, j->d->reader, &j->shade, j->err, sizeof j->err);
  else
    j->failed = export_write(j->file, j->d->reader, &j->spec, log_warning, j->err,
                             sizeof j->err);
  if (j->failed) return;
  off_t size = ftello(j->file);
  if (size < 0 || fseeko(j->file, 0, SEEK_SET) != 0) {
    j->failed = SERVER_EFAIL;
    snprintf(j->err, sizeof j->err, "temporary file: %s", strerror(errno));
    return;
  }
  j->size = (size_t)size;
}

/* Loop thread: the reply, when the transaction is still there; frees the job. */
static void job_done(uv_work_t *req, int status) {
  http_job *j = req->data;
  j->d->jobs--;
  if (status == UV_ECANCELED) j->failed = SERVER_OK; /* the client left before it started */
  /* a report of a sweep the store lacks, or the shade of a run without a site, is
   * the client's mistake, not a failure */
  bool unknown = j->kind == JOB_REPORT && j->failed == SERVER_EINPUT;
  bool refused = j->kind == JOB_SHADE && j->failed == SERVER_EINPUT;
  if (j->failed && !unknown && !refused) {
    if (j->kind == JOB_REPORT)
      server_log(NULL, "report of sweep \"%s\" failed: %s", j->name, j->err);
    else
      server_log(j->name, "%s failed: %s", j->kind == JOB_SHADE ? "shade" : "export", j->err);
  }
  http_pss *pss = j->pss;
  if (!pss) {
    if (j->kind == JOB_REPORT)
      server_log(NULL, "report of sweep \"%s\": the client left before it was written",
                 j->name);
    else
      server_log(j->name, "%s: the client left before it was written",
                 j->kind == JOB_SHADE ? "shade" : "export");
  } else {
    pss->job = NULL;
    char q[80];
    if (unknown) {
      reply_text(pss, 404, "no sweep \"%s\"", shown(q, sizeof q, j->name));
    } else if (refused) {
      reply_text(pss, 400, "%s", j->err);
    } else if (j->failed) {
      reply_text(pss, 500, "%s", j->err);
    } else {
      pss->status = 200;
      pss->file = j->file;
      pss->len = j->size;
      pss->off = 0;
      j->file = NULL;
    }
    /* the reply has HTTP_TIMEOUT_SECS between chunks again (see http_callback);
     * the watch timer stops by itself now that there is no job (4.1.6 cannot
     * cancel it: LWS_SET_TIMER_USEC_CANCEL schedules it at once) */
    lws_set_timeout(j->wsi, PENDING_TIMEOUT_HTTP_CONTENT, HTTP_TIMEOUT_SECS);
    lws_callback_on_writable(j->wsi);
  }
  if (j->file) fclose(j->file);
  free(j->name);
  free(j);
}

/* A new job named name (a run's or a sweep's), or NULL after a reply saying why
 * not (the daemon stopping, --max-jobs, memory). */
static http_job *new_job(server *d, http_pss *pss, job_kind kind, const char *name) {
  if (d->stopping) {
    reply_text(pss, 503, "the daemon is stopping");
    return NULL;
  }
  const char *busy = runs_job_room(d);
  if (busy) {
    reply_text(pss, 503, "%s", busy);
    return NULL;
  }
  http_job *j = calloc(1, sizeof *j);
  if (!j || !(j->name = strdup(name))) {
    free(j);
    reply_text(pss, 500, "out of memory");
    return NULL;
  }
  j->d = d;
  j->kind = kind;
  j->work.data = j;
  return j;
}

/* Queues j on libuv's threadpool (with the other jobs, apart from the runs' pool);
 * the reply, of content type `type`, follows when it is done. */
static void queue_job(server *d, struct lws *wsi, http_pss *pss, http_job *j, const char *type) {
  if (uv_queue_work(&d->loop, &j->work, job_work, job_done) != 0) {
    const char *what = j->kind == JOB_REPORT ? "report" : j->kind == JOB_SHADE ? "shade" : "export";
    free(j->name);
    free(j);
    reply_text(pss, 500, "cannot queue the %s", what);
    return;
  }
  d->jobs++;
  j->wsi = wsi;
  j->pss = pss;
  pss->job = j;
  pss->type = type;
}

/* Starts writing spec off the loop; the reply follows when it is done. */
static void start_export(server *d, struct lws *wsi, http_pss *pss, const run *r,
                         const export_spec *spec) {
  http_job *j = new_job(d, pss, JOB_EXPORT, r->name);
  if (!j) return;
  j->spec = *spec;
  j->spec.run = r->id;
  j->spec.name = j->name;
  queue_job(d, wsi, pss, j, export_types[spec->format]);
}

/* An iteration given in a query: decimal digits only, 0 to INT_MAX. */
static bool parse_iteration(const char *text, int *out) {
  size_t n = strlen(text);
  if (n == 0 || n > 10) return false;
  long long v = 0;
  for (const char *c = text; *c; c++) {
    if (*c < '0' || *c > '9') return false;
    v = v * 10 + (*c - '0');
  }
  if (v > INT_MAX) return false;
  *out = (int)v;
  return true;
}

/* One parameter of a query, its value "" when it has no '='; false after a 400
 * reply saying why it is bad. */
typedef bool (*query_arg_fn)(http_pss *pss, const char *key, const char *value, void *ctx);

/* Gives each parameter of the request's query (lws has split it at '&' and
 * URL-decoded each part) to fn; false with a 400 reply when the query is too long
 * or fn refuses one. */
static bool each_query_arg(struct lws *wsi, http_pss *pss, query_arg_fn fn, void *ctx) {
  char arg[512];
  if (lws_hdr_total_length(wsi, WSI_TOKEN_HTTP_URI_ARGS) >= (int)sizeof arg) {
    reply_text(pss, 400, "query: longer than %zu bytes", sizeof arg - 1);
    return false;
  }
  /* every part fits, so a failed copy is the end of the parts; an empty part
   * ("a=1&&b=2", or a trailing '&' or '?', which lws 4.1.6 gives as "/") is skipped */
  for (int i = 0; lws_hdr_copy_fragment(wsi, arg, sizeof arg, WSI_TOKEN_HTTP_URI_ARGS, i) >= 0;
       i++) {
    if (!arg[0] || strcmp(arg, "/") == 0) continue;
    char *value = strchr(arg, '=');
    if (value) *value++ = '\0';
    if (!fn(pss, arg, value ? value : "", ctx)) return false;
  }
  return true;
}

/* The index of key among a route's parameter names, marked seen; -1 after a 400
 * reply when it is unknown (naming the known ones) or given again. */
static int query_key(http_pss *pss, const char *key, const char *const *names, int count,
                     bool *seen) {
  int k = 0;
  while (k < count && strcmp(key, names[k]) != 0) k++;
  if (k == count) {
    char known[128] = "", q[80];
    for (int i = 0; i < count; i++)
      snprintf(known + strlen(known), sizeof known - strlen(known), "%s%s", i ? ", " : "",
               names[i]);
    reply_text(pss, 400, "%s: unknown parameter (known: %s)", shown(q, sizeof q, key), known);
    return -1;
  }
  if (seen[k]) {
    reply_text(pss, 400, "%s: given more than once", names[k]);
    return -1;
  }
  seen[k] = true;
  return k;
}

/* An iteration of run r given as `iteration`: 0 to its current one; false after a
 * 400 reply. */
static bool query_iteration(http_pss *pss, const run *r, const char *value, int *out) {
  char q[80];
  if (!parse_iteration(value, out)) {
    reply_text(pss, 400, "iteration: expected an integer from 0 to %d, got \"%s\"", r->iteration,
               shown(q, sizeof q, value));
    return false;
  }
  if (*out <= r->iteration) return true;
  reply_text(pss, 400, "iteration: run \"%s\" has iterations 0 to %d", shown(q, sizeof q, r->name),
             r->iteration);
  return false;
}

enum { ARG_FORMAT, ARG_ITERATION, ARG_OBSTACLES, ARG_COUNT };
static const char *const arg_names[ARG_COUNT] = {"format", "iteration", "obstacles"};

/* An export's query as it is read. */
typedef struct export_args {
  const run *r;
  export_spec *spec;
  bool seen[ARG_COUNT];
} export_args;

/* Reads one parameter of an export's query into its spec (query_arg_fn). */
static bool export_arg(http_pss *pss, const char *key, const char *value, void *ctx) {
  export_args *a = ctx;
  char q[80];
  switch (query_key(pss, key, arg_names, ARG_COUNT, a->seen)) {
  case -1: return false;
  case ARG_FORMAT:
    if (export_format_parse(value, &a->spec->format)) return true;
    reply_text(pss, 400, "format: \"%s\" is not " EXPORT_FORMAT_NAMES, shown(q, sizeof q, value));
    return false;
  case ARG_ITERATION: return query_iteration(pss, a->r, value, &a->spec->iteration);
  default:
    if (strcmp(value, "1") == 0 || strcmp(value, "0") == 0) {
      a->spec->obstacles = value[0] == '1';
      return true;
    }
    reply_text(pss, 400, "obstacles: expected 1 or 0, got \"%s\"", shown(q, sizeof q, value));
    return false;
  }
}

/* The query of an export into spec; false with a 400 reply when it is bad. */
static bool export_query(struct lws *wsi, http_pss *pss, const run *r, export_spec *spec) {
  export_args a = {.r = r, .spec = spec};
  if (!each_query_arg(wsi, pss, export_arg, &a)) return false;
  if (!a.seen[ARG_FORMAT]) {
    reply_text(pss, 400, "format: required (" EXPORT_FORMAT_NAMES ")");
    return false;
  }
  if (!a.seen[ARG_ITERATION]) spec->iteration = r->iteration;
  return true;
}

enum { SHADE_ITERATION, SHADE_DATE, SHADE_FROM, SHADE_TO, SHADE_ARG_COUNT };
static const char *const shade_arg_names[SHADE_ARG_COUNT] = {"iteration", "date", "from", "to"};

/* A shade layer's query as it is read. */
typedef struct shade_args {
  const run *r;
  shade_request *q;
  bool seen[SHADE_ARG_COUNT];
} shade_args;

/* A message that quotes the query, its control characters as '?'. */
static void reply_quoting(http_pss *pss, char *msg) {
  for (char *c = msg; *c; c++)
    if ((unsigned char)*c < 0x20 || *c == 0x7F) *c = '?';
  reply_text(pss, 400, "%s", msg);
}

/* Reads one parameter of a shade layer's query (query_arg_fn). */
static bool shade_arg(http_pss *pss, const char *key, const char *value, void *ctx) {
  shade_args *a = ctx;
  char err[300];
  switch (query_key(pss, key, shade_arg_names, SHADE_ARG_COUNT, a->seen)) {
  case -1: return false;
  case SHADE_ITERATION: return query_iteration(pss, a->r, value, &a->q->iteration);
  default:
    if (!shade_request_arg(a->q, key, value, err, sizeof err)) return true;
    reply_quoting(pss, err);
    return false;
  }
}

/* The query of a shade layer into q (the run's current iteration and the route's
 * day by default); false with a 400 reply when it is bad. */
static bool shade_query(struct lws *wsi, http_pss *pss, const run *r, shade_request *q) {
  *q = shade_request_default();
  q->run = r->id;
  q->iteration = r->iteration;
  shade_args a = {.r = r, .q = q};
  if (!each_query_arg(wsi, pss, shade_arg, &a)) return false;
  char err[300];
  if (!shade_request_check(q, err, sizeof err)) return true;
  reply_text(pss, 400, "%s", err);
  return false;
}

/* Starts the shade layer of q off the loop; the reply follows when it is done. */
static void start_shade(server *d, struct lws *wsi, http_pss *pss, const run *r,
                        const shade_request *q) {
  http_job *j = new_job(d, pss, JOB_SHADE, r->name);
  if (!j) return;
  j->shade = *q;
  queue_job(d, wsi, pss, j, "application/json");
}

/* A name fit for a file name in Content-Disposition: at most 200 bytes, those
 * outside [A-Za-z0-9._-] (and a leading dot) as '_'. */
static void file_name(char out[201], const char *name) {
  size_t n = 0;
  for (const char *c = name; *c && n < 200; c++) {
    bool keep = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                (*c >= '0' && *c <= '9') || *c == '-' || *c == '_' || (*c == '.' && n > 0);
    out[n++] = keep ? *c : '_';
  }
  out[n] = '\0';
}

/* Content-Disposition of an export: NAME-iT.ext (NAME as file_name makes it). */
static void export_disposition(http_pss *pss, const run *r, const export_spec *spec) {
  char name[201];
  file_name(name, r->name);
  snprintf(pss->disposition, sizeof pss->disposition, "attachment; filename=\"%s-i%d.%s\"", name,
           spec->iteration, export_format_extension(spec->format));
}

/* ---- a sweep's report ----------------------------------------------------------- */

/* A report's query as it is read: the text of its years. */
typedef struct report_args {
  bool seen;
  char given[512];
} report_args;

/* Reads the one parameter of a report's query (query_arg_fn). */
static bool report_arg(http_pss *pss, const char *key, const char *value, void *ctx) {
  static const char *const names[] = {"years"};
  report_args *a = ctx;
  if (query_key(pss, key, names, 1, &a->seen) < 0) return false;
  snprintf(a->given, sizeof a->given, "%s", value);
  return true;
}

/* The years of a report's query: "years=10,20,40", or none for
 * REPORT_DEFAULT_YEARS; false with a 400 reply when it is bad. */
static bool report_query(struct lws *wsi, http_pss *pss, int years[REPORT_MAX_YEARS],
                         int *nyears) {
  report_args a = {.seen = false};
  if (!each_query_arg(wsi, pss, report_arg, &a)) return false;
  char err[256], msg[300];
  if (report_parse_years(a.seen ? a.given : REPORT_DEFAULT_YEARS, years, nyears, err,
                         sizeof err))
    return true;
  snprintf(msg, sizeof msg, "years: %s", err);
  reply_quoting(pss, msg);
  return false;
}

/* /api/sweeps/NAME/report.EXT (uri: what follows "/api/sweeps/"): the sweep's
 * report, written off the loop as `sylva report --sweep NAME` writes it; no reply
 * when the URI is not of this shape. The store says whether it has the sweep (a
 * sweep stored after the daemon started too): the job replies 404 when not. */
static void sweep_report(server *d, struct lws *wsi, http_pss *pss, const char *uri) {
  static const char *const suffixes[] = {[REPORT_CSV] = "/report.csv",
                                         [REPORT_HTML] = "/report.html",
                                         [REPORT_PDF] = "/report.pdf"};
  size_t lu = strlen(uri);
  for (int f = REPORT_CSV; f <= REPORT_PDF; f++) {
    size_t ls = strlen(suffixes[f]);
    if (lu <= ls || strcmp(uri + lu - ls, suffixes[f]) != 0) continue;
    int years[REPORT_MAX_YEARS], nyears = 0;
    if (!report_query(wsi, pss, years, &nyears)) return;
    /* lws has URL-decoded the path already */
    char name[1024], safe[201];
    snprintf(name, sizeof name, "%.*s", (int)(lu - ls), uri);
    http_job *j = new_job(d, pss, JOB_REPORT, name);
    if (!j) return;
    j->format = (report_format)f;
    memcpy(j->years, years, sizeof years);
    j->nyears = nyears;
    file_name(safe, name);
    snprintf(pss->disposition, sizeof pss->disposition,
             "attachment; filename=\"%s-report.%s\"", safe, report_extensions[f]);
    queue_job(d, wsi, pss, j, report_types[f]);
    return;
  }
}

/* The run /api/runs/NAME/<suffix> names (uri: what follows "/api/runs/"), or NULL
 * after a 404 reply (a URI not of this shape: no reply, NULL, *shaped false). */
static run *run_of_uri(server *d, http_pss *pss, const char *uri, const char *suffix,
                       bool *shaped) {
  size_t lu = strlen(uri), ls = strlen(suffix);
  *shaped = lu > ls && strcmp(uri + lu - ls, suffix) == 0;
  if (!*shaped) return NULL;
  /* lws has URL-decoded the path already */
  run *r = run_find_name(d, uri, lu - ls);
  if (r) return r;
  char name[512], q[80];
  snprintf(name, sizeof name, "%.*s", (int)(lu - ls), uri);
  reply_text(pss, 404, "no run \"%s\"", shown(q, sizeof q, name));
  return NULL;
}

/* ---- the routes ----------------------------------------------------------------- */

static bool starts(const char *s, const char *prefix) {
  return strncmp(s, prefix, strlen(prefix)) == 0;
}

/* Whether the request may read uri: with a token (and without --public-read) every
 * route but /healthz needs "Authorization: Bearer TOKEN"; otherwise the reply is
 * set (401, or 429 while wrong tokens are throttled). */
static bool authorized(server *d, struct lws *wsi, http_pss *pss, const char *uri) {
  if (!d->opt.token || d->opt.public_read || strcmp(uri, "/healthz") == 0) return true;
  char buf[512];
  switch (access_check_token(&d->access, access_bearer(wsi, buf, sizeof buf), uv_now(&d->loop))) {
  case ACCESS_OK: return true;
  case ACCESS_WRONG:
    reply_text(pss, 401, "a token is needed: Authorization: Bearer TOKEN");
    pss->challenge = true;
    return false;
  case ACCESS_THROTTLED:
    reply_text(pss, 429, "too many wrong tokens; try again in a second");
    return false;
  }
  return false;
}

/* Sets the reply of uri, or starts the job that will. */
static void route(server *d, struct lws *wsi, http_pss *pss, const char *uri) {
  bool shaped = false;
  run *r;
  if (!authorized(d, wsi, pss, uri)) return;
  if (strcmp(uri, "/healthz") == 0) {
    reply_built(pss, "application/json", healthz_text(d));
  } else if (strcmp(uri, "/metrics") == 0) {
    reply_built(pss, "text/plain; version=0.0.4", metrics_text(d));
  } else if (strcmp(uri, "/api/runs") == 0) {
    reply_built(pss, "application/json", runs_json(d, false, NULL));
  } else if (starts(uri, "/api/scenarios/")) {
    scenario_file(d, pss, uri + strlen("/api/scenarios/"));
  } else if (starts(uri, "/api/sweeps/")) {
    sweep_report(d, wsi, pss, uri + strlen("/api/sweeps/"));
  } else if (starts(uri, "/api/runs/")) {
    const char *tail = uri + strlen("/api/runs/");
    export_spec spec = {.format = EXPORT_CSV, .sides = sylva_mesh_default_options().sides};
    if ((r = run_of_uri(d, pss, tail, "/stats.csv", &shaped))) {
      spec.iteration = r->iteration;
      start_export(d, wsi, pss, r, &spec);
    } else if (!shaped && (r = run_of_uri(d, pss, tail, "/export", &shaped))) {
      if (export_query(wsi, pss, r, &spec)) {
        export_disposition(pss, r, &spec);
        start_export(d, wsi, pss, r, &spec);
      }
    } else if (!shaped && (r = run_of_uri(d, pss, tail, "/shade", &shaped))) {
      shade_request q;
      if (shade_query(wsi, pss, r, &q)) start_shade(d, wsi, pss, r, &q);
    }
  }
  if (!pss->status && !pss->job) reply_text(pss, 404, "not found");
}

static int send_headers(struct lws *wsi, http_pss *pss) {
  uint8_t buf[LWS_PRE + 2048], *start = &buf[LWS_PRE], *p = start, *end = &buf[sizeof buf - 1];
  if (lws_add_http_common_headers(wsi, pss->status, pss->type, pss->len, &p, end)) return -1;
  if (pss->disposition[0] &&
      lws_add_http_header_by_name(wsi, (const unsigned char *)"content-disposition:",
                                  (const unsigned char *)pss->disposition,
                                  (int)strlen(pss->disposition), &p, end))
    return -1;
  if (pss->challenge &&
      lws_add_http_header_by_name(wsi, (const unsigned char *)"www-authenticate:",
                                  (const unsigned char *)"Bearer", 6, &p, end))
    return -1;
  return lws_finalize_write_http_header(wsi, start, &p, end) ? -1 : 0;
}

/* The reply is out: ready for the next request on the connection (lws frees pss). */
static int finish(struct lws *wsi, http_pss *pss) {
  release(pss);
  return lws_http_transaction_completed(wsi) ? -1 : 0;
}

/* Whether the client closed the connection (or it broke), looking without taking
 * anything. A client that only shut down its sending side counts as gone, as it
 * does for lws when it reads. */
static bool client_left(struct lws *wsi) {
  char c;
  ssize_t n = recv(lws_get_socket_fd(wsi), &c, 1, MSG_PEEK | MSG_DONTWAIT);
  return n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR);
}

/* One step of the reply: the headers with the first chunk of the body, or the
 * next chunk. Under a flood of busy connections each turn of the loop is long,
 * and a /healthz that took a turn for each step would wait for all of them (abuse
 * row 8): the headers and a small body leave together, and for a client that
 * closes after the reply, in the turn its request came in (in_request: called
 * from LWS_CALLBACK_HTTP, where lws still holds the request, so the transaction
 * is completed from the next writable callback). */
static int write_reply(struct lws *wsi, http_pss *pss, bool in_request) {
  /* a client that stops reading is closed after HTTP_TIMEOUT_SECS */
  lws_set_timeout(wsi, PENDING_TIMEOUT_HTTP_CONTENT, HTTP_TIMEOUT_SECS);
  if (pss->headers_sent && pss->off == pss->len) return finish(wsi, pss); /* all out */
  if (!pss->headers_sent) {
    if (send_headers(wsi, pss)) return -1;
    pss->headers_sent = true;
    if (pss->len == 0) {
      if (in_request) {
        lws_callback_on_writable(wsi);
        return 0;
      }
      return finish(wsi, pss);
    }
  }
  unsigned char buf[LWS_PRE + HTTP_CHUNK], *start = &buf[LWS_PRE];
  size_t n = pss->len - pss->off;
  if (n > HTTP_CHUNK) n = HTTP_CHUNK;
  if (pss->file) {
    if (fread(start, 1, n, pss->file) != n) {
      server_log(NULL, "export: reading the temporary file: %s",
                 ferror(pss->file) ? strerror(errno) : "it got shorter");
      return -1;
    }
  } else {
    memcpy(start, pss->body + pss->off, n);
  }
  bool last = pss->off + n == pss->len;
  if (lws_write(wsi, start, n, last ? LWS_WRITE_HTTP_FINAL : LWS_WRITE_HTTP) != (int)n) return -1;
  pss->off += n;
  if (last && !in_request) return finish(wsi, pss);
  lws_callback_on_writable(wsi);
  return 0;
}

int http_callback(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in,
                  size_t len) {
  http_pss *pss = user;
  server *d = lws_context_user(lws_get_context(wsi));
  switch (reason) {
  case LWS_CALLBACK_FILTER_NETWORK_CONNECTION:
    /* a new connection, before anything is read: descriptors are handed out lowest
     * first, so a high one means few are left; refusing it keeps a reserve, and
     * accept() never fails for want of one (libwebsockets would retry at once) */
    if ((lws_intptr_t)in < d->fd_ceiling) return 0;
    server_log_limited(NULL, "refused a connection: %d of the open files are in use",
                       (int)(lws_intptr_t)in);
    return 1;
  case LWS_CALLBACK_FILTER_HTTP_CONNECTION:
    /* every request, the static files too: the Host must name this daemon */
    if (access_host_ok(&d->access, wsi)) return 0;
    lws_return_http_status(wsi, 421,
                           "this daemon does not serve that Host (see --allow-host)");
    return 1;
  case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION:
    /* an upgrade without the sylva.v1 subprotocol lands here: refused */
    lws_return_http_status(wsi, HTTP_STATUS_FORBIDDEN,
                           "WebSockets are served on /ws with the subprotocol sylva.v1");
    return 1;
  case LWS_CALLBACK_HTTP: {
    char uri[1024];
    if (lws_hdr_copy(wsi, uri, sizeof uri, WSI_TOKEN_GET_URI) < 0) uri[0] = '\0';
    route(d, wsi, pss, uri);
    if (pss->job) {
      /* lws allows timeout_secs for the whole transaction; the export may take
       * longer. lws does not read the socket until the reply is out, so it would
       * not notice the client leaving (and the loop would wake for its unread end
       * of file on every turn): a timer looks, and closes the connection, which
       * detaches the job. (lws_rx_flow_control, which would stop the polling,
       * stops the daemon from accepting connections in 4.1.6 on libuv.) */
      lws_set_timeout(wsi, NO_PENDING_TIMEOUT, 0);
      lws_set_timer_usecs(wsi, HTTP_WATCH_USECS);
      return 0;
    }
    if (!pss->status) return 0;
    /* a client that asked to close after this reply (as a health check does) gets
     * it at once; a kept-alive connection waits for the writable turn, so that
     * its transaction completes in the turn its last byte leaves */
    char conn[32];
    if (lws_hdr_copy(wsi, conn, sizeof conn, WSI_TOKEN_CONNECTION) > 0 &&
        strcasecmp(conn, "close") == 0)
      return write_reply(wsi, pss, true);
    lws_callback_on_writable(wsi);
    return 0;
  }
  case LWS_CALLBACK_TIMER:
    if (!pss || !pss->job) break;
    if (client_left(wsi))
      lws_set_timeout(wsi, PENDING_TIMEOUT_USER_OK, LWS_TO_KILL_ASYNC);
    else
      lws_set_timer_usecs(wsi, HTTP_WATCH_USECS);
    return 0;
  case LWS_CALLBACK_HTTP_WRITEABLE:
    if (!pss || !pss->status || pss->job) break; /* no reply yet */
    return write_reply(wsi, pss, false);
  case LWS_CALLBACK_HTTP_DROP_PROTOCOL:
  case LWS_CALLBACK_CLOSED_HTTP:
    if (!pss) break;
    if (pss->job) {
      /* a job not started yet is cancelled; a running one goes on and its result
       * is freed when it is done */
      uv_cancel((uv_req_t *)&pss->job->work);
      pss->job->pss = NULL;
      pss->job->wsi = NULL;
      pss->job = NULL;
    }
    release(pss);
    break;
  default: break;
  }
  return lws_callback_http_dummy(wsi, reason, user, in, len);
}
