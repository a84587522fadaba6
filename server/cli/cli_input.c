#include "cli_input.h"

#include <stdio.h>

#include "files.h"
#include "measured.h"
#include "server_error.h"

int cli_input_scenario(const char *path, unsigned flags, sylva_scenario **out) {
  char err[1200];
  int rc = files_load_scenario(path, flags, out, err, sizeof err);
  if (!rc) { /* the measured trees of its plants, read beside it */
    char why[1000];
    int e = sylva_import_measured(path, *out, why, sizeof why);
    if (e) {
      snprintf(err, sizeof err, "%.180s: %s", path, why);
      rc = e == SYLVA_ENOMEM ? SERVER_ENOMEM : SERVER_EINPUT;
      sylva_scenario_free(*out);
      *out = NULL;
    }
  }
  if (rc) fprintf(stderr, "sylva: %s\n", err);
  return server_exit_status(rc);
}

int cli_input_world(const char *path, const sylva_scenario *s, sylva_world **out) {
  char err[1200];
  int rc = files_build_world(path, s, out, err, sizeof err);
  if (rc) fprintf(stderr, "sylva: %s\n", err);
  return server_exit_status(rc);
}
