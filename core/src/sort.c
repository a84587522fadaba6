#include "sort.h"

#include <string.h>

#include "debug.h"

static void swap(unsigned char *a, unsigned char *b, size_t size) {
  unsigned char t[SYLVA__SORT_MAX_ELEM];
  memcpy(t, a, size);
  memcpy(a, b, size);
  memcpy(b, t, size);
}

/* Moves element i down the max-heap of the first n elements. */
static void sift(unsigned char *e, size_t i, size_t n, size_t size,
                 int (*cmp)(const void *, const void *)) {
  for (;;) {
    size_t big = i, l = 2 * i + 1, r = l + 1;
    if (l < n && cmp(e + l * size, e + big * size) > 0) big = l;
    if (r < n && cmp(e + r * size, e + big * size) > 0) big = r;
    if (big == i) return;
    swap(e + i * size, e + big * size, size);
    i = big;
  }
}

void sylva__sort(void *base, size_t n, size_t size, int (*cmp)(const void *, const void *)) {
  SYLVA_ASSERT(size <= SYLVA__SORT_MAX_ELEM);
  unsigned char *e = base;
  if (n < 2) return;
  for (size_t i = n / 2; i-- > 0;) sift(e, i, n, size, cmp);
  for (size_t end = n - 1; end > 0; end--) {
    swap(e, e + end * size, size);
    sift(e, 0, end, size, cmp);
  }
}
