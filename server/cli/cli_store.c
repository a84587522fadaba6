#include "cli_store.h"

#include <stdio.h>
#include <stdlib.h>

#include "options.h"

int cli_store_open(const char *path, bool create, store **out) {
  int rc = store_open(path, create, out);
  if (rc) {
    fprintf(stderr, "sylva: %s\n", store_open_error());
    return server_exit_status(rc);
  }
  return CLI_EXIT_OK;
}

int cli_store_new_run(const char *db, const char *name, const sylva_scenario *s, int limit,
                      grow_job *job) {
  int rc = cli_store_open(db, true, &job->st);
  if (rc) return rc;
  char *json = sylva_scenario_json(s);
  if (!json) {
    fprintf(stderr, "sylva: out of memory\n");
    return CLI_EXIT_FAILURE;
  }
  int failed = store_create_run(job->st, name, json, s->seed, limit, job->snapshot_every, job->w,
                                &job->run);
  free(json);
  if (failed) {
    fprintf(stderr, "sylva: %s\n", store_error(job->st));
    return server_exit_status(failed);
  }
  return CLI_EXIT_OK;
}

int cli_store_find(store *st, const char *db, const char *name, store_run *out) {
  bool found;
  if (store_find_run(st, name, out, &found)) {
    fprintf(stderr, "sylva: %s\n", store_error(st));
    return CLI_EXIT_FAILURE;
  }
  if (!found) {
    fprintf(stderr, "sylva: %s: no run named \"%s\" ('sylva runs --db %s' lists them)\n", db,
            name, db);
    return CLI_EXIT_USAGE;
  }
  return CLI_EXIT_OK;
}

int cli_open_run(const char *command, const char *db, const char *name, store **st,
                 store_run *out) {
  *st = NULL;
  if (!db || !db[0]) return cli_usage_error(command, "--db FILE is required");
  if (!name || !name[0]) return cli_usage_error(command, "--name NAME is required");
  int rc = cli_store_open(db, false, st);
  if (rc) return rc;
  rc = cli_store_find(*st, db, name, out);
  if (rc) {
    store_close(*st);
    *st = NULL;
  }
  return rc;
}

int cli_stored_iteration(const char *db, const store_run *r, bool given, uint64_t iteration,
                         int *at) {
  *at = r->last_iteration;
  if (!given) return CLI_EXIT_OK;
  if (iteration > (uint64_t)r->last_iteration) {
    fprintf(stderr, "sylva: %s: run \"%s\" has no iteration %llu (it has 0 to %d)\n", db,
            r->name, (unsigned long long)iteration, r->last_iteration);
    return CLI_EXIT_USAGE;
  }
  *at = (int)iteration;
  return CLI_EXIT_OK;
}

void cli_store_warn(const char *msg) { fprintf(stderr, "sylva: warning: %s\n", msg); }

int cli_store_world_at(store *st, const store_run *r, int at, sylva_world **out) {
  if (store_world_at(st, r->id, at, cli_store_warn, out) == SERVER_OK) return CLI_EXIT_OK;
  fprintf(stderr, "sylva: run \"%s\": %s\n", r->name, store_error(st));
  return CLI_EXIT_FAILURE;
}
