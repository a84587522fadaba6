/* The obstacle index: the per-column lists answer blocked, under an obstacle and
 * light exactly as a scan of every obstacle does, on thousands of random boxes and
 * after removals; labels and ids are found without a scan (100,000 obstacles, then
 * a few churning), in the order they were added; duplicate labels are refused; an
 * addition that runs out of memory at any of its allocations leaves the grid as it
 * was; a snapshot of a world with removed obstacles loads into the same world,
 * whose index answers too. */
#include <stdint.h>
#include <string.h>

#include "../check.h"
#include "grid.h"
#include "rng.h"
#include "sylva/sylva.h"

/* The definitions, over every live obstacle. */
static bool scan_blocked(const sylva__grid *g, const int v[3]) {
  for (int s = 0; s < g->obstacle_slots; s++) {
    const sylva__obstacle *o = &g->obstacles[s];
    if (o->live && v[0] >= o->lo[0] && v[0] < o->hi[0] && v[1] >= o->lo[1] && v[1] < o->hi[1] &&
        v[2] >= o->lo[2] && v[2] < o->hi[2])
      return true;
  }
  return false;
}

static bool scan_under(const sylva__grid *g, const int v[3]) {
  for (int s = 0; s < g->obstacle_slots; s++) {
    const sylva__obstacle *o = &g->obstacles[s];
    if (o->live && v[0] >= o->lo[0] && v[0] < o->hi[0] && v[1] >= o->lo[1] && v[1] < o->hi[1] &&
        v[2] < o->hi[2])
      return true;
  }
  return false;
}

static double scan_light(const sylva__grid *g, const int v[3]) {
  if (scan_under(g, v)) return 0.0;
  double l = 1.0 - (double)sylva__grid_shade_raw(g, v) / SYLVA__SHADE_ONE;
  return l > 0.0 ? l : 0.0;
}

/* A random box over the grid [0, 20] x [0, 20] x [0, 6]: mostly inside, some
 * across or beyond an edge, some above the top, some thinner than a voxel. */
static void random_box(sylva__rng *r, double mn[3], double mx[3]) {
  double top[3] = {20, 20, 6};
  for (int a = 0; a < 3; a++) {
    mn[a] = -1.0 + (top[a] + 2.0) * sylva__rng_unit(r);
    double side = sylva__rng_below(r, 4) == 0 ? 0.02 : (a < 2 ? 3.0 : 1.0) * sylva__rng_unit(r);
    mx[a] = mn[a] + side + 1e-3;
  }
}

/* A voxel to ask: anywhere, or at a corner of a live obstacle's box, one voxel off
 * or not (where the comparisons are decided). */
static void random_voxel(sylva__rng *r, const sylva__grid *g, int v[3]) {
  const sylva__obstacle *o = NULL;
  if (g->obstacle_count && sylva__rng_below(r, 2))
    o = sylva__grid_obstacle_at(g, (int)sylva__rng_below(r, (uint32_t)g->obstacle_count));
  for (int a = 0; a < 3; a++) {
    int x = (int)sylva__rng_below(r, (uint32_t)g->n[a]);
    if (o) x = (sylva__rng_below(r, 2) ? o->lo[a] : o->hi[a]) - 1 + (int)sylva__rng_below(r, 3);
    v[a] = x < 0 ? 0 : x >= g->n[a] ? g->n[a] - 1 : x;
  }
}

/* The index holds each live obstacle exactly once in each column it overlaps, and
 * nothing else. */
static long index_errors(const sylva__grid *g) {
  long bad = 0, listed = 0, expected = 0;
  size_t ncols = (size_t)g->c[0] * (size_t)g->c[1];
  for (size_t c = 0; g->obstacle_cols && c < ncols; c++)
    if (g->obstacle_cols[c]) {
      listed += g->obstacle_cols[c]->count;
      bad += g->obstacle_cols[c]->count == 0; /* empty lists are freed */
    }
  for (int i = 0; i < g->obstacle_count; i++) {
    const sylva__obstacle *o = sylva__grid_obstacle_at(g, i);
    if (o->hi[0] <= o->lo[0] || o->hi[1] <= o->lo[1]) continue;
    for (int cy = o->lo[1] >> 4; cy <= (o->hi[1] - 1) >> 4; cy++)
      for (int cx = o->lo[0] >> 4; cx <= (o->hi[0] - 1) >> 4; cx++) {
        const sylva__obstacle_list *l = g->obstacle_cols[(size_t)cy * (size_t)g->c[0] + (size_t)cx];
        int found = 0;
        for (int32_t k = 0; l && k < l->count; k++)
          if (l->box[k].id == o->id)
            found += memcmp(l->box[k].lo, o->lo, sizeof o->lo) == 0 &&
                     memcmp(l->box[k].hi, o->hi, sizeof o->hi) == 0;
        bad += found != 1;
        expected++;
      }
  }
  return bad + (listed != expected);
}

/* Blocked, under and light on random voxels, index against scan; the number that
 * differ. */
static long disagreements(sylva__rng *r, const sylva__grid *g, int queries) {
  long bad = 0;
  for (int q = 0; q < queries; q++) {
    int v[3];
    random_voxel(r, g, v);
    bad += sylva__grid_blocked(g, v) != scan_blocked(g, v);
    bad += sylva__grid_under_obstacle(g, v) != scan_under(g, v);
    double l = sylva__grid_light(g, v), expect = scan_light(g, v);
    bad += memcmp(&l, &expect, sizeof l) != 0; /* the same bits */
  }
  return bad;
}

static void test_random_boxes(void) {
  sylva__grid g;
  double mn[3] = {0, 0, 0}, mx[3] = {20, 20, 6};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
  sylva__rng r;
  sylva__rng_seed(&r, 2024);
  /* some shade, so that light is not 1 wherever no obstacle is */
  sylva__pyramid p = {.depth = 8, .column = (int64_t)(0.01 * SYLVA__SHADE_ONE)};
  for (int q = 1; q <= 8; q++) {
    p.w[q - 1] = (int64_t)(pow(1.7, -q) * SYLVA__SHADE_ONE);
    p.half[q - 1] = q;
  }
  for (int i = 0; i < 300; i++) {
    int v[3];
    for (int a = 0; a < 3; a++) v[a] = (int)sylva__rng_below(&r, (uint32_t)g.n[a]);
    CHECK_INT(sylva__grid_stamp(&g, v, &p, +1), 0);
  }
  enum { N = 4000 };
  static int ids[N];
  static char live[N];
  for (int i = 0; i < N; i++) {
    char label[16];
    snprintf(label, sizeof label, "b%d", i);
    double bmn[3], bmx[3];
    random_box(&r, bmn, bmx);
    ids[i] = sylva__grid_add_obstacle(&g, label, bmn, bmx);
    CHECK_INT(ids[i], i);
    live[i] = 1;
  }
  CHECK_INT(g.obstacle_count, N);
  CHECK_INT(index_errors(&g), 0);
  CHECK_INT(disagreements(&r, &g, 20000), 0);
  /* remove three in four in a random order; the dead slots are compacted on the way */
  int32_t perm[N];
  sylva__rng_permutation(&r, perm, N);
  for (int k = 0; k < 3 * N / 4; k++) {
    CHECK_INT(sylva__grid_remove_obstacle(&g, ids[perm[k]]), 0);
    live[perm[k]] = 0;
    if (k == N / 3) { /* with dead slots waiting */
      CHECK(g.obstacle_slots > g.obstacle_count);
      CHECK_INT(index_errors(&g), 0);
      CHECK_INT(disagreements(&r, &g, 20000), 0);
    }
  }
  CHECK_INT(g.obstacle_count, N / 4);
  CHECK_INT(index_errors(&g), 0);
  CHECK_INT(disagreements(&r, &g, 20000), 0);
  /* the survivors in the order they were added, found by label; the removed gone */
  long order = 0, labels = 0;
  for (int i = 0, k = 0; i < N; i++) {
    char label[16];
    snprintf(label, sizeof label, "b%d", i);
    if (live[i]) order += k >= g.obstacle_count || sylva__grid_obstacle_at(&g, k++)->id != ids[i];
    labels += sylva__grid_find_obstacle(&g, label) != (live[i] ? ids[i] : SYLVA_ENOTFOUND);
    if (!live[i]) labels += sylva__grid_remove_obstacle(&g, ids[i]) != SYLVA_ENOTFOUND;
    double bmn[3] = {1, 1, 1}, bmx[3] = {2, 2, 2};
    if (live[i] && i % 7 == 0) /* still in use */
      labels += sylva__grid_add_obstacle(&g, label, bmn, bmx) != SYLVA_EINVAL;
  }
  CHECK_INT(order, 0);
  CHECK_INT(labels, 0);
  /* removed labels may be used again; the new boxes come last */
  for (int i = 0; i < N; i += 3)
    if (!live[i]) {
      char label[16];
      snprintf(label, sizeof label, "b%d", i);
      double bmn[3], bmx[3];
      random_box(&r, bmn, bmx);
      int id = sylva__grid_add_obstacle(&g, label, bmn, bmx);
      CHECK(id >= N);
      CHECK_INT(sylva__grid_find_obstacle(&g, label), id);
      CHECK_INT(sylva__grid_obstacle_at(&g, g.obstacle_count - 1)->id, id);
    }
  CHECK_INT(index_errors(&g), 0);
  CHECK_INT(disagreements(&r, &g, 20000), 0);
  /* all gone: no list left, light as without obstacles */
  while (g.obstacle_count)
    CHECK_INT(sylva__grid_remove_obstacle(&g, sylva__grid_obstacle_at(&g, 0)->id), 0);
  CHECK_INT(g.obstacle_list_bytes, 0);
  CHECK_INT(index_errors(&g), 0);
  CHECK_INT(disagreements(&r, &g, 20000), 0);
  sylva__grid_free(&g);
}

static void test_many(void) {
  sylva__grid g;
  double mn[3] = {0, 0, 0}, mx[3] = {100, 100, 10};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
  sylva__rng r;
  sylva__rng_seed(&r, 5);
  enum { N = 100000 };
  static int ids[N];
  long bad = 0;
  for (int i = 0; i < N; i++) {
    char label[16];
    snprintf(label, sizeof label, "o%d", i);
    double bmn[3], bmx[3];
    for (int a = 0; a < 3; a++) {
      bmn[a] = (a < 2 ? 99.0 : 9.0) * sylva__rng_unit(&r);
      bmx[a] = bmn[a] + 0.01 + 0.5 * sylva__rng_unit(&r);
    }
    ids[i] = sylva__grid_add_obstacle(&g, label, bmn, bmx);
    bad += ids[i] != i;
  }
  CHECK_INT(bad, 0);
  CHECK_INT(g.obstacle_count, N);
  /* every label found; a label in use refused, with nothing added */
  bad = 0;
  for (int i = 0; i < N; i++) {
    char label[16];
    snprintf(label, sizeof label, "o%d", i);
    bad += sylva__grid_find_obstacle(&g, label) != ids[i];
  }
  CHECK_INT(bad, 0);
  double bmn[3] = {1, 1, 1}, bmx[3] = {2, 2, 2};
  CHECK_INT(sylva__grid_add_obstacle(&g, "o0", bmn, bmx), SYLVA_EINVAL);
  CHECK_INT(sylva__grid_add_obstacle(&g, "o99999", bmn, bmx), SYLVA_EINVAL);
  CHECK_INT(sylva__grid_find_obstacle(&g, "o100000"), SYLVA_ENOTFOUND);
  CHECK_INT(g.obstacle_count, N);
  /* removed by id, the oldest first; the rest keep their order */
  bad = 0;
  for (int i = 0; i < N; i++) {
    bad += sylva__grid_remove_obstacle(&g, ids[i]) != SYLVA_OK;
    if (i % 9973 == 0 && g.obstacle_count) {
      bad += sylva__grid_obstacle_at(&g, 0)->id != ids[i + 1];
      int half = g.obstacle_count / 2;
      bad += sylva__grid_obstacle_at(&g, half)->id != ids[i + 1 + half];
      bad += sylva__grid_obstacle_at(&g, g.obstacle_count - 1)->id != ids[N - 1];
      bad += sylva__grid_find_obstacle(&g, "o0") != SYLVA_ENOTFOUND;
    }
  }
  CHECK_INT(bad, 0);
  CHECK_INT(g.obstacle_count, 0);
  CHECK_INT(sylva__grid_remove_obstacle(&g, ids[N / 2]), SYLVA_ENOTFOUND);
  CHECK_INT(g.obstacle_list_bytes, 0);
  /* a few obstacles churning in the large table: each removal may compact */
  bad = 0;
  for (int i = 0; i < 20000; i++) {
    char label[16];
    snprintf(label, sizeof label, "c%d", i);
    ids[i] = sylva__grid_add_obstacle(&g, label, bmn, bmx);
    if (i >= 3) bad += sylva__grid_remove_obstacle(&g, ids[i - 3]) != SYLVA_OK;
  }
  CHECK_INT(bad, 0);
  CHECK_INT(g.obstacle_count, 3);
  for (int k = 0; k < 3; k++) {
    char label[16];
    snprintf(label, sizeof label, "c%d", 19997 + k);
    CHECK_INT(sylva__grid_obstacle_at(&g, k)->id, ids[19997 + k]);
    CHECK_INT(sylva__grid_find_obstacle(&g, label), ids[19997 + k]);
  }
  CHECK_INT(sylva__grid_find_obstacle(&g, "c19996"), SYLVA_ENOTFOUND);
  sylva__grid_free(&g);
}

/* An allocator that fails the allocation `allocations_left` calls from now (-1:
 * never). */
static long allocations_left = -1;
static bool failing(void) { return allocations_left >= 0 && allocations_left-- == 0; }
static void *test_malloc(size_t n, void *ctx) {
  (void)ctx;
  return failing() ? NULL : malloc(n);
}
static void *test_realloc(void *block, size_t n, void *ctx) {
  (void)ctx;
  return failing() ? NULL : realloc(block, n);
}
static void test_free(void *block, void *ctx) {
  (void)ctx;
  free(block);
}

/* What the obstacles answer over the region 0..4 m: blocked and under per voxel. */
static uint64_t answers(const sylva__grid *g) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (int z = 0; z < g->n[2]; z += 3)
    for (int y = 0; y < 80; y++)
      for (int x = 0; x < 80; x++) {
        int v[3] = {x, y, z};
        unsigned bits = sylva__grid_blocked(g, v) | (unsigned)sylva__grid_under_obstacle(g, v) << 1;
        h = (h ^ bits) * 0x100000001b3ULL;
      }
  return h;
}

/* Adds a box, failing first its first allocation, then its second, and so on until it
 * succeeds (what a failed attempt grew, the next one finds); after each failure the
 * grid answers as before. The number of failures. */
static int add_failing(sylva__grid *g, const char *label, const double mn[3], const double mx[3]) {
  uint64_t before = answers(g);
  int count = g->obstacle_count, next = g->next_obstacle_id;
  for (int k = 0;; k++) {
    allocations_left = k;
    int rc = sylva__grid_add_obstacle(g, label, mn, mx);
    allocations_left = -1;
    if (rc >= 0) {
      CHECK_INT(rc, next);
      return k;
    }
    CHECK_INT(rc, SYLVA_ENOMEM);
    CHECK_INT(g->obstacle_count, count);
    CHECK_INT(g->next_obstacle_id, next);
    CHECK_INT(sylva__grid_find_obstacle(g, label), SYLVA_ENOTFOUND);
    CHECK_INT(index_errors(g), 0);
    CHECK(answers(g) == before);
  }
}

static void test_out_of_memory(void) {
  sylva_allocator a = {test_malloc, test_realloc, test_free, NULL};
  CHECK_INT(sylva_set_allocator(&a), 0);
  sylva__grid g;
  double mn[3] = {0, 0, 0}, mx[3] = {20, 20, 6};
  CHECK_INT(sylva__grid_init(&g, mn, mx, 0.05), 0);
  /* the first: the slots, ranks, label table, column table and one list */
  double bmn[3] = {0.1, 0.1, 1.0}, bmx[3] = {0.2, 0.2, 1.1};
  CHECK(add_failing(&g, "a0", bmn, bmx) >= 3);
  /* three more over the same column fill its list; four elsewhere fill the slots */
  for (int i = 1; i < 8; i++) {
    char label[16];
    snprintf(label, sizeof label, "a%d", i);
    double off = i < 4 ? 0.1 * i : 1.0 * i;
    double omn[3] = {off, off, 1.0 + 0.1 * i}, omx[3] = {off + 0.1, off + 0.1, 1.2 + 0.1 * i};
    add_failing(&g, label, omn, omx);
  }
  CHECK_INT(g.obstacle_slots, g.obstacle_cap);
  /* then one over 4 x 4 columns: the slots, ranks and label table grow, the full list
   * grows and fifteen lists are made, each of which fails once at least */
  double big_mn[3] = {0.05, 0.05, 2.0}, big_mx[3] = {3.1, 3.1, 2.5};
  CHECK(add_failing(&g, "big", big_mn, big_mx) >= 15);
  CHECK(sylva__grid_blocked(&g, (int[3]){50, 50, 45}));
  CHECK(sylva__grid_under_obstacle(&g, (int[3]){60, 2, 0}));
  CHECK_INT(disagreements(&(sylva__rng){{1, 2, 3, 4}}, &g, 20000), 0);
  sylva__grid_free(&g);
  CHECK_INT(sylva_set_allocator(NULL), 0);
}

static int add_box(sylva_world *w, const char *label, double x, double y, double z) {
  sylva_obstacle_def o = {label, {x, y, z}, {x + 0.7, y + 0.4, z + 0.1}, SYLVA_OBSTACLE_SOLID, {0}};
  return sylva_world_add_obstacle(w, &o);
}

/* A world whose obstacles were partly removed saves the same image as its loaded
 * copy; the copy finds, refuses, lights and removes like the original. */
static void test_snapshot(void) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w = NULL, *copy = NULL;
  CHECK_INT(sylva_world_create(&wd, &w), 0);
  if (!w) return;
  enum { N = 60 };
  int ids[N];
  for (int i = 0; i < N; i++) {
    char label[16];
    snprintf(label, sizeof label, "board%d", i);
    ids[i] = add_box(w, label, -4.0 + 0.13 * i, -3.0 + 0.1 * i, 0.5 + 0.05 * i);
    CHECK_INT(ids[i], i);
  }
  for (int i = 0; i < N; i += 3) CHECK_INT(sylva_world_remove_obstacle(w, ids[i]), 0);
  CHECK_INT(sylva_world_obstacle_count(w), N - N / 3);
  uint8_t *image = NULL, *again = NULL;
  size_t size = 0, again_size = 0;
  CHECK_INT(sylva_snapshot_save(w, &image, &size), 0);
  CHECK_INT(sylva_snapshot_load(image, size, &copy), 0);
  if (!copy) {
    sylva_free(image);
    sylva_world_destroy(w);
    return;
  }
  CHECK_INT(sylva_snapshot_save(copy, &again, &again_size), 0);
  CHECK(again_size == size && memcmp(image, again, size) == 0);
  CHECK(sylva_world_hash(copy) == sylva_world_hash(w));
  CHECK_INT(sylva_world_obstacle_count(copy), sylva_world_obstacle_count(w));
  long bad = 0;
  for (int i = 0; i < sylva_world_obstacle_count(w); i++) {
    int a = -1, b = -2;
    sylva_obstacle_def oa, ob;
    sylva_world_obstacle_at(w, i, &a, &oa);
    sylva_world_obstacle_at(copy, i, &b, &ob);
    bad += a != b || strcmp(oa.label, ob.label) != 0;
    bad += sylva_world_find_obstacle(copy, oa.label) != a;
  }
  CHECK_INT(bad, 0);
  CHECK_INT(sylva_world_find_obstacle(copy, "board0"), SYLVA_ENOTFOUND);
  CHECK_INT(add_box(copy, "board1", 0, 0, 1), SYLVA_EINVAL); /* still in use */
  CHECK_INT(add_box(copy, "board0", 0, 0, 1), N);          /* freed, and the next id */
  /* the same light everywhere on a grid of points through the boards */
  bad = 0;
  CHECK_INT(sylva_world_remove_obstacle(copy, N), 0);
  for (double x = -4.5; x < 4.5; x += 0.037)
    for (double y = -3.5; y < 3.5; y += 0.041) {
      double p[3] = {x, y, 0.5 + 0.5 * fabs(x)};
      double a = sylva_world_light_at(w, p), b = sylva_world_light_at(copy, p);
      bad += memcmp(&a, &b, sizeof a) != 0;
    }
  CHECK_INT(bad, 0);
  CHECK_INT(sylva_world_remove_obstacle(copy, ids[1]), 0);
  CHECK_INT(sylva_world_remove_obstacle(copy, ids[1]), SYLVA_ENOTFOUND);
  CHECK_INT(sylva_world_remove_obstacle(copy, ids[0]), SYLVA_ENOTFOUND);
  sylva_free(image);
  sylva_free(again);
  sylva_world_destroy(copy);
  sylva_world_destroy(w);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {CHECK_TEST(random_boxes), CHECK_TEST(many),
                                     CHECK_TEST(out_of_memory), CHECK_TEST(snapshot)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("obstacles");
}
