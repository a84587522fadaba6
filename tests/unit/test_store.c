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
  sylva_plant_def pd = {s, "shrub", (const double(*)[3])roots, 2};
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

int main(void) {
  char dir[] = "/tmp/sylva-store-XXXXXX";
  CHECK(mkdtemp(dir) != NULL);
  char path[256], foreign[256], newer[256];
  snprintf(path, sizeof path, "%s/runs.db", dir);
  snprintf(foreign, sizeof foreign, "%s/foreign.db", dir);
  snprintf(newer, sizeof newer, "%s/newer.db", dir);

  store *st = NULL;
  CHECK_INT(store_open(path, false, &st), SERVER_EINPUT); /* not created without create */
  CHECK(strstr(store_open_error(), "runs.db") != NULL);
  CHECK_INT(store_open(path, true, &st), 0);
  sylva_world *w = small_world();
  int64_t run = 0, other = 0;
  CHECK_INT(store_create_run(st, "r1", "{}", 7, 12, 3, w, &run), 0);
  CHECK_INT(store_create_run(st, "r1", "{}", 7, 12, 3, w, &other), SERVER_EINPUT); /* taken */
  CHECK(strstr(store_error(st), "exists") != NULL);
  uint64_t hashes[8];
  hashes[0] = sylva_world_hash(w);
  for (int t = 1; t <= 7; t++) {
    const sylva_journal *j;
    CHECK_INT(sylva_world_step(w, &j), 0);
    hashes[t] = sylva_world_hash(w);
    CHECK_INT(store_save_iteration(st, run, w, j, t % 3 == 0), 0);
  }
  store_run r;
  bool found;
  CHECK_INT(store_find_run(st, "r1", &r, &found), 0);
  CHECK(found);
  CHECK_INT(r.last_iteration, 7);
  CHECK_INT(r.snapshot_every, 3);
  CHECK_INT(r.status, SYLVA_RUN_RUNNING);
  CHECK_INT((long long)r.nodes, (long long)sylva_world_node_count(w));
  store_run_free(&r);
  CHECK_INT(store_find_run(st, "nope", &r, &found), 0);
  CHECK(!found);

  /* the newest snapshot at or before 7 is 6; at or before 2 it is the planted world */
  sylva_world *back;
  int from = -1;
  CHECK_INT(store_load_world(st, run, 7, NULL, &back, &from), 0);
  CHECK_INT(from, 6);
  CHECK(sylva_world_hash(back) == hashes[6]);
  sylva_world_destroy(back);
  CHECK_INT(store_load_world(st, run, 2, NULL, &back, &from), 0);
  CHECK_INT(from, 0);
  CHECK(sylva_world_hash(back) == hashes[0]);
  sylva_world_destroy(back);
  uint64_t h;
  CHECK_INT(store_iteration_hash(st, run, 5, &h, &found), 0);
  CHECK(found && h == hashes[5]);

  int rows = 0;
  CHECK_INT(store_each_stats(st, run, 7, count_rows, &rows), 0);
  CHECK_INT(rows, 7 * 2); /* every iteration, both stems */
  rows = 0;
  CHECK_INT(store_each_stats(st, run, 3, count_rows, &rows), 0);
  CHECK_INT(rows, 3 * 2);

  int64_t seq = 0, n = 0;
  CHECK_INT(store_log_command(st, run, 4, "{\"type\":\"edit\"}", &seq), 0);
  CHECK_INT(seq, 1);
  CHECK_INT(store_log_command(st, run, 6, "{\"type\":\"control\"}", &seq), 0);
  CHECK_INT(seq, 2);
  CHECK_INT(store_command_count(st, run, &n), 0);
  CHECK_INT(n, 2);

  CHECK_INT(store_set_status(st, run, SYLVA_RUN_FINISHED, "limit", 0), 0);
  store_run *all;
  size_t count;
  CHECK_INT(store_list_runs(st, &all, &count), 0);
  CHECK_INT(count, 1);
  if (count) CHECK(strcmp(all[0].reason, "limit") == 0 && all[0].iterations == 12);
  store_runs_free(all, count);
  store_close(st);

  /* reopened, the same; a corrupt snapshot falls back to the previous one */
  CHECK_INT(store_open(path, false, &st), 0);
  exec_sql(path, "UPDATE iterations SET snapshot = substr(snapshot, 1, 100) || x'00' ||"
                 " substr(snapshot, 102) WHERE iteration = 6");
  CHECK_INT(store_load_world(st, run, 7, NULL, &back, &from), 0);
  CHECK_INT(from, 3);
  if (back) CHECK(sylva_world_hash(back) == hashes[3]);
  sylva_world_destroy(back);
  store_close(st);

  /* foreign and newer files are refused, and left as they were */
  exec_sql(foreign, "CREATE TABLE t (a)");
  CHECK_INT(store_open(foreign, true, &st), SERVER_EINPUT);
  CHECK(strstr(store_open_error(), "another program") != NULL);
  CHECK_INT(store_open(newer, true, &st), 0);
  store_close(st);
  exec_sql(newer, "PRAGMA user_version = 99");
  CHECK_INT(store_open(newer, false, &st), SERVER_EINPUT);
  CHECK(strstr(store_open_error(), "newer") != NULL);

  sylva_world_destroy(w);
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  CHECK_INT(system(cmd), 0);
  return check_summary("store");
}
