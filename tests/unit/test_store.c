/* The store module on a real SQLite file: schema marks, runs, iterations with and
 * without snapshots, stats rows (with the ages and start year of a run in years),
 * the command log, restoring with fallback, migrations of older schemas (leaf areas
 * NULL in the rows of a store before foliage), and
 * refusal of foreign and newer files. */
#include <math.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../check.h"
#include "store.h"
#include "sylva/sylva.h"

/* A shrub of two stems; with years, of a species that counts in years, planted at
 * the age of 2 beside a tree of an IGM species (no years). */
static sylva_world *world_of(bool years) {
  sylva_world_def wd = sylva_default_world_def();
  wd.min[0] = wd.min[1] = -2, wd.max[0] = wd.max[1] = 2, wd.max[2] = 5;
  sylva_world *w;
  if (sylva_world_create(&wd, &w)) return NULL;
  sylva_species_def sp = sylva_default_species_def();
  sp.tropism[2] = 1.0;
  sp.years = years;
  int s = sylva_world_add_species(w, &sp, "x");
  double roots[2][3] = {{0, 0, 0}, {0.5, 0.5, 0}};
  sylva_plant_def pd = {s, "shrub", (const double(*)[3])roots, 2, years ? 2 : 0, NULL, 0};
  sylva_world_add_plant(w, &pd, NULL);
  if (years) {
    sylva_species_def igm = sylva_default_species_def();
    igm.tropism[2] = 1.0;
    double root[1][3] = {{-1, -1, 0}};
    sylva_plant_def tree = {sylva_world_add_species(w, &igm, "igm"), "tree",
                            (const double(*)[3])root, 1, 0, NULL, 0};
    sylva_world_add_plant(w, &tree, NULL);
  }
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
 * world_of(false) (with fixture_open_as, of world_of(years) and a scenario from 2027
 * whose species x counts in years): 7 of 12 iterations, a snapshot every 3;
 * hashes[t] is the world's hash after iteration t as the store keeps it (the newest
 * definition), hashes1[t] by the first (the runs of a store before schema 8). */
typedef struct fixture {
  tmp t;
  char path[256];
  store *st;
  sylva_world *w;
  int64_t run;
  uint64_t hashes[8], hashes1[8];
} fixture;

static void fixture_open_as(fixture *f, bool years) {
  memset(f, 0, sizeof *f);
  tmp_open(&f->t);
  tmp_file(&f->t, "runs.db", f->path, sizeof f->path);
  CHECK_INT(store_open(f->path, true, &f->st), 0);
  f->w = world_of(years);
  const char *scenario =
      years ? "{\"start_year\": 2027, \"species\": {\"x\": {\"years\": 1}, \"igm\": {}}}" : "{}";
  CHECK_INT(store_create_run(f->st, "r1", scenario, 7, 12, 3, f->w, &f->run), 0);
  for (int t = 0; t <= 7; t++) {
    const sylva_journal *j;
    if (t > 0) CHECK_INT(sylva_world_step(f->w, &j), 0);
    f->hashes[t] = sylva_world_hash_of(f->w, SYLVA_WORLD_HASH_VERSION);
    f->hashes1[t] = sylva_world_hash(f->w);
    if (t == 0) continue;
    CHECK_INT(store_save_iteration(f->st, f->run, f->w, j, t % 3 == 0), 0);
  }
}

static void fixture_open(fixture *f) { fixture_open_as(f, false); }

/* The fixture's closed store as a store before schema 8 kept it: the run's rows hold
 * the first definition's hashes. */
static void fixture_hashes_v1(const fixture *f) {
  char sql[160];
  for (int t = 0; t <= 7; t++) {
    snprintf(sql, sizeof sql, "UPDATE iterations SET hash = %lld WHERE run = %lld AND iteration = %d",
             (long long)f->hashes1[t], (long long)f->run, t);
    exec_sql(f->path, sql);
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
  CHECK(sylva_world_hash(back) == f.hashes1[6]);
  sylva_world_destroy(back);
  CHECK_INT(store_load_world(f.st, f.run, 2, NULL, &back, &from), 0);
  CHECK_INT(from, 0);
  CHECK(sylva_world_hash(back) == f.hashes1[0]);
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
  if (back) CHECK(sylva_world_hash(back) == f.hashes1[3]);
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

/* The column schema 8 added, dropped: a store of schema 7 again (its hashes made
 * the first definition's by fixture_hashes_v1). */
#define BACK_TO_SCHEMA_7 "ALTER TABLE runs DROP COLUMN hash_version; PRAGMA user_version = 7;"

/* The columns schemas 8 and 7 added, dropped: a store of schema 6 again. */
#define BACK_TO_SCHEMA_6                                                                  \
  BACK_TO_SCHEMA_7 " ALTER TABLE stats DROP COLUMN alive; ALTER TABLE stats DROP COLUMN died;"              \
  " ALTER TABLE stats DROP COLUMN vigour; ALTER TABLE iterations DROP COLUMN stand_area;"  \
  " ALTER TABLE iterations DROP COLUMN stand_alive;"                                      \
  " ALTER TABLE iterations DROP COLUMN stand_died;"                                       \
  " ALTER TABLE iterations DROP COLUMN stems_per_ha;"                                     \
  " ALTER TABLE iterations DROP COLUMN basal_area; ALTER TABLE iterations DROP COLUMN qmd;" \
  " ALTER TABLE iterations DROP COLUMN dominant_height;"                                  \
  " ALTER TABLE iterations DROP COLUMN sdi; ALTER TABLE iterations DROP COLUMN cv_height;" \
  " ALTER TABLE iterations DROP COLUMN cv_dbh; PRAGMA user_version = 6;"

/* The columns schemas 8 to 6 added, dropped: a store of schema 5 again. */
#define BACK_TO_SCHEMA_5                                                                  \
  BACK_TO_SCHEMA_6 " ALTER TABLE stats DROP COLUMN crown_area; ALTER TABLE stats DROP COLUMN wood_volume;"    \
  " ALTER TABLE stats DROP COLUMN biomass; ALTER TABLE stats DROP COLUMN biomass_model;"   \
  " ALTER TABLE stats DROP COLUMN carbon; ALTER TABLE stats DROP COLUMN co2;"              \
  " ALTER TABLE stats DROP COLUMN co2_sequestered;"                                       \
  " ALTER TABLE iterations DROP COLUMN canopy_cover; PRAGMA user_version = 5;"

/* The columns schemas 8 to 5 added, dropped: a store of schema 4 again. */
#define BACK_TO_SCHEMA_4                                                                  \
  BACK_TO_SCHEMA_5 " ALTER TABLE stats DROP COLUMN leaf_area; PRAGMA user_version = 4;"

/* The tables schema 4 added and the columns schemas 5 and 3 added, dropped: a store of
 * schema 2 again. */
#define BACK_TO_SCHEMA_2                                                                  \
  BACK_TO_SCHEMA_4                                                                        \
  " DROP TABLE run_axes; DROP TABLE sweep_runs; DROP TABLE sweeps;"                        \
  " ALTER TABLE stats DROP COLUMN age; ALTER TABLE stats DROP COLUMN crown_height;"        \
  " ALTER TABLE runs DROP COLUMN start_year; PRAGMA user_version = 2;"

/* A store of schema 1 (before conflicts) is migrated in place: its rows stay, and
 * read as not reporting conflicts (pruned -1, zones and clearance NULL). */
static void test_schema1_migrates(void) {
  fixture f;
  fixture_open(&f);
  const char *path = f.path;
  store_close(f.st);
  f.st = NULL;
  /* back to schema 1: the columns of migrations 2 and 1 gone */
  fixture_hashes_v1(&f);
  exec_sql(path, BACK_TO_SCHEMA_2
                 "ALTER TABLE stats DROP COLUMN clearance; ALTER TABLE stats DROP COLUMN zones;"
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

/* The schema version of a store file. */
static int user_version(const char *path) {
  sqlite3 *db;
  sqlite3_stmt *q;
  int v = -1;
  sqlite3_open(path, &db);
  if (sqlite3_prepare_v2(db, "PRAGMA user_version", -1, &q, NULL) == SQLITE_OK) {
    if (sqlite3_step(q) == SQLITE_ROW) v = sqlite3_column_int(q, 0);
    sqlite3_finalize(q);
  }
  sqlite3_close(db);
  return v;
}

/* The fixture's store taken back to an older schema by `sql` (which leaves it at
 * `version`), then opened again: migrated to this build's schema. */
static void fixture_reopen_from(fixture *f, const char *sql, int version) {
  fixture_open(f);
  store_close(f->st);
  f->st = NULL;
  fixture_hashes_v1(f);
  exec_sql(f->path, sql);
  CHECK_INT(user_version(f->path), version);
  CHECK_INT(store_open(f->path, false, &f->st), 0);
  CHECK_INT(user_version(f->path), STORE_SCHEMA_VERSION);
}

/* A store of schema 2 (before years) is migrated in place: its rows stay and read
 * without ages (age -1, crown height NaN), its runs without a start year, and the
 * run grows on into the new columns. */
static void test_schema2_migrates(void) {
  fixture f;
  fixture_reopen_from(&f, BACK_TO_SCHEMA_2, 2);
  store_stats_row r = {.iteration = -1};
  if (f.st) CHECK_INT(store_each_stats(f.st, f.run, 7, first_row, &r), 0);
  CHECK_INT(r.iteration, 1);
  CHECK(r.age == -1 && isnan(r.crown_height));
  int rows = 0;
  if (f.st) CHECK_INT(store_each_stats(f.st, f.run, 7, count_rows, &rows), 0);
  CHECK_INT(rows, 7 * 2);
  store_run sr;
  bool found = false;
  if (f.st) CHECK_INT(store_find_run(f.st, "r1", &sr, &found), 0);
  CHECK(found);
  if (found) {
    CHECK(sr.start_year == 0 && !sr.years);
    store_run_free(&sr);
  }
  const sylva_journal *j;
  CHECK_INT(sylva_world_step(f.w, &j), 0);
  if (f.st) CHECK_INT(store_save_iteration(f.st, f.run, f.w, j, true), 0);
  rows = 0;
  if (f.st) CHECK_INT(store_each_stats(f.st, f.run, 8, count_rows, &rows), 0);
  CHECK_INT(rows, 8 * 2);
  fixture_close(&f);
}

/* A stats row's leaf area at iterations 1..8 (stem 0), for test_schema4_migrates. */
static int leaf_area_row(const store_stats_row *r, void *ctx) {
  double *out = ctx;
  if (r->stem == 0 && r->iteration >= 1 && r->iteration <= 8) out[r->iteration] = r->leaf_area;
  return 0;
}

/* A store of schema 4 (before foliage) is migrated in place: its rows stay and read
 * without a leaf area (NaN), and the run grows on into the new column, which holds
 * the stem's leaf_area as the world measures it. */
static void test_schema4_migrates(void) {
  fixture f;
  fixture_reopen_from(&f, BACK_TO_SCHEMA_4, 4);
  const sylva_journal *j;
  CHECK_INT(sylva_world_step(f.w, &j), 0);
  if (f.st) CHECK_INT(store_save_iteration(f.st, f.run, f.w, j, true), 0);
  double leaf[9];
  for (int i = 0; i < 9; i++) leaf[i] = -1.0;
  if (f.st) CHECK_INT(store_each_stats(f.st, f.run, 8, leaf_area_row, leaf), 0);
  for (int t = 1; t <= 7; t++) CHECK(isnan(leaf[t]));
  sylva_stem_stats st;
  CHECK_INT(sylva_world_stem_stats(f.w, 0, &st), 0);
  CHECK(st.leaf_area > 0 && leaf[8] == st.leaf_area);
  fixture_close(&f);
}

/* A stats row's crown area and canopy cover at iterations 1..8 (stem 0), for
 * test_schema5_migrates. */
static int canopy_row(const store_stats_row *r, void *ctx) {
  double(*out)[9] = ctx;
  if (r->stem == 0 && r->iteration >= 1 && r->iteration <= 8) {
    out[0][r->iteration] = r->crown_area;
    out[1][r->iteration] = r->canopy_cover;
    out[2][r->iteration] = r->wood_volume;
  }
  return 0;
}

/* A store of schema 5 (before crown area, wood and carbon) is migrated in place: its
 * rows stay and read without them (NaN), and the run grows on into the new columns,
 * which hold the world's measures. */
static void test_schema5_migrates(void) {
  fixture f;
  fixture_reopen_from(&f, BACK_TO_SCHEMA_5, 5);
  const sylva_journal *j;
  CHECK_INT(sylva_world_step(f.w, &j), 0);
  if (f.st) CHECK_INT(store_save_iteration(f.st, f.run, f.w, j, true), 0);
  double got[3][9];
  for (int k = 0; k < 3; k++)
    for (int i = 0; i < 9; i++) got[k][i] = -1.0;
  if (f.st) CHECK_INT(store_each_stats(f.st, f.run, 8, canopy_row, got), 0);
  for (int t = 1; t <= 7; t++) CHECK(isnan(got[0][t]) && isnan(got[1][t]) && isnan(got[2][t]));
  sylva_stem_stats st;
  CHECK_INT(sylva_world_stem_stats(f.w, 0, &st), 0);
  CHECK(st.crown_area > 0 && got[0][8] == st.crown_area);
  CHECK(st.wood_volume > 0 && got[2][8] == st.wood_volume);
  CHECK(got[1][8] == sylva_world_canopy_cover(f.w) && got[1][8] > 0);
  fixture_close(&f);
}

/* A stats row's stand figures at iterations 1..8 (stem 0), for test_schema6_migrates. */
static int stand_row(const store_stats_row *r, void *ctx) {
  store_stats_row *out = ctx;
  if (r->stem == 0 && r->iteration >= 1 && r->iteration <= 8) out[r->iteration] = *r;
  return 0;
}

/* A store of schema 6 (before stands) holding a run in years (a stand) is migrated in
 * place: its rows stay and read without alive, died, vigour and the stand (-1, NaN),
 * the run reads as without stands, and grows on into the new columns, which hold the
 * world's stem and stand figures. */
static void test_schema6_migrates(void) {
  fixture f;
  fixture_open_as(&f, true);
  store_close(f.st);
  f.st = NULL;
  fixture_hashes_v1(&f);
  exec_sql(f.path, BACK_TO_SCHEMA_6);
  CHECK_INT(user_version(f.path), 6);
  CHECK_INT(store_open(f.path, false, &f.st), 0);
  CHECK_INT(user_version(f.path), STORE_SCHEMA_VERSION);
  bool stand = true;
  if (f.st) CHECK_INT(store_run_stand(f.st, f.run, &stand), 0);
  CHECK(!stand);
  const sylva_journal *j;
  CHECK_INT(sylva_world_step(f.w, &j), 0);
  if (f.st) CHECK_INT(store_save_iteration(f.st, f.run, f.w, j, true), 0);
  if (f.st) CHECK_INT(store_run_stand(f.st, f.run, &stand), 0);
  CHECK(stand);
  store_stats_row got[9] = {0};
  if (f.st) CHECK_INT(store_each_stats(f.st, f.run, 8, stand_row, got), 0);
  for (int t = 1; t <= 7; t++)
    CHECK(got[t].iteration == t && got[t].alive == -1 && got[t].died == -1 &&
          isnan(got[t].vigour) && got[t].stand.alive == -1 && got[t].stand.died == -1 &&
          isnan(got[t].stand.stems_per_ha) && isnan(got[t].stand.cv_dbh));
  sylva_stem_stats st;
  sylva_stand_stats want;
  CHECK_INT(sylva_world_stem_stats(f.w, 0, &st), 0);
  sylva_world_stand(f.w, &want);
  CHECK(got[8].iteration == 8 && got[8].alive == st.alive && got[8].died == st.died &&
        (isnan(st.vigour) ? isnan(got[8].vigour) : got[8].vigour == st.vigour));
  CHECK(want.alive == 3 && got[8].stand.alive == want.alive && got[8].stand.died == want.died);
  CHECK(got[8].stand.stems_per_ha == want.stems_per_ha && got[8].stand.qmd == want.qmd &&
        got[8].stand.dominant_height == want.dominant_height);
  fixture_close(&f);
}

/* A store of schema 7 is migrated in place: its run keeps the first definition of the
 * world hash, restores and regrows every iteration against it, and grows on storing
 * it, while a new run keeps the newest; a run that names a definition this build does
 * not know is refused by name, and its rows stay as they were. */
static void test_schema7_keeps_hash1(void) {
  fixture f;
  fixture_reopen_from(&f, BACK_TO_SCHEMA_7, 7);
  uint64_t h = 0;
  bool found = false;
  for (int t = 0; t <= 7 && f.st; t++) {
    sylva_world *w = NULL;
    CHECK_INT(store_world_at(f.st, f.run, t, NULL, &w), 0);
    CHECK(w && sylva_world_hash(w) == f.hashes1[t]);
    sylva_world_destroy(w);
  }
  const sylva_journal *j;
  CHECK_INT(sylva_world_step(f.w, &j), 0);
  if (f.st) CHECK_INT(store_save_iteration(f.st, f.run, f.w, j, false), 0);
  if (f.st) CHECK_INT(store_iteration_hash(f.st, f.run, 8, &h, &found), 0);
  CHECK(found && h == sylva_world_hash(f.w) && h != sylva_world_hash_of(f.w, 2));
  int64_t fresh = 0;
  if (f.st) CHECK_INT(store_create_run(f.st, "fresh", "{}", 7, 12, 3, f.w, &fresh), 0);
  if (f.st) CHECK_INT(store_iteration_hash(f.st, fresh, 8, &h, &found), 0);
  CHECK(found && h == sylva_world_hash_of(f.w, SYLVA_WORLD_HASH_VERSION));
  store_close(f.st);
  exec_sql(f.path, "UPDATE runs SET hash_version = 3 WHERE name = 'r1'");
  f.st = NULL;
  CHECK_INT(store_open(f.path, false, &f.st), 0);
  sylva_world *w = NULL;
  if (f.st) CHECK_INT(store_world_at(f.st, f.run, 4, NULL, &w), SERVER_EFAIL);
  CHECK(w == NULL);
  if (f.st) CHECK(strstr(store_error(f.st), "version 3") != NULL);
  if (f.st) CHECK_INT(store_iteration_hash(f.st, f.run, 4, &h, &found), 0);
  CHECK(found && h == f.hashes1[4]);
  fixture_close(&f);
}

/* The stats of a run in years as stored, for test_years_round_trip. */
typedef struct years_rows {
  int count, bad;
  int age[8][3];
  double crown_height[8][3];
} years_rows;

static int years_row(const store_stats_row *r, void *ctx) {
  years_rows *y = ctx;
  y->count++;
  if (r->iteration > 7 || r->stem > 2) {
    y->bad++;
    return 0;
  }
  y->age[r->iteration][r->stem] = r->age;
  y->crown_height[r->iteration][r->stem] = r->crown_height;
  return 0;
}

static int age_row(int64_t run, const char *plant, int age, void *ctx) {
  char *out = ctx;
  size_t n = strlen(out);
  snprintf(out + n, 256 - n, "%lld %s %d;", (long long)run, plant, age);
  return 0;
}

/* A run in years: its start year and years read back from its scenario; every
 * stem's age (its plant's age at planting and the iterations since; null for the
 * IGM tree) and crown height exactly as the regrown world measures them; the
 * plants' ages at the last stored iteration; a run without either reads as such. */
static void test_years_round_trip(void) {
  fixture f;
  fixture_open_as(&f, true);
  store_run r;
  bool found = false;
  CHECK_INT(store_find_run(f.st, "r1", &r, &found), 0);
  CHECK(found);
  if (found) {
    CHECK_INT(r.start_year, 2027);
    CHECK(r.years);
    store_run_free(&r);
  }
  int start_year = 0;
  bool years = false;
  CHECK_INT(store_run_calendar(f.st, f.run, &start_year, &years), 0);
  CHECK(start_year == 2027 && years);
  years_rows y = {0};
  CHECK_INT(store_each_stats(f.st, f.run, 7, years_row, &y), 0);
  CHECK_INT(y.count, 7 * 3);
  CHECK_INT(y.bad, 0);
  for (int it = 1; it <= 7; it++) {
    for (int k = 0; k < 2; k++) CHECK_INT(y.age[it][k], 2 + it); /* the shrub's two stems */
    CHECK_INT(y.age[it][2], -1);                                 /* the IGM tree */
    sylva_world *w = NULL;
    CHECK_INT(store_world_at(f.st, f.run, it, NULL, &w), 0);
    for (int k = 0; w && k < 3; k++) {
      sylva_stem_stats st;
      CHECK_INT(sylva_world_stem_stats(w, k, &st), 0);
      CHECK_INT(y.age[it][k], st.age);
      CHECK(isnan(st.crown_height) ? isnan(y.crown_height[it][k])
                                   : y.crown_height[it][k] == st.crown_height);
    }
    sylva_world_destroy(w);
  }
  char ages[256] = "", want[256];
  CHECK_INT(store_each_age(f.st, age_row, ages), 0);
  snprintf(want, sizeof want, "%lld shrub 9;", (long long)f.run);
  CHECK(strcmp(ages, want) == 0);
  if (strcmp(ages, want) != 0) fprintf(stderr, "ages: %s (want %s)\n", ages, want);
  int64_t plain = 0;
  CHECK_INT(store_create_run(f.st, "plain", "{}", 7, 12, 3, f.w, &plain), 0);
  CHECK_INT(store_run_calendar(f.st, plain, &start_year, &years), 0);
  CHECK(start_year == 0 && !years);
  fixture_close(&f);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {
      CHECK_TEST(open_needs_create), CHECK_TEST(run_name_taken), CHECK_TEST(find_run),
      CHECK_TEST(load_world), CHECK_TEST(iteration_hash), CHECK_TEST(stats_rows),
      CHECK_TEST(command_log), CHECK_TEST(list_runs), CHECK_TEST(corrupt_snapshot_falls_back),
      CHECK_TEST(foreign_file_refused), CHECK_TEST(newer_file_refused),
      CHECK_TEST(schema1_migrates), CHECK_TEST(schema2_migrates), CHECK_TEST(schema4_migrates), CHECK_TEST(schema5_migrates),
      CHECK_TEST(schema6_migrates), CHECK_TEST(schema7_keeps_hash1),
      CHECK_TEST(years_round_trip)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("store");
}
