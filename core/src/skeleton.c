#include "skeleton.h"

#include <string.h>

#include "alloc.h"
#include "debug.h"

#define SYLVA__SKELETON_FIELDS(X)                                                          \
  X(id) X(x) X(y) X(z) X(radius) X(parent) X(axis_child) X(lateral_child) X(birth) X(stem) \
  X(depth) X(flags) X(leaves)

void sylva__skeleton_free(sylva__skeleton *s) {
#define SYLVA__FREE(f) sylva__free(s->f);
  SYLVA__SKELETON_FIELDS(SYLVA__FREE)
#undef SYLVA__FREE
  memset(s, 0, sizeof *s);
}

int sylva__skeleton_reserve(sylva__skeleton *s, size_t n) {
  if (s->count + n <= s->cap) return 0;
  size_t cap = s->cap ? s->cap : 1024;
  while (cap < s->count + n) cap += cap / 4; /* modest steps keep the bytes per node low */
  if (cap > (size_t)INT32_MAX) return -1;
  /* Each array is grown on its own; a failure part way leaves the grown ones
   * larger, which is harmless because cap is only raised when all succeeded. */
#define SYLVA__GROW(f)                                          \
  {                                                             \
    void *p = sylva__realloc(s->f, cap * sizeof *s->f);                \
    if (!p) return -1;                                          \
    s->f = p;                                                   \
  }
  SYLVA__SKELETON_FIELDS(SYLVA__GROW)
#undef SYLVA__GROW
  s->cap = cap;
  return 0;
}

int32_t sylva__skeleton_append(sylva__skeleton *s, int32_t id, int32_t parent, float x, float y,
                               float z, float radius, int32_t birth, int32_t stem, int32_t depth,
                               uint8_t flags) {
  SYLVA_ASSERT(s->count < s->cap); /* room was reserved */
  SYLVA_ASSERT(s->count == 0 || id > s->id[s->count - 1]); /* ids rise with slots */
  SYLVA_ASSERT(parent < (int32_t)s->count);
  size_t i = s->count++;
  s->id[i] = id;
  s->x[i] = x;
  s->y[i] = y;
  s->z[i] = z;
  s->radius[i] = radius;
  s->parent[i] = parent;
  s->axis_child[i] = -1;
  s->lateral_child[i] = -1;
  s->birth[i] = birth;
  s->stem[i] = stem;
  s->depth[i] = depth;
  s->flags[i] = (uint8_t)(flags | SYLVA__NODE_ALIVE);
  s->leaves[i] = 0;
  s->live++;
  return (int32_t)i;
}

void sylva__skeleton_compact(sylva__skeleton *s, int32_t *remap) {
  size_t j = 0;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) {
      remap[i] = -1;
      continue;
    }
    remap[i] = (int32_t)j;
    if (j != i) {
#define SYLVA__MOVE(f) s->f[j] = s->f[i];
      SYLVA__SKELETON_FIELDS(SYLVA__MOVE)
#undef SYLVA__MOVE
    }
    j++;
  }
  for (size_t i = 0; i < j; i++) {
    int32_t *links[3] = {&s->parent[i], &s->axis_child[i], &s->lateral_child[i]};
    for (int k = 0; k < 3; k++)
      if (*links[k] >= 0) *links[k] = remap[*links[k]];
  }
  s->count = j;
  /* give back memory after a large shedding */
  if (s->cap > 4096 && s->cap > j + j / 2) {
    size_t cap = j + j / 4 + 1024;
    /* an array whose shrink fails keeps its larger block: cap is then the least
     * capacity of all, which is what appends may rely on */
#define SYLVA__SHRINK(f)                                    \
  {                                                         \
    void *p = sylva__realloc(s->f, cap * sizeof *s->f);            \
    if (p) s->f = p;                                        \
  }
    SYLVA__SKELETON_FIELDS(SYLVA__SHRINK)
#undef SYLVA__SHRINK
    s->cap = cap;
  }
}

int32_t sylva__skeleton_find(const sylva__skeleton *s, int32_t id) {
  size_t lo = 0, hi = s->count;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (s->id[mid] < id)
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo < s->count && s->id[lo] == id && (s->flags[lo] & SYLVA__NODE_ALIVE)) return (int32_t)lo;
  return -1;
}

size_t sylva__skeleton_bytes(const sylva__skeleton *s) { return s->cap * SYLVA__NODE_BYTES; }
