/* sylva: the allocator behind every allocation of libsylva-core.
 *
 *   static void *my_malloc(size_t n, void *ctx) { ... }
 *   static void *my_realloc(void *p, size_t n, void *ctx) { ... }
 *   static void my_free(void *p, void *ctx) { ... }
 *   sylva_allocator a = {my_malloc, my_realloc, my_free, &my_state};
 *   sylva_set_allocator(&a);   // before the first world
 *
 * Every block the library takes (worlds, their voxels and skeletons, scratch,
 * snapshot images) comes from malloc_fn or realloc_fn and goes back through free_fn.
 * An allocation that fails makes the call that needed it return SYLVA_ENOMEM and
 * change nothing: a world whose step ran out of memory is as it was before the step
 * and may step again. */
#ifndef SYLVA_ALLOC_H
#define SYLVA_ALLOC_H

#include <stddef.h>

/** The hooks, each given ctx. The library never passes a size of 0 or a NULL block:
 *  realloc_fn always resizes a block malloc_fn or realloc_fn returned, and free_fn
 *  always releases one. Blocks must be aligned as malloc() aligns them. On failure
 *  malloc_fn and realloc_fn return NULL; realloc_fn then leaves the block as it was. */
typedef struct sylva_allocator {
  void *(*malloc_fn)(size_t size, void *ctx);
  void *(*realloc_fn)(void *block, size_t size, void *ctx);
  void (*free_fn)(void *block, void *ctx);
  void *ctx;
} sylva_allocator;

/** Puts an allocator in place for every later allocation; NULL puts back the C
 *  library's malloc, realloc and free. SYLVA_EINVAL (and nothing changes) when a hook
 *  is missing. A block must go back to the allocator that gave it, so set it while
 *  the library holds no memory: before the first world is created or loaded, or once
 *  every world is destroyed and every image freed. Not synchronised: set it before
 *  any thread uses the library. */
int sylva_set_allocator(const sylva_allocator *allocator);

/** Releases a block the library handed to the caller (sylva_snapshot_save's image)
 *  through the allocator in place; NULL is ignored. */
void sylva_free(void *block);

#endif
