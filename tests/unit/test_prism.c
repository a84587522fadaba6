/* Prisms (docs/model.md, "Obstacles"): a footprint's voxel columns are those whose
 * centres it holds (against the inside test, column by column), their area is the
 * polygon's within 3% for buildings at 30 degrees and an L with a courtyard; a prism
 * equal to a voxel-aligned box grows the same trees as the box, bit for bit; the
 * index finds them as a scan does and forgets them when removed; conflicts measure
 * the footprint, not its bounds; a snapshot carries them; bad footprints are refused
 * and change nothing. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../check.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include "grid.h"
#include "prism.h"
#include "world_impl.h"
#include "sylva/snapshot.h"
#include "sylva/sylva.h"

/* A rectangle w x h centred at (cx, cy), turned by deg degrees: 4 points. */
static void turned_rect(double cx, double cy, double w, double h, double deg, double out[4][2]) {
  double c = cos(deg * M_PI / 180.0), s = sin(deg * M_PI / 180.0);
  const double local[4][2] = {{-w / 2, -h / 2}, {w / 2, -h / 2}, {w / 2, h / 2}, {-w / 2, h / 2}};
  for (int i = 0; i < 4; i++) {
    out[i][0] = cx + c * local[i][0] - s * local[i][1];
    out[i][1] = cy + s * local[i][0] + c * local[i][1];
  }
}

/* An L of 24 x 18 m with arms 8 m wide and a courtyard of 4 x 4 m in its corner
 * square, turned by 30 degrees about (cx, cy): 6 + 4 points, area 24*8 + 10*8 - 16. */
static int l_shape(double cx, double cy, double out[10][2], int rings[2]) {
  const double local[10][2] = {{0, 0},  {24, 0}, {24, 8}, {8, 8},  {8, 18}, {0, 18},
                               {2, 2},  {6, 2},  {6, 6},  {2, 6}};
  double c = cos(M_PI / 6), s = sin(M_PI / 6);
  for (int i = 0; i < 10; i++) {
    out[i][0] = cx + c * local[i][0] - s * local[i][1];
    out[i][1] = cy + s * local[i][0] + c * local[i][1];
  }
  rings[0] = 6;
  rings[1] = 4;
  return 10;
}

static double polygon_area(const double (*pt)[2], const int *rings, int ring_count) {
  double total = 0.0;
  for (int r = 0, first = 0; r < ring_count; first += rings[r++]) {
    double a = 0.0;
    for (int i = 0; i < rings[r]; i++) {
      const double *p = pt[first + i], *q = pt[first + (i + 1) % rings[r]];
      a += p[0] * q[1] - q[0] * p[1];
    }
    total += r == 0 ? fabs(a) / 2 : -fabs(a) / 2;
  }
  return total;
}

static sylva__grid new_grid(double voxel) {
  sylva__grid g;
  double mn[3] = {-40, -40, 0}, mx[3] = {40, 40, 20};
  int rc = sylva__grid_init(&g, mn, mx, voxel);
  CHECK_INT(rc, 0);
  return g;
}

/* Voxel columns blocked at height z (voxel k) over the whole grid, each checked
 * against the footprint's inside test at its centre. */
static long blocked_columns(const sylva__grid *g, const sylva__footprint *f, int k, long *wrong) {
  long n = 0;
  for (int y = 0; y < g->n[1]; y++)
    for (int x = 0; x < g->n[0]; x++) {
      int v[3] = {x, y, k};
      bool b = sylva__grid_blocked(g, v);
      n += b;
      bool in = sylva__footprint_inside(f, g->min[0] + (x + 0.5) * g->voxel, g->min[1] + (y + 0.5) * g->voxel);
      *wrong += b != in;
    }
  return n;
}

static void test_voxel_area(void) {
  sylva__grid g = new_grid(0.25);
  double pts[3][4][2];
  const double sizes[3][2] = {{12, 9}, {20, 6.5}, {7.3, 15.1}};
  const double centres[3][2] = {{-20, -15}, {-5, 18}, {20, -20}};
  int rings[1] = {4};
  for (int b = 0; b < 3; b++) {
    turned_rect(centres[b][0], centres[b][1], sizes[b][0], sizes[b][1], 30, pts[b]);
    char label[8];
    snprintf(label, sizeof label, "b%d", b);
    sylva_obstacle_def d = {label, {0, 0, 0}, {0, 0, 9}, SYLVA_OBSTACLE_SOLID,
                            {(const double(*)[2])pts[b], 4, rings, 1}};
    int id = sylva__grid_add_obstacle_def(&g, g.next_obstacle_id, &d);
    CHECK(id >= 0);
    const sylva__obstacle *o = &g.obstacles[sylva__grid_obstacle_slot(&g, id)];
    long wrong = 0;
    /* the other buildings are elsewhere: count this one's columns in its bounds */
    long n = 0;
    for (int y = o->lo[1]; y < o->hi[1]; y++)
      for (int x = o->lo[0]; x < o->hi[0]; x++) {
        int v[3] = {x, y, 2};
        bool blk = sylva__grid_blocked(&g, v);
        n += blk;
        wrong += blk != sylva__footprint_inside(o->fp, g.min[0] + (x + 0.5) * g.voxel,
                                                 g.min[1] + (y + 0.5) * g.voxel);
      }
    double area = n * g.voxel * g.voxel, want = sizes[b][0] * sizes[b][1];
    CHECK_INT(wrong, 0);
    CHECK(fabs(area - want) <= 0.03 * want);
    printf("building %d at 30 degrees: %.2f m2 of voxels, polygon %.2f m2 (%+.2f %%), %d rectangles\n",
           b, area, want, 100 * (area - want) / want, o->fp->rect_count);
  }
  double lpts[10][2];
  int lrings[2];
  l_shape(0, -10, lpts, lrings);
  sylva_obstacle_def l = {"L", {0, 0, 0}, {0, 0, 12}, SYLVA_OBSTACLE_SOLID,
                          {(const double(*)[2])lpts, 10, lrings, 2}};
  int id = sylva__grid_add_obstacle_def(&g, g.next_obstacle_id, &l);
  CHECK(id >= 0);
  const sylva__obstacle *o = &g.obstacles[sylva__grid_obstacle_slot(&g, id)];
  sylva__grid alone = new_grid(0.25);
  CHECK(sylva__grid_add_obstacle_def(&alone, 0, &l) == 0);
  long wrong = 0, n = blocked_columns(&alone, alone.obstacles[0].fp, 5, &wrong);
  double area = n * 0.0625, want = polygon_area((const double(*)[2])lpts, lrings, 2);
  CHECK_INT(wrong, 0);
  CHECK(fabs(want - 256.0) < 1e-9);
  CHECK(fabs(area - want) <= 0.03 * want);
  printf("L with a courtyard at 30 degrees: %.2f m2 of voxels, polygon %.2f m2 (%+.2f %%)\n", area,
         want, 100 * (area - want) / want);
  /* the courtyard is open to the sky: its centre is under nothing */
  double cx = 4 * cos(M_PI / 6) - 4 * sin(M_PI / 6), cy = -10 + 4 * sin(M_PI / 6) + 4 * cos(M_PI / 6);
  int v[3] = {(int)((cx + 40) / 0.25), (int)((cy + 40) / 0.25), 0};
  CHECK(!sylva__grid_under_obstacle(&alone, v));
  CHECK(!sylva__footprint_inside(o->fp, cx, cy));
  /* removed, it leaves no column behind */
  CHECK_INT(sylva__grid_remove_obstacle(&alone, 0), 0);
  wrong = 0;
  CHECK_INT(blocked_columns(&alone, o->fp, 5, &wrong), 0);
  CHECK(alone.obstacle_list_bytes == 0 && alone.footprint_bytes == 0);
  sylva__grid_free(&alone);
  sylva__grid_free(&g);
}

/* The footprint of a voxel-aligned box gives the box's one rectangle. */
static void test_box_equal(void) {
  sylva__grid g = new_grid(0.125);
  double pts[4][2] = {{1, -2}, {1.25, -2}, {1.25, 2}, {1, 2}};
  int rings[1] = {4};
  sylva_obstacle_def d = {"p", {0, 0, 0}, {0, 0, 3}, SYLVA_OBSTACLE_SOLID,
                          {(const double(*)[2])pts, 4, rings, 1}};
  double bmn[3] = {1, -2, 0}, bmx[3] = {1.25, 2, 3};
  CHECK(sylva__grid_add_obstacle_def(&g, 0, &d) == 0);
  CHECK(sylva__grid_add_obstacle(&g, "b", bmn, bmx) == 1);
  const sylva__obstacle *p = &g.obstacles[0], *b = &g.obstacles[1];
  CHECK_INT(p->fp->rect_count, 1);
  const int32_t *r = p->fp->rect[0];
  CHECK(r[0] == b->lo[0] && r[1] == b->lo[1] && r[2] == b->hi[0] && r[3] == b->hi[1]);
  CHECK(memcmp(p->lo, b->lo, sizeof p->lo) == 0 && memcmp(p->hi, b->hi, sizeof p->hi) == 0);
  sylva__grid_free(&g);
}

static sylva_world *stand(bool prism) {
  sylva_world_def wd = sylva_default_world_def();
  wd.min[0] = wd.min[1] = -4, wd.max[0] = wd.max[1] = 4, wd.max[2] = 8;
  wd.voxel = 0.125;
  wd.seed = 7;
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&wd, &w), 0);
  sylva_species_def sp = sylva_default_species_def();
  sp.growth.p[1] = 60; /* igm-fig13's tree on a shorter life, as unit-conflicts grows it */
  sp.tau = 5;
  sp.b_max = 2.3;
  sp.apical_flow = 0.01;
  int s = sylva_world_add_species(w, &sp, "tree");
  double roots[2][3] = {{0.3, 0.2, 0}, {-1.5, -0.7, 0}};
  sylva_plant_def a = {s, "a", (const double(*)[3])roots[0], 1, 0, NULL, 0};
  sylva_plant_def b = {s, "b", (const double(*)[3])roots[1], 1, 0, NULL, 0};
  CHECK(sylva_world_add_plant(w, &a, NULL) >= 0);
  CHECK(sylva_world_add_plant(w, &b, NULL) >= 0);
  /* a wall east of the trees, a board over the second */
  double wall[4][2] = {{1, -2}, {1.25, -2}, {1.25, 2}, {1, 2}};
  double board[4][2] = {{-3, -1.5}, {-0.5, -1.5}, {-0.5, 1}, {-3, 1}};
  int rings[1] = {4};
  sylva_obstacle_def ow = {"wall", {1, -2, 0}, {1.25, 2, 3}, SYLVA_OBSTACLE_SOLID, {0}};
  sylva_obstacle_def ob = {"board", {-3, -1.5, 1.5}, {-0.5, 1, 1.625}, SYLVA_OBSTACLE_SOLID, {0}};
  if (prism) {
    ow.footprint = (sylva_footprint){(const double(*)[2])wall, 4, rings, 1};
    ob.footprint = (sylva_footprint){(const double(*)[2])board, 4, rings, 1};
  }
  CHECK(sylva_world_add_obstacle(w, &ow) >= 0);
  CHECK(sylva_world_add_obstacle(w, &ob) >= 0);
  return w;
}

static void test_prism_grows_as_box(void) {
  sylva_world *box = stand(false), *prism = stand(true);
  for (int i = 0; i < 40; i++) {
    int a = sylva_world_step(box, NULL), b = sylva_world_step(prism, NULL);
    CHECK(a == b && (a == 0 || a == SYLVA_EFINISHED));
  }
  size_t n = sylva_world_node_count(box);
  CHECK(n > 50);
  CHECK_INT(sylva_world_node_count(prism), n);
  size_t same = 0;
  for (size_t i = 0; i < n && i < sylva_world_node_count(prism); i++) {
    sylva_node_info a, b;
    sylva_world_node_at(box, i, &a);
    sylva_world_node_at(prism, i, &b);
    same += memcmp(&a, &b, sizeof a) == 0;
  }
  CHECK_INT(same, n);
  printf("a prism equal to a box: %zu of %zu nodes the same after 40 iterations\n", same, n);
  /* and the world gives its footprint back, bounds and all */
  sylva_obstacle_def d;
  CHECK_INT(sylva_world_obstacle_at(prism, 0, NULL, &d), 0);
  CHECK(d.footprint.ring_count == 1 && d.footprint.point_count == 4 && d.min[0] == 1 &&
        d.max[0] == 1.25 && d.min[1] == -2 && d.max[1] == 2 && d.min[2] == 0 && d.max[2] == 3);
  /* a snapshot carries it: loaded, the two step on in lockstep */
  uint8_t *img = NULL;
  size_t size = 0;
  CHECK_INT(sylva_snapshot_save(prism, &img, &size), 0);
  sylva_world *back = NULL;
  CHECK_INT(sylva_snapshot_load(img, size, &back), 0);
  free(img);
  CHECK(back && sylva_world_hash(back) == sylva_world_hash(prism));
  for (int i = 0; back && i < 5; i++) {
    sylva_world_step(back, NULL);
    sylva_world_step(prism, NULL);
  }
  CHECK(back && sylva_world_hash(back) == sylva_world_hash(prism));
  sylva_world_destroy(back);
  sylva_world_destroy(box);
  sylva_world_destroy(prism);
}

/* Conflicts measure the footprint: a triangle's clearance from a node beside its
 * long edge, where its bounds would say 0; a triangular zone counts the nodes whose
 * (x, y) it holds. */
static void test_conflicts(void) {
  sylva__footprint *f = NULL;
  double tri[3][2] = {{0, 0}, {4, 0}, {0, 4}};
  int rings[1] = {3};
  sylva_footprint in = {(const double(*)[2])tri, 3, rings, 1};
  CHECK_INT(sylva__footprint_copy(&in, &f), 0);
  CHECK(fabs(sylva__footprint_dist2(f, 3, 3) - 2.0) < 1e-12); /* (3,3) to x + y = 4 */
  CHECK(sylva__footprint_dist2(f, 1, 1) == 0.0);
  CHECK(fabs(sylva__footprint_dist2(f, -3, 0) - 9.0) < 1e-12);
  CHECK(sylva__footprint_inside(f, 1, 1) && !sylva__footprint_inside(f, 2.5, 2.5));
  sylva__footprint_free(f);

  sylva_world *w = stand(false);
  for (int i = 0; i < 30; i++) sylva_world_step(w, NULL);
  /* the zone: the triangle under the first tree's crown, x + y < 1.5 of its quarter */
  double zt[3][2] = {{0.3, 0.2}, {3.3, 0.2}, {0.3, 3.2}};
  sylva_obstacle_def z = {"tri", {0, 0, 0.5}, {0, 0, 8}, SYLVA_OBSTACLE_ZONE,
                          {(const double(*)[2])zt, 3, rings, 1}};
  int id = sylva_world_add_obstacle(w, &z);
  CHECK(id >= 0);
  long want = 0;
  for (size_t i = 0; i < sylva_world_node_count(w); i++) {
    sylva_node_info n;
    sylva_world_node_at(w, i, &n);
    if (n.plant == 0 && n.z >= 0.5 && n.x >= 0.3 && n.y >= 0.2 && (n.x - 0.3) + (n.y - 0.2) <= 3.0)
      want++;
  }
  sylva_conflicts c = sylva_world_conflicts(w);
  long got = 0;
  for (size_t i = 0; i < c.zone_count; i++)
    if (c.zones[i].obstacle == id && c.zones[i].stem == 0) got = c.zones[i].nodes;
  CHECK(want > 0);
  CHECK_INT(got, want);
  printf("a triangular zone holds %ld of the first tree's nodes\n", got);
  sylva_world_destroy(w);
}

static void test_bad_footprints(void) {
  sylva__grid g = new_grid(0.25);
  double line[3][2] = {{0, 0}, {1, 1}, {2, 2}}, sq[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  double nan_pt[3][2] = {{0, 0}, {NAN, 0}, {0, 1}};
  int three[1] = {3}, four[1] = {4}, two[2] = {2, 2}, wrong_sum[1] = {3};
  const sylva_footprint bad[] = {
      {(const double(*)[2])line, 3, three, 1},   /* no area */
      {(const double(*)[2])sq, 4, two, 2},       /* rings of 2 points */
      {(const double(*)[2])sq, 4, wrong_sum, 1}, /* sizes do not sum to the points */
      {(const double(*)[2])nan_pt, 3, three, 1}, /* not finite */
      {(const double(*)[2])sq, 4, NULL, 1},      /* no sizes */
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    sylva_obstacle_def d = {"bad", {0, 0, 0}, {0, 0, 1}, SYLVA_OBSTACLE_SOLID, bad[i]};
    CHECK_INT(sylva__grid_add_obstacle_def(&g, g.next_obstacle_id, &d), SYLVA_EINVAL);
  }
  sylva_obstacle_def flat = {"flat", {0, 0, 1}, {0, 0, 1}, SYLVA_OBSTACLE_SOLID,
                             {(const double(*)[2])sq, 4, four, 1}};
  CHECK_INT(sylva__grid_add_obstacle_def(&g, g.next_obstacle_id, &flat), SYLVA_EINVAL);
  CHECK(g.obstacle_count == 0 && g.obstacle_list_bytes == 0 && g.footprint_bytes == 0);
  sylva__grid_free(&g);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {CHECK_TEST(voxel_area), CHECK_TEST(box_equal),
                                     CHECK_TEST(prism_grows_as_box), CHECK_TEST(conflicts),
                                     CHECK_TEST(bad_footprints)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("prism");
}
