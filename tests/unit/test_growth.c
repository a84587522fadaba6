/* Hand-built skeletons: pipe-model radii (and a short tip's share at a rho below
 * ref_rho, and heartwood), shedding of a dark branch (nodes, occupancy and shade
 * removed exactly), a world that grows, and snapshots. */
#include <math.h>
#include <string.h>

#include "../check.h"
#include "sylva/sylva.h"
#include "world_impl.h"

/* Allocation at iteration T of a world set up by hand: every stem's clock (its time on
 * its growth equation, docs/model.md "Stands") where a stem that grew each season up
 * to T - 1 has it, as sylva_world_step would have left it. */
static int allocate_at(sylva_world *w, int T) {
  for (int k = 0; k < w->stem_count; k++) {
    w->stems[k].clock = (double)(T - 1 - w->stems[k].born);
    w->stems[k].clock_prev = w->stems[k].clock - 1.0;
  }
  return sylva__allocate(w, T);
}

static sylva_world *one_tree(sylva_species_def *sp, double h) {
  sylva_world_def wd = sylva_default_world_def();
  wd.max[2] = h;
  sylva_world *w;
  if (sylva_world_create(&wd, &w)) return NULL;
  int s = sylva_world_add_species(w, sp, "x");
  double root[1][3] = {{0, 0, 0}};
  sylva_plant_def pd = {s, "t", (const double(*)[3])root, 1, 0, NULL, 0};
  if (sylva_world_add_plant(w, &pd, NULL) < 0) return NULL;
  return w;
}

static void test_radii(void) {
  sylva_species_def sp = sylva_default_species_def();
  sp.initial_nodes = 2;
  sylva_world *w = one_tree(&sp, 5);
  CHECK(w != NULL);
  /* root(0) - a(1) - b(2), plus a lateral c on a */
  double pc[3] = {0.07, 0, 0.17};
  w->iteration = 1;
  int32_t c = sylva__add_node(w, 1, true, pc, 0, 1);
  CHECK_INT(c, 3);
  CHECK_INT(sylva__reserve_scratch(w), 0);
  CHECK_INT(sylva__radii(w, 1), 0);
  double v = sp.pipe_exponent, r = sp.r_tip, ra = pow(2 * pow(r, v), 1 / v);
  sylva__skeleton *k = &w->nodes;
  CHECK_NEAR(k->radius[2], r, 1e-8); /* stored as float */
  CHECK_NEAR(k->radius[3], r, 1e-8);
  CHECK_NEAR(k->radius[1], ra, 1e-7);
  CHECK_NEAR(k->radius[0], ra, 1e-7); /* one child: the same radius */
  /* radii never shrink: drop c, recompute, a keeps its radius */
  k->flags[3] = 0;
  k->live--;
  k->lateral_child[1] = -1;
  CHECK_INT(sylva__radii(w, 2), 0);
  CHECK_NEAR(k->radius[1], ra, 1e-7);
  sylva_world_destroy(w);
}

/* At rho = ref_rho / 2 a tip whose shoot is one node long carries half a tip's pipes
 * (docs/model.md, "Species in years", "Pipes at a finer rho"); a tip two nodes
 * from its branching carries a whole one. */
static void test_tip_share(void) {
  sylva_species_def sp = sylva_default_species_def();
  sp.initial_nodes = 2;
  sp.ref_rho = 2.0 * sp.rho; /* the trunk: 2 x 2 nodes above the root */
  sylva_world *w = one_tree(&sp, 5);
  CHECK(w != NULL);
  if (!w) return;
  CHECK_INT((int)w->nodes.count, 5);
  double pc[3] = {0.07, 0, 0.17};
  w->iteration = 1;
  int32_t c = sylva__add_node(w, 1, true, pc, 0, 1); /* a one-node lateral on node 1 */
  CHECK_INT(c, 5);
  CHECK_INT(sylva__reserve_scratch(w), 0);
  CHECK_INT(sylva__radii(w, 1), 0);
  double v = sp.pipe_exponent, r = sp.r_tip;
  sylva__skeleton *k = &w->nodes;
  CHECK_NEAR(k->radius[5], r, 1e-8);
  CHECK_NEAR(k->radius[3], r, 1e-8); /* the trunk's tip 4 is two nodes from node 1 */
  CHECK_NEAR(k->radius[1], pow(1.5 * pow(r, v), 1 / v), 1e-7);
  sylva_world_destroy(w);
}

/* Heartwood h (docs/model.md, "Species in years", "Heartwood"): a trunk of four nodes
 * above its root with one tip, grown no further. Each season every node's r^v grows by
 * h r_tip^v, the tip's functional pipes: after n seasons r^v = (1 + n h) r_tip^v at
 * every node below the tip, the same at the root as at the tip's parent (a node's own
 * share is not added again below it). A lateral with a second tip doubles the
 * increment below its fork, where a node's pipes are the larger of its own grown and
 * its children's; h = 0 leaves the radii as the pipe model sets them. */
static void test_heartwood(void) {
  for (int pass = 0; pass < 2; pass++) {
    sylva_species_def sp = sylva_default_species_def();
    sp.initial_nodes = 4;
    sp.heartwood = pass ? 0.1 : 0.0;
    sylva_world *w = one_tree(&sp, 5);
    CHECK(w != NULL);
    if (!w) return;
    CHECK_INT(sylva__reserve_scratch(w), 0);
    double v = sp.pipe_exponent, r = sp.r_tip, h = sp.heartwood;
    sylva__skeleton *k = &w->nodes;
    for (int season = 1; season <= 3; season++) {
      w->iteration = season;
      CHECK_INT(sylva__radii(w, season), 0);
      double inner = r * pow(1.0 + season * h, 1.0 / v);
      CHECK_NEAR(k->radius[4], r, 1e-8); /* the tip */
      for (int n = 0; n < 4; n++) CHECK_NEAR(k->radius[n], inner, 1e-7);
    }
    /* a one-node lateral on node 2 from season 4: two tips above node 2 */
    double pc[3] = {0.07, 0, 0.27};
    w->iteration = 4;
    int32_t c = sylva__add_node(w, 2, true, pc, 0, 4);
    CHECK_INT(c, 5);
    CHECK_INT(sylva__reserve_scratch(w), 0);
    CHECK_INT(sylva__radii(w, 4), 0);
    /* node 2: its children's pipes (1 + 4h) + 1 exceed its own (1 + 3h) + 2h */
    CHECK_NEAR(k->radius[3], r * pow(1.0 + 4 * h, 1.0 / v), 1e-7);
    CHECK_NEAR(k->radius[2], r * pow(2.0 + 4 * h, 1.0 / v), 1e-7);
    CHECK_NEAR(k->radius[0], r * pow(2.0 + 4 * h, 1.0 / v), 1e-7);
    /* a fifth season: its own (2 + 4h) + 2h exceed its children's (1 + 5h) + 1 */
    w->iteration = 5;
    CHECK_INT(sylva__radii(w, 5), 0);
    CHECK_NEAR(k->radius[5], r, 1e-8);
    CHECK_NEAR(k->radius[3], r * pow(1.0 + 5 * h, 1.0 / v), 1e-7);
    CHECK_NEAR(k->radius[2], r * pow(2.0 + 6 * h, 1.0 / v), 1e-7);
    CHECK_NEAR(k->radius[0], r * pow(2.0 + 6 * h, 1.0 / v), 1e-7);
    sylva_world_destroy(w);
  }
}

/* A trunk with two laterals: one in the open, one under a box. Shedding removes the
 * dark one (and its occupancy and shade); the grid then equals a world that never
 * had it. */
static void test_shedding(void) {
  sylva_species_def sp = sylva_default_species_def();
  sp.initial_nodes = 10;
  sp.r_s = 0.35;
  sylva_world *w = one_tree(&sp, 5), *ref = one_tree(&sp, 5);
  CHECK(w && ref);
  sylva_obstacle_def box = {"box", {-1.5, -0.3, 0.9}, {0.0, 0.3, 1.0}, SYLVA_OBSTACLE_SOLID, {0}};
  CHECK(sylva_world_add_obstacle(w, &box) >= 0);
  CHECK(sylva_world_add_obstacle(ref, &box) >= 0);
  w->iteration = ref->iteration = 1;
  /* the open lateral, in both worlds */
  double open1[3] = {0.1, 0, 0.55}, open2[3] = {0.2, 0, 0.6};
  sylva_world *both[2] = {w, ref};
  for (int i = 0; i < 2; i++) {
    int32_t a = sylva__add_node(both[i], 5, true, open1, 0, 1);
    int32_t b = sylva__add_node(both[i], a, false, open2, 0, 1);
    CHECK(a > 0 && b > 0);
    CHECK_INT(sylva__shade_node(both[i], a, +1), 0);
    CHECK_INT(sylva__shade_node(both[i], b, +1), 0);
  }
  /* the dark lateral, under the box, only in w */
  double d1[3] = {-0.1, 0, 0.65}, d2[3] = {-0.2, 0, 0.7}, d3[3] = {-0.3, 0, 0.75};
  int32_t x = sylva__add_node(w, 6, true, d1, 0, 1);
  int32_t y = sylva__add_node(w, x, false, d2, 0, 1);
  int32_t z = sylva__add_node(w, y, false, d3, 0, 1);
  CHECK(x > 0 && y > 0 && z > 0);
  int32_t dark_id = w->nodes.id[x];
  for (int32_t n = x; n <= z; n++) CHECK_INT(sylva__shade_node(w, n, +1), 0);
  int vz[3];
  sylva__node_voxel(w, z, vz);
  CHECK_INT(sylva__grid_occupant(&w->grid, vz), 0);
  CHECK_NEAR(sylva__grid_light(&w->grid, vz), 0.0, 0.0);
  for (int i = 0; i < 2; i++) { /* as a step's reserve_rest */
    CHECK_INT(sylva__reserve_scratch(both[i]), 0);
    CHECK_INT(sylva__reserve_removal(both[i]), 0);
  }
  CHECK_INT(sylva__shed(w, 2), 0);
  CHECK_INT(w->shed.len, 1);
  if (w->shed.len) CHECK_INT(w->shed.data[0], dark_id);
  CHECK_INT(w->nodes.live, ref->nodes.live);
  CHECK_INT(w->stems[0].stats.shed, 3);
  CHECK_INT(sylva__grid_occupant(&w->grid, vz), -1);
  CHECK(w->nodes.flags[6] & SYLVA__NODE_SCAR);
  CHECK_INT(w->nodes.lateral_child[6], -1);
  /* shade identical to the world that never had the branch */
  int same = 1;
  for (int zz = 0; zz < 40; zz++)
    for (int yy = 90; yy < 110; yy++)
      for (int xx = 80; xx < 120; xx++) {
        int v[3] = {xx, yy, zz};
        same &= sylva__grid_shade_raw(&w->grid, v) == sylva__grid_shade_raw(&ref->grid, v);
      }
  CHECK(same);
  /* the open lateral stays */
  CHECK_INT(sylva__shed(ref, 2), 0);
  CHECK_INT(ref->shed.len, 0);
  sylva_world_destroy(w);
  sylva_world_destroy(ref);
}

/* A small stand grown with snapshots taken at every iteration: each restored world
 * continues in lockstep with the original, hash for hash. */
static sylva_world *small_stand(uint64_t seed) {
  sylva_world_def wd = sylva_default_world_def();
  wd.min[0] = wd.min[1] = -3, wd.max[0] = wd.max[1] = 3, wd.max[2] = 8;
  wd.seed = seed;
  sylva_world *w;
  if (sylva_world_create(&wd, &w)) return NULL;
  sylva_species_def sp = sylva_default_species_def();
  sp.growth.p[1] = 40; /* a short life keeps the test fast */
  int s = sylva_world_add_species(w, &sp, "x");
  double roots[3][3] = {{0, 0, 0}, {1.2, 0, 0}, {0, 1.2, 0}};
  for (int i = 0; i < 3; i++) {
    char label[8] = {'t', (char)('0' + i), 0};
    sylva_plant_def pd = {s, label, (const double(*)[3])roots[i], 1, 0, NULL, 0};
    if (sylva_world_add_plant(w, &pd, NULL) < 0) return NULL;
  }
  sylva_obstacle_def wall = {"wall", {-3, -2, 0}, {-2.8, 2, 2}, SYLVA_OBSTACLE_SOLID, {0}};
  sylva_world_add_obstacle(w, &wall);
  return w;
}

static void test_snapshot_lockstep(void) {
  sylva_world *w = small_stand(5);
  CHECK(w != NULL);
  int steps = 0;
  while (!sylva_world_finished(w) && steps < 25) {
    uint8_t *img;
    size_t n;
    CHECK_INT(sylva_snapshot_save(w, &img, &n), 0);
    sylva_world *r;
    CHECK_INT(sylva_snapshot_load(img, n, &r), 0);
    free(img);
    if (!r) break;
    CHECK(sylva_world_hash(r) == sylva_world_hash(w));
    /* both continue: three iterations in lockstep */
    for (int k = 0; k < 3 && !sylva_world_finished(w); k++) {
      int a = sylva_world_step(w, NULL), b = sylva_world_step(r, NULL);
      CHECK_INT(a, b);
      CHECK(sylva_world_hash(r) == sylva_world_hash(w));
    }
    steps += 3;
    sylva_world_destroy(r);
  }
  sylva_world_destroy(w);
}

static void test_snapshot_bad_images(void) {
  sylva_world *w = small_stand(9);
  for (int i = 0; i < 6; i++) sylva_world_step(w, NULL);
  uint8_t *img;
  size_t n;
  CHECK_INT(sylva_snapshot_save(w, &img, &n), 0);
  sylva_world *r = (sylva_world *)1;
  CHECK_INT(sylva_snapshot_load(img, 10, &r), SYLVA_ETRUNCATED);
  CHECK(r == NULL);
  CHECK_INT(sylva_snapshot_load(img, n - 1, &r), SYLVA_ETRUNCATED);
  uint8_t *bad = malloc(n);
  memcpy(bad, img, n);
  bad[0] = 'X';
  CHECK_INT(sylva_snapshot_load(bad, n, &r), SYLVA_EBADIMAGE);
  memcpy(bad, img, n);
  bad[8] = 99;
  CHECK_INT(sylva_snapshot_load(bad, n, &r), SYLVA_EVERSION);
  /* any flipped byte of the payload is caught by the checksum */
  int caught = 0;
  for (size_t pos = 32; pos < n; pos += 1 + n / 200) {
    memcpy(bad, img, n);
    bad[pos] ^= 0x5a;
    caught += sylva_snapshot_load(bad, n, &r) == SYLVA_ECHECKSUM;
  }
  CHECK(caught > 150);
  /* a forged image with a valid checksum but broken content never crashes */
  uint64_t h0 = sylva_world_hash(w);
  for (size_t pos = 32; pos < n; pos += 1 + n / 300) {
    memcpy(bad, img, n);
    bad[pos] ^= 0xff;
    uint64_t sum = 0xcbf29ce484222325ULL;
    for (size_t i = 32; i < n; i++) sum = (sum ^ bad[i]) * 0x100000001b3ULL;
    for (int i = 0; i < 8; i++) bad[24 + i] = (uint8_t)(sum >> (8 * i));
    int rc = sylva_snapshot_load(bad, n, &r);
    if (rc == 0) {
      for (int k = 0; k < 2; k++) sylva_world_step(r, NULL);
      sylva_world_destroy(r);
    }
  }
  CHECK(sylva_world_hash(w) == h0); /* the source world is untouched */
  free(bad);
  free(img);
  sylva_world_destroy(w);
}

static void test_add_plant_errors(void) {
  sylva_world *w = small_stand(3);
  double inside[1][3] = {{-2.9, 0, 0.5}}, out[1][3] = {{9, 0, 0}}, taken[1][3] = {{0, 0, 0}};
  sylva_plant_def a = {0, "a", (const double(*)[3])inside, 1, 0, NULL, 0};
  int bad = 0;
  uint64_t h = sylva_world_hash(w);
  CHECK_INT(sylva_world_add_plant(w, &a, &bad), SYLVA_EBLOCKED);
  CHECK_INT(bad, 0);
  sylva_plant_def b = {0, "b", (const double(*)[3])out, 1, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(w, &b, &bad), SYLVA_EOUTSIDE);
  sylva_plant_def c = {0, "c", (const double(*)[3])taken, 1, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(w, &c, &bad), SYLVA_EOCCUPIED);
  double two[2][3] = {{2, 2, 0}, {2.01, 2.01, 0}}; /* two roots of one shrub in one voxel */
  sylva_plant_def d = {0, "d", (const double(*)[3])two, 2, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(w, &d, &bad), SYLVA_EOCCUPIED);
  CHECK_INT(bad, 1);
  double free_spot[1][3] = {{2, -2, 0}};
  sylva_plant_def e = {0, "t1", (const double(*)[3])free_spot, 1, 0, NULL, 0}; /* a label in use */
  CHECK_INT(sylva_world_add_plant(w, &e, &bad), SYLVA_EINVAL);
  CHECK(sylva_world_hash(w) == h); /* nothing changed */
  CHECK_INT(sylva_world_plant_count(w), 3);
  /* many plants: labels stay unique and findable as the index grows */
  for (int i = 0; i < 300; i++) {
    char label[16];
    snprintf(label, sizeof label, "p%d", i);
    double root[1][3] = {{-2.5 + (i % 20) * 0.25, -2.5 + (i / 20) * 0.25, 0}};
    sylva_plant_def pd = {0, label, (const double(*)[3])root, 1, 0, NULL, 0};
    int rc = sylva_world_add_plant(w, &pd, NULL);
    if (rc < 0 && rc != SYLVA_EOCCUPIED && rc != SYLVA_EBLOCKED) CHECK_INT(rc, 0);
  }
  sylva_plant_def again = {0, "p7", (const double(*)[3])free_spot, 1, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(w, &again, &bad), SYLVA_EINVAL);
  sylva_world_destroy(w);
}

/* Only leaf-bearing nodes collect: the initial trunk (birth 0) collects alpha in
 * full light until it is older than leaf_age, then nothing; a lateral bud on a
 * leafless node gets no resource and does not sprout. */
static void test_leaves(void) {
  sylva_species_def sp = sylva_default_species_def();
  sp.leaf_age = 2;
  sylva_world *w = one_tree(&sp, 5);
  CHECK(w != NULL);
  CHECK_INT(sylva__reserve_scratch(w), 0);
  sylva__skeleton *k = &w->nodes;
  sylva__light_collect(w, 2, w->light); /* age 2: leaves */
  CHECK_NEAR(w->light[2], sp.alpha, 0.0); /* the unshaded top: alpha * 1^(2^sigma) */
  CHECK(w->light[1] > 0.0 && w->light[1] < sp.alpha); /* under the top's pyramid */
  sylva__light_collect(w, 3, w->light); /* age 3: bare wood */
  for (size_t i = 0; i < k->count; i++) CHECK_NEAR(w->light[i], 0.0, 0.0);
  CHECK_NEAR(w->q[k->count - 1], 0.0, 0.0);
  /* a sprouting pass at T = 3 finds no light to share: no sprout at all */
  w->iteration = 2;
  CHECK_INT(allocate_at(w, 3), 0);
  CHECK_INT((int)w->sprouts.len, 0);
  sylva_world_destroy(w);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {
      CHECK_TEST(leaves), CHECK_TEST(radii), CHECK_TEST(tip_share), CHECK_TEST(heartwood),
      CHECK_TEST(shedding), CHECK_TEST(snapshot_lockstep),
      CHECK_TEST(snapshot_bad_images), CHECK_TEST(add_plant_errors)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("growth");
}
