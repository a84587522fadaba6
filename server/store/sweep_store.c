/* The store's sweeps: each sweep's plan, every swept run's place in it, and merging
 * the stores of a sweep's tasks into one (docs/store.md, "Sweeps"). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "store_impl.h"
#include "sweep_store.h"

static int set_sweep_run_unlocked(store *st, int64_t run, const char *sweep, const char *plan,
                                  int position, const store_axis *axes, int n) {
  if (store__exec(st, "BEGIN IMMEDIATE", "recording a run's place in its sweep"))
    return SERVER_EFAIL;
  sqlite3_stmt *q = NULL;
  const char *sql[] = {
      "INSERT INTO sweeps (name, plan) VALUES (?1, ?2) ON CONFLICT (name) DO NOTHING",
      "INSERT OR REPLACE INTO sweep_runs (run, sweep, position) VALUES (?1, ?2, ?3)",
      "DELETE FROM run_axes WHERE run = ?1",
  };
  for (int s = 0; s < 3; s++) {
    if (sqlite3_prepare_v2(st->db, sql[s], -1, &q, NULL) != SQLITE_OK) goto failed;
    if (s == 0) {
      sqlite3_bind_text(q, 1, sweep, -1, SQLITE_STATIC);
      sqlite3_bind_text(q, 2, plan, -1, SQLITE_STATIC);
    } else {
      sqlite3_bind_int64(q, 1, run);
      if (s == 1) {
        sqlite3_bind_text(q, 2, sweep, -1, SQLITE_STATIC);
        sqlite3_bind_int(q, 3, position);
      }
    }
    if (sqlite3_step(q) != SQLITE_DONE) goto failed;
    sqlite3_finalize(q);
    q = NULL;
  }
  if (sqlite3_prepare_v2(st->db, "INSERT INTO run_axes (run, axis, value) VALUES (?1, ?2, ?3)",
                         -1, &q, NULL) != SQLITE_OK)
    goto failed;
  for (int i = 0; i < n; i++) {
    sqlite3_reset(q);
    sqlite3_bind_int64(q, 1, run);
    sqlite3_bind_text(q, 2, axes[i].axis, -1, SQLITE_STATIC);
    sqlite3_bind_text(q, 3, axes[i].value, -1, SQLITE_STATIC);
    if (sqlite3_step(q) != SQLITE_DONE) goto failed;
  }
  sqlite3_finalize(q);
  q = NULL;
  if (store__exec(st, "COMMIT", "recording a run's place in its sweep")) goto failed;
  return SERVER_OK;
failed:
  store__fail(st, "recording the place of run %lld in sweep \"%s\"", (long long)run, sweep);
  sqlite3_finalize(q);
  store__rollback(st);
  return SERVER_EFAIL;
}

int store_set_sweep_run(store *st, int64_t run, const char *sweep, const char *plan_json,
                        int position, const store_axis *axes, int n) {
  LOCKED(st, set_sweep_run_unlocked(st, run, sweep, plan_json, position, axes, n));
}

static int each_sweep_run_unlocked(store *st, const char *sweep,
                                   int (*fn)(const store_sweep_run *r, void *ctx), void *ctx) {
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(
          st->db,
          "SELECT r.id, r.name, w.sweep, w.position, r.status,"
          " (SELECT json_group_object(axis, value) FROM"
          "   (SELECT axis, value FROM run_axes a WHERE a.run = r.id ORDER BY a.rowid)),"
          " r.reason, r.iterations,"
          " (SELECT coalesce(max(iteration), 0) FROM iterations i WHERE i.run = r.id)"
          " FROM sweep_runs w JOIN runs r ON r.id = w.run"
          " WHERE ?1 IS NULL OR w.sweep = ?1 ORDER BY w.sweep, w.position",
          -1, &q, NULL) != SQLITE_OK)
    return store__fail(st, "listing swept runs");
  if (sweep) sqlite3_bind_text(q, 1, sweep, -1, SQLITE_STATIC);
  int rc;
  while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
    const char *status = (const char *)sqlite3_column_text(q, 4);
    store_sweep_run r = {
        .run = sqlite3_column_int64(q, 0),
        .name = (const char *)sqlite3_column_text(q, 1),
        .sweep = (const char *)sqlite3_column_text(q, 2),
        .position = sqlite3_column_int(q, 3),
        .finished = status && strcmp(status, "finished") == 0,
        .axes = (const char *)sqlite3_column_text(q, 5),
        .reason = (const char *)sqlite3_column_text(q, 6),
        .iterations = sqlite3_column_int(q, 7),
        .last_iteration = sqlite3_column_int(q, 8),
    };
    if (fn(&r, ctx)) {
      sqlite3_finalize(q);
      return store__fail(st, "listing swept runs: stopped");
    }
  }
  sqlite3_finalize(q);
  return rc == SQLITE_DONE ? SERVER_OK : store__fail(st, "listing swept runs");
}

int store_each_sweep_run(store *st, const char *sweep,
                         int (*fn)(const store_sweep_run *r, void *ctx), void *ctx) {
  LOCKED(st, each_sweep_run_unlocked(st, sweep, fn, ctx));
}

static int sweep_plan_unlocked(store *st, const char *sweep, char **plan) {
  *plan = NULL;
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(st->db, "SELECT plan FROM sweeps WHERE name = ?1", -1, &q, NULL) !=
      SQLITE_OK)
    return store__fail(st, "reading the plan of sweep \"%s\"", sweep);
  sqlite3_bind_text(q, 1, sweep, -1, SQLITE_STATIC);
  int rc = sqlite3_step(q);
  if (rc == SQLITE_ROW) {
    const unsigned char *t = sqlite3_column_text(q, 0);
    *plan = strdup(t ? (const char *)t : "");
    if (!*plan) rc = SQLITE_NOMEM;
  }
  sqlite3_finalize(q);
  if (rc == SQLITE_ROW || rc == SQLITE_DONE) return SERVER_OK;
  return store__fail(st, "reading the plan of sweep \"%s\"", sweep);
}

int store_sweep_plan(store *st, const char *sweep, char **plan) {
  LOCKED(st, sweep_plan_unlocked(st, sweep, plan));
}

/* ---- merging --------------------------------------------------------------------- */

/* Copies the rows of `table` whose column `key` is `from_run` in src to dst, with that
 * column set to `to_run` (every other column as it is: both files have one schema). */
static int copy_rows(sqlite3 *src, sqlite3 *dst, const char *table, const char *key,
                     int64_t from_run, int64_t to_run) {
  char sql[256];
  snprintf(sql, sizeof sql, "SELECT * FROM %s WHERE %s = ?1 ORDER BY rowid", table, key);
  sqlite3_stmt *in = NULL, *out = NULL;
  if (sqlite3_prepare_v2(src, sql, -1, &in, NULL) != SQLITE_OK) return SQLITE_ERROR;
  sqlite3_bind_int64(in, 1, from_run);
  int cols = sqlite3_column_count(in), keycol = -1;
  char insert[1024];
  int len = snprintf(insert, sizeof insert, "INSERT INTO %s VALUES (", table);
  for (int c = 0; c < cols && len < (int)sizeof insert - 8; c++) {
    if (strcmp(sqlite3_column_name(in, c), key) == 0) keycol = c;
    len += snprintf(insert + len, sizeof insert - (size_t)len, c ? ", ?" : "?");
  }
  snprintf(insert + len, sizeof insert - (size_t)len, ")");
  int rc = keycol < 0 ? SQLITE_ERROR : sqlite3_prepare_v2(dst, insert, -1, &out, NULL);
  while (rc == SQLITE_OK && (rc = sqlite3_step(in)) == SQLITE_ROW) {
    sqlite3_reset(out);
    for (int c = 0; c < cols; c++) {
      if (c == keycol) sqlite3_bind_int64(out, c + 1, to_run);
      else sqlite3_bind_value(out, c + 1, sqlite3_column_value(in, c));
    }
    rc = sqlite3_step(out) == SQLITE_DONE ? SQLITE_OK : SQLITE_ERROR;
  }
  sqlite3_finalize(in);
  sqlite3_finalize(out);
  return rc == SQLITE_DONE ? SQLITE_OK : SQLITE_ERROR;
}

/* Copies one run of src (its row under a new id, and its rows of every table). */
static int copy_run(sqlite3 *src, sqlite3 *dst, int64_t from_run) {
  sqlite3_stmt *in = NULL, *out = NULL;
  int rc = sqlite3_prepare_v2(src, "SELECT * FROM runs WHERE id = ?1", -1, &in, NULL);
  if (rc == SQLITE_OK) {
    sqlite3_bind_int64(in, 1, from_run);
    rc = sqlite3_step(in) == SQLITE_ROW ? SQLITE_OK : SQLITE_ERROR;
  }
  char insert[1024];
  int cols = rc == SQLITE_OK ? sqlite3_column_count(in) : 0;
  int len = snprintf(insert, sizeof insert, "INSERT INTO runs VALUES (NULL");
  for (int c = 1; c < cols && len < (int)sizeof insert - 8; c++)
    len += snprintf(insert + len, sizeof insert - (size_t)len, ", ?");
  snprintf(insert + len, sizeof insert - (size_t)len, ")");
  if (rc == SQLITE_OK) rc = sqlite3_prepare_v2(dst, insert, -1, &out, NULL);
  if (rc == SQLITE_OK) {
    for (int c = 1; c < cols; c++) sqlite3_bind_value(out, c, sqlite3_column_value(in, c));
    rc = sqlite3_step(out) == SQLITE_DONE ? SQLITE_OK : SQLITE_ERROR;
  }
  sqlite3_finalize(in);
  sqlite3_finalize(out);
  if (rc != SQLITE_OK) return rc;
  int64_t to_run = sqlite3_last_insert_rowid(dst);
  static const char *const tables[] = {"iterations", "stats", "commands", "sweep_runs",
                                       "run_axes"};
  for (size_t t = 0; t < sizeof tables / sizeof *tables && rc == SQLITE_OK; t++)
    rc = copy_rows(src, dst, tables[t], "run", from_run, to_run);
  return rc;
}

/* Whether dst has a run named like src's run (merged before). */
static int has_run(sqlite3 *dst, const char *name, bool *has) {
  sqlite3_stmt *q;
  if (sqlite3_prepare_v2(dst, "SELECT 1 FROM runs WHERE name = ?1", -1, &q, NULL) != SQLITE_OK)
    return SQLITE_ERROR;
  sqlite3_bind_text(q, 1, name, -1, SQLITE_STATIC);
  int rc = sqlite3_step(q);
  *has = rc == SQLITE_ROW;
  sqlite3_finalize(q);
  return rc == SQLITE_ROW || rc == SQLITE_DONE ? SQLITE_OK : SQLITE_ERROR;
}

/* Opens a task store read-only and checks that it is a sylva store of this schema. */
static int open_source(const char *path, sqlite3 **out, char *why, size_t n) {
  *out = NULL;
  if (sqlite3_open_v2(path, out, SQLITE_OPEN_READONLY, NULL) != SQLITE_OK) {
    snprintf(why, n, "%s", *out ? sqlite3_errmsg(*out) : "cannot open");
    return SERVER_EINPUT;
  }
  sqlite3_busy_timeout(*out, 5000);
  sqlite3_stmt *q;
  int64_t app = -1, version = -1;
  if (sqlite3_prepare_v2(*out, "SELECT * FROM pragma_application_id, pragma_user_version", -1,
                         &q, NULL) == SQLITE_OK) {
    if (sqlite3_step(q) == SQLITE_ROW) {
      app = sqlite3_column_int64(q, 0);
      version = sqlite3_column_int64(q, 1);
    }
    sqlite3_finalize(q);
  }
  if (app != STORE_APPLICATION_ID) {
    snprintf(why, n, "not a sylva store");
    return SERVER_EINPUT;
  }
  if (version != STORE_SCHEMA_VERSION) {
    snprintf(why, n, "a store of schema %lld (this build merges schema %d)", (long long)version,
             STORE_SCHEMA_VERSION);
    return SERVER_EINPUT;
  }
  return SERVER_OK;
}

typedef struct merge_source {
  const char *path;
  sqlite3 *db;
} merge_source;

/* Copies the finished runs of one task store that dst lacks, inside dst's open
 * transaction. */
static int merge_one(store *st, merge_source *s, const char *sweep, const char *plan_json,
                     store_merge_report *rep) {
  sqlite3_stmt *q;
  /* a task store of another plan of the same name (an older --slurm DIR written
   * again) holds runs that look like this plan's: leave it out */
  if (sqlite3_prepare_v2(s->db, "SELECT plan FROM sweeps WHERE name = ?1", -1, &q, NULL) !=
      SQLITE_OK) {
    snprintf(store__last_error, sizeof store__last_error, "%s: reading its plan: %s", s->path,
             sqlite3_errmsg(s->db));
    return SERVER_EFAIL;
  }
  sqlite3_bind_text(q, 1, sweep, -1, SQLITE_STATIC);
  bool other = false;
  if (sqlite3_step(q) == SQLITE_ROW) {
    const char *plan = (const char *)sqlite3_column_text(q, 0);
    other = !plan || strcmp(plan, plan_json) != 0;
  }
  sqlite3_finalize(q);
  if (other) {
    if (rep->on_missing) rep->on_missing(s->path, "its runs are of another plan", rep->ctx);
    rep->missing++;
    return SERVER_OK;
  }
  if (sqlite3_prepare_v2(s->db,
                         "SELECT r.id, r.name, r.status, w.position FROM sweep_runs w"
                         " JOIN runs r ON r.id = w.run WHERE w.sweep = ?1 ORDER BY w.position",
                         -1, &q, NULL) != SQLITE_OK) {
    snprintf(store__last_error, sizeof store__last_error, "%s: reading its runs: %s", s->path,
             sqlite3_errmsg(s->db));
    return SERVER_EFAIL;
  }
  sqlite3_bind_text(q, 1, sweep, -1, SQLITE_STATIC);
  int rc;
  while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
    int64_t id = sqlite3_column_int64(q, 0);
    const char *name = (const char *)sqlite3_column_text(q, 1);
    const char *status = (const char *)sqlite3_column_text(q, 2);
    int position = sqlite3_column_int(q, 3);
    bool has = false;
    if (has_run(st->db, name, &has) != SQLITE_OK) break;
    if (has) {
      rep->kept++;
    } else if (!status || strcmp(status, "finished") != 0) {
      if (rep->on_unfinished) rep->on_unfinished(s->path, name, position, rep->ctx);
      rep->unfinished++;
    } else {
      if (copy_run(s->db, st->db, id) != SQLITE_OK) {
        /* name lives in q's row: the message first */
        store__fail(st, "merging run \"%s\" of %s", name, s->path);
        sqlite3_finalize(q);
        return SERVER_EFAIL;
      }
      rep->copied++;
    }
  }
  sqlite3_finalize(q);
  if (rc != SQLITE_DONE) return store__fail(st, "merging %s", s->path);
  return SERVER_OK;
}

static int merge_unlocked(store *st, const char *sweep, const char *plan_json,
                          const char *const *paths, int n, store_merge_report *rep) {
  merge_source *src = calloc((size_t)(n > 0 ? n : 1), sizeof *src);
  if (!src) {
    snprintf(store__last_error, sizeof store__last_error, "%s: out of memory", st->path);
    return SERVER_EFAIL;
  }
  for (int i = 0; i < n; i++) {
    char why[256];
    src[i].path = paths[i];
    if (open_source(paths[i], &src[i].db, why, sizeof why)) {
      sqlite3_close_v2(src[i].db);
      src[i].db = NULL;
      if (rep->on_missing) rep->on_missing(paths[i], why, rep->ctx);
      rep->missing++;
    }
  }
  /* one transaction: the merged store gains every task's runs or none */
  int rc = store__exec(st, "BEGIN IMMEDIATE", "merging");
  if (rc == SERVER_OK) {
    sqlite3_stmt *q;
    if (sqlite3_prepare_v2(st->db,
                           "INSERT INTO sweeps (name, plan) VALUES (?1, ?2)"
                           " ON CONFLICT (name) DO NOTHING",
                           -1, &q, NULL) != SQLITE_OK) {
      rc = store__fail(st, "merging");
    } else {
      sqlite3_bind_text(q, 1, sweep, -1, SQLITE_STATIC);
      sqlite3_bind_text(q, 2, plan_json, -1, SQLITE_STATIC);
      if (sqlite3_step(q) != SQLITE_DONE) rc = store__fail(st, "merging");
      sqlite3_finalize(q);
    }
  }
  for (int i = 0; i < n && rc == SERVER_OK; i++)
    if (src[i].db) rc = merge_one(st, &src[i], sweep, plan_json, rep);
  if (rc == SERVER_OK && store__exec(st, "COMMIT", "merging")) rc = SERVER_EFAIL;
  if (rc != SERVER_OK) store__rollback(st);
  for (int i = 0; i < n; i++) sqlite3_close_v2(src[i].db);
  free(src);
  return rc;
}

int store_merge(store *st, const char *sweep, const char *plan_json, const char *const *paths,
                int n, store_merge_report *rep) {
  LOCKED(st, merge_unlocked(st, sweep, plan_json, paths, n, rep));
}
