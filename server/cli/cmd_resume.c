/* `sylva resume`: continue a stored run from its last snapshot. */
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "commands.h"
#include "cli_store.h"
#include "grow.h"
#include "options.h"
#include "sylva/encode.h"
#include "sylva/scenario.h"

enum { OPT_DB, OPT_NAME, OPT_ITERATIONS, OPT_THREADS, OPT_QUIET, OPT_HELP, OPT_COUNT };

static const cli_option resume_options[OPT_COUNT] = {
    [OPT_DB] = {"db", 0, "FILE", "the store (required)"},
    [OPT_NAME] = {"name", 0, "NAME", "the run to continue (required)"},
    [OPT_ITERATIONS] = {"iterations", 0, "N", "a new iteration limit (1 to 100000)"},
    [OPT_THREADS] = {"threads", 0, "N",
                     "threads the world grows on (1 to 256, default: the cores)"},
    [OPT_QUIET] = {"quiet-progress", 0, NULL, "no progress bar on stderr"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void resume_usage(FILE *f) {
  fputs("Usage: sylva resume --db FILE --name NAME [OPTIONS]\n"
        "\n"
        "Continues a stored run after a crash, a failure or its iteration limit. The run\n"
        "is restored from its newest good snapshot, regrown silently to its last stored\n"
        "iteration (each checked against the stored world), then grown on. The lines it\n"
        "prints are the ones the uninterrupted run would have printed after that\n"
        "iteration (elapsed_ms aside), ending with the done line.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, resume_options, OPT_COUNT);
}

int cmd_resume(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "resume", resume_options, OPT_COUNT, argc, argv);
  const char *db = NULL, *name = NULL, *arg;
  uint64_t iterations = 0;
  bool quiet = false;
  int first = argc, opt, threads = cli_default_threads(1);
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
    case OPT_DB: db = arg; break;
    case OPT_NAME: name = arg; break;
    case OPT_ITERATIONS:
      if (cli_parse_u64("resume", "iterations", arg, 1, SYLVA_SCENARIO_MAX_ITERATIONS, &iterations))
        return CLI_EXIT_USAGE;
      break;
    case OPT_THREADS:
      if (cli_parse_threads("resume", arg, &threads)) return CLI_EXIT_USAGE;
      break;
    case OPT_QUIET: quiet = true; break;
    default:
      resume_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (first != argc) return cli_usage_error("resume", "unexpected argument '%s'", argv[first]);
  store *st;
  store_run r;
  int rc = cli_open_run("resume", db, name, &st, &r);
  if (rc) return rc;
  store_set_threads(st, threads); /* the regrowing to its last iteration too */
  grow_job job = {.label = r.name, .threads = threads,
                  .limit = iterations ? (int)iterations : r.iterations,
                  .progress = !quiet && isatty(STDERR_FILENO), .st = st, .run = r.id,
                  .snapshot_every = r.snapshot_every, .start_year = r.start_year};
  rc = cli_store_world_at(st, &r, r.last_iteration, &job.w);
  if (rc == CLI_EXIT_OK && store_set_status(st, r.id, SYLVA_RUN_RUNNING, NULL, job.limit)) {
    fprintf(stderr, "sylva: %s\n", store_error(st));
    rc = CLI_EXIT_FAILURE;
  }
  if (rc == CLI_EXIT_OK) rc = grow_run(&job);
  sylva_world_destroy(job.w);
  store_run_free(&r);
  store_close(st);
  return rc;
}
