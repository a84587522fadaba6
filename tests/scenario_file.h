/* Test and benchmark helper: reads and parses a scenario file, or exits with the
 * error (a broken shipped scenario is a failure of the suite, not a case). */
#ifndef SYLVA_TEST_SCENARIO_FILE_H
#define SYLVA_TEST_SCENARIO_FILE_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "read_file.h"
#include "sylva/scenario.h"

static sylva_scenario *scenario_file(const char *dir, const char *name) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  size_t n;
  char *buf = read_file(path, &n);
  if (!buf) {
    fprintf(stderr, "cannot read %s\n", path);
    exit(1);
  }
  sylva_scenario *s = NULL;
  char err[512];
  int rc = sylva_scenario_parse(buf, n, &s, err, sizeof err);
  free(buf);
  if (rc < 0) {
    fprintf(stderr, "%s: %s\n", path, err);
    exit(1);
  }
  return s;
}

/* The world of a parsed scenario, or exits with the error. */
static inline sylva_world *scenario_world(const sylva_scenario *s) {
  sylva_world *w = NULL;
  char err[512];
  if (sylva_scenario_build(s, &w, err, sizeof err) < 0) {
    fprintf(stderr, "build: %s\n", err);
    exit(1);
  }
  return w;
}

/* The world of a scenario given as JSON text, or exits with the error. */
static inline sylva_world *json_world(const char *json) {
  sylva_scenario *s = NULL;
  char err[512];
  if (sylva_scenario_parse(json, strlen(json), &s, err, sizeof err) < 0) {
    fprintf(stderr, "scenario: %s\n", err);
    exit(1);
  }
  sylva_world *w = scenario_world(s);
  sylva_scenario_free(s);
  return w;
}
#endif
