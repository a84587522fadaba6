#include "cli_input.h"

#include <stdio.h>

#include "files.h"
#include "server_error.h"

int cli_input_scenario(const char *path, unsigned flags, sylva_scenario **out) {
  char err[1200];
  int rc = files_load_scenario(path, flags, out, err, sizeof err);
  if (rc) fprintf(stderr, "sylva: %s\n", err);
  return server_exit_status(rc);
}

int cli_input_world(const char *path, const sylva_scenario *s, sylva_world **out) {
  char err[1200];
  int rc = files_build_world(path, s, out, err, sizeof err);
  if (rc) fprintf(stderr, "sylva: %s\n", err);
  return server_exit_status(rc);
}
