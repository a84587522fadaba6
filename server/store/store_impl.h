/* The store's inside, shared by its files (store.c: runs, iterations, stats and
 * commands; sweep_store.c: sweeps, run axes and merging). Not for other libraries. */
#ifndef SYLVA_SERVER_STORE_IMPL_H
#define SYLVA_SERVER_STORE_IMPL_H

#include <pthread.h>
#include <sqlite3.h>

#include "store.h"

struct store {
  sqlite3 *db;
  char *path;
  pthread_mutex_t lock; /* recursive: one caller at a time on the one connection */
  int threads;          /* the worlds it restores grow on this many (store_set_threads) */
  sylva_threads *shared; /* or share these (store_share_threads) */
};

#define STORE_ERROR_MAX 512
/** This thread's last failure (store_error). */
extern _Thread_local char store__last_error[STORE_ERROR_MAX];

/** Records "PATH: what: SQLite's reason" and returns SERVER_EFAIL. */
int store__fail(store *st, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/** Runs SQL; on failure records "PATH: what: reason" and returns SERVER_EFAIL. */
int store__exec(store *st, const char *sql, const char *what);
/** Rolls the open transaction back (its failure is the caller's failure already). */
void store__rollback(store *st);
/** Now, UTC, ISO 8601. */
void store__utc_now(char out[32]);

/* The store is used from several threads (the daemon's loop and its workers), on
 * one SQLite connection: each entry point holds the store's lock for its own
 * statements and transaction, and no longer. Regrowing a world (store_world_at)
 * holds it only for each read. */
#define LOCKED(st, call)                  \
  do {                                    \
    pthread_mutex_lock(&(st)->lock);      \
    int locked_rc_ = (call);              \
    pthread_mutex_unlock(&(st)->lock);    \
    return locked_rc_;                    \
  } while (0)

#endif
