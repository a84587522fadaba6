/* sylva server: a pool of worker processes. Each job runs in a child of its own
 * (fork), at most `workers` at a time; a child dies with its parent (a killed sweep
 * leaves no runs growing behind it). */
#ifndef SYLVA_SERVER_PROCS_H
#define SYLVA_SERVER_PROCS_H

/** What the pool calls: job runs in the child and returns its exit status (0: done
 *  well); started and done run in the parent, in the order things happen. */
typedef struct pool_def {
  int workers;
  int count;                 /**< jobs 0 to count - 1 are run in that order */
  int (*job)(int i, void *ctx);
  void (*started)(int i, void *ctx);
  void (*done)(int i, int status, double seconds, void *ctx);
  void *ctx;
} pool_def;

/** Runs every job; returns the number that failed (a non-zero status, or killed),
 *  or -1 when no child could be started (errno says why). */
int pool_run(const pool_def *def);

#endif
