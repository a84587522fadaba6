/* The store module on a real SQLite file: schema marks, runs, iterations with and
 * without snapshots, stats rows, the command log, restoring with fallback, and
 * refusal of foreign and newer files. */
#include <math.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../check.h"
#include "store.h"
#include "sylva/sylva.h"

static sylva_world *small_world(void) {
  sylva_world_def wd = sylva_default_world_def();
  wd.min[0] = wd.min[1] = -2, wd.max[0] = wd.max[1] = 2, wd.max[2] = 5;
  sylva_world *w;
  if (sylva_world_create(&wd, &w)) return NULL;
  sylva_species_def sp = sylva_default_species_def();
  sp.tropism[2] = 1.0;
  int s = sylva_world_add_species(w, &sp, "x");
  double roots[2][3] = {{0, 0, 0}, {0.5, 0.5, 0}};
  sylva_plant_def pd = {s, "shrub", (const double(*)[3])roots, 2, 0};
  sylva_world_add_plant(w, &pd, NULL);
  return w;
}

static int count_rows(const store_stats_row *r, void *ctx) {
  int *n = ctx;
  (*n)++;
  return isfinite(r->height) && r->plant[0] ? 0 : 1;
}

static void exec_sql(const char *path, const char *sql) {
  sqlite3 *db;
  sqlite3_open(path, &db);
  sqlite3_exec(db, sql, NULL, NULL, NULL);
  sqlite3_close(db);
}

/* A temporary directory (tmp_open), and the path of a file in it. */
typedef struct tmp {
  char dir[32];
} tmp;

static void tmp_open(tmp *t) {
  snprintf(t->dir, sizeof t->dir, "/tmp/sylva-store-XXXXXX");
  CHECK(mkdtemp(t->dir) != NULL);
}

static void tmp_close(const tmp *t) {
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", t->dir);
  CHECK_INT(system(cmd), 0);
}

static const char *tmp_file(const tmp *t, const char *name, char *buf, size_t size) {
  snprintf(buf, size, "%s/%s", t->dir, name);
  return buf;
}

/* A store, runs.db in a temporary directory, holding the run "r1" of
 * small_world(): 7 of 12 iterations, a snapshot every 3; hashes[t] is the world's
 * hash after iteration t. */
typedef struct fixture {
  tmp t;
  char path[256];
  store *st;
  sylva_world *w;
  int64_t run;
  uint64_t hashes[8];
} fixture;

static void fixture_open(fixture *f) {
  memset(f, 0, sizeof *f);
  tmp_open(&f->t);
  tmp_file(&f->t, "runs.db", f->path, sizeof f->path);
  CHECK_INT(store_open(f->path, true, &f->st), 0);
  f->w = small_world();
  CHECK_INT(store_create_run(f->st, "r1", "{}", 7, 12, 3, f->w, &f->run), 0);
  f->hashes[0] = sylva_world_hash(f->w);
  for (int t = 1; t <= 7; t++) {
    const sylva_journal *j;
    CHECK_INT(sylva_world_step(f->w, &j), 0);
    f->hashes[t] = sylva_world_hash(f->w);
    CHECK_INT(store_save_iteration(f->st, f->run, f->w, j, t % 3 == 0), 0);
  }
}

static void fixture_close(fixture *f) {
  store_close(f->st);
  sylva_world_destroy(f->w);
  tmp_close(&f->t);
}

/* A store is not created without create, and the error names the file. */
static void test_open_needs_create(void) {
  tmp t;
  tmp_open(&t);
  char path[256];
  tmp_file(&t, "runs.db", path, sizeof path);
  store *st = NULL;
  CHECK_INT(store_open(path, false, &st), SERVER_EINPUT);
  CHECK(strstr(store_open_error(), "runs.db") != NULL);
  CHECK_INT(store_open(path, true, &st), 0);
  store_close(st);
  tmp_close(&t);
}

/* A run name is taken once. */
static void test_run_name_taken(void) {
  fixture f;
  fixture_open(&f);
  int64_t other = 0;
  CHECK_INT(store_create_run(f.st, "r1", "{}", 7, 12, 3, f.w, &other), SERVER_EINPUT);
  CHECK(strstr(store_error(f.st), "exists") != NULL);
  fixture_close(&f);
}

/* A run is found by its name, with its last iteration, settings, status and nodes. */
static void test_find_run(void) {
  fixture f;
  fixture_open(&f);
  store_run r;
  bool found;
  CHECK_INT(store_find_run(f.st, "r1", &r, &found), 0);
  CHECK(found);
  CHECK_INT(r.last_iteration, 7);
  CHECK_INT(r.snapshot_every, 3);
  CHECK_INT(r.status, SYLVA_RUN_RUNNING);
  CHECK_INT((long long)r.nodes, (long long)sylva_world_node_count(f.w));
  store_run_free(&r);
  CHECK_INT(store_find_run(f.st, "nope", &r, &found), 0);
  CHECK(!found);
  fixture_close(&f);
}

/* A world loads from the newest snapshot at or before it: 6 for 7, the planted one for 2. */
static void test_load_world(void) {
  fixture f;
  fixture_open(&f);
  sylva_world *back;
  int from = -1;
  CHECK_INT(store_load_world(f.st, f.run, 7, NULL, &back, &from), 0);
  CHECK_INT(from, 6);
  CHECK(sylva_world_hash(back) == f.hashes[6]);
  sylva_world_destroy(back);
  CHECK_INT(store_load_world(f.st, f.run, 2, NULL, &back, &from), 0);
  CHECK_INT(from, 0);
  CHECK(sylva_world_hash(back) == f.hashes[0]);
  sylva_world_destroy(back);
  fixture_close(&f);
}

/* The stored hash of an iteration is its world's. */
static void test_iteration_hash(void) {
  fixture f;
  fixture_open(&f);
  uint64_t h;
  bool found;
  CHECK_INT(store_iteration_hash(f.st, f.run, 5, &h, &found), 0);
  CHECK(found && h == f.hashes[5]);
  fixture_close(&f);
}

/* Stats rows: every iteration up to the one asked, both stems. */
static void test_stats_rows(void) {
  fixture f;
  fixture_open(&f);
  int rows = 0;
  CHECK_INT(store_each_stats(f.st, f.run, 7, count_rows, &rows), 0);
  CHECK_INT(rows, 7 * 2);
  rows = 0;
  CHECK_INT(store_each_stats(f.st, f.run, 3, count_rows, &rows), 0);
  CHECK_INT(rows, 3 * 2);
  fixture_close(&f);
}

/* Logged commands are numbered from 1 and counted. */
static void test_command_log(void) {
  fixture f;
  fixture_open(&f);
  int64_t seq = 0, n = 0;
  CHECK_INT(store_log_command(f.st, f.run, 4, "{\"type\":\"edit\"}", &seq), 0);
  CHECK_INT(seq, 1);
  CHECK_INT(store_log_command(f.st, f.run, 6, "{\"type\":\"control\"}", &seq), 0);
  CHECK_INT(seq, 2);
  CHECK_INT(store_command_count(f.st, f.run, &n), 0);
  CHECK_INT(n, 2);
  fixture_close(&f);
}

/* The run list shows a finished run with its reason and iteration limit. */
static void test_list_runs(void) {
  fixture f;
  fixture_open(&f);
  CHECK_INT(store_set_status(f.st, f.run, SYLVA_RUN_FINISHED, "limit", 0), 0);
  store_run *all;
  size_t count;
  CHECK_INT(store_list_runs(f.st, &all, &count), 0);
  CHECK_INT(count, 1);
  if (count) CHECK(strcmp(all[0].reason, "limit") == 0 && all[0].iterations == 12);
  store_runs_free(all, count);
  fixture_close(&f);
}

/* Reopened, a corrupt snapshot falls back to the previous one. */
static void test_corrupt_snapshot_falls_back(void) {
  fixture f;
  fixture_open(&f);
  store_close(f.st);
  CHECK_INT(store_open(f.path, false, &f.st), 0);
  exec_sql(f.path, "UPDATE iterations SET snapshot = substr(snapshot, 1, 100) || x'00' ||"
                   " substr(snapshot, 102) WHERE iteration = 6");
  sylva_world *back;
  int from = -1;
  CHECK_INT(store_load_world(f.st, f.run, 7, NULL, &back, &from), 0);
  CHECK_INT(from, 3);
  if (back) CHECK(sylva_world_hash(back) == f.hashes[3]);
  sylva_world_destroy(back);
  fixture_close(&f);
}

/* A file of another program is refused. */
static void test_foreign_file_refused(void) {
  tmp t;
  tmp_open(&t);
  char foreign[256];
  tmp_file(&t, "foreign.db", foreign, sizeof foreign);
  exec_sql(foreign, "CREATE TABLE t (a)");
  store *st = NULL;
  CHECK_INT(store_open(foreign, true, &st), SERVER_EINPUT);
  CHECK(strstr(store_open_error(), "another program") != NULL);
  tmp_close(&t);
}

/* A store of a newer schema is refused. */
static void test_newer_file_refused(void) {
  tmp t;
  tmp_open(&t);
  char newer[256];
  tmp_file(&t, "newer.db", newer, sizeof newer);
  store *st = NULL;
  CHECK_INT(store_open(newer, true, &st), 0);
  store_close(st);
  exec_sql(newer, "PRAGMA user_version = 99");
  CHECK_INT(store_open(newer, false, &st), SERVER_EINPUT);
  CHECK(strstr(store_open_error(), "newer") != NULL);
  tmp_close(&t);
}

static int first_row(const store_stats_row *r, void *ctx) {
  store_stats_row *out = ctx;
  if (out->iteration < 0) *out = *r;
  return 0;
}

/* A store of schema 1 (before conflicts) is migrated in place: its rows stay, and
 * read as not reporting conflicts (pruned -1, zones and clearance NULL). */
static void test_schema1_migrates(void) {
  fixture f;
  fixture_open(&f);
  const char *path = f.path;
  store_close(f.st);
  f.st = NULL;
  /* back to schema 1: the columns of migration 1 gone */
  exec_sql(path, "ALTER TABLE stats DROP COLUMN clearance; ALTER TABLE stats DROP COLUMN zones;"
                 " ALTER TABLE stats DROP COLUMN pruned; PRAGMA user_version = 1");
  CHECK_INT(store_open(path, false, &f.st), 0);
  store_stats_row r = {.iteration = -1};
  if (f.st) CHECK_INT(store_each_stats(f.st, f.run, 7, first_row, &r), 0);
  CHECK_INT(r.iteration, 1);
  CHECK(r.pruned == -1 && r.zones == NULL && r.clearance == NULL);
  int rows = 0;
  if (f.st) CHECK_INT(store_each_stats(f.st, f.run, 7, count_rows, &rows), 0);
  CHECK_INT(rows, 7 * 2);
  fixture_close(&f);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {
      CHECK_TEST(open_needs_create), CHECK_TEST(run_name_taken), CHECK_TEST(find_run),
      CHECK_TEST(load_world), CHECK_TEST(iteration_hash), CHECK_TEST(stats_rows),
      CHECK_TEST(command_log), CHECK_TEST(list_runs), CHECK_TEST(corrupt_snapshot_falls_back),
      CHECK_TEST(foreign_file_refused), CHECK_TEST(newer_file_refused),
      CHECK_TEST(schema1_migrates)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("store");
}
