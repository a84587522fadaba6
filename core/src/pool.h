/* The world's threads: a fixed pool that runs one parallel loop at a time for the
 * phases whose work splits into independent parts (docs/model.md, "Determinism");
 * several worlds may share one (sylva_threads).
 * A loop's body writes only what its own indices own and never allocates, so the
 * results do not depend on how the indices are shared out, nor on the number of
 * threads. */
#ifndef SYLVA_POOL_H
#define SYLVA_POOL_H

#include <stddef.h>

typedef struct sylva__pool sylva__pool;

/** The body of a parallel loop: indices [begin, end). */
typedef void (*sylva__range_fn)(void *ctx, size_t begin, size_t end);

/** A pool of threads - 1 workers beside the caller; *out NULL for one thread.
 *  SYLVA_ENOMEM (or a thread that would not start) leaves *out NULL: one thread. */
int sylva__pool_create(int threads, sylva__pool **out);
void sylva__pool_destroy(sylva__pool *p);
/** Threads that run a loop, the caller's included (1 for a NULL pool). */
int sylva__pool_threads(const sylva__pool *p);
/** Runs fn over [0, n) in pieces of grain indices (the last may be shorter), on
 *  the workers and the caller, and returns when every piece is done. With a NULL
 *  pool, a single piece, or while the pool runs another caller's loop, the caller
 *  runs it all. */
void sylva__pool_for(sylva__pool *p, size_t n, size_t grain, sylva__range_fn fn, void *ctx);

#endif
