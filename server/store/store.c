/* The SQLite store: schema, migrations, runs, iterations, stats, commands. */
#include "store.h"

#include <math.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "command_log.h"
#include "store_impl.h"
#include "sylva/encode.h"
#include "sylva/snapshot.h"

/* The last failure of this thread's store calls (as errno is), so that a message
 * read after a call is that call's, whatever other threads do meanwhile. */
_Thread_local char store__last_error[STORE_ERROR_MAX];
#define last_error store__last_error

const char *store_error(const store *st) {
  (void)st;
  return last_error;
}
const char *store_open_error(void) { return last_error; }

int store__fail(store *st, const char *fmt, ...) {
  char what[384];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(what, sizeof what, fmt, ap);
  va_end(ap);
  int code = sqlite3_errcode(st->db);
  if (code != SQLITE_OK && code != SQLITE_ROW && code != SQLITE_DONE)
    snprintf(last_error, sizeof last_error, "%s: %s: %s", st->path, what, sqlite3_errmsg(st->db));
  else
    snprintf(last_error, sizeof last_error, "%s: %s", st->path, what);
  return SERVER_EFAIL;
}

int store__exec(store *st, const char *sql, const char *what) {
  char *msg = NULL;
  if (sqlite3_exec(st->db, sql, NULL, NULL, &msg) != SQLITE_OK) {
    snprintf(last_error, sizeof last_error, "%s: %s: %s", st->path, what,
             msg ? msg : "SQLite error");
    sqlite3_free(msg);
    return SERVER_EFAIL;
  }
  return SERVER_OK;
}

/* Prepares sql and binds ?1 to run and ?2 to n. */
static int prepare_run(store *st, const char *sql, int64_t run, int n, sqlite3_stmt **q) {
  if (sqlite3_prepare_v2(st->db, sql, -1, q, NULL) != SQLITE_OK) return SERVER_EFAIL;
  sqlite3_bind_int64(*q, 1, run);
  sqlite3_bind_int(*q, 2, n);
  return SERVER_OK;
}

void store__rollback(store *st) { sqlite3_exec(st->db, "ROLLBACK", NULL, NULL, NULL); }

void store__utc_now(char out[32]) {
  time_t t = time(NULL);
  struct tm tm;
  gmtime_r(&t, &tm);
  strftime(out, 32, "%Y-%m-%dT%H:%M:%SZ", &tm);
}

static int64_t pragma_int(store *st, const char *sql, bool *ok) {
  sqlite3_stmt *q;
  *ok = false;
  if (sqlite3_prepare_v2(st->db, sql, -1, &q, NULL) != SQLITE_OK) return 0;
  int64_t v = 0;
  if (sqlite3_step(q) == SQLITE_ROW) {
    v = sqlite3_column_int64(q, 0);
    *ok = true;
  }
  sqlite3_finalize(q);
  return v;
}

/* ---- schema ------------------------------------------------------------------- */

/* Migration i brings a store from user_version i to i + 1. */
static const char *const migrations[STORE_SCHEMA_VERSION] = {
    "CREATE TABLE runs ("
    "  id INTEGER PRIMARY KEY,"
    "  name TEXT NOT NULL UNIQUE,"
    "  scenario TEXT NOT NULL,"
    "  seed INTEGER NOT NULL,"
    "  iterations INTEGER NOT NULL CHECK (iterations > 0),"
    "  snapshot_every INTEGER NOT NULL CHECK (snapshot_every > 0),"
    "  status TEXT NOT NULL CHECK (status IN ('running', 'paused', 'finished', 'failed')),"
    "  reason TEXT,"
    "  created TEXT NOT NULL,"
    "  updated TEXT NOT NULL);"
    "CREATE TABLE iterations ("
    "  run INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,"
    "  iteration INTEGER NOT NULL CHECK (iteration >= 0),"
    "  hash INTEGER NOT NULL,"
    "  nodes INTEGER NOT NULL,"
    "  snapshot BLOB,"
    "  PRIMARY KEY (run, iteration));"
    "CREATE TABLE stats ("
    "  run INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,"
    "  iteration INTEGER NOT NULL,"
    "  stem INTEGER NOT NULL,"
    "  plant TEXT NOT NULL,"
    "  plant_stem INTEGER NOT NULL,"
    "  height REAL, dbh REAL, crown_width REAL, crown_base REAL,"
    "  nodes INTEGER NOT NULL, shed INTEGER NOT NULL, light REAL,"
    "  cap INTEGER NOT NULL, finished INTEGER NOT NULL,"
    "  PRIMARY KEY (run, iteration, stem));"
    "CREATE TABLE commands ("
    "  run INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,"
    "  seq INTEGER NOT NULL,"
    "  iteration INTEGER NOT NULL,"
    "  command TEXT NOT NULL,"
    "  created TEXT NOT NULL,"
    "  PRIMARY KEY (run, seq));",
    /* 1 -> 2: conflicts (docs/store.md): NULL where the run does not report them */
    "ALTER TABLE stats ADD COLUMN pruned INTEGER;"
    "ALTER TABLE stats ADD COLUMN zones TEXT;"
    "ALTER TABLE stats ADD COLUMN clearance TEXT;",
    /* 2 -> 3: years (docs/store.md): the scenario's start year, NULL without one;
     * ages, NULL for species without years */
    "ALTER TABLE stats ADD COLUMN age INTEGER;"
    "ALTER TABLE stats ADD COLUMN crown_height REAL;"
    "ALTER TABLE runs ADD COLUMN start_year INTEGER;",
    /* 3 -> 4: sweeps (docs/store.md): each sweep's plan, and every swept run's place
     * in it, its position in the plan's product and its value on each axis */
    "CREATE TABLE sweeps ("
    "  name TEXT PRIMARY KEY,"
    "  plan TEXT NOT NULL);"
    "CREATE TABLE sweep_runs ("
    "  run INTEGER PRIMARY KEY REFERENCES runs(id) ON DELETE CASCADE,"
    "  sweep TEXT NOT NULL REFERENCES sweeps(name),"
    "  position INTEGER NOT NULL CHECK (position >= 0),"
    "  UNIQUE (sweep, position));"
    "CREATE TABLE run_axes ("
    "  run INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,"
    "  axis TEXT NOT NULL,"
    "  value TEXT NOT NULL,"
    "  PRIMARY KEY (run, axis));",
    /* 4 -> 5: foliage (docs/store.md): each stem's leaf area, NULL in older rows */
    "ALTER TABLE stats ADD COLUMN leaf_area REAL;",
    /* 5 -> 6: what the trees give (docs/store.md): each stem's crown area, wood and
     * carbon, each iteration's canopy cover; NULL in older rows and where a measure
     * does not apply */
    "ALTER TABLE stats ADD COLUMN crown_area REAL;"
    "ALTER TABLE stats ADD COLUMN wood_volume REAL;"
    "ALTER TABLE stats ADD COLUMN biomass REAL;"
    "ALTER TABLE stats ADD COLUMN biomass_model REAL;"
    "ALTER TABLE stats ADD COLUMN carbon REAL;"
    "ALTER TABLE stats ADD COLUMN co2 REAL;"
    "ALTER TABLE stats ADD COLUMN co2_sequestered REAL;"
    "ALTER TABLE iterations ADD COLUMN canopy_cover REAL;",
    /* 6 -> 7: stands (docs/store.md): each stem's alive, died and vigour, each
     * iteration's stand figures; NULL in older rows and in runs without stands */
    "ALTER TABLE stats ADD COLUMN alive INTEGER;"
    "ALTER TABLE stats ADD COLUMN died INTEGER;"
    "ALTER TABLE stats ADD COLUMN vigour REAL;"
    "ALTER TABLE iterations ADD COLUMN stand_area REAL;"
    "ALTER TABLE iterations ADD COLUMN stand_alive INTEGER;"
    "ALTER TABLE iterations ADD COLUMN stand_died INTEGER;"
    "ALTER TABLE iterations ADD COLUMN stems_per_ha REAL;"
    "ALTER TABLE iterations ADD COLUMN basal_area REAL;"
    "ALTER TABLE iterations ADD COLUMN qmd REAL;"
    "ALTER TABLE iterations ADD COLUMN dominant_height REAL;"
    "ALTER TABLE iterations ADD COLUMN sdi REAL;"
    "ALTER TABLE iterations ADD COLUMN cv_height REAL;"
    "ALTER TABLE iterations ADD COLUMN cv_dbh REAL;",
    /* 7 -> 8: the world hash's definition per run (docs/store.md, "The world hash"):
     * the runs stored before keep hash 1 */
    "ALTER TABLE runs ADD COLUMN hash_version INTEGER NOT NULL DEFAULT 1;",
};

static int migrate(store *st) {
  if (sqlite3_exec(st->db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK) {
    if ((sqlite3_errcode(st->db) & 0xff) == SQLITE_NOTADB) {
      store__fail(st, "not a sylva store (not an SQLite database)");
      return SERVER_EINPUT;
    }
    return store__fail(st, "cannot open the store");
  }
  bool ok1, ok2, ok3;
  int64_t app = pragma_int(st, "PRAGMA application_id", &ok1);
  int64_t version = pragma_int(st, "PRAGMA user_version", &ok2);
  int64_t objects = pragma_int(st, "SELECT count(*) FROM sqlite_schema", &ok3);
  if (!ok1 || !ok2 || !ok3) {
    store__rollback(st);
    store__fail(st, "not a sylva store (cannot read it as an SQLite database)");
    return SERVER_EINPUT;
  }
  if (app != STORE_APPLICATION_ID && (app != 0 || objects > 0)) {
    store__rollback(st);
    store__fail(st, "not a sylva store (an SQLite file of another program, application_id 0x%llx)",
         (unsigned long long)app);
    return SERVER_EINPUT;
  }
  if (version > STORE_SCHEMA_VERSION) {
    store__rollback(st);
    store__fail(st, "written by a newer sylva (schema %lld; this build knows up to %d)",
         (long long)version, STORE_SCHEMA_VERSION);
    return SERVER_EINPUT;
  }
  for (int64_t v = version; v < STORE_SCHEMA_VERSION; v++) {
    if (store__exec(st, migrations[v], "migrating the schema")) {
      store__rollback(st);
      return SERVER_EFAIL;
    }
  }
  char sql[96];
  snprintf(sql, sizeof sql, "PRAGMA application_id = %d; PRAGMA user_version = %d",
           STORE_APPLICATION_ID, STORE_SCHEMA_VERSION);
  if (store__exec(st, sql, "migrating the schema") || store__exec(st, "COMMIT", "migrating the schema")) {
    store__rollback(st);
    return SERVER_EFAIL;
  }
  return SERVER_OK;
}

int store_open(const char *path, bool create, store **out) {
  *out = NULL;
  store *st = calloc(1, sizeof *st);
  if (!st || !(st->path = strdup(path)) || pthread_mutex_init(&st->lock, NULL)) {
    if (st) free(st->path);
    free(st);
    snprintf(last_error, sizeof last_error, "%s: out of memory", path);
    return SERVER_EFAIL;
  }
  int flags = SQLITE_OPEN_READWRITE | (create ? SQLITE_OPEN_CREATE : 0);
  if (sqlite3_open_v2(path, &st->db, flags, NULL) != SQLITE_OK) {
    int rc = SERVER_EFAIL;
    snprintf(last_error, sizeof last_error, "%s: %s", path,
             st->db ? sqlite3_errmsg(st->db) : "cannot open");
    if (!create && st->db && sqlite3_errcode(st->db) == SQLITE_CANTOPEN) {
      snprintf(last_error, sizeof last_error, "%s: no such store (or it cannot be opened)", path);
      rc = SERVER_EINPUT;
    }
    store_close(st);
    return rc;
  }
  sqlite3_busy_timeout(st->db, 5000);
  sqlite3_extended_result_codes(st->db, 1);
  /* WAL with full syncs: a commit that returned survives a crash of the program
   * and of the machine; foreign keys keep runs and their rows together. */
  int rc = migrate(st);
  if (rc || store__exec(st, "PRAGMA journal_mode = WAL", "opening the store") ||
      store__exec(st, "PRAGMA synchronous = FULL", "opening the store") ||
      store__exec(st, "PRAGMA foreign_keys = ON", "opening the store")) {
        store_close(st);
    return rc == SERVER_EINPUT ? SERVER_EINPUT : SERVER_EFAIL;
  }
  *out = st;
  return SERVER_OK;
}

void store_set_threads(store *st, int threads) { st->threads = threads; }

void store_share_threads(store *st, sylva_threads *t) { st->shared = t; }

void store_close(store *st) {
  if (!st) return;
  sqlite3_close_v2(st->db);
  pthread_mutex_destroy(&st->lock);
  free(st->path);
  free(st);
}

/* ---- runs ---------------------------------------------------------------------- */

static void bind_real_or_null(sqlite3_stmt *q, int col, double v) {
  if (isnan(v))
    sqlite3_bind_null(q, col);
  else
    sqlite3_bind_double(q, col, v);
}

/* An integer, or NULL where it is negative (a null count or iteration). */
static void bind_int_or_null(sqlite3_stmt *q, int col, int64_t v) {
  if (v < 0)
    sqlite3_bind_null(q, col);
  else
    sqlite3_bind_int64(q, col, v);
}

/* The world's hash by the definition the run keeps (docs/store.md, "The world hash"). */
static int world_hash_unlocked(store *st, int64_t run, const sylva_world *w, uint64_t *hash) {
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db, "SELECT hash_version FROM runs WHERE id = ?", -1, &q, NULL) !=
      SQLITE_OK)
    return store__fail(st, "reading a run's hash version");
  sqlite3_bind_int64(q, 1, run);
  int rc = sqlite3_step(q);
  int64_t version = rc == SQLITE_ROW ? sqlite3_column_int64(q, 0) : 0;
  sqlite3_finalize(q);
  if (rc != SQLITE_ROW) return store__fail(st, "reading a run's hash version");
  if (version < 1 || version > SYLVA_WORLD_HASH_VERSION) {
    snprintf(last_error, sizeof last_error,
             "%s: run %lld keeps world hashes of version %lld, which this build does not know "
             "(it knows 1 to %d)", st->path, (long long)run, (long long)version,
             SYLVA_WORLD_HASH_VERSION);
    return SERVER_EINPUT;
  }
  *hash = sylva_world_hash_of(w, (int)version);
  return SERVER_OK;
}

/* Inserts an iteration record (and its snapshot) inside the caller's transaction. */
static int insert_iteration(store *st, int64_t run, const sylva_world *w, bool snapshot) {
  uint8_t *img = NULL;
  size_t size = 0;
  int it = sylva_world_iteration(w);
  uint64_t hash;
  if (world_hash_unlocked(st, run, w, &hash)) return SERVER_EFAIL;
  if (snapshot) {
    int rc = sylva_snapshot_save(w, &img, &size);
    if (rc) return store__fail(st, "snapshot of iteration %d: %s", it, sylva_strerror(rc));
  }
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db,
                         "INSERT INTO iterations (run, iteration, hash, nodes, snapshot,"
                         " canopy_cover, stand_area, stand_alive, stand_died, stems_per_ha,"
                         " basal_area, qmd, dominant_height, sdi, cv_height, cv_dbh)"
                         " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                         -1, &q, NULL) != SQLITE_OK) {
    free(img);
    return store__fail(st, "storing iteration %d", it);
  }
  sqlite3_bind_int64(q, 1, run);
  sqlite3_bind_int(q, 2, it);
  sqlite3_bind_int64(q, 3, (int64_t)hash);
  sqlite3_bind_int64(q, 4, (int64_t)sylva_world_node_count(w));
  /* the image carries its own checksum (sylva_snapshot_load verifies it) */
  if (img)
    sqlite3_bind_blob64(q, 5, img, size, SQLITE_STATIC);
  else
    sqlite3_bind_null(q, 5);
  sqlite3_bind_double(q, 6, sylva_world_canopy_cover(w));
  /* the stand's figures where the lines give them (docs/model.md, "Stands"), else NULL */
  if (sylva_encode_stand(w)) {
    sylva_stand_stats s;
    sylva_world_stand(w, &s);
    const double fig[] = {s.stems_per_ha, s.basal_area,      s.qmd,      s.dominant_height,
                          s.sdi,          s.cv_height,       s.cv_dbh};
    bind_real_or_null(q, 7, s.area);
    sqlite3_bind_int(q, 8, s.alive);
    sqlite3_bind_int(q, 9, s.died);
    for (int i = 0; i < 7; i++) bind_real_or_null(q, 10 + i, fig[i]);
  }
  int rc = sqlite3_step(q);
  sqlite3_finalize(q);
  free(img);
  if (rc != SQLITE_DONE) return store__fail(st, "storing iteration %d", it);
  return SERVER_OK;
}

static int create_run_unlocked(store *st, const char *name, const char *scenario_json,
                               uint64_t seed, int iterations, int snapshot_every,
                               const sylva_world *w, int64_t *run) {
  char now[32];
  store__utc_now(now);
  char what[320];
  snprintf(what, sizeof what, "creating run \"%s\"", name);
  if (store__exec(st, "BEGIN IMMEDIATE", what)) return SERVER_EFAIL;
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db,
                         "INSERT INTO runs (name, scenario, seed, iterations, snapshot_every,"
                         " status, reason, created, updated, start_year, hash_version)"
                         " VALUES (?1, ?2, ?3, ?4, ?5, 'running', NULL, ?6, ?7,"
                         " json_extract(CASE WHEN json_valid(?2) THEN ?2 END, '$.start_year'), ?8)",
                         -1, &q, NULL) != SQLITE_OK) {
    store__rollback(st);
    return store__fail(st, "creating run \"%s\"", name);
  }
  sqlite3_bind_text(q, 1, name, -1, SQLITE_STATIC);
  sqlite3_bind_text(q, 2, scenario_json, -1, SQLITE_STATIC);
  sqlite3_bind_int64(q, 3, (int64_t)seed);
  sqlite3_bind_int(q, 4, iterations);
  sqlite3_bind_int(q, 5, snapshot_every);
  sqlite3_bind_text(q, 6, now, -1, SQLITE_STATIC);
  sqlite3_bind_text(q, 7, now, -1, SQLITE_STATIC);
  sqlite3_bind_int(q, 8, SYLVA_WORLD_HASH_VERSION);
  int rc = sqlite3_step(q);
  sqlite3_finalize(q);
  if (rc == SQLITE_CONSTRAINT_UNIQUE) {
    store__rollback(st);
    snprintf(last_error, sizeof last_error,
             "%s: a run named \"%s\" exists already (continue it with 'sylva resume', or "
             "choose another --name)", st->path, name);
    return SERVER_EINPUT;
  }
  if (rc != SQLITE_DONE) {
    store__fail(st, "creating run \"%s\"", name);
    store__rollback(st);
    return SERVER_EFAIL;
  }
  *run = sqlite3_last_insert_rowid(st->db);
  if (insert_iteration(st, *run, w, true)) {
    store__rollback(st);
    return SERVER_EFAIL;
  }
  if (store__exec(st, "COMMIT", what)) {
    store__rollback(st);
    return SERVER_EFAIL;
  }
  return SERVER_OK;
}

static char *dup_column(sqlite3_stmt *q, int col) {
  const unsigned char *t = sqlite3_column_text(q, col);
  return strdup(t ? (const char *)t : "");
}

static void copy_column(sqlite3_stmt *q, int col, char *out, size_t n) {
  const unsigned char *t = sqlite3_column_text(q, col);
  snprintf(out, n, "%s", t ? (const char *)t : "");
}

/* Whether the scenario of run r has a species that counts in years (the canonical
 * JSON writes "years" only when it is 1). */
#define SCENARIO_YEARS                                                                      \
  "CASE WHEN json_valid(r.scenario) THEN EXISTS (SELECT 1 FROM json_each(r.scenario,"       \
  " '$.species') sp WHERE json_extract(sp.value, '$.years') = 1) ELSE 0 END"

/* Whether run r stored an iteration with the stand's figures (store_run_stand). */
#define RUN_STAND                                                                           \
  "EXISTS (SELECT 1 FROM iterations i WHERE i.run = r.id AND i.stand_alive IS NOT NULL)"

#define RUN_COLUMNS                                                                         \
  "SELECT r.id, r.name, r.scenario, r.seed, r.iterations, r.snapshot_every, r.status,"      \
  " r.reason, r.created, r.updated,"                                                        \
  " (SELECT max(iteration) FROM iterations i WHERE i.run = r.id),"                          \
  " (SELECT nodes FROM iterations i WHERE i.run = r.id ORDER BY iteration DESC LIMIT 1),"   \
  " (SELECT count(*) FROM stats s WHERE s.run = r.id AND s.iteration ="                     \
  "   (SELECT max(iteration) FROM stats t WHERE t.run = r.id)),"                            \
  " (SELECT count(s.zones) FROM stats s WHERE s.run = r.id AND s.iteration ="               \
  "   (SELECT max(iteration) FROM stats t WHERE t.run = r.id)),"                            \
  " (SELECT total(json_extract(z.value, '$.nodes')) FROM stats s, json_each(s.zones) z"     \
  "   WHERE s.run = r.id AND s.iteration = (SELECT max(iteration) FROM stats t"             \
  "   WHERE t.run = r.id)),"                                                                \
  " (SELECT count(*) FROM stats s, json_each(s.zones) z WHERE s.run = r.id AND"             \
  "   s.iteration = (SELECT max(iteration) FROM stats t WHERE t.run = r.id)),"              \
  " r.start_year, " SCENARIO_YEARS ", " RUN_STAND                                         \
  " FROM runs r"

static int read_run(sqlite3_stmt *q, store_run *r) {
  memset(r, 0, sizeof *r);
  r->id = sqlite3_column_int64(q, 0);
  r->name = dup_column(q, 1);
  r->scenario = dup_column(q, 2);
  r->seed = (uint64_t)sqlite3_column_int64(q, 3);
  r->iterations = sqlite3_column_int(q, 4);
  r->snapshot_every = sqlite3_column_int(q, 5);
  /* the schema's CHECK admits only the four names; anything else reads as failed */
  char status[16];
  copy_column(q, 6, status, sizeof status);
  if (sylva_run_status_parse(status, &r->status)) r->status = SYLVA_RUN_FAILED;
  copy_column(q, 7, r->reason, sizeof r->reason);
  copy_column(q, 8, r->created, sizeof r->created);
  copy_column(q, 9, r->updated, sizeof r->updated);
  r->last_iteration = sqlite3_column_int(q, 10);
  r->nodes = sqlite3_column_int64(q, 11);
  r->stems = sqlite3_column_int(q, 12);
  r->reports_conflicts = sqlite3_column_int(q, 13) > 0;
  r->zone_nodes = (int64_t)sqlite3_column_double(q, 14);
  r->zone_pairs = sqlite3_column_int64(q, 15);
  r->start_year = sqlite3_column_int(q, 16);
  r->years = sqlite3_column_int(q, 17) != 0;
  r->stand = sqlite3_column_int(q, 18) != 0;
  return r->name && r->scenario ? 0 : SERVER_EFAIL;
}

void store_run_free(store_run *r) {
  if (!r) return;
  free(r->name);
  free(r->scenario);
  r->name = r->scenario = NULL;
}

void store_runs_free(store_run *runs, size_t count) {
  for (size_t i = 0; i < count; i++) store_run_free(&runs[i]);
  free(runs);
}

static int find_run_unlocked(store *st, const char *name, store_run *out, bool *found) {
  *found = false;
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db, RUN_COLUMNS " WHERE r.name = ?", -1, &q, NULL) != SQLITE_OK)
    return store__fail(st, "looking up run \"%s\"", name);
  sqlite3_bind_text(q, 1, name, -1, SQLITE_STATIC);
  int rc = sqlite3_step(q);
  if (rc == SQLITE_ROW) {
    if (read_run(q, out)) {
      store_run_free(out);
      sqlite3_finalize(q);
      snprintf(last_error, sizeof last_error, "%s: out of memory", st->path);
      return SERVER_EFAIL;
    }
    *found = true;
  }
  sqlite3_finalize(q);
  if (rc != SQLITE_ROW && rc != SQLITE_DONE) return store__fail(st, "looking up run \"%s\"", name);
  return SERVER_OK;
}

static int list_runs_unlocked(store *st, store_run **out, size_t *count) {
  *out = NULL;
  *count = 0;
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db, RUN_COLUMNS " ORDER BY r.id", -1, &q, NULL) != SQLITE_OK)
    return store__fail(st, "listing runs");
  size_t n = 0, cap = 0;
  store_run *runs = NULL;
  int rc;
  while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
    if (n == cap) {
      cap = cap ? 2 * cap : 8;
      store_run *p = realloc(runs, cap * sizeof *p);
      if (!p) break;
      runs = p;
    }
    if (read_run(q, &runs[n])) {
      store_run_free(&runs[n]);
      break;
    }
    n++;
  }
  sqlite3_finalize(q);
  if (rc != SQLITE_DONE) {
    store_runs_free(runs, n);
    if (rc == SQLITE_ROW) {
      snprintf(last_error, sizeof last_error, "%s: out of memory", st->path);
      return SERVER_EFAIL;
    }
    return store__fail(st, "listing runs");
  }
  *out = runs;
  *count = n;
  return SERVER_OK;
}

/* ---- iterations ---------------------------------------------------------------- */

static int run_calendar_unlocked(store *st, int64_t run, int *start_year, bool *years) {
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db,
                         "SELECT r.start_year, " SCENARIO_YEARS " FROM runs r WHERE r.id = ?", -1,
                         &q, NULL) != SQLITE_OK)
    return store__fail(st, "reading a run's start year");
  sqlite3_bind_int64(q, 1, run);
  int rc = sqlite3_step(q);
  if (rc == SQLITE_ROW) {
    *start_year = sqlite3_column_int(q, 0);
    if (years) *years = sqlite3_column_int(q, 1) != 0;
  }
  sqlite3_finalize(q);
  return rc == SQLITE_ROW ? SERVER_OK : store__fail(st, "reading a run's start year");
}

static int run_stand_unlocked(store *st, int64_t run, bool *stand) {
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db, "SELECT " RUN_STAND " FROM runs r WHERE r.id = ?", -1, &q,
                         NULL) != SQLITE_OK)
    return store__fail(st, "reading whether a run has stands");
  sqlite3_bind_int64(q, 1, run);
  int rc = sqlite3_step(q);
  if (rc == SQLITE_ROW) *stand = sqlite3_column_int(q, 0) != 0;
  sqlite3_finalize(q);
  return rc == SQLITE_ROW ? SERVER_OK : store__fail(st, "reading whether a run has stands");
}

static int save_iteration_unlocked(store *st, int64_t run, const sylva_world *w,
                                   const sylva_journal *j, bool snapshot) {
  int it = j->iteration;
  char now[32], what[64];
  store__utc_now(now);
  snprintf(what, sizeof what, "storing iteration %d", it);
  /* zone entries are dated as the run's lines date them: in years from its start year */
  int start_year = 0;
  if (sylva_world_reports_conflicts(w) && run_calendar_unlocked(st, run, &start_year, NULL))
    return SERVER_EFAIL;
  if (store__exec(st, "BEGIN IMMEDIATE", what)) return SERVER_EFAIL;
  if (insert_iteration(st, run, w, snapshot)) {
    store__rollback(st);
    return SERVER_EFAIL;
  }
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db,
                         "INSERT INTO stats (run, iteration, stem, plant, plant_stem, height, dbh,"
                         " crown_width, crown_base, nodes, shed, light, cap, finished, pruned,"
                         " zones, clearance, age, crown_height, leaf_area, crown_area,"
                         " wood_volume, biomass, biomass_model, carbon, co2, co2_sequestered,"
                         " alive, died, vigour)"
                         " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?,"
                         " ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                         -1, &q, NULL) != SQLITE_OK) {
    store__fail(st, "storing iteration %d", it);
    store__rollback(st);
    return SERVER_EFAIL;
  }
  bool stand = sylva_encode_stand(w);
  for (size_t k = 0; k < j->stem_count; k++) {
    const sylva_stem_stats *s = &j->stats[k];
    sqlite3_reset(q);
    sqlite3_bind_int64(q, 1, run);
    sqlite3_bind_int(q, 2, it);
    sqlite3_bind_int(q, 3, (int)k);
    sqlite3_bind_text(q, 4, sylva_world_plant_label(w, s->plant), -1, SQLITE_STATIC);
    sqlite3_bind_int(q, 5, s->stem);
    bind_real_or_null(q, 6, s->height);
    bind_real_or_null(q, 7, s->dbh);
    bind_real_or_null(q, 8, s->crown_width);
    bind_real_or_null(q, 9, s->crown_base);
    sqlite3_bind_int64(q, 10, s->nodes);
    sqlite3_bind_int64(q, 11, s->shed);
    bind_real_or_null(q, 12, s->light);
    sqlite3_bind_int(q, 13, s->cap);
    sqlite3_bind_int(q, 14, s->finished);
    char *zones = NULL, *clearance = NULL;
    bool ok = true;
    if (s->age >= 0)
      sqlite3_bind_int(q, 18, s->age);
    else
      sqlite3_bind_null(q, 18);
    bind_real_or_null(q, 19, s->crown_height);
    bind_real_or_null(q, 20, s->leaf_area);
    bind_real_or_null(q, 21, s->crown_area);
    bind_real_or_null(q, 22, s->wood_volume);
    bind_real_or_null(q, 23, s->biomass);
    bind_real_or_null(q, 24, s->biomass_model);
    bind_real_or_null(q, 25, s->carbon);
    bind_real_or_null(q, 26, s->co2);
    bind_real_or_null(q, 27, s->co2_sequestered);
    if (stand) { /* as the lines give them; NULL where they do not (docs/store.md) */
      sqlite3_bind_int(q, 28, s->alive);
      bind_int_or_null(q, 29, s->died);
      bind_real_or_null(q, 30, s->vigour);
    } else {
      for (int col = 28; col <= 30; col++) sqlite3_bind_null(q, col);
    }
    if (sylva_world_reports_conflicts(w)) {
      zones = sylva_encode_stem_conflicts(w, (int)k, false, start_year);
      clearance = sylva_encode_stem_conflicts(w, (int)k, true, start_year);
      ok = zones && clearance;
      sqlite3_bind_int64(q, 15, s->pruned);
      sqlite3_bind_text(q, 16, zones, -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(q, 17, clearance, -1, SQLITE_TRANSIENT);
    } else {
      for (int col = 15; col <= 17; col++) sqlite3_bind_null(q, col);
    }
    free(zones);
    free(clearance);
    if (!ok || sqlite3_step(q) != SQLITE_DONE) {
      store__fail(st, "storing iteration %d", it);
      sqlite3_finalize(q);
      store__rollback(st);
      return SERVER_EFAIL;
    }
  }
  sqlite3_finalize(q);
  if (sqlite3_prepare_v2(st->db, "UPDATE runs SET updated = ? WHERE id = ?", -1, &q, NULL) !=
      SQLITE_OK) {
    store__fail(st, "storing iteration %d", it);
    store__rollback(st);
    return SERVER_EFAIL;
  }
  sqlite3_bind_text(q, 1, now, -1, SQLITE_STATIC);
  sqlite3_bind_int64(q, 2, run);
  int rc = sqlite3_step(q);
  sqlite3_finalize(q);
  if (rc != SQLITE_DONE || store__exec(st, "COMMIT", what)) {
    if (rc != SQLITE_DONE) store__fail(st, "storing iteration %d", it);
    store__rollback(st);
    return SERVER_EFAIL;
  }
  return SERVER_OK;
}

bool store_step_snapshot(const sylva_world *w, const sylva_journal *j, int every, int limit) {
  bool last = sylva_world_finished(w) || j->iteration >= limit;
  return last || j->iteration % every == 0;
}

int store_save_step(store *st, int64_t run, const sylva_world *w, const sylva_journal *j,
                    int every, int limit) {
  return store_save_iteration(st, run, w, j, store_step_snapshot(w, j, every, limit));
}

static int save_snapshot_unlocked(store *st, int64_t run, const sylva_world *w) {
  int it = sylva_world_iteration(w);
  uint8_t *img = NULL;
  size_t size = 0;
  int rc = sylva_snapshot_save(w, &img, &size);
  if (rc) return store__fail(st, "snapshot of iteration %d: %s", it, sylva_strerror(rc));
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db, "UPDATE iterations SET snapshot = ? WHERE run = ? AND iteration = ?",
                         -1, &q, NULL) != SQLITE_OK) {
    free(img);
    return store__fail(st, "storing the snapshot of iteration %d", it);
  }
  sqlite3_bind_blob64(q, 1, img, size, SQLITE_STATIC);
  sqlite3_bind_int64(q, 2, run);
  sqlite3_bind_int(q, 3, it);
  rc = sqlite3_step(q);
  bool changed = rc == SQLITE_DONE && sqlite3_changes(st->db) == 1;
  sqlite3_finalize(q);
  free(img);
  if (rc != SQLITE_DONE) return store__fail(st, "storing the snapshot of iteration %d", it);
  if (!changed) return store__fail(st, "storing the snapshot of iteration %d: no such iteration", it);
  return SERVER_OK;
}

int store_save_snapshot(store *st, int64_t run, const sylva_world *w) {
  LOCKED(st, save_snapshot_unlocked(st, run, w));
}

static int set_status_unlocked(store *st, int64_t run, sylva_run_status status, const char *reason,
                               int iterations) {
  char now[32];
  store__utc_now(now);
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db,
                         "UPDATE runs SET status = ?, reason = ?, updated = ?,"
                         " iterations = CASE WHEN ? > 0 THEN ? ELSE iterations END WHERE id = ?",
                         -1, &q, NULL) != SQLITE_OK)
    return store__fail(st, "setting the status of a run");
  sqlite3_bind_text(q, 1, sylva_run_status_name(status), -1, SQLITE_STATIC);
  if (reason)
    sqlite3_bind_text(q, 2, reason, -1, SQLITE_STATIC);
  else
    sqlite3_bind_null(q, 2);
  sqlite3_bind_text(q, 3, now, -1, SQLITE_STATIC);
  sqlite3_bind_int(q, 4, iterations);
  sqlite3_bind_int(q, 5, iterations);
  sqlite3_bind_int64(q, 6, run);
  int rc = sqlite3_step(q);
  sqlite3_finalize(q);
  return rc == SQLITE_DONE ? 0 : store__fail(st, "setting the status of a run");
}

static int iteration_hash_unlocked(store *st, int64_t run, int iteration, uint64_t *hash,
                                   bool *found) {
  *found = false;
  sqlite3_stmt *q;
  if (prepare_run(st, "SELECT hash FROM iterations WHERE run = ? AND iteration = ?",
                  run, iteration, &q))
    return store__fail(st, "reading iteration %d", iteration);
  int rc = sqlite3_step(q);
  if (rc == SQLITE_ROW) {
    *hash = (uint64_t)sqlite3_column_int64(q, 0);
    *found = true;
  }
  sqlite3_finalize(q);
  return rc == SQLITE_ROW || rc == SQLITE_DONE ? 0 : store__fail(st, "reading iteration %d", iteration);
}

static int load_world_unlocked(store *st, int64_t run, int at, void (*warn)(const char *msg),
                               sylva_world **world_out, int *from) {
  *world_out = NULL;
  sqlite3_stmt *q;
  if (prepare_run(st, "SELECT iteration, snapshot, hash FROM iterations"
                      " WHERE run = ? AND iteration <= ? AND snapshot IS NOT NULL"
                      " ORDER BY iteration DESC",
                  run, at, &q))
    return store__fail(st, "reading snapshots");
  int rc;
  while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
    int it = sqlite3_column_int(q, 0);
    const uint8_t *img = sqlite3_column_blob(q, 1);
    size_t size = (size_t)sqlite3_column_bytes(q, 1);
    const char *problem = NULL;
    int load = 0;
    uint64_t hash = 0;
    if (!img)
      problem = "empty";
    else if ((load = sylva_snapshot_load(img, size, world_out)) != 0)
      problem = sylva_strerror(load);
    else if (sylva_world_iteration(*world_out) != it)
      problem = "it holds another iteration";
    else {
      /* one thread if the system gives no more: the same world */
      if (st->shared)
        sylva_world_share_threads(*world_out, st->shared);
      else if (st->threads > 1)
        sylva_world_set_threads(*world_out, st->threads);
      if (world_hash_unlocked(st, run, *world_out, &hash)) {
        sylva_world_destroy(*world_out);
        *world_out = NULL;
        sqlite3_finalize(q);
        return SERVER_EFAIL;
      }
      if (hash != (uint64_t)sqlite3_column_int64(q, 2))
        /* a valid image, but not of the world stored for this iteration */
        problem = "it holds another world than the one stored";
    }
    if (problem && *world_out) {
      sylva_world_destroy(*world_out);
      *world_out = NULL;
    }
    if (!problem) {
      *from = it;
      sqlite3_finalize(q);
      return 0;
    }
    if (load == SYLVA_ENOMEM) {
      sqlite3_finalize(q);
      snprintf(last_error, sizeof last_error, "%s: out of memory restoring iteration %d", st->path,
               it);
      return SERVER_EFAIL;
    }
    if (warn) {
      char msg[512];
      snprintf(msg, sizeof msg, "%s: the snapshot of iteration %d is corrupt (%s); using an "
               "earlier one", st->path, it, problem);
      warn(msg);
    }
  }
  sqlite3_finalize(q);
  if (rc != SQLITE_DONE) return store__fail(st, "reading snapshots");
  snprintf(last_error, sizeof last_error, "%s: no good snapshot at or before iteration %d",
           st->path, at);
  return SERVER_EFAIL;
}

static int log_command_unlocked(store *st, int64_t run, int iteration, const char *command_json,
                                int64_t *seq);

/* Replays one logged record on *w. */
static int replay_record(const char *json, sylva_world **w, char *why, size_t whylen) {
  edit e;
  int rc = command_log_decode(json, &e, why, whylen);
  sylva_world *edited = NULL;
  if (rc == SERVER_OK && edit_apply(*w, &e, &edited, why, whylen) != SYLVA_OK) rc = SERVER_EINPUT;
  edit_free(&e);
  if (rc == SERVER_OK) {
    sylva_world_destroy(*w);
    *w = edited;
  }
  return rc;
}

/* Replays the commands logged at iteration `it` on *w. */
static int replay_commands(store *st, int64_t run, int it, sylva_world **w) {
  sqlite3_stmt *q;
  if (prepare_run(st, "SELECT seq, command FROM commands WHERE run = ? AND iteration = ?"
                      " ORDER BY seq",
                  run, it, &q))
    return store__fail(st, "reading the command log");
  int rc;
  while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
    const char *json = (const char *)sqlite3_column_text(q, 1);
    char why[400] = "not text";
    if (!json || replay_record(json, w, why, sizeof why)) {
      snprintf(last_error, sizeof last_error, "%s: replaying command %lld after iteration %d: %s",
               st->path, (long long)sqlite3_column_int64(q, 0), it, why);
      sqlite3_finalize(q);
      return SERVER_EFAIL;
    }
  }
  sqlite3_finalize(q);
  return rc == SQLITE_DONE ? SERVER_OK : store__fail(st, "reading the command log");
}

static int apply_edit_unlocked(store *st, int64_t run, const sylva_world *w, const edit *e) {
  int it = sylva_world_iteration(w);
  char what[64];
  snprintf(what, sizeof what, "storing an edit after iteration %d", it);
  char *record = command_log_encode(e);
  if (!record) return store__fail(st, "%s: out of memory", what);
  uint8_t *img;
  size_t size;
  int rc = sylva_snapshot_save(w, &img, &size);
  if (rc || store__exec(st, "BEGIN IMMEDIATE", what)) {
    free(record);
    free(img);
    return rc ? store__fail(st, "%s: %s", what, sylva_strerror(rc)) : SERVER_EFAIL;
  }
  sqlite3_stmt *q;
  uint64_t hash;
  if (world_hash_unlocked(st, run, w, &hash)) {
    store__rollback(st);
    free(record);
    free(img);
    return SERVER_EFAIL;
  }
  rc = sqlite3_prepare_v2(st->db,
                          "UPDATE iterations SET snapshot = ?, hash = ?, nodes = ?"
                          " WHERE run = ? AND iteration = ?",
                          -1, &q, NULL);
  if (rc == SQLITE_OK) {
    sqlite3_bind_blob64(q, 1, img, size, SQLITE_STATIC);
    sqlite3_bind_int64(q, 2, (int64_t)hash);
    sqlite3_bind_int64(q, 3, (int64_t)sylva_world_node_count(w));
    sqlite3_bind_int64(q, 4, run);
    sqlite3_bind_int(q, 5, it);
    rc = sqlite3_step(q);
    sqlite3_finalize(q);
  }
  free(img);
  if (rc != SQLITE_DONE || sqlite3_changes(st->db) != 1 ||
      log_command_unlocked(st, run, it, record, NULL) || store__exec(st, "COMMIT", what)) {
    if (rc != SQLITE_DONE) store__fail(st, "%s", what);
    store__rollback(st);
    free(record);
    return SERVER_EFAIL;
  }
  free(record);
  return SERVER_OK;
}

int store_world_at(store *st, int64_t run, int at, void (*warn)(const char *msg),
                   sylva_world **world_out) {
  sylva_world *w;
  int from;
  *world_out = NULL;
  if (store_load_world(st, run, at, warn, &w, &from)) return SERVER_EFAIL;
  while (sylva_world_iteration(w) < at) {
    int status = sylva_world_step(w, NULL);
    int it = sylva_world_iteration(w);
    uint64_t hash, mine = 0;
    bool found = false;
    int failed = 0;
    if (status == SYLVA_OK) {
      pthread_mutex_lock(&st->lock);
      failed = replay_commands(st, run, it, &w);
      pthread_mutex_unlock(&st->lock);
    }
    if (status == SYLVA_OK &&
        (failed || store_iteration_hash(st, run, it, &hash, &found) ||
         (found && store_world_hash(st, run, w, &mine)))) {
      sylva_world_destroy(w);
      return SERVER_EFAIL;
    }
    if (status != SYLVA_OK || (found && hash != mine)) {
      snprintf(last_error, sizeof last_error,
               "%s: regrowing iteration %d from the snapshot of %d %s", st->path, it, from,
               status != SYLVA_OK ? sylva_strerror(status)
                                  : "gives another world than the one stored");
      sylva_world_destroy(w);
      return SERVER_EFAIL;
    }
  }
  *world_out = w;
  return SERVER_OK;
}

static int run_scenario_unlocked(store *st, int64_t run, char **json) {
  *json = NULL;
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db, "SELECT scenario FROM runs WHERE id = ?", -1, &q, NULL) !=
      SQLITE_OK)
    return store__fail(st, "reading a run's scenario");
  sqlite3_bind_int64(q, 1, run);
  int rc = sqlite3_step(q);
  if (rc == SQLITE_ROW) *json = dup_column(q, 0);
  sqlite3_finalize(q);
  if (rc != SQLITE_ROW) return store__fail(st, "reading a run's scenario");
  if (!*json) {
    snprintf(last_error, sizeof last_error, "%s: out of memory", st->path);
    return SERVER_EFAIL;
  }
  return SERVER_OK;
}

static double column_real(sqlite3_stmt *q, int col) {
  return sqlite3_column_type(q, col) == SQLITE_NULL ? NAN : sqlite3_column_double(q, col);
}

static int column_int_or(sqlite3_stmt *q, int col, int null) {
  return sqlite3_column_type(q, col) == SQLITE_NULL ? null : sqlite3_column_int(q, col);
}

static int each_stats_unlocked(store *st, int64_t run, int to,
                               int (*fn)(const store_stats_row *row, void *ctx), void *ctx) {
  sqlite3_stmt *q;
  if (prepare_run(st, "SELECT s.iteration, stem, plant, plant_stem, height, dbh, crown_width,"
                      " crown_base, s.nodes, shed, light, cap, finished, pruned, zones, clearance,"
                      " age, crown_height, leaf_area, crown_area, wood_volume, biomass,"
                      " biomass_model, carbon, co2, co2_sequestered, i.canopy_cover,"
                      " alive, died, vigour, stand_area, stand_alive, stand_died, stems_per_ha,"
                      " basal_area, qmd, dominant_height, sdi, cv_height, cv_dbh"
                      " FROM stats s LEFT JOIN iterations i"
                      " ON i.run = s.run AND i.iteration = s.iteration"
                      " WHERE s.run = ? AND s.iteration <= ? ORDER BY s.iteration, stem",
                  run, to, &q))
    return store__fail(st, "reading stats");
  int rc;
  while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
    store_stats_row r = {
        .iteration = sqlite3_column_int(q, 0),
        .stem = sqlite3_column_int(q, 1),
        .plant = (const char *)sqlite3_column_text(q, 2),
        .plant_stem = sqlite3_column_int(q, 3),
        .height = column_real(q, 4),
        .dbh = column_real(q, 5),
        .crown_width = column_real(q, 6),
        .crown_base = column_real(q, 7),
        .nodes = sqlite3_column_int64(q, 8),
        .shed = sqlite3_column_int64(q, 9),
        .light = column_real(q, 10),
        .cap = sqlite3_column_int(q, 11),
        .finished = sqlite3_column_int(q, 12) != 0,
        .pruned = sqlite3_column_type(q, 13) == SQLITE_NULL ? -1 : sqlite3_column_int64(q, 13),
        .zones = (const char *)sqlite3_column_text(q, 14),
        .clearance = (const char *)sqlite3_column_text(q, 15),
        .age = column_int_or(q, 16, -1),
        .crown_height = column_real(q, 17),
        .leaf_area = column_real(q, 18),
        .crown_area = column_real(q, 19),
        .wood_volume = column_real(q, 20),
        .biomass = column_real(q, 21),
        .biomass_model = column_real(q, 22),
        .carbon = column_real(q, 23),
        .co2 = column_real(q, 24),
        .co2_sequestered = column_real(q, 25),
        .canopy_cover = column_real(q, 26),
        .alive = column_int_or(q, 27, -1),
        .died = column_int_or(q, 28, -1),
        .vigour = column_real(q, 29),
        .stand = {.area = column_real(q, 30),
                  .alive = column_int_or(q, 31, -1),
                  .died = column_int_or(q, 32, -1),
                  .stems_per_ha = column_real(q, 33),
                  .basal_area = column_real(q, 34),
                  .qmd = column_real(q, 35),
                  .dominant_height = column_real(q, 36),
                  .sdi = column_real(q, 37),
                  .cv_height = column_real(q, 38),
                  .cv_dbh = column_real(q, 39)},
    };
    if (!r.plant) r.plant = "";
    if (fn(&r, ctx)) {
      sqlite3_finalize(q);
      snprintf(last_error, sizeof last_error, "%s: reading stats: stopped", st->path);
      return SERVER_EFAIL;
    }
  }
  sqlite3_finalize(q);
  return rc == SQLITE_DONE ? 0 : store__fail(st, "reading stats");
}

static int each_age_unlocked(store *st,
                             int (*fn)(int64_t run, const char *plant, int age, void *ctx),
                             void *ctx) {
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db,
                         "SELECT r.id, s.plant, s.age FROM runs r JOIN stats s ON s.run = r.id AND"
                         " s.iteration = (SELECT max(iteration) FROM stats t WHERE t.run = r.id)"
                         " WHERE s.plant_stem = 0 AND s.age IS NOT NULL ORDER BY r.id, s.stem",
                         -1, &q, NULL) != SQLITE_OK)
    return store__fail(st, "reading ages");
  int rc;
  while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
    const char *plant = (const char *)sqlite3_column_text(q, 1);
    if (fn(sqlite3_column_int64(q, 0), plant ? plant : "", sqlite3_column_int(q, 2), ctx)) {
      sqlite3_finalize(q);
      snprintf(last_error, sizeof last_error, "%s: reading ages: stopped", st->path);
      return SERVER_EFAIL;
    }
  }
  sqlite3_finalize(q);
  return rc == SQLITE_DONE ? 0 : store__fail(st, "reading ages");
}

/* ---- commands ------------------------------------------------------------------ */

static int log_command_unlocked(store *st, int64_t run, int iteration, const char *command_json,
                                int64_t *seq) {
  char now[32];
  store__utc_now(now);
  sqlite3_stmt *q;
  if (prepare_run(st, "INSERT INTO commands (run, seq, iteration, command, created)"
                      " VALUES (?1, (SELECT coalesce(max(seq), 0) + 1 FROM commands"
                      " WHERE run = ?1), ?2, ?3, ?4) RETURNING seq",
                  run, iteration, &q))
    return store__fail(st, "logging a command");
  sqlite3_bind_text(q, 3, command_json, -1, SQLITE_STATIC);
  sqlite3_bind_text(q, 4, now, -1, SQLITE_STATIC);
  int rc = sqlite3_step(q);
  if (rc == SQLITE_ROW && seq) *seq = sqlite3_column_int64(q, 0);
  if (rc == SQLITE_ROW) rc = sqlite3_step(q);
  sqlite3_finalize(q);
  return rc == SQLITE_DONE ? 0 : store__fail(st, "logging a command");
}

static int command_count_unlocked(store *st, int64_t run, int64_t *count) {
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db, "SELECT count(*) FROM commands WHERE run = ?", -1, &q, NULL) !=
      SQLITE_OK)
    return store__fail(st, "counting commands");
  sqlite3_bind_int64(q, 1, run);
  int rc = sqlite3_step(q);
  if (rc == SQLITE_ROW) *count = sqlite3_column_int64(q, 0);
  sqlite3_finalize(q);
  return rc == SQLITE_ROW ? 0 : store__fail(st, "counting commands");
}

/* ---- the entry points: one caller at a time (LOCKED, store_impl.h) ------------------- */

int store_create_run(store *st, const char *name, const char *scenario_json, uint64_t seed,
                     int iterations, int snapshot_every, const sylva_world *w, int64_t *run) {
  LOCKED(st, create_run_unlocked(st, name, scenario_json, seed, iterations, snapshot_every, w,
                                 run));
}

int store_find_run(store *st, const char *name, store_run *out, bool *found) {
  LOCKED(st, find_run_unlocked(st, name, out, found));
}

int store_list_runs(store *st, store_run **out, size_t *count) {
  LOCKED(st, list_runs_unlocked(st, out, count));
}

int store_world_hash(store *st, int64_t run, const sylva_world *w, uint64_t *hash) {
  LOCKED(st, world_hash_unlocked(st, run, w, hash));
}

int store_save_iteration(store *st, int64_t run, const sylva_world *w, const sylva_journal *j,
                         bool snapshot) {
  LOCKED(st, save_iteration_unlocked(st, run, w, j, snapshot));
}

int store_set_status(store *st, int64_t run, sylva_run_status status, const char *reason,
                     int iterations) {
  LOCKED(st, set_status_unlocked(st, run, status, reason, iterations));
}

int store_iteration_hash(store *st, int64_t run, int iteration, uint64_t *hash, bool *found) {
  LOCKED(st, iteration_hash_unlocked(st, run, iteration, hash, found));
}

int store_load_world(store *st, int64_t run, int at, void (*warn)(const char *msg),
                     sylva_world **world_out, int *from) {
  LOCKED(st, load_world_unlocked(st, run, at, warn, world_out, from));
}

int store_apply_edit(store *st, int64_t run, const sylva_world *w, const edit *e) {
  LOCKED(st, apply_edit_unlocked(st, run, w, e));
}

int store_run_scenario(store *st, int64_t run, char **json) {
  LOCKED(st, run_scenario_unlocked(st, run, json));
}

int store_run_calendar(store *st, int64_t run, int *start_year, bool *years) {
  LOCKED(st, run_calendar_unlocked(st, run, start_year, years));
}

int store_run_stand(store *st, int64_t run, bool *stand) {
  LOCKED(st, run_stand_unlocked(st, run, stand));
}

int store_each_age(store *st, int (*fn)(int64_t run, const char *plant, int age, void *ctx),
                   void *ctx) {
  LOCKED(st, each_age_unlocked(st, fn, ctx));
}

int store_each_stats(store *st, int64_t run, int to,
                     int (*fn)(const store_stats_row *row, void *ctx), void *ctx) {
  LOCKED(st, each_stats_unlocked(st, run, to, fn, ctx));
}

int store_log_command(store *st, int64_t run, int iteration, const char *command_json,
                      int64_t *seq) {
  LOCKED(st, log_command_unlocked(st, run, iteration, command_json, seq));
}

int store_command_count(store *st, int64_t run, int64_t *count) {
  LOCKED(st, command_count_unlocked(st, run, count));
}
