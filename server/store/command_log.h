/* sylva server: the command log's own record format. Every command applied to a
 * run between iterations is stored as one JSON record, versioned apart from the
 * wire protocol, so that a later protocol still replays old stores
 * (docs/store.md, "The command log"):
 *
 *   {"format": 2, "command": "edit",
 *    "remove_obstacles": ["wall"],
 *    "add_obstacles": [{"id": "box", "kind": "box", "min": [x, y, z], "max": [x, y, z]}],
 *    "add_plants": [{"id": "oak2", "species": "oak", "roots": [[x, y, z]]}],
 *    "prune": {"zone": "road"}}
 *
 * Format 4 added prisms ({"id", "kind": "prism" or "zone", "polygon", "holes", "z"},
 * docs/scenario.md, "Obstacles"), its obstacles read as a scenario's are; format 3
 * added a plant's optional "age" (years at planting); format 2 added zones
 * (kind "zone") and the optional prune; format 1 has neither.
 * Records without "format" are read as format 0: the protocol-1 `edit` message
 * that stores written before the format existed hold (the same three arrays,
 * beside "type", "run" and "id"). */
#ifndef SYLVA_SERVER_COMMAND_LOG_H
#define SYLVA_SERVER_COMMAND_LOG_H

#include <stddef.h>

#include "edit.h"

/** The newest format, which this build writes for an edit that needs it (a prism;
 *  3 for a plant with an age); other edits are written as format 2. It reads every
 *  format up to it. */
#define COMMAND_LOG_FORMAT 4

/** The record of an edit (malloc'd, no newline), or NULL when memory ran out. The
 *  same edit always gives the same bytes; numbers round-trip exactly. */
char *command_log_encode(const edit *e);

/** Reads a record into *out (zeroed first; edit_free it in every case). Returns
 *  SERVER_OK, SERVER_EINPUT (err names the JSON pointer and the problem: "/format:
 *  format 3 is newer than this sylva reads (up to 2)") or SERVER_ENOMEM. */
int command_log_decode(const char *json, edit *out, char *err, size_t errlen);

#endif
