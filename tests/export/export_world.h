/* The world of the export tests (test_mesh.c, test_gltf.c): a tree "oak" of species
 * "x" at (-2, 0), a two-root shrub "hazel bush" (a label with a space) of species
 * "y" at (2, 0) and (2.4, 0.3), and the obstacles given, grown some iterations.
 * Both species grow alike (buds break from the start, so a few iterations already
 * branch); they differ in foliage only (y: leaves of 0.15 m, 3 a node), which
 * changes no growth. And a file in memory to export into. */
#ifndef SYLVA_TEST_EXPORT_WORLD_H
#define SYLVA_TEST_EXPORT_WORLD_H

#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "sylva/sylva.h"

/* The world with leaf colours x and y; NULL when it could not be made. */
static sylva_world *export_world(int colour_x, int colour_y, const sylva_obstacle_def *obstacles,
                                 int nobstacles, int iterations) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w;
  if (sylva_world_create(&wd, &w) < 0) return NULL;
  sylva_species_def sp = sylva_default_species_def();
  sp.apical_zone = 0;
  sp.leaf_colour = colour_x;
  int x = sylva_world_add_species(w, &sp, "x");
  sp.leaf_colour = colour_y;
  sp.leaf_size = 0.15;
  sp.leaf_density = 3;
  int y = sylva_world_add_species(w, &sp, "y");
  double tree[1][3] = {{-2.0, 0.0, 0.0}};
  double shrub[2][3] = {{2.0, 0.0, 0.0}, {2.4, 0.3, 0.0}};
  sylva_plant_def p1 = {x, "oak", (const double(*)[3])tree, 1, 0, NULL, 0};
  sylva_plant_def p2 = {y, "hazel bush", (const double(*)[3])shrub, 2, 0, NULL, 0};
  bool ok = x >= 0 && y >= 0 && sylva_world_add_plant(w, &p1, NULL) >= 0 &&
            sylva_world_add_plant(w, &p2, NULL) >= 0;
  for (int i = 0; ok && i < nobstacles; i++) ok = sylva_world_add_obstacle(w, &obstacles[i]) >= 0;
  if (!ok) {
    sylva_world_destroy(w);
    return NULL;
  }
  const sylva_journal *j;
  for (int i = 0; i < iterations; i++)
    if (sylva_world_step(w, &j) < 0) break;
  return w;
}

/* An export in memory: its bytes and what the writer returned. */
typedef struct blob {
  char *data;
  size_t size;
  int rc;
} blob;

/* A stream into b (open_memstream); exits the test when there is none. */
static FILE *blob_open(blob *b) {
  b->data = NULL;
  b->size = 0;
  b->rc = 0;
  FILE *f = open_memstream(&b->data, &b->size);
  if (!f) {
    fprintf(stderr, "open_memstream failed\n");
    exit(1);
  }
  return f;
}

/* A writer under test: writes some export of ctx to f, returns its status. */
typedef int (*export_writer)(FILE *f, const void *ctx);

/* The status of write into /dev/full, which fails every write with ENOSPC once the
 * stream's buffer is flushed, and the errno it left (-1 when there is no /dev/full). */
static int write_to_full(export_writer write, const void *ctx, int *err) {
  FILE *f = fopen("/dev/full", "w");
  *err = -1;
  if (!f) return 0;
  errno = 0;
  int rc = write(f, ctx);
  *err = errno;
  fclose(f);
  return rc;
}

#endif
