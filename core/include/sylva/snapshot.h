/* sylva: versioned binary image of a whole world. */
#ifndef SYLVA_SNAPSHOT_H
#define SYLVA_SNAPSHOT_H

#include <stddef.h>
#include <stdint.h>

#include "world.h"

/** Format version written by this build. */
#define SYLVA_SNAPSHOT_VERSION 4

/** Serialises w into a buffer (*data, *size) from the allocator in place; the caller
 *  releases it with sylva_free() (free() while the default allocator is in place). */
int sylva_snapshot_save(const sylva_world *w, uint8_t **data, size_t *size);
/** Builds a new world from an image. A bad image (magic, version, checksum,
 *  truncation, inconsistent content) returns a negative status and creates nothing.
 *  The restored world has no clock (see sylva_world_set_clock). */
int sylva_snapshot_load(const uint8_t *data, size_t size, sylva_world **out);

#endif
