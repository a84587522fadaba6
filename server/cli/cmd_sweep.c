/* `sylva sweep`: a plan's runs, locally in worker processes, as a Slurm array job,
 * or merged from the array's task stores (docs/cli.md, "sweep"). */
#include <errno.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli_store.h"
#include "commands.h"
#include "files.h"
#include "grow.h"
#include "measured.h"
#include "options.h"
#include "plan.h"
#include "procs.h"
#include "slurm.h"
#include "store.h"
#include "sweep_store.h"
#include "sylva/scenario.h"

enum {
  OPT_DB, OPT_JOBS, OPT_THREADS, OPT_ITERATIONS, OPT_FORCE, OPT_SLURM, OPT_SUBMIT, OPT_TASKS,
  OPT_TASK, OPT_MERGE, OPT_QUIET, OPT_HELP, OPT_COUNT
};

static const cli_option sweep_options[OPT_COUNT] = {
    [OPT_DB] = {"db", 0, "FILE", "the store of the sweep's runs (a task's store with --task)"},
    [OPT_JOBS] = {"jobs", 'j', "N", "runs at a time, each in a process (default: the cores)"},
    [OPT_THREADS] = {"threads", 0, "N",
                     "threads per run (1 to 256; default: the cores / --jobs, at least 1; "
                     "1 with --slurm)"},
    [OPT_ITERATIONS] = {"iterations", 0, "N", "every run's iteration limit (1 to 100000)"},
    [OPT_FORCE] = {"force", 0, NULL, "run a plan of more than 10000 runs"},
    [OPT_SLURM] = {"slurm", 0, "DIR", "write DIR/sweep.sbatch, a Slurm array job of the plan"},
    [OPT_SUBMIT] = {"submit", 0, NULL, "with --slurm: submit it with sbatch"},
    [OPT_TASKS] = {"tasks", 0, "T", "with --slurm: array tasks (default: the runs, up to 64)"},
    [OPT_TASK] = {"task", 0, "K", "grow task K's share of the runs (the array script's)"},
    [OPT_MERGE] = {"merge", 0, "DIR", "merge DIR's task stores into --db"},
    [OPT_QUIET] = {"quiet-progress", 0, NULL, "no progress on stderr"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void sweep_usage(FILE *f) {
  fputs("Usage: sylva sweep PLAN.json --db OUT.db [--jobs N]\n"
        "       sylva sweep PLAN.json --slurm DIR [--tasks T] [--jobs N] [--submit]\n"
        "       sylva sweep PLAN.json --merge DIR --db OUT.db\n"
        "\n"
        "Runs a plan (sylva.sweep/1): a base scenario and the axes to vary, species,\n"
        "seeds and variants (JSON Patches of the scenario). Every run of their product\n"
        "is stored in one store, with its place on the axes. A sweep started again\n"
        "continues: finished runs are kept, unfinished ones resume from the store.\n"
        "With --slurm it writes an sbatch array script instead: each task grows its\n"
        "share of the runs into DIR/task-K.db, and --merge gathers them into one store.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, sweep_options, OPT_COUNT);
}

typedef struct sweep_ctx {
  const sweep_plan *plan;
  const char *db;
  int iterations;   /* 0: the scenario's */
  int threads;      /* each run's */
  int *pending;     /* the positions still to grow, in plan order */
  int count, done, failed;
  bool progress;
  double t0, busy;  /* wall clock at the start; summed seconds of finished runs */
  int jobs;
} sweep_ctx;

static double wall_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Builds a run's world from its scenario text; measured trees ("from") are read
 * against the plan's base path. */
static int run_world(const sweep_plan *p, const sweep_run *r, sylva_scenario **s,
                     sylva_world **w) {
  char err[1200];
  if (sylva_scenario_parse(r->scenario, strlen(r->scenario), s, err, sizeof err)) {
    fprintf(stderr, "sylva: %s: %s\n", r->name, err);
    return CLI_EXIT_USAGE;
  }
  int e = sylva_import_measured(p->base, *s, err, sizeof err);
  if (e) {
    fprintf(stderr, "sylva: %s: %s\n", r->name, err);
    return e == SYLVA_ENOMEM ? CLI_EXIT_FAILURE : CLI_EXIT_USAGE;
  }
  if (files_build_world(p->base, *s, w, err, sizeof err)) {
    fprintf(stderr, "sylva: %s: %s\n", r->name, err);
    return CLI_EXIT_FAILURE;
  }
  return CLI_EXIT_OK;
}

/* The place of a run on the plan's axes. */
static int record_place(store *st, const sweep_plan *p, const sweep_run *r, int64_t run) {
  store_axis axes[SWEEP_MAX_AXES];
  for (int a = 0; a < p->axis_count; a++)
    axes[a] = (store_axis){p->axes[a].name, p->axes[a].values[r->value[a]]};
  if (store_set_sweep_run(st, run, p->name, p->canonical, r->position, axes, p->axis_count)) {
    fprintf(stderr, "sylva: %s\n", store_error(st));
    return CLI_EXIT_FAILURE;
  }
  return CLI_EXIT_OK;
}

/* Whether a stored run needs no more growing under an iteration limit (0: its own):
 * it ended, and either every stem finished or it reached the limit. A finished run
 * is left as it is, not even its row rewritten, so that sweeping again changes
 * nothing. */
static bool run_complete(bool finished, const char *reason, int last_iteration, int limit) {
  return finished && (limit == 0 || last_iteration >= limit ||
                      (reason && strcmp(reason, "finished") == 0));
}

/* Grows one run of the plan into the store, on `threads` threads: creates it, or
 * resumes it from its last stored iteration when an earlier sweep left it
 * unfinished. Runs in a worker. */
static int grow_one(const sweep_plan *p, const char *db, int position, int iterations,
                    int threads) {
  sweep_run r;
  char err[1024];
  if (sweep_plan_run(p, position, &r, err, sizeof err)) {
    fprintf(stderr, "sylva: %s: run %d: %s\n", p->name, position, err);
    return CLI_EXIT_FAILURE;
  }
  store *st;
  int rc = cli_store_open(db, true, &st);
  store_run stored;
  bool found = false;
  if (rc == CLI_EXIT_OK && store_find_run(st, r.name, &stored, &found)) {
    fprintf(stderr, "sylva: %s\n", store_error(st));
    rc = CLI_EXIT_FAILURE;
  }
  sylva_scenario *s = NULL;
  if (rc == CLI_EXIT_OK) store_set_threads(st, threads); /* a resumed run's regrowing too */
  grow_job job = {.label = r.name, .silent = true, .st = st, .threads = threads};
  if (rc == CLI_EXIT_OK && found) {
    job.run = stored.id;
    job.limit = iterations ? iterations : stored.iterations;
    job.snapshot_every = stored.snapshot_every;
    job.start_year = stored.start_year;
    if (run_complete(stored.status == SYLVA_RUN_FINISHED, stored.reason, stored.last_iteration,
                     job.limit)) {
      store_run_free(&stored);
      store_close(st);
      sweep_run_free(&r);
      return CLI_EXIT_OK;
    }
    /* a sweep killed between creating the run and recording its place left it
     * without one */
    rc = record_place(st, p, &r, stored.id);
    if (rc == CLI_EXIT_OK) rc = cli_store_world_at(st, &stored, stored.last_iteration, &job.w);
    if (rc == CLI_EXIT_OK && store_set_status(st, stored.id, SYLVA_RUN_RUNNING, NULL, job.limit)) {
      fprintf(stderr, "sylva: %s\n", store_error(st));
      rc = CLI_EXIT_FAILURE;
    }
    store_run_free(&stored);
  } else if (rc == CLI_EXIT_OK) {
    rc = run_world(p, &r, &s, &job.w);
    if (rc == CLI_EXIT_OK) {
      job.limit = iterations ? iterations : s->iterations;
      job.snapshot_every = STORE_SNAPSHOT_EVERY;
      job.start_year = s->start_year;
      char *json = sylva_scenario_json(s);
      bool nomem = !json;
      int failed = json ? store_create_run(st, r.name, json, s->seed, job.limit,
                                           job.snapshot_every, job.w, &job.run)
                        : SERVER_ENOMEM;
      free(json);
      if (failed) {
        fprintf(stderr, "sylva: %s\n", nomem ? "out of memory" : store_error(st));
        rc = CLI_EXIT_FAILURE;
      } else {
        rc = record_place(st, p, &r, job.run);
      }
    }
  }
  if (rc == CLI_EXIT_OK) rc = grow_run(&job);
  if (job.w) sylva_world_destroy(job.w);
  sylva_scenario_free(s);
  store_close(st);
  sweep_run_free(&r);
  return rc;
}

static int pool_job(int i, void *ctx) {
  sweep_ctx *c = ctx;
  return grow_one(c->plan, c->db, c->pending[i], c->iterations, c->threads);
}

/* One line per started run: how far the sweep is, and which run it grows now. */
static void show_progress(const sweep_ctx *c, int started) {
  if (!c->progress) return;
  char left[64] = "";
  if (c->done > 0) /* the mean run so far, over the processes */
    snprintf(left, sizeof left, ", about %.0f s left",
             (c->count - c->done) * (c->busy / c->done) / c->jobs);
  sweep_run r;
  char err[256];
  if (started >= 0 && sweep_plan_run(c->plan, c->pending[started], &r, err, sizeof err) == 0) {
    fprintf(stderr, "sweep: %d/%d runs done%s; growing %s\n", c->done, c->count, left, r.name);
    sweep_run_free(&r);
  } else {
    fprintf(stderr, "sweep: %d/%d runs done in %.0f s%s\n", c->done, c->count,
            wall_seconds() - c->t0, c->failed ? ", some failed" : "");
  }
}

static void pool_started(int i, void *ctx) { show_progress(ctx, i); }

static void pool_done(int i, int status, double seconds, void *ctx) {
  sweep_ctx *c = ctx;
  c->done++;
  c->busy += seconds;
  if (status) {
    c->failed++;
    sweep_run r;
    char err[256];
    if (sweep_plan_run(c->plan, c->pending[i], &r, err, sizeof err) == 0) {
      fprintf(stderr, "sylva: sweep: run \"%s\" failed (status %d)\n", r.name, status);
      sweep_run_free(&r);
    }
  }
  if (c->done == c->count) show_progress(c, -1);
}

typedef struct finished_set {
  bool *finished;
  int runs;
  int iterations; /* the sweep's --iterations, 0: each run's own */
} finished_set;

static int mark_finished(const store_sweep_run *r, void *ctx) {
  finished_set *f = ctx;
  if (r->position >= 0 && r->position < f->runs &&
      run_complete(r->finished, r->reason, r->last_iteration, f->iterations))
    f->finished[r->position] = true;
  return 0;
}

/* Which of the plan's runs the store holds finished (and grown to the iteration
 * limit, when one is given); refuses a store whose sweep of this name was another
 * plan. */
static int stored_state(const sweep_plan *p, const char *db, int iterations, bool *finished) {
  store *st;
  int rc = cli_store_open(db, true, &st);
  if (rc) return rc;
  char *plan = NULL;
  if (store_sweep_plan(st, p->name, &plan)) {
    fprintf(stderr, "sylva: %s\n", store_error(st));
    rc = CLI_EXIT_FAILURE;
  } else if (plan && strcmp(plan, p->canonical) != 0) {
    fprintf(stderr, "sylva: %s: the sweep \"%s\" it holds was run with another plan (rename the "
                    "plan's \"name\", or use another --db)\n", db, p->name);
    rc = CLI_EXIT_USAGE;
  } else {
    finished_set f = {finished, p->runs, iterations};
    if (store_each_sweep_run(st, p->name, mark_finished, &f)) {
      fprintf(stderr, "sylva: %s\n", store_error(st));
      rc = CLI_EXIT_FAILURE;
    }
  }
  free(plan);
  store_close(st);
  return rc;
}

/* Runs the positions of the plan that are not finished in db (of task k of t, or
 * all when t is 0), in up to jobs processes of `threads` threads each. */
static int run_local(const sweep_plan *p, const char *db, int jobs, int threads, int iterations,
                     int k, int t, bool progress) {
  bool *finished = calloc((size_t)p->runs, sizeof *finished);
  int *pending = malloc((size_t)p->runs * sizeof *pending);
  if (!finished || !pending) {
    free(finished);
    free(pending);
    fprintf(stderr, "sylva: out of memory\n");
    return CLI_EXIT_FAILURE;
  }
  int rc = stored_state(p, db, iterations, finished);
  sweep_ctx c = {.plan = p, .db = db, .iterations = iterations, .threads = threads,
                 .pending = pending,
                 .progress = progress, .t0 = wall_seconds(), .jobs = jobs};
  int kept = 0;
  for (int i = 0; i < p->runs && rc == CLI_EXIT_OK; i++) {
    if (t && i % t != k) continue;
    /* a finished run is kept, unless a new limit asks for more */
    if (finished[i]) kept++;
    else pending[c.count++] = i;
  }
  if (rc == CLI_EXIT_OK && progress)
    fprintf(stderr, "sweep: %s: %d runs to grow in %d processes (%d thread%s each)%s\n",
            p->name, c.count, jobs, threads, threads == 1 ? "" : "s",
            kept ? " (the finished ones kept)" : "");
  if (rc == CLI_EXIT_OK && c.count > 0) {
    pool_def def = {.workers = jobs, .count = c.count, .job = pool_job, .started = pool_started,
                    .done = pool_done, .ctx = &c};
    int failed = pool_run(&def);
    if (failed < 0) {
      fprintf(stderr, "sylva: sweep: cannot start a worker: %s\n", strerror(errno));
      rc = CLI_EXIT_FAILURE;
    } else if (failed > 0) {
      fprintf(stderr, "sylva: sweep: %d of %d runs failed; run the sweep again to retry them\n",
              failed, c.count);
      rc = CLI_EXIT_FAILURE;
    }
  }
  free(finished);
  free(pending);
  return rc;
}

static void merge_missing(const char *path, const char *why, void *ctx) {
  (void)ctx;
  fprintf(stderr, "sylva: sweep --merge: %s: left out: %s\n", path, why);
}

static void merge_unfinished(const char *path, const char *run, int position, void *ctx) {
  (void)ctx;
  fprintf(stderr, "sylva: sweep --merge: %s: run %d \"%s\" is not finished: left out\n", path,
          position, run);
}

static int mark_merged(const store_sweep_run *r, void *ctx) {
  finished_set *f = ctx;
  if (r->finished && r->position >= 0 && r->position < f->runs) f->finished[r->position] = true;
  return 0;
}

/* Names each task store that lacks some of its runs after a merge (a task that was
 * killed, is still running, or did not start), and returns how many runs are
 * missing. */
static int report_missing(const sweep_plan *p, char *const *paths, int tasks, const bool *have) {
  int missing = 0;
  for (int k = 0; k < tasks; k++) {
    int lack = 0, first = -1, of = 0;
    for (int i = k; i < p->runs; i += tasks) {
      of++;
      if (have[i]) continue;
      if (first < 0) first = i;
      lack++;
    }
    if (lack)
      fprintf(stderr, "sylva: sweep --merge: %s: %d of its %d runs are missing (the first: "
                      "position %d)\n", paths[k], lack, of, first);
    missing += lack;
  }
  return missing;
}

static int merge(const sweep_plan *p, const char *dir, const char *db) {
  char err[1024];
  int tasks;
  if (slurm_script_tasks(dir, &tasks, err, sizeof err)) {
    fprintf(stderr, "sylva: sweep --merge: %s\n", err);
    return CLI_EXIT_USAGE;
  }
  char **paths = calloc((size_t)tasks, sizeof *paths);
  bool ok = paths != NULL;
  for (int k = 0; ok && k < tasks; k++) ok = (paths[k] = slurm_task_store(dir, k)) != NULL;
  store *st = NULL;
  int rc = ok ? cli_store_open(db, true, &st) : CLI_EXIT_FAILURE;
  if (!ok) fprintf(stderr, "sylva: out of memory\n");
  char *stored_plan = NULL;
  if (rc == CLI_EXIT_OK && store_sweep_plan(st, p->name, &stored_plan)) {
    fprintf(stderr, "sylva: %s\n", store_error(st));
    rc = CLI_EXIT_FAILURE;
  } else if (stored_plan && strcmp(stored_plan, p->canonical) != 0) {
    /* its runs of that name would pass for this plan's */
    fprintf(stderr, "sylva: %s: the sweep \"%s\" it holds was run with another plan (merge "
                    "into another --db)\n", db, p->name);
    rc = CLI_EXIT_USAGE;
  }
  free(stored_plan);
  store_merge_report rep = {.on_missing = merge_missing, .on_unfinished = merge_unfinished};
  int present = 0;
  if (rc == CLI_EXIT_OK) {
    /* a task store that is not there is named, and left out */
    const char **exist = calloc((size_t)tasks, sizeof *exist);
    for (int k = 0; exist && k < tasks; k++) {
      if (access(paths[k], F_OK) == 0) exist[present++] = paths[k];
      else merge_missing(paths[k], "missing (the task did not start, or not yet)", NULL), rep.missing++;
    }
    if (!exist || store_merge(st, p->name, p->canonical, exist, present, &rep)) {
      fprintf(stderr, "sylva: %s\n", exist ? store_error(st) : "out of memory");
      rc = CLI_EXIT_FAILURE;
    }
    free(exist);
  }
  bool *have = rc == CLI_EXIT_OK ? calloc((size_t)p->runs, sizeof *have) : NULL;
  finished_set merged = {have, p->runs, 0};
  if (rc == CLI_EXIT_OK && (!have || store_each_sweep_run(st, p->name, mark_merged, &merged))) {
    fprintf(stderr, "sylva: %s\n", have ? store_error(st) : "out of memory");
    rc = CLI_EXIT_FAILURE;
  }
  if (rc == CLI_EXIT_OK) {
    int missing = report_missing(p, paths, tasks, have);
    fprintf(stderr, "sweep --merge: %d runs copied, %d there already; %s holds %d of the plan's %d runs\n",
            rep.copied, rep.kept, db, p->runs - missing, p->runs);
    if (missing) {
      fprintf(stderr, "sylva: sweep --merge: %d runs are missing; merge again when their tasks "
                      "have finished\n", missing);
      rc = CLI_EXIT_FAILURE;
    }
  }
  free(have);
  store_close(st);
  for (int k = 0; paths && k < tasks; k++) free(paths[k]);
  free(paths);
  return rc;
}

static int write_slurm(const sweep_plan *p, const char *plan_path, const char *dir, int tasks,
                       int jobs, int threads, bool submit) {
  char exe[4096];
  ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) {
    fprintf(stderr, "sylva: sweep --slurm: cannot find the sylva binary: %s\n", strerror(errno));
    return CLI_EXIT_FAILURE;
  }
  exe[n] = '\0';
  slurm_script s = {.dir = dir, .exe = exe, .plan = plan_path, .tasks = tasks, .jobs = jobs,
                    .threads = threads, .runs = p->runs, .force = p->runs > SWEEP_MAX_RUNS};
  char *script, err[1024];
  if (slurm_write_script(&s, &script, err, sizeof err)) {
    fprintf(stderr, "sylva: sweep --slurm: %s\n", err);
    return CLI_EXIT_FAILURE;
  }
  int rc = CLI_EXIT_OK;
  if (submit) {
    char id[64];
    if (slurm_submit(script, id, sizeof id, err, sizeof err)) {
      fprintf(stderr, "sylva: sweep --submit: %s\n", err);
      rc = CLI_EXIT_FAILURE;
    } else {
      printf("%s\n", id);
    }
  } else {
    printf("sbatch %s\n", script);
  }
  free(script);
  return rc;
}

int cmd_sweep(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "sweep", sweep_options, OPT_COUNT, argc, argv);
  const char *db = NULL, *slurm = NULL, *merge_dir = NULL, *arg;
  uint64_t jobs = 0, iterations = 0, tasks = 0, task = 0;
  int threads = 0; /* 0: not given */
  bool force = false, submit = false, quiet = false, has_task = false;
  int first = argc, opt;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
    case OPT_DB: db = arg; break;
    case OPT_JOBS:
      if (cli_parse_u64("sweep", "jobs", arg, 1, 1024, &jobs)) return CLI_EXIT_USAGE;
      break;
    case OPT_THREADS:
      if (cli_parse_threads("sweep", arg, &threads)) return CLI_EXIT_USAGE;
      break;
    case OPT_ITERATIONS:
      if (cli_parse_u64("sweep", "iterations", arg, 1, SYLVA_SCENARIO_MAX_ITERATIONS, &iterations))
        return CLI_EXIT_USAGE;
      break;
    case OPT_FORCE: force = true; break;
    case OPT_SLURM: slurm = arg; break;
    case OPT_SUBMIT: submit = true; break;
    case OPT_TASKS:
      if (cli_parse_u64("sweep", "tasks", arg, 1, 100000, &tasks)) return CLI_EXIT_USAGE;
      break;
    case OPT_TASK:
      if (cli_parse_u64("sweep", "task", arg, 0, 99999, &task)) return CLI_EXIT_USAGE;
      has_task = true;
      break;
    case OPT_MERGE: merge_dir = arg; break;
    case OPT_QUIET: quiet = true; break;
    default:
      sweep_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (argc - first != 1)
    return cli_usage_error("sweep", argc - first == 0 ? "missing PLAN.json"
                                                      : "expected one PLAN.json");
  if ((slurm != NULL) + (merge_dir != NULL) + has_task > 1)
    return cli_usage_error("sweep", "--slurm, --merge and --task go one at a time");
  if (slurm && db) return cli_usage_error("sweep", "--slurm writes a script: no --db");
  if (!slurm && !db) return cli_usage_error("sweep", "--db FILE is required");
  if ((submit || tasks) && !slurm && !has_task)
    return cli_usage_error("sweep", "--submit and --tasks go with --slurm");
  if (has_task && !tasks) return cli_usage_error("sweep", "--task K needs --tasks T");
  if (has_task && task >= tasks)
    return cli_usage_error("sweep", "--task %llu: the tasks are 0 to %llu",
                           (unsigned long long)task, (unsigned long long)tasks - 1);
  if (merge_dir && (jobs || threads || iterations))
    return cli_usage_error("sweep", "--merge takes no --jobs, --threads or --iterations");
  if (slurm && iterations)
    return cli_usage_error("sweep", "--iterations is the plan's to say with --slurm "
                                    "(a variant may replace /iterations)");

  const char *plan_path = argv[first];
  sweep_plan *plan;
  char err[2048];
  if (sweep_plan_load(plan_path, force, &plan, err, sizeof err)) {
    fprintf(stderr, "sylva: %s\n", err);
    return CLI_EXIT_USAGE;
  }
  int rc;
  if (merge_dir) {
    rc = merge(plan, merge_dir, db);
  } else if (slurm) {
    int t = tasks ? (int)tasks : plan->runs < 64 ? plan->runs : 64;
    if (t > plan->runs) { /* the tasks past the runs would have nothing to grow */
      fprintf(stderr, "sylva: sweep --slurm: --tasks %d is more than the plan's %d runs: "
                      "%d tasks\n", t, plan->runs, plan->runs);
      t = plan->runs;
    }
    rc = write_slurm(plan, plan_path, slurm, t, jobs ? (int)jobs : 1, threads ? threads : 1,
                     submit);
  } else {
    int j = jobs ? (int)jobs : has_task ? 1 : cli_cores();
    /* by default jobs x threads stays within the cores */
    rc = run_local(plan, db, j, threads ? threads : cli_default_threads(j), (int)iterations,
                   (int)task, has_task ? (int)tasks : 0, !quiet);
  }
  sweep_plan_free(plan);
  return rc;
}
