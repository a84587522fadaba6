/* Test and benchmark helper: reads and parses a scenario file, or exits with the
 * error (a broken shipped scenario is a failure of the suite, not a case). */
#ifndef SYLVA_TEST_SCENARIO_FILE_H
#define SYLVA_TEST_SCENARIO_FILE_H

#include <stdio.h>
#include <stdlib.h>

#include "sylva/scenario.h"

static sylva_scenario *scenario_file(const char *dir, const char *name) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "cannot open %s\n", path);
    exit(1);
  }
  static char buf[1 << 20];
  size_t n = fread(buf, 1, sizeof buf, f);
  fclose(f);
  sylva_scenario *s = NULL;
  char err[512];
  if (sylva_scenario_parse(buf, n, &s, err, sizeof err) < 0) {
    fprintf(stderr, "%s: %s\n", path, err);
    exit(1);
  }
  return s;
}
#endif
