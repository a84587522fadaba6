#include "replay.h"

#include <stdio.h>

#include "edit.h"

void store_warn_stderr(const char *msg) { fprintf(stderr, "sylva: warning: %s\n", msg); }

int store_world_at_logged(store *st, const store_run *r, int at, sylva_world **out) {
  if (store_world_at(st, r->id, at, store_warn_stderr, out)) {
    fprintf(stderr, "sylva: run \"%s\": %s\n", r->name, store_error(st));
    return SERVER_EFAIL;
  }
  return SERVER_OK;
}
