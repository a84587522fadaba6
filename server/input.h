/* sylva server: reading scenario files given on the command line. */
#ifndef SYLVA_SERVER_INPUT_H
#define SYLVA_SERVER_INPUT_H

#include <stddef.h>

#include "sylva/scenario.h"

/** Largest input file, bytes. */
#define CLI_MAX_INPUT (64u << 20)

/** Reads a whole regular file of at most max bytes into a malloc'd buffer
 *  (NUL-terminated, *len without the NUL). Returns 0, or an errno value
 *  (EFBIG when the file is larger than max, EISDIR for a directory). */
int cli_read_file(const char *path, size_t max, char **data, size_t *len);

/** Reads and parses a scenario file (flags: SYLVA_SCENARIO_*, as for
 *  sylva_scenario_parse_ex()). On failure prints "sylva: PATH: message" to stderr
 *  and returns the exit status (2 for bad or unreadable input, 1 when out of
 *  memory); 0 and *out on success. */
int cli_load_scenario(const char *path, unsigned flags, sylva_scenario **out);

/** Builds the world of a scenario loaded from path; on failure prints
 *  "sylva: PATH: message" and returns the exit status; 0 and *out on success. */
int cli_build_world(const char *path, const sylva_scenario *s, sylva_world **out);

#endif
