/* sylva server: reading files: whole files and the scenario files given on the
 * command line or to the daemon. */
#ifndef SYLVA_SERVER_FILES_H
#define SYLVA_SERVER_FILES_H

#include <stddef.h>

#include "sylva/world.h"

#include "sylva/scenario.h"

/** Largest input file, bytes. */
#define FILES_MAX_INPUT (64u << 20)

/** Reads a whole regular file of at most max bytes into a malloc'd buffer
 *  (NUL-terminated, *len without the NUL). Returns 0, or an errno value
 *  (EFBIG when the file is larger than max, EISDIR for a directory). */
int files_read(const char *path, size_t max, char **data, size_t *len);

/** Reads and parses a scenario file (flags: SYLVA_SCENARIO_*, as for
 *  sylva_scenario_parse_ex()). On failure err says "PATH: message" and the result
 *  is SERVER_EINPUT for bad or unreadable input, SERVER_ENOMEM when out of memory;
 *  SERVER_OK and *out on success. */
int files_load_scenario(const char *path, unsigned flags, sylva_scenario **out, char *err,
                        size_t errlen);

/** Builds the world of a scenario loaded from path; on failure err says "PATH:
 *  message" and the result is SERVER_EINPUT or SERVER_ENOMEM; SERVER_OK and *out on
 *  success. */
int files_build_world(const char *path, const sylva_scenario *s, sylva_world **out, char *err,
                      size_t errlen);

#endif
