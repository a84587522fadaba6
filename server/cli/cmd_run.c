/* `sylva run`: grow a scenario headless, one JSON stats line per iteration. */
#include <errno.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "commands.h"
#include "grow.h"
#include "cli_input.h"
#include "options.h"
#include "outfile.h"
#include "store.h"
#include "cli_store.h"
#include "sylva/encode.h"
#include "sylva/status.h"

enum {
  OPT_SEED, OPT_ITERATIONS, OPT_THREADS, OPT_DB, OPT_NAME, OPT_SNAPSHOT_EVERY, OPT_EXPORT,
  OPT_QUIET, OPT_HELP, OPT_COUNT
};

static const cli_option run_options[OPT_COUNT] = {
    [OPT_SEED] = {"seed", 0, "N", "override the scenario's seed (0 to 2^53)"},
    [OPT_ITERATIONS] = {"iterations", 0, "N", "override the iteration limit (1 to 100000)"},
    [OPT_THREADS] = {"threads", 0, "N",
                     "threads the world grows on (1 to 256, default: the cores)"},
    [OPT_DB] = {"db", 0, "FILE", "store the run (snapshots and stats) in this SQLite file"},
    [OPT_NAME] = {"name", 0, "NAME", "name of the stored run (default: the scenario's name)"},
    [OPT_SNAPSHOT_EVERY] = {"snapshot-every", 0, "N",
                            "a full snapshot every N stored iterations (default 5)"},
    [OPT_EXPORT] = {"export", 0, "FILE", "write the final skeleton (sylva.skeleton/1) to FILE"},
    [OPT_QUIET] = {"quiet-progress", 0, NULL, "no progress bar on stderr"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void run_usage(FILE *f) {
  fputs("Usage: sylva run SCENARIO.json [OPTIONS]\n"
        "\n"
        "Grows the scenario until every stem has finished or the iteration limit is\n"
        "reached. stdout gets one JSON object per iteration, describing every stem after\n"
        "that iteration:\n"
        "  {\"iteration\": 7, \"elapsed_ms\": 12.5, \"stems\": [{\"plant\": \"t1\", \"stem\": 0,\n"
        "   \"height\": 1.9, \"dbh\": 0.031, \"crown_width\": 1.2, \"crown_base\": 0.4,\n"
        "   \"nodes\": 183, \"shed\": 0, \"light\": 402.1, \"cap\": 5, \"finished\": false}]}\n"
        "and a last line {\"done\": true, \"iterations\": N, \"reason\": \"finished\"|\"limit\"}.\n"
        "When stderr is a terminal, a progress bar is shown there.\n"
        "With --db, every iteration is stored in one transaction (its stats, and a full\n"
        "snapshot every --snapshot-every iterations and at the end); 'sylva resume'\n"
        "continues a stored run after a crash or a stop.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, run_options, OPT_COUNT);
}

int cmd_run(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "run", run_options, OPT_COUNT, argc, argv);
  const char *seed_text = NULL, *export_path = NULL, *db_path = NULL, *name = NULL, *arg;
  uint64_t seed = 0, iterations = 0, snapshot_every = STORE_SNAPSHOT_EVERY;
  bool quiet = false;
  int first = argc, opt, threads = cli_default_threads(1);
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    switch (opt) {
    case OPT_THREADS:
      if (cli_parse_threads("run", arg, &threads)) return CLI_EXIT_USAGE;
      break;
    case OPT_SEED:
      if (cli_parse_u64("run", "seed", arg, 0, (uint64_t)SYLVA_SCENARIO_SEED_MAX, &seed))
        return CLI_EXIT_USAGE;
      seed_text = arg;
      break;
    case OPT_ITERATIONS:
      if (cli_parse_u64("run", "iterations", arg, 1, SYLVA_SCENARIO_MAX_ITERATIONS, &iterations))
        return CLI_EXIT_USAGE;
      break;
    case OPT_EXPORT:
      if (arg[0] == '\0') return cli_usage_error("run", "--export: empty file name");
      export_path = arg;
      break;
    case OPT_DB:
      if (arg[0] == '\0') return cli_usage_error("run", "--db: empty file name");
      db_path = arg;
      break;
    case OPT_NAME:
      if (arg[0] == '\0') return cli_usage_error("run", "--name: empty name");
      name = arg;
      break;
    case OPT_SNAPSHOT_EVERY:
      if (cli_parse_u64("run", "snapshot-every", arg, 1, SYLVA_SCENARIO_MAX_ITERATIONS,
                        &snapshot_every))
        return CLI_EXIT_USAGE;
      break;
    case OPT_QUIET: quiet = true; break;
    default:
      run_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (argc - first != 1)
    return cli_usage_error("run", argc - first == 0 ? "missing SCENARIO.json"
                                                    : "expected one SCENARIO.json");
  if ((name || snapshot_every != STORE_SNAPSHOT_EVERY) && !db_path)
    return cli_usage_error("run", "--name and --snapshot-every need --db");
  const char *path = argv[first];

  sylva_scenario *s;
  int rc = cli_input_scenario(path, SYLVA_SCENARIO_NEED_PLANTS, &s);
  if (rc) return rc;
  if (seed_text) s->seed = seed;
  int limit = iterations ? (int)iterations : s->iterations;

  /* Open the export file now, so that a bad path fails before a long run. */
  cli_outfile export_out = {0};
  if (export_path && (rc = cli_outfile_open(&export_out, "--export", export_path, false))) {
    sylva_scenario_free(s);
    return rc;
  }

  sylva_world *w = NULL;
  rc = cli_input_world(path, s, &w);
  grow_job job = {.label = path, .w = w, .threads = threads, .limit = limit,
                  .progress = !quiet && isatty(STDERR_FILENO),
                  .snapshot_every = (int)snapshot_every, .start_year = s->start_year};
  if (rc == CLI_EXIT_OK && db_path) rc = cli_store_new_run(db_path, name ? name : s->name, s,
                                                            limit, &job);
  if (rc == CLI_EXIT_OK) rc = grow_run(&job);
  store_close(job.st);

  if (export_path && rc == CLI_EXIT_OK) {
    char *skeleton = sylva_encode_skeleton(w);
    if (skeleton) {
      fputs(skeleton, export_out.f);
    } else {
      fprintf(stderr, "sylva: --export: out of memory\n");
      rc = CLI_EXIT_FAILURE;
    }
    free(skeleton);
  }
  rc = cli_outfile_close(&export_out, rc);
  if (w) sylva_world_destroy(w);
  sylva_scenario_free(s);
  return rc;
}
