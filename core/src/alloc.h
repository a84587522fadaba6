/* The library's allocation calls: every block goes through the allocator of
 * sylva_set_allocator (sylva/alloc.h), the C library's by default. */
#ifndef SYLVA_ALLOC_INTERNAL_H
#define SYLVA_ALLOC_INTERNAL_H

#include <stddef.h>

/** A block of size bytes (at least 1), or NULL. */
void *sylva__malloc(size_t size);
/** A zeroed block of n * size bytes, or NULL (also when the product overflows). */
void *sylva__calloc(size_t n, size_t size);
/** Resizes block (NULL: allocates) to size bytes; NULL on failure, block untouched. */
void *sylva__realloc(void *block, size_t size);
/** Releases block; NULL is ignored. */
void sylva__free(void *block);

#endif
