/* sylva server: the ready scenarios the daemon offers (its --scenarios
 * directory): which names may be asked for, where their files are, and the
 * `scenarios` message, built off the loop thread (it reads and parses every
 * file). */
#ifndef SYLVA_SERVER_SCENARIOS_H
#define SYLVA_SERVER_SCENARIOS_H

#include <stdbool.h>
#include <stddef.h>

#include "client.h"

/** Most bytes of a scenario file that is listed or served. */
#define SCENARIOS_MAX_FILE (4u << 20)
/** Longest NAME (the file name without .json). */
#define SCENARIOS_MAX_NAME 200
/** Most scenarios listed. */
#define SCENARIOS_MAX_LISTED 256

/** NAME: [A-Za-z0-9_-][A-Za-z0-9._-]*, 1 to SCENARIOS_MAX_NAME bytes. */
bool scenarios_name_ok(const char *name);

/** Writes dir/NAME.json into path; false when NAME is not a valid name or the
 *  path does not fit. */
bool scenarios_path(const char *dir, const char *name, char *path, size_t size);

/** Answers `scenarios` for client c: the files of dir (may be NULL: none) whose
 *  names are valid, at most SCENARIOS_MAX_FILE bytes, and that parse as scenarios,
 *  sorted by name, at most SCENARIOS_MAX_LISTED. Read on a worker thread; the reply
 *  goes to the client if it is still connected. */
void scenarios_list(uv_loop_t *loop, client_set *clients, client *c, const char *dir,
                    const char *ref);

#endif
