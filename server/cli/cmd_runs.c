/* `sylva runs`: the stored runs and their state. */
#include <stdio.h>
#include <stdlib.h>

#include "commands.h"
#include "options.h"
#include "cli_store.h"

enum { OPT_DB, OPT_HELP, OPT_COUNT };

static const cli_option runs_options[OPT_COUNT] = {
    [OPT_DB] = {"db", 0, "FILE", "the store (required)"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static void runs_usage(FILE *f) {
  fputs("Usage: sylva runs --db FILE\n"
        "\n"
        "Lists the runs of a store, oldest first, one per line: name, status (running,\n"
        "paused, finished, failed), why it ended (finished by the growth equations, or\n"
        "its iteration limit), the last stored iteration and the limit, live nodes, seed,\n"
        "and when it was created and last updated (UTC).\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, runs_options, OPT_COUNT);
}

int cmd_runs(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "runs", runs_options, OPT_COUNT, argc, argv);
  const char *db = NULL, *arg;
  int first = argc, opt;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    if (opt == OPT_DB) {
      db = arg;
    } else {
      runs_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (first != argc) return cli_usage_error("runs", "unexpected argument '%s'", argv[first]);
  if (!db || !db[0]) return cli_usage_error("runs", "--db FILE is required");
  store *st;
  int rc = cli_store_open(db, false, &st);
  if (rc) return rc;
  store_run *runs;
  size_t n;
  if (store_list_runs(st, &runs, &n)) {
    fprintf(stderr, "sylva: %s\n", store_error(st));
    store_close(st);
    return CLI_EXIT_FAILURE;
  }
  int width = 4;
  for (size_t i = 0; i < n; i++) {
    int len = (int)snprintf(NULL, 0, "%s", runs[i].name);
    if (len > width) width = len;
  }
  printf("%-*s  %-8s  %-8s  %9s  %9s  %20s  %-20s  %s\n", width, "NAME", "STATUS", "ENDED",
         "ITERATION", "NODES", "SEED", "CREATED", "UPDATED");
  for (size_t i = 0; i < n; i++) {
    const store_run *r = &runs[i];
    char it[32];
    snprintf(it, sizeof it, "%d/%d", r->last_iteration, r->iterations);
    printf("%-*s  %-8s  %-8s  %9s  %9lld  %20llu  %-20s  %s\n", width, r->name, sylva_run_status_name(r->status),
           r->reason[0] ? r->reason : "-", it, (long long)r->nodes, (unsigned long long)r->seed,
           r->created, r->updated);
  }
  store_runs_free(runs, n);
  store_close(st);
  return fflush(stdout) == 0 ? CLI_EXIT_OK : CLI_EXIT_FAILURE;
}
