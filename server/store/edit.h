/* sylva server: edits of a run's world between iterations (protocol `edit`): add
 * plants, add and remove obstacles. An edit is all or nothing. */
#ifndef SYLVA_SERVER_EDIT_H
#define SYLVA_SERVER_EDIT_H

#include <stddef.h>

#include "sylva/protocol.h"
#include "sylva/world.h"

/** Makes *out, a copy of w with a parsed edit applied, and returns 0. On failure w
 *  is untouched, err names what and where ("/add_plants/1/roots/0: root inside an
 *  obstacle") and the status is negative (SYLVA_ENOMEM when memory ran out,
 *  SYLVA_EINVAL for a bad edit). */
int edit_apply(const sylva_world *w, const sylva_msg *m, sylva_world **out, char *err,
               size_t errlen);

/** Replays a logged edit message (its JSON text) on *w; for restoring runs. */
int edit_replay(sylva_world **w, const char *json, char *err, size_t errlen);
#endif
