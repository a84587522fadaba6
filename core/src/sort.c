#include "sort.h"

#include <string.h>

#include "debug.h"

static void swap(unsigned char *a, unsigned char *b, size_t size) {
  unsigned char t[SYLVA__SORT_MAX_ELEM];
  memcpy(t, a, size);
  memcpy(a, b, size);
  memcpy(b, t, size);
}

/* Quicksort (Hoare's partition about the median of the first, middle and last) down
 * to runs of 12, which insertion sort finishes; it recurses into the smaller side
 * only, so the stack holds O(log n) frames. */
void sylva__sort(void *base, size_t n, size_t size, int (*cmp)(const void *, const void *)) {
  SYLVA_ASSERT(size <= SYLVA__SORT_MAX_ELEM);
  unsigned char *e = base, pivot[SYLVA__SORT_MAX_ELEM];
  while (n > 12) {
    unsigned char *a = e, *m = e + (n / 2) * size, *z = e + (n - 1) * size;
    if (cmp(m, a) < 0) swap(m, a, size);
    if (cmp(z, m) < 0) {
      swap(z, m, size);
      if (cmp(m, a) < 0) swap(m, a, size);
    }
    memcpy(pivot, m, size);
    /* [0, j] holds no element above the pivot, (j, n) none below; both are shorter
     * than n, as the pivot is an element and the middle one */
    ptrdiff_t i = -1, j = (ptrdiff_t)n;
    for (;;) {
      do i++;
      while (cmp(e + (size_t)i * size, pivot) < 0);
      do j--;
      while (cmp(pivot, e + (size_t)j * size) < 0);
      if (i >= j) break;
      swap(e + (size_t)i * size, e + (size_t)j * size, size);
    }
    size_t left = (size_t)j + 1, right = n - left;
    if (left < right) {
      sylva__sort(e, left, size, cmp);
      e += left * size;
      n = right;
    } else {
      sylva__sort(e + left * size, right, size, cmp);
      n = left;
    }
  }
  for (size_t k = 1; k < n; k++)
    for (size_t j = k; j > 0 && cmp(e + (j - 1) * size, e + j * size) > 0; j--)
      swap(e + (j - 1) * size, e + j * size, size);
}
