/* The import suite, trees (server/import/tree.c): cylinder models built here turned
 * into internodes (resampling, branches and their gaps, pieces, births, stages), then
 * every ITSMe TreeQSM file against its own treedata. */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../check.h"
#include "../list_dir.h"
#include "fit.h"
#include "qsm.h"
#include "sylva/library.h"
#include "sylva/status.h"
#include "tree.h"
#include "utdb.h"

#ifndef QSM_DATA
#error "QSM_DATA: the folder of the ITSMe files"
#endif
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static bool is_mat(const char *name) {
  size_t n = strlen(name);
  return n > 4 && strcmp(name + n - 4, ".mat") == 0;
}

/* ---- a failing allocator: the test links with --wrap for malloc, calloc, realloc ---- */

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t n);
void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t size);
void *__wrap_realloc(void *p, size_t n);

static long alloc_calls, alloc_fail_at; /* the allocation that fails, 0 for none */

static bool refuse(void) { return alloc_fail_at > 0 && ++alloc_calls == alloc_fail_at; }
void *__wrap_malloc(size_t n) { return refuse() ? NULL : __real_malloc(n); }
void *__wrap_calloc(size_t n, size_t size) { return refuse() ? NULL : __real_calloc(n, size); }
void *__wrap_realloc(void *p, size_t n) { return refuse() ? NULL : __real_realloc(p, n); }

/* ---- building models ---- */

/* A cylinder from start to end. */
typedef struct spec {
  double s[3], e[3], radius;
  int parent, branch;
} spec;

static sylva_qsm model(const spec *sp, size_t n) {
  sylva_qsm q = {.cyl = calloc(n, sizeof(sylva_qsm_cylinder)), .count = n, .models = 1};
  if (!q.cyl) abort();
  for (size_t i = 0; i < n; i++) {
    sylva_qsm_cylinder *c = &q.cyl[i];
    double d[3], len = 0;
    for (int j = 0; j < 3; j++) {
      d[j] = sp[i].e[j] - sp[i].s[j];
      len += d[j] * d[j];
    }
    len = sqrt(len);
    c->length = len;
    c->radius = sp[i].radius;
    for (int j = 0; j < 3; j++) {
      c->start[j] = sp[i].s[j];
      c->axis[j] = d[j] / len;
    }
    c->parent = sp[i].parent;
    c->branch = sp[i].branch;
  }
  char err[256];
  int rc = sylva_qsm_check(&q, err, sizeof err);
  if (rc) {
    fprintf(stderr, "a test model is bad: %s\n", err);
    abort();
  }
  return q;
}

/* A linear height curve: 0.5 m at age 0, 0.1 m a year, to 40 years. */
#define CURVE_YEARS 40
static double curve[CURVE_YEARS + 1];
static void linear_curve(void) {
  for (int a = 0; a <= CURVE_YEARS; a++) curve[a] = 0.5 + 0.1 * a;
}

static sylva_tree_options options(int age) {
  linear_curve();
  return (sylva_tree_options){.rho = 0.25, .base = {0, 0, 0}, .heights = curve,
                              .years = CURVE_YEARS, .age = age, .pipe_exponent = 2.5};
}

static sylva_tree build(const sylva_qsm *q, const sylva_tree_options *o) {
  sylva_tree t;
  char err[256] = "";
  int rc = sylva_tree_build(q, o, &t, err, sizeof err);
  if (rc) fprintf(stderr, "build: %s\n", err);
  CHECK_INT(rc, 0);
  if (rc) abort();
  return t;
}

static double dist(const double a[3], const double b[3]) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

/* The skeleton's shape (tree.h): parents first, one root per stem, at most one axis
 * child and one lateral child per node, births monotone and in -age..0. */
static void check_shape(const sylva_tree *t) {
  int *axis_children = calloc(t->count + 1, sizeof(int));
  int *laterals = calloc(t->count + 1, sizeof(int));
  if (!axis_children || !laterals) abort();
  int roots = 0;
  bool parents_first = true, monotone = true, in_range = true;
  for (size_t i = 0; i < t->count; i++) {
    const sylva_tree_node *n = &t->node[i];
    if (n->birth > 0 || n->birth < -t->age) in_range = false;
    if (n->parent < 0) {
      roots++;
      CHECK_INT(n->lateral, 0);
      continue;
    }
    if ((size_t)n->parent >= i) parents_first = false;
    else if (n->birth < t->node[n->parent].birth) monotone = false;
    if (n->lateral) laterals[n->parent]++;
    else axis_children[n->parent]++;
  }
  CHECK(parents_first);
  CHECK(monotone);
  CHECK(in_range);
  CHECK_INT(roots, t->stems);
  int over = 0;
  for (size_t i = 0; i < t->count; i++)
    if (axis_children[i] > 1 || laterals[i] > 1) over++;
  CHECK_INT(over, 0);
  free(axis_children);
  free(laterals);
}

static bool is_tip(const sylva_tree *t, size_t i) {
  for (size_t k = i + 1; k < t->count; k++)
    if (t->node[k].parent == (int)i) return false;
  return true;
}

/* ---- the tests ---- */

/* A straight trunk of three cylinders: a node every rho and the end, radii of the
 * cylinder each node lies on, the volume of the cylinders, births from the tips. */
static void test_straight_trunk(void) {
  const spec sp[] = {{{5, 5, 2}, {5, 5, 3}, 0.1, -1, 1},
                     {{5, 5, 3}, {5, 5, 4}, 0.08, 0, 1},
                     {{5, 5, 4}, {5, 5, 4.7}, 0.05, 1, 1}};
  sylva_qsm q = model(sp, 3);
  sylva_tree_options o = options(20);
  sylva_tree t = build(&q, &o);
  CHECK_INT(t.count, (long long)ceil(2.7 / 0.25) + 1);
  CHECK_INT(t.stems, 1);
  CHECK_INT(t.pieces_dropped, 0);
  CHECK_INT(t.branches, 0);
  CHECK_INT(t.max_order, 0);
  CHECK_NEAR(t.node[0].p[2], 0, 1e-12); /* based at the origin */
  CHECK_NEAR(t.node[0].p[0], 0, 1e-12);
  CHECK_NEAR(t.node[t.count - 1].p[2], 2.7, 1e-12); /* the tip is kept */
  CHECK_NEAR(t.node[4].p[2], 1.0, 1e-12);
  CHECK_NEAR(t.node[4].radius, 0.1, 0); /* a joint belongs to the cylinder below */
  CHECK_NEAR(t.node[5].radius, 0.08, 0);
  CHECK_NEAR(t.height, 2.7, 1e-12);
  CHECK_NEAR(t.length, 2.7, 1e-12);
  CHECK_NEAR(t.dbh, 0.16, 0); /* 1.3 m lies on the second cylinder */
  CHECK_NEAR(t.volume, t.cylinder_volume, 1e-12);
  CHECK_NEAR(t.cylinder_volume, M_PI * (0.01 + 0.0064 + 0.0025 * 0.7), 1e-12);
  CHECK_INT(t.age, 20);
  CHECK_INT(t.node[t.count - 1].birth, 0);
  CHECK_INT(t.node[0].birth, -20);
  /* births: the scaled curve S(a) = (0.5 + 0.1 a) 2.7 / 2.5 reaches a trunk node's
   * height (H - d = z) at the first a with S(a) >= z */
  double scale = 2.7 / curve[20];
  for (size_t i = 0; i < t.count; i++) {
    int a = 0;
    while (a < 20 && curve[a] * scale < t.node[i].p[2]) a++;
    CHECK_INT(t.node[i].birth, a - 20);
  }
  check_shape(&t);
  sylva_tree_free(&t);

  /* the age from the height: the first age at which the curve reaches 2.7 m */
  o.age = 0;
  t = build(&q, &o);
  CHECK_INT(t.age, 22);
  CHECK_INT(t.node[0].birth, -22);
  sylva_tree_free(&t);
  /* without a curve every node is born at 0 */
  o.heights = NULL;
  o.age = 7;
  t = build(&q, &o);
  CHECK_INT(t.age, 7);
  CHECK_INT(t.node[0].birth, 0);
  sylva_tree_free(&t);
  /* a length that rho divides, given off by a rounding: no internode of nothing */
  const spec exact[] = {{{0, 0, 0}, {0, 0, 0.75 + 1e-9}, 0.1, -1, 1}};
  sylva_qsm q2 = model(exact, 1);
  o = options(10);
  t = build(&q2, &o);
  CHECK_INT(t.count, 4);
  sylva_tree_free(&t);
  sylva_qsm_free(&q2);
  sylva_qsm_free(&q);
}

/* Two branches from the same place of the trunk: the first takes the nearest node,
 * the second the nearest free one of the same axis. */
static void test_two_branches_one_place(void) {
  const spec sp[] = {{{0, 0, 0}, {0, 0, 1}, 0.1, -1, 1},
                     {{0, 0, 1}, {0, 0, 2}, 0.08, 0, 1},
                     {{0, 0, 1}, {0.6, 0, 1}, 0.02, 0, 2},
                     {{0, 0, 1}, {0, 0.6, 1}, 0.02, 0, 3}};
  sylva_qsm q = model(sp, 4);
  sylva_tree_options o = options(15);
  sylva_tree t = build(&q, &o);
  CHECK_INT(t.branches, 2);
  CHECK_INT(t.max_order, 1);
  CHECK_INT(t.laterals_moved, 1);
  CHECK_INT(t.laterals_off_axis, 0);
  CHECK_INT(t.count, 9 + 3 + 3); /* trunk 0..2 m; each branch 0.25, 0.5, 0.6 */
  check_shape(&t);
  /* the first branch on the node at 1 m, the second on the one below (a tie with the
   * one above, settled by order) */
  int first = -1, second = -1;
  for (size_t i = 0; i < t.count; i++)
    if (t.node[i].lateral) {
      if (first < 0) first = (int)i;
      else second = (int)i;
    }
  CHECK(first > 0 && second > 0);
  CHECK_NEAR(t.node[t.node[first].parent].p[2], 1.0, 1e-12);
  CHECK_NEAR(t.node[t.node[second].parent].p[2], 0.75, 1e-12);
  CHECK_NEAR(t.node[first].p[0], 0.25, 1e-12);
  CHECK_NEAR(t.node[second].p[1], 0.25, 1e-12);
  sylva_tree_free(&t);

  /* the same tree without branch numbers, the branch listed before the trunk's next
   * cylinder: the child closest in direction goes on */
  const spec nonum[] = {{{0, 0, 0}, {0, 0, 1}, 0.1, -1, 0},
                        {{0, 0, 1}, {0.6, 0, 1.1}, 0.02, 0, 0},
                        {{0, 0, 1}, {0, 0, 2}, 0.08, 0, 0}};
  sylva_qsm q2 = model(nonum, 3);
  t = build(&q2, &o);
  CHECK_INT(t.branches, 1);
  CHECK_NEAR(t.height, 2.0, 1e-12);
  CHECK_INT(t.node[8].lateral, 0); /* the trunk's nodes first, to its top */
  CHECK_NEAR(t.node[8].p[2], 2.0, 1e-12);
  check_shape(&t);
  sylva_tree_free(&t);
  sylva_qsm_free(&q2);

  /* more branches than nodes on a short axis (one node: it is shorter than rho): the
   * first takes its node, the others the nearest free nodes of the stem */
  const spec crowded[] = {{{0, 0, 0}, {0, 0, 0.4}, 0.1, -1, 1},
                          {{0, 0, 0.4}, {0, 0.2, 0.45}, 0.03, 0, 2},
                          {{0, 0.2, 0.45}, {0.5, 0.2, 0.5}, 0.02, 1, 3},
                          {{0, 0.2, 0.45}, {-0.5, 0.2, 0.5}, 0.02, 1, 4},
                          {{0, 0.2, 0.45}, {0, 0.7, 0.5}, 0.02, 1, 5}};
  sylva_qsm q3 = model(crowded, 5);
  t = build(&q3, &o);
  CHECK_INT(t.branches, 4);
  CHECK(t.max_order >= 2); /* a branch on a sibling's node is one order deeper */
  check_shape(&t);
  CHECK_INT(t.laterals_moved, 0);
  CHECK_INT(t.laterals_off_axis, 2);
  sylva_tree_free(&t);
  sylva_qsm_free(&q3);
  sylva_qsm_free(&q);
}

/* A branch whose first cylinder starts off its parent (TreeQSM starts branches on
 * the parent's surface): the first internode joins the trunk's node to the branch. */
static void test_gap_healed(void) {
  const spec sp[] = {{{0, 0, 0}, {0, 0, 1}, 0.1, -1, 1},
                     {{0, 0, 1}, {0, 0, 2}, 0.08, 0, 1},
                     {{0.1, 0, 1.05}, {1.1, 0, 1.05}, 0.02, 0, 2}};
  sylva_qsm q = model(sp, 3);
  sylva_tree_options o = options(15);
  sylva_tree t = build(&q, &o);
  check_shape(&t);
  size_t b = 9; /* the branch's first node follows the trunk's nine */
  CHECK_INT(t.node[b].lateral, 1);
  CHECK_NEAR(t.node[b].p[0], 0.35, 1e-12);
  CHECK_NEAR(t.node[b].p[2], 1.05, 1e-12);
  const sylva_tree_node *p = &t.node[t.node[b].parent];
  CHECK_NEAR(p->p[2], 1.0, 1e-12); /* the trunk's node nearest the branch's start */
  CHECK_NEAR(p->p[0], 0.0, 1e-12);
  double bridge = dist(p->p, t.node[b].p);
  CHECK_NEAR(bridge, sqrt(0.35 * 0.35 + 0.05 * 0.05), 1e-12);
  CHECK_NEAR(t.length, 2.0 + bridge + 0.75, 1e-12);
  CHECK_NEAR(t.node[t.count - 1].p[0], 1.1, 1e-12);
  sylva_tree_free(&t);
  sylva_qsm_free(&q);
}

/* A floating piece in the crown is dropped; the tree is the rest. */
static void test_floating_piece(void) {
  const spec sp[] = {{{0, 0, 0}, {0, 0, 2}, 0.1, -1, 1},
                     {{0, 0, 1}, {1, 1, 1.5}, 0.02, 0, 2},
                     {{0.5, 0.5, 1.6}, {0.8, 0.6, 1.9}, 0.01, -1, 3},
                     {{0.8, 0.6, 1.9}, {0.9, 0.7, 2.1}, 0.01, 2, 3}};
  sylva_qsm q = model(sp, 4);
  sylva_tree_options o = options(15);
  sylva_tree t = build(&q, &o);
  CHECK_INT(t.stems, 1);
  CHECK_INT(t.pieces_dropped, 1);
  CHECK_INT(t.cylinders, 2);
  CHECK_INT(t.cylinders_dropped, 2);
  CHECK_NEAR(t.height, 2.0, 1e-12); /* the piece reached 2.1 m */
  CHECK_INT(t.branches, 1);
  check_shape(&t);
  sylva_tree_free(&t);
  sylva_qsm_free(&q);
}

/* Two roots on the ground: a plant of two stems; a third root 0.9 m up is dropped. */
static void test_two_stems(void) {
  const spec sp[] = {{{3, 3, 1}, {3, 3, 3}, 0.1, -1, 1},
                     {{3, 3, 2}, {4.5, 4.5, 2.5}, 0.02, 0, 2},
                     {{3.8, 3.5, 1.3}, {3.9, 3.5, 2.8}, 0.06, -1, 3},
                     {{3.5, 3.5, 1.9}, {3.6, 3.6, 2.5}, 0.01, -1, 4}};
  sylva_qsm q = model(sp, 4);
  sylva_tree_options o = options(15);
  o.base[0] = 10;
  sylva_tree t = build(&q, &o);
  CHECK_INT(t.stems, 2);
  CHECK_INT(t.pieces_dropped, 1);
  check_shape(&t);
  /* the first stem's root at the base, the second where it stood beside it */
  int second = -1;
  for (size_t i = 1; i < t.count; i++)
    if (t.node[i].parent < 0) second = (int)i;
  CHECK(second > 0);
  CHECK_NEAR(t.node[0].p[0], 10, 1e-12);
  CHECK_NEAR(t.node[0].p[2], 0, 1e-12);
  CHECK_NEAR(t.node[second].p[0], 10.8, 1e-12);
  CHECK_NEAR(t.node[second].p[1], 0.5, 1e-12);
  CHECK_NEAR(t.node[second].p[2], 0.3, 1e-12);
  /* the stems' nodes are contiguous: nothing before `second` hangs from it */
  for (int i = second + 1; i < (int)t.count; i++) CHECK(t.node[i].parent >= second);
  CHECK_NEAR(t.height, 2.0, 1e-12);
  sylva_tree_free(&t);
  sylva_qsm_free(&q);
}

/* A trunk of 3 m with a short branch at 1 m, its curve scaled by 1 (H = curve[25]). */
static sylva_qsm branched_model(void) {
  const spec sp[] = {{{0, 0, 0}, {0, 0, 1.5}, 0.1, -1, 1},
                     {{0, 0, 1.5}, {0, 0, 3}, 0.06, 0, 1},
                     {{0, 0, 1}, {0.5, 0, 1}, 0.02, 0, 2}};
  return model(sp, 3);
}

/* Stages 0, 5 and 15 years before: subsets closed under parents, shrinking; stage 0 is
 * the tree itself. */
static void test_stages(void) {
  sylva_qsm q = branched_model();
  sylva_tree_options o = options(25);
  sylva_tree t = build(&q, &o);
  check_shape(&t);
  sylva_tree s0 = {0}, s5 = {0}, s15 = {0};
  CHECK_INT(sylva_tree_stage(&t, 0, 2.5, &s0), 0);
  CHECK_INT(s0.count, t.count);
  CHECK(memcmp(s0.node, t.node, t.count * sizeof *t.node) == 0);
  CHECK(s0.height == t.height && s0.volume == t.volume && s0.length == t.length);
  CHECK_INT(s0.age, t.age);
  CHECK_INT(s0.branches, t.branches);
  CHECK_INT(sylva_tree_stage(&t, 5, 2.5, &s5), 0);
  CHECK_INT(sylva_tree_stage(&t, 15, 2.5, &s15), 0);
  CHECK_INT(s5.age, 20);
  CHECK_INT(s15.age, 10);
  CHECK(s15.count < s5.count && s5.count < t.count);
  CHECK(s15.height < s5.height && s5.height < t.height);
  CHECK(s15.volume < s5.volume && s5.volume < t.volume);
  /* H = 3 m = curve[25]: 20 years old the tree was curve[20] = 2.5 m, 10 years old 1.5 m */
  CHECK_NEAR(s5.height, 2.5, 1e-9);
  CHECK_NEAR(s15.height, 1.5, 1e-9);
  check_shape(&s5);
  check_shape(&s15);
  /* births shifted to the stage's season; its tips then were born by then */
  for (size_t i = 0; i < s5.count; i++) CHECK(s5.node[i].birth <= 0);
  /* the stage of a stage is the stage */
  sylva_tree s5_10 = {0};
  CHECK_INT(sylva_tree_stage(&s5, 10, 2.5, &s5_10), 0);
  CHECK_INT(s5_10.count, s15.count);
  /* out of range */
  sylva_tree bad = {0};
  CHECK_INT(sylva_tree_stage(&t, 26, 2.5, &bad), SYLVA_ERANGE);
  CHECK_INT(sylva_tree_stage(&t, -1, 2.5, &bad), SYLVA_ERANGE);
  CHECK_INT(bad.count, 0);
  CHECK_INT(sylva_tree_stage(&t, 25, 2.5, &bad), 0); /* the planted tree */
  CHECK(bad.count >= 1);
  CHECK_INT(bad.age, 0);
  sylva_tree_free(&bad);
  sylva_tree_free(&s5_10);
  sylva_tree_free(&s0);
  sylva_tree_free(&s5);
  sylva_tree_free(&s15);
  sylva_tree_free(&t);
  sylva_qsm_free(&q);
}

/* Pipe radii: 5 years before, the branch at 1 m was not yet born, so the trunk below
 * it carried one tip instead of two: r (1/2)^(1/v). Above it nothing changed. */
static void test_stage_pipe_radii(void) {
  sylva_qsm q = branched_model();
  sylva_tree_options o = options(25);
  sylva_tree t = build(&q, &o);
  sylva_tree s = {0};
  CHECK_INT(sylva_tree_stage(&t, 5, 2.5, &s), 0);
  CHECK_INT(s.branches, 0);
  CHECK_INT(t.branches, 1);
  /* trunk nodes 0..12 keep their order; the stage holds those up to 2.5 m */
  CHECK_INT(s.count, 11);
  for (size_t i = 0; i < s.count; i++) {
    CHECK_NEAR(s.node[i].p[2], t.node[i].p[2], 0);
    /* the stage's tip is the trunk's node at 2.5 m: one tip throughout */
    double tips0 = t.node[i].p[2] <= 1.0 ? 2 : 1;
    CHECK_NEAR(s.node[i].radius, t.node[i].radius * pow(1.0 / tips0, 1 / 2.5), 1e-15);
  }
  CHECK(is_tip(&s, s.count - 1));
  CHECK_NEAR(s.node[2].radius, 0.1 * pow(0.5, 0.4), 1e-15);
  sylva_tree_free(&s);
  /* the branch is born late: its base is 0.5 m from its tip, the trunk's top 2 m */
  int lateral = -1;
  for (size_t i = 0; i < t.count; i++)
    if (t.node[i].lateral) lateral = (int)i;
  CHECK(lateral > 0);
  CHECK(t.node[lateral].birth > -5);
  sylva_tree_free(&t);
  sylva_qsm_free(&q);
}

/* Bad options are refused with a message; nothing is left to free. */
static void test_bad_options(void) {
  sylva_qsm q = branched_model();
  sylva_tree_options o = options(25);
  sylva_tree t;
  char err[256];
  o.rho = 0;
  CHECK_INT(sylva_tree_build(&q, &o, &t, err, sizeof err), SYLVA_EINVAL);
  CHECK(strstr(err, "rho") != NULL);
  CHECK(t.node == NULL && t.count == 0);
  o = options(41);
  CHECK_INT(sylva_tree_build(&q, &o, &t, err, sizeof err), SYLVA_EINVAL);
  CHECK(strstr(err, "age 41") != NULL);
  double falling[3] = {1, 2, 1.5};
  o = options(2);
  o.heights = falling;
  o.years = 2;
  CHECK_INT(sylva_tree_build(&q, &o, &t, err, sizeof err), SYLVA_EINVAL);
  CHECK(strstr(err, "decreases at age 2") != NULL);
  o = options(10);
  o.rho = 1e-9;
  CHECK_INT(sylva_tree_build(&q, &o, &t, err, sizeof err), SYLVA_ETOOBIG);
  CHECK(strstr(err, "rho") != NULL);
  sylva_qsm_free(&q);
}

/* Every allocation of a build and of a stage fails once, in turn: the call returns
 * SYLVA_ENOMEM and leaves nothing to free (the sanitizer build finds a leak), or
 * absorbs it; a call retried then gives the same tree. */
static void test_out_of_memory(void) {
  sylva_qsm q = branched_model();
  sylva_tree_options o = options(25);
  sylva_tree good = build(&q, &o), stage_good = {0};
  CHECK_INT(sylva_tree_stage(&good, 5, 2.5, &stage_good), 0);
  int failures = 0;
  for (long n = 1;; n++) {
    alloc_calls = 0;
    alloc_fail_at = n;
    sylva_tree t, s = {0};
    char err[256] = "";
    int rc = sylva_tree_build(&q, &o, &t, err, sizeof err);
    int rs = rc ? 0 : sylva_tree_stage(&t, 5, 2.5, &s);
    long reached = alloc_calls;
    alloc_fail_at = 0;
    if (rc) {
      failures++;
      CHECK_INT(rc, SYLVA_ENOMEM);
      CHECK(strstr(err, "out of memory") != NULL);
      CHECK(t.node == NULL && t.count == 0);
    } else {
      CHECK_INT(t.count, good.count);
      CHECK(memcmp(t.node, good.node, t.count * sizeof *t.node) == 0);
      if (rs) {
        failures++;
        CHECK_INT(rs, SYLVA_ENOMEM);
        CHECK(s.node == NULL && s.count == 0);
      } else {
        CHECK_INT(s.count, stage_good.count);
        CHECK(s.count == stage_good.count &&
              memcmp(s.node, stage_good.node, s.count * sizeof *s.node) == 0);
      }
    }
    sylva_tree_free(&s);
    sylva_tree_free(&t);
    if (reached < n) break; /* a run that no longer met its failure */
  }
  CHECK(failures >= 10);
  sylva_tree_free(&stage_good);
  sylva_tree_free(&good);
  sylva_qsm_free(&q);
}

/* ---- the ITSMe files ---- */

/* The default species' height curve and rho, as `sylva import` takes them. */
static int plac_curve(double *heights, int *years, double *rho, double *pipe) {
  sylva_species_def def;
  if (sylva_library_find("utdb:NoEast:PLAC", &def)) return -1;
  *rho = def.rho;
  *pipe = def.pipe_exponent;
  sylva_utdb *u = NULL;
  if (sylva_utdb_builtin(&u)) return -1;
  sylva_fit_targets targets;
  char err[256];
  const sylva_utdb_species *s = sylva_utdb_find(u, "NoEast", "PLAC");
  int rc = s ? sylva_fit_targets_utdb(s, &targets, err, sizeof err) : -1;
  sylva_utdb_free(u);
  if (rc) return rc;
  *years = targets.years;
  for (int a = 0; a <= targets.years; a++) heights[a] = targets.at[a].height;
  return 0;
}

static bool stages_monotone(const sylva_tree *a, const sylva_tree *b) {
  return b->count <= a->count && b->height <= a->height && b->volume <= a->volume;
}

/* The tree through TreeQSM's text and SimpleForest's CSV (written from the .mat's
 * cylinders, read back) is the .mat's tree, node for node. */
static void same_through_text_and_csv(const sylva_qsm *q, const sylva_tree_options *o,
                                      const sylva_tree *t, const char *name) {
  char dir[] = "/tmp/sylva-tree-XXXXXX";
  if (!mkdtemp(dir)) {
    CHECK(false);
    return;
  }
  for (int k = 0; k < 2; k++) {
    char path[128], err[512];
    snprintf(path, sizeof path, "%s/tree.%s", dir, k ? "csv" : "txt");
    int rc = k ? sylva_qsm_write_csv(q, path) : sylva_qsm_write_text(q, path);
    CHECK_INT(rc, 0);
    sylva_qsm back = {0};
    if (!rc) rc = sylva_qsm_read(path, k ? SYLVA_QSM_CSV : SYLVA_QSM_TEXT, 0, &back, err, sizeof err);
    CHECK_INT(rc, 0);
    if (!rc) {
      sylva_tree u = build(&back, o);
      bool same = u.count == t->count;
      for (size_t i = 0; same && i < t->count; i++) {
        const sylva_tree_node *a = &u.node[i], *b = &t->node[i];
        same = a->p[0] == b->p[0] && a->p[1] == b->p[1] && a->p[2] == b->p[2] &&
               a->radius == b->radius && a->parent == b->parent && a->lateral == b->lateral &&
               a->birth == b->birth;
      }
      if (!same) fprintf(stderr, "%s through %s: %zu nodes against %zu\n", name, k ? "csv" : "text",
                         u.count, t->count);
      CHECK(same);
      sylva_tree_free(&u);
    }
    sylva_qsm_free(&back);
    remove(path);
  }
  rmdir(dir);
}

/* Every ITSMe file: height within 2% of TreeHeight, DBH within 10% of DBHqsm, volume
 * within 10% of TotalVolume, stages 0, 5 and 15 years before shrinking, stage 0 the
 * import itself. */
static void test_itsme(void) {
  static double heights[SYLVA_FIT_MAX_YEARS + 1];
  int years = 0;
  double rho = 0, pipe = 0;
  int rc = plac_curve(heights, &years, &rho, &pipe);
  CHECK_INT(rc, 0);
  if (rc) return;
  size_t count = 0;
  char **names = list_dir(QSM_DATA, is_mat, &count);
  CHECK(count >= 9);
  for (size_t f = 0; f < count; f++) {
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", QSM_DATA, names[f]);
    sylva_qsm q = {0};
    char err[512];
    rc = sylva_qsm_read(path, SYLVA_QSM_UNKNOWN, 0, &q, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    CHECK_INT(rc, 0);
    if (rc) continue;
    sylva_tree_options o = {.rho = rho, .heights = heights, .years = years, .pipe_exponent = pipe};
    sylva_tree t = build(&q, &o);
    const sylva_qsm_treedata *d = &q.treedata;
    CHECK(q.has_treedata);
    printf("%s: %zu cylinders, %zu nodes, height %.3f (%.3f), dbh %.4f (%.4f), volume %.4f "
           "(%.4f) m3, age %d\n",
           names[f], q.count, t.count, t.height, d->height, t.dbh, d->dbh, t.volume,
           d->total_volume / 1000, t.age);
    CHECK_NEAR(t.height / d->height, 1, 0.02);
    CHECK_NEAR(t.dbh / d->dbh, 1, 0.10);
    CHECK_NEAR(t.volume / (d->total_volume / 1000), 1, 0.10);
    check_shape(&t);
    sylva_tree s0 = {0}, s5 = {0}, s15 = {0};
    CHECK_INT(sylva_tree_stage(&t, 0, pipe, &s0), 0);
    CHECK_INT(s0.count, t.count);
    CHECK(s0.count == t.count && memcmp(s0.node, t.node, t.count * sizeof *t.node) == 0);
    CHECK(s0.height == t.height && s0.volume == t.volume && s0.dbh == s0.dbh);
    CHECK_INT(sylva_tree_stage(&t, 5 < t.age ? 5 : t.age, pipe, &s5), 0);
    CHECK_INT(sylva_tree_stage(&t, 15 < t.age ? 15 : t.age, pipe, &s15), 0);
    CHECK(stages_monotone(&t, &s5));
    CHECK(stages_monotone(&s5, &s15));
    check_shape(&s5);
    check_shape(&s15);
    sylva_tree_free(&s0);
    sylva_tree_free(&s5);
    sylva_tree_free(&s15);
    same_through_text_and_csv(&q, &o, &t, names[f]);
    sylva_tree_free(&t);
    sylva_qsm_free(&q);
  }
  list_dir_free(names, count);
}

static const check_test tests[] = {
    CHECK_TEST(straight_trunk), CHECK_TEST(two_branches_one_place), CHECK_TEST(gap_healed),
    CHECK_TEST(floating_piece), CHECK_TEST(two_stems),              CHECK_TEST(stages),
    CHECK_TEST(stage_pipe_radii), CHECK_TEST(bad_options),          CHECK_TEST(out_of_memory),
    CHECK_TEST(itsme),
};

int main(int argc, char **argv) {
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("import-tree");
}
