/* sylva server: a stored iteration of a run written as a skeleton (JSON), a mesh
 * of its branches (OBJ, PLY), a scene of its branches and leaves (binary glTF), or the per-stem stats of every iteration up to it
 * (CSV). `sylva export` and the daemon's GET /api/runs/NAME/export both write
 * with export_write, so they give the same bytes. */
#ifndef SYLVA_SERVER_EXPORT_H
#define SYLVA_SERVER_EXPORT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "store.h"

/** The formats. */
typedef enum export_format {
  EXPORT_SKELETON,
  EXPORT_OBJ,
  EXPORT_PLY,
  EXPORT_CSV,
  EXPORT_GLB
} export_format;

/** The format names, for messages. */
#define EXPORT_FORMAT_NAMES "skeleton, obj, ply, csv or glb"

/** The format called `name` ("skeleton", "obj", "ply", "csv" or "glb"); false for none. */
bool export_format_parse(const char *name, export_format *out);

/** The extension of its files, without the dot ("json", "obj", "ply", "csv", "glb"). */
const char *export_format_extension(export_format format);

/** What to write. */
typedef struct export_spec {
  int64_t run;          /**< the store's run id */
  const char *name;     /**< the run's name, for messages */
  int iteration;        /**< a stored iteration, 0 to the run's last */
  export_format format;
  int sides;            /**< obj, ply, glb: vertices per branch ring (mesh.h) */
  bool obstacles;       /**< obj, ply, glb: also the obstacles (boxes and prisms) */
} export_spec;

/** Writes spec to f (flushed, not closed): the world is restored from the store
 *  (the newest good snapshot at or before the iteration, regrown to it: seconds
 *  for a large run), the CSV streams from it. Safe on any thread (the store locks
 *  itself). warn (may be NULL) hears of damaged snapshots passed over. Returns
 *  SERVER_OK; SERVER_EFAIL when the store failed, SERVER_ENOMEM, SERVER_EWRITE when
 *  writing to f failed; err then says why in one line. */
int export_write(FILE *f, store *st, const export_spec *spec, void (*warn)(const char *msg),
                 char *err, size_t errlen);

#endif
