/* The allocator in place (sylva/alloc.h): the C library's until one is set. */
#include "alloc.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/alloc.h"
#include "sylva/status.h"

/* All hooks NULL: the C library's functions, called directly (calloc then keeps
 * its zeroed pages untouched until used). */
static sylva_allocator current;

int sylva_set_allocator(const sylva_allocator *allocator) {
  if (!allocator) {
    memset(&current, 0, sizeof current);
    return SYLVA_OK;
  }
  if (!allocator->malloc_fn || !allocator->realloc_fn || !allocator->free_fn) return SYLVA_EINVAL;
  current = *allocator;
  return SYLVA_OK;
}

void sylva_free(void *block) { sylva__free(block); }

void *sylva__malloc(size_t size) {
  if (size == 0) size = 1;
  return current.malloc_fn ? current.malloc_fn(size, current.ctx) : malloc(size);
}

void *sylva__calloc(size_t n, size_t size) {
  if (size && n > SIZE_MAX / size) return NULL;
  if (!current.malloc_fn) return calloc(n ? n : 1, size ? size : 1);
  void *block = sylva__malloc(n * size);
  if (block) memset(block, 0, n * size);
  return block;
}

void *sylva__realloc(void *block, size_t size) {
  if (!block) return sylva__malloc(size);
  if (size == 0) size = 1;
  return current.realloc_fn ? current.realloc_fn(block, size, current.ctx) : realloc(block, size);
}

void sylva__free(void *block) {
  if (!block) return;
  if (current.free_fn)
    current.free_fn(block, current.ctx);
  else
    free(block);
}
