/* Canopy cover and crown areas (docs/model.md, "Canopy cover"), and the year's
 * sequestered CO2 through planting and an image: a hand-worked crown
 * beside a wall; and the street's crowns, every few iterations, against a count made
 * here over the world's nodes as the API gives them (leaves, positions, parents):
 * each stem's cells, their union counted once where crowns overlap, less the cells
 * under the solid obstacles on the floor. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../check.h"
#include "../scenario_file.h"
#include "sylva/sylva.h"



/* One leaf-bearing node of 0.1 m leaves at (1.05, 1.05) in 0.1 m cells: a leaf
 * reaches 0.1 m, half a cell's diagonal more makes 0.1707 m, which takes the node's
 * cell and its eight neighbours (0.1 and 0.1414 m away) and no farther one (0.2 m):
 * 0.09 m^2. A wall on the floor over x < 1 covers 200 of the 400 cells and 3 of the
 * crown's 9: the cover is 6 / 200. */
static void test_hand_worked(void) {
  sylva_world *w = json_world(
      "{\"format\": \"sylva.scenario/1\", \"seed\": 1, \"iterations\": 1,"
      " \"world\": {\"min\": [0, 0, 0], \"max\": [2, 2, 2], \"voxel\": 0.1},"
      " \"species\": {\"s\": {\"leaf_size\": 0.1}},"
      " \"plants\": [{\"id\": \"t\", \"species\": \"s\", \"roots\": [[1.05, 1.05, 0]]}],"
      " \"obstacles\": [{\"id\": \"wall\", \"kind\": \"box\", \"min\": [0, 0, 0],"
      " \"max\": [1, 2, 1.5]}]}");
  sylva_stem_stats st;
  CHECK_INT(sylva_world_stem_stats(w, 0, &st), 0);
  CHECK(fabs(st.crown_area - 0.09) < 1e-12);
  CHECK(fabs(sylva_world_canopy_cover(w) - 6.0 / 200.0) < 1e-12);
  sylva_world_destroy(w);
}

/* The cells within r of segment a-b, marked in mark[] (cells of edge e from min). */
static void mark_segment(unsigned char *mark, const int n[2], const double min[2], double e,
                         const double a[2], const double b[2], double r) {
  for (int y = 0; y < n[1]; y++) {
    double cy = min[1] + (y + 0.5) * e;
    if (cy < fmin(a[1], b[1]) - r - e || cy > fmax(a[1], b[1]) + r + e) continue;
    for (int x = 0; x < n[0]; x++) {
      double cx = min[0] + (x + 0.5) * e;
      if (cx < fmin(a[0], b[0]) - r - e || cx > fmax(a[0], b[0]) + r + e) continue;
      double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy, t = 0.0;
      if (l2 > 0) t = fmax(0.0, fmin(1.0, ((cx - a[0]) * dx + (cy - a[1]) * dy) / l2));
      double px = a[0] + t * dx - cx, py = a[1] + t * dy - cy;
      if (px * px + py * py <= r * r) mark[(size_t)y * n[0] + x] = 1;
    }
  }
}

/* Compares the world's crown areas and canopy cover with a count made here. */
static void check_counted(const sylva_world *w, const char *where) {
  const sylva_world_def *def = sylva_world_get_def(w);
  double e = def->voxel;
  int n[2] = {(int)ceil((def->max[0] - def->min[0]) / e - 1e-9),
              (int)ceil((def->max[1] - def->min[1]) / e - 1e-9)};
  size_t cells = (size_t)n[0] * n[1];
  int stems = sylva_world_stem_count(w);
  unsigned char *any = calloc(cells, 1), *one = calloc(cells, 1), *foot = calloc(cells, 1);
  size_t count = sylva_world_node_count(w);
  sylva_node_info *nodes = calloc(count ? count : 1, sizeof *nodes);
  for (size_t i = 0; i < count; i++) sylva_world_node_at(w, i, &nodes[i]);
  double sum = 0.0;
  for (int k = 0; k < stems; k++) {
    memset(one, 0, cells);
    sylva_stem_stats st;
    sylva_world_stem_stats(w, k, &st);
    double leaf = sylva_world_species(w, sylva_world_plant_species(w, st.plant))->leaf_size;
    double r = leaf + e * sqrt(0.5);
    for (size_t i = 0; i < count; i++) {
      const sylva_node_info *nd = &nodes[i];
      if (nd->leaves <= 0 || sylva_world_stem_index(w, nd->plant, nd->stem) != k) continue;
      double b[2] = {nd->x, nd->y}, a[2] = {nd->x, nd->y};
      for (size_t j = 0; j < i && nd->parent >= 0; j++) /* parents come first */
        if (nodes[j].id == nd->parent) a[0] = nodes[j].x, a[1] = nodes[j].y;
      mark_segment(one, n, def->min, e, a, b, r);
    }
    size_t area = 0;
    for (size_t c = 0; c < cells; c++) area += one[c], any[c] |= one[c];
    if (fabs(st.crown_area - (double)area * e * e) > 1e-9)
      fprintf(stderr, "%s stem %d: crown_area %.6f, counted %.6f\n", where, k, st.crown_area,
              (double)area * e * e);
    CHECK(fabs(st.crown_area - (double)area * e * e) <= 1e-9);
    sum += st.crown_area;
  }
  for (int i = 0; i < sylva_world_obstacle_count(w); i++) {
    sylva_obstacle_def o;
    int id;
    sylva_world_obstacle_at(w, i, &id, &o);
    if (o.kind != SYLVA_OBSTACLE_SOLID || o.min[2] > def->min[2] + 0.5 * e) continue;
    for (int y = 0; y < n[1]; y++)
      for (int x = 0; x < n[0]; x++) {
        double cx = def->min[0] + (x + 0.5) * e, cy = def->min[1] + (y + 0.5) * e;
        if (cx >= o.min[0] && cx < o.max[0] && cy >= o.min[1] && cy < o.max[1])
          foot[(size_t)y * n[0] + x] = 1;
      }
  }
  size_t open = 0, covered = 0, union_all = 0;
  for (size_t c = 0; c < cells; c++) {
    open += !foot[c];
    covered += any[c] && !foot[c];
    union_all += any[c];
  }
  double want = open ? (double)covered / (double)open : 0.0;
  double got = sylva_world_canopy_cover(w);
  if (fabs(got - want) > 1e-12) fprintf(stderr, "%s: cover %.6f, counted %.6f\n", where, got, want);
  CHECK(fabs(got - want) <= 0.02); /* the tolerance: 2 points */
  CHECK(fabs(got - want) <= 1e-12); /* and in fact the same count */
  /* overlaps counted once: the union is no more than the crowns' sum */
  CHECK((double)union_all * e * e <= sum + 1e-9);
  free(any);
  free(one);
  free(foot);
  free(nodes);
}

/* The street (five planes, two facades on the floor, an awning above it) at
 * iterations 0, 4, 8 and 12. */
static void test_street(void) {
  sylva_scenario *s = scenario_file(SOURCE_ROOT "/scenarios", "street.json");
  sylva_world *w = scenario_world(s);
  for (int t = 0; t <= 12; t++) {
    if (t % 4 == 0) {
      char where[32];
      snprintf(where, sizeof where, "street %d", t);
      check_counted(w, where);
    }
    if (t < 12) CHECK_INT(sylva_world_step(w, NULL), 0);
  }
  CHECK(sylva_world_canopy_cover(w) > 0.05);
  sylva_world_destroy(w);
  sylva_scenario_free(s);
}

/* Two planes 1.5 m apart: their crowns overlap, and the ground under both counts
 * once (the union is smaller than the sum). */
static void test_overlap(void) {
  sylva_world *w = json_world(
      "{\"format\": \"sylva.scenario/1\", \"seed\": 3, \"iterations\": 6,"
      " \"world\": {\"min\": [-5, -5, 0], \"max\": [5, 5, 12]},"
      " \"species\": {\"plane\": {\"preset\": \"utdb:NoEast:PLAC\"}},"
      " \"plants\": [{\"id\": \"a\", \"species\": \"plane\", \"roots\": [[-0.75, 0, 0]]},"
      " {\"id\": \"b\", \"species\": \"plane\", \"roots\": [[0.75, 0, 0]]}]}");
  for (int t = 0; t < 6; t++) CHECK_INT(sylva_world_step(w, NULL), 0);
  check_counted(w, "overlap");
  sylva_stem_stats a, b;
  sylva_world_stem_stats(w, 0, &a);
  sylva_world_stem_stats(w, 1, &b);
  double union_area = sylva_world_canopy_cover(w) * 100.0; /* open ground: 10 x 10 m */
  CHECK(union_area < a.crown_area + b.crown_area - 1.0);
  CHECK(union_area > fmax(a.crown_area, b.crown_area));
  sylva_world_destroy(w);
}

/* co2_sequestered: 0 at planting, then the year's change of co2; an image keeps it,
 * and the world read back goes on as the one that was not saved. */
static void test_sequestered(void) {
  sylva_world *w = json_world(
      "{\"format\": \"sylva.scenario/1\", \"seed\": 4, \"iterations\": 3,"
      " \"world\": {\"min\": [-4, -4, 0], \"max\": [4, 4, 12]},"
      " \"species\": {\"plane\": {\"preset\": \"utdb:NoEast:PLAC\"}},"
      " \"plants\": [{\"id\": \"a\", \"species\": \"plane\", \"roots\": [[0, 0, 0]]}]}");
  sylva_stem_stats s0, s1, s2, r1, r2;
  CHECK_INT(sylva_world_stem_stats(w, 0, &s0), 0);
  CHECK(s0.co2 > 0 && s0.co2_sequestered == 0.0);
  CHECK_INT(sylva_world_step(w, NULL), 0);
  CHECK_INT(sylva_world_stem_stats(w, 0, &s1), 0);
  CHECK(s1.co2_sequestered == s1.co2 - s0.co2 && s1.co2 > s0.co2);
  uint8_t *img = NULL;
  size_t n = 0;
  CHECK_INT(sylva_snapshot_save(w, &img, &n), 0);
  sylva_world *r = NULL;
  CHECK_INT(sylva_snapshot_load(img, n, &r), 0);
  sylva_free(img);
  if (r) {
    CHECK_INT(sylva_world_stem_stats(r, 0, &r1), 0);
    CHECK(r1.co2_sequestered == s1.co2_sequestered && r1.co2 == s1.co2);
    CHECK(r1.crown_area == s1.crown_area && r1.wood_volume == s1.wood_volume);
    CHECK(sylva_world_canopy_cover(r) == sylva_world_canopy_cover(w));
    CHECK_INT(sylva_world_step(w, NULL), 0);
    CHECK_INT(sylva_world_step(r, NULL), 0);
    sylva_world_stem_stats(w, 0, &s2);
    sylva_world_stem_stats(r, 0, &r2);
    CHECK(r2.co2_sequestered == s2.co2_sequestered && s2.co2_sequestered == s2.co2 - s1.co2);
    sylva_world_destroy(r);
  }
  sylva_world_destroy(w);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {CHECK_TEST(hand_worked), CHECK_TEST(street),
                                     CHECK_TEST(overlap), CHECK_TEST(sequestered)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("canopy");
}
