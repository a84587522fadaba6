/* A sort that never allocates, for the bodies of the pool's parallel loops, which
 * must not (pool.h): glibc's qsort takes a buffer from malloc for all but the
 * smallest arrays. */
#ifndef SYLVA_SORT_H
#define SYLVA_SORT_H

#include <stddef.h>

/** Largest element sylva__sort takes, in bytes. */
#define SYLVA__SORT_MAX_ELEM 64

/** Sorts n elements of size bytes (at most SYLVA__SORT_MAX_ELEM) in place by cmp, as
 *  qsort does, on the stack alone (a quicksort that recurses into its smaller side).
 *  Not stable: under a total order (no two elements equal) the result is the one
 *  qsort gives. */
void sylva__sort(void *base, size_t n, size_t size, int (*cmp)(const void *, const void *));

#endif
