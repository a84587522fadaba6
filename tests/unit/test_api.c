/* The public API's contract for bad ids (a negative status or NULL, and nothing
 * changes), the species field list (sylva/species_fields.h): its defaults, its
 * ranges as sylva_species_check applies them, and a snapshot that keeps every field;
 * each stem's leaf_area against its leaf-bearing nodes; the light kept between steps,
 * dropped by every change; a busy pool's loop run on its caller; and, in debug builds, the phase checks that stop a step on
 * a broken invariant. */
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../check.h"
#include "pool.h"
#include "sylva/sylva.h"
#include "world_impl.h"

static sylva_world *small_world(void) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w = NULL;
  if (sylva_world_create(&wd, &w)) return NULL;
  sylva_species_def sp = sylva_default_species_def();
  int s = sylva_world_add_species(w, &sp, "oak");
  double roots[2][3] = {{0, 0, 0}, {1, 0, 0}};
  sylva_plant_def pd = {s, "shrub", (const double(*)[3])roots, 2, 0, NULL, 0};
  sylva_obstacle_def wall = {"wall", {2, -1, 0}, {2.2, 1, 2}, SYLVA_OBSTACLE_SOLID, {0}};
  if (s < 0 || sylva_world_add_plant(w, &pd, NULL) < 0 || sylva_world_add_obstacle(w, &wall) < 0) {
    sylva_world_destroy(w);
    return NULL;
  }
  return w;
}

static void test_bad_ids(void) {
  sylva_world *w = small_world();
  CHECK(w != NULL);
  if (!w) return;
  CHECK_INT(sylva_world_step(w, NULL), 0);
  uint64_t h = sylva_world_hash(w);
  int bad[] = {-1, 1, 2, 1000000, -2147483647 - 1};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    int id = bad[i];
    CHECK(sylva_world_species(w, id) == NULL);
    CHECK(sylva_world_species_label(w, id) == NULL);
    CHECK(sylva_world_plant_label(w, id) == NULL);
    CHECK_INT(sylva_world_plant_species(w, id), SYLVA_ENOTFOUND);
    CHECK_INT(sylva_world_plant_stem_count(w, id), SYLVA_ENOTFOUND);
    CHECK_INT(sylva_world_stem_index(w, id, 0), SYLVA_ENOTFOUND);
    CHECK_INT(sylva_world_remove_obstacle(w, id), SYLVA_ENOTFOUND);
    sylva_obstacle_def o = {0};
    int oid = 77;
    CHECK_INT(sylva_world_obstacle_at(w, id, &oid, &o), SYLVA_ENOTFOUND);
    CHECK(oid == 77 && o.label == NULL);
    double plant_root[1][3] = {{-2, -2, 0}};
    sylva_plant_def pd = {id, "late", (const double(*)[3])plant_root, 1, 0, NULL, 0};
    CHECK(sylva_world_add_plant(w, &pd, NULL) < 0);
  }
  /* stems: 0 and 1 exist (the shrub's two roots) */
  int bad_stems[] = {-1, 2, 99};
  for (size_t i = 0; i < sizeof bad_stems / sizeof bad_stems[0]; i++) {
    int stem = bad_stems[i];
    CHECK_INT(sylva_world_stem_index(w, 0, stem), SYLVA_ENOTFOUND);
    double root[3] = {7, 7, 7};
    CHECK_INT(sylva_world_stem_root(w, stem, root), SYLVA_ENOTFOUND);
    CHECK(root[0] == 7 && root[1] == 7 && root[2] == 7);
    sylva_stem_stats st = {.plant = 42};
    CHECK_INT(sylva_world_stem_stats(w, stem, &st), SYLVA_ENOTFOUND);
    CHECK_INT(st.plant, 42);
  }
  sylva_node_info ni = {.id = 42};
  CHECK_INT(sylva_world_node_at(w, sylva_world_node_count(w), &ni), SYLVA_ENOTFOUND);
  CHECK_INT(sylva_world_node_at(w, (size_t)-1, &ni), SYLVA_ENOTFOUND);
  CHECK_INT(ni.id, 42);
  /* the good ones still answer */
  CHECK(sylva_world_species(w, 0) != NULL && strcmp(sylva_world_species_label(w, 0), "oak") == 0);
  CHECK_INT(sylva_world_stem_index(w, 0, 1), 1);
  double root[3];
  CHECK_INT(sylva_world_stem_root(w, 1, root), 0);
  CHECK(root[0] == 1);
  CHECK_INT(sylva_world_node_at(w, 0, &ni), 0);
  CHECK_INT(ni.parent, -1);
  /* a node's index by its id, for every node; no index for an id no node has */
  for (size_t i = 0; i < sylva_world_node_count(w); i++) {
    sylva_node_info at;
    sylva_world_node_at(w, i, &at);
    CHECK_INT(sylva_world_node_index(w, at.id), (int64_t)i);
  }
  CHECK_INT(sylva_world_node_index(w, -1), SYLVA_ENOTFOUND);
  CHECK_INT(sylva_world_node_index(w, 1 << 30), SYLVA_ENOTFOUND);
  CHECK(sylva_world_hash(w) == h); /* nothing changed */
  sylva_world_destroy(w);
}

/* Checks def with one field set to v (an int field when is_int): accepted when ok,
 * else refused with the name reported. */
static void check_value(const char *name, const char *reported, sylva_species_def def,
                        size_t offset, bool is_int, double v, bool ok) {
  char *at = (char *)&def + offset;
  if (is_int) {
    int iv = (int)v;
    memcpy(at, &iv, sizeof iv);
  } else {
    memcpy(at, &v, sizeof v);
  }
  const char *field = NULL;
  int rc = sylva_species_check(&def, &field);
  bool as_expected = ok ? rc == 0 : rc == SYLVA_ERANGE && field && strcmp(field, reported) == 0;
  if (!as_expected)
    fprintf(stderr, "%s = %.17g: status %d, field %s\n", name, v, rc, field ? field : "(none)");
  CHECK(as_expected);
}

/* Each listed field: the default is the list's; the check takes min and max unless
 * they are excluded, refuses what lies just outside, and names the field (markers
 * for the marker keys). */
#define IS_INT_double false
#define IS_INT_int true
#define REPORTED_species(name) #name
#define REPORTED_markers(name) "markers"
/* bad_root is optional: a measured plant added without it, good and bad. */
static void test_measured_without_bad_root(void) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&wd, &w), 0);
  sylva_species_def d = sylva_default_species_def();
  int sp = sylva_world_add_species(w, &d, "s");
  sylva_plant_node nodes[2] = {{.p = {0, 0, 0}, .radius = 0.01, .parent = -1},
                               {.p = {0, 0, 0.1}, .radius = 0.01, .parent = 0}};
  sylva_plant_def pd = {.species = sp, .label = "m", .nodes = nodes, .node_count = 2};
  CHECK_INT(sylva_world_add_plant(w, &pd, NULL), 0);
  nodes[1].parent = 1; /* its own parent */
  pd.label = "n";
  CHECK(sylva_world_add_plant(w, &pd, NULL) < 0);
  CHECK_INT(sylva_world_plant_count(w), 1);
  sylva_world_destroy(w);
}

static void test_species_fields(void) {
  const sylva_species_def def = sylva_default_species_def();
  CHECK_INT(sylva_species_check(&def, NULL), 0);
  /* the rules between fields (b_max >= b_min, m_min <= m0) kept out of the way */
  sylva_species_def base = def;
  base.b_max = 1000, base.m0 = 1000, base.m_min = 0;
#define FIELD(name, type, dflt, lo, hi, bounds, group, snap)                            \
  {                                                                                     \
    CHECK(def.name == (type)(dflt));                                                    \
    bool is_int = IS_INT_##type;                                                        \
    bool lo_in = !((bounds) & SYLVA_FIELD_MIN_EXCLUSIVE);                               \
    bool hi_in = !((bounds) & SYLVA_FIELD_MAX_EXCLUSIVE);                               \
    double step = is_int ? 1.0 : 1e-9 * (1.0 + fabs((double)(hi)));                     \
    size_t at = offsetof(sylva_species_def, name);                                      \
    const char *reported = REPORTED_##group(name);                                      \
    check_value(#name, reported, base, at, is_int, lo, lo_in);                          \
    check_value(#name, reported, base, at, is_int, hi, hi_in);                          \
    check_value(#name, reported, base, at, is_int, (double)(lo) - step, false);         \
    check_value(#name, reported, base, at, is_int, (double)(hi) + step, false);         \
  }
  SYLVA_SPECIES_FIELDS(FIELD)
#undef FIELD
  /* doubles must be finite */
  check_value("rho", "rho", def, offsetof(sylva_species_def, rho), false, NAN, false);
  check_value("shade_column", "shade_column", def, offsetof(sylva_species_def, shade_column),
              false, INFINITY, false);
  /* the rules the list leaves to hand-written checks */
  check_value("b_max", "b_max", def, offsetof(sylva_species_def, b_max), false, def.b_min - 0.1,
              false);
  check_value("m_min", "markers", def, offsetof(sylva_species_def, m_min), true, def.m0 + 1,
              false);
  check_value("tropism", "tropism", def, offsetof(sylva_species_def, tropism[1]), false, 1001,
              false);
}
#undef IS_INT_double
#undef IS_INT_int
#undef REPORTED_species
#undef REPORTED_markers

/* w saved to a snapshot image and loaded again (NULL if either failed). */
static sylva_world *snapshot_copy(const sylva_world *w) {
  uint8_t *img = NULL;
  size_t n = 0;
  sylva_world *r = NULL;
  CHECK_INT(sylva_snapshot_save(w, &img, &n), 0);
  if (img) CHECK_INT(sylva_snapshot_load(img, n, &r), 0);
  sylva_free(img);
  return r;
}

/* A species whose every field differs from the default survives a snapshot. */
static void test_species_snapshot(void) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&wd, &w), 0);
  sylva_species_def d = sylva_default_species_def();
#define SHIFT(name, type, dflt, lo, hi, bounds, group, snap) \
  d.name = (type)((lo) + ((hi) - (lo)) * (0.25 + 0.01 * (snap)));
  SYLVA_SPECIES_FIELDS(SHIFT)
#undef SHIFT
  d.b_max = d.b_min + 0.5;
  d.m0 = d.m_min + 3;
  d.growth = (sylva_equation){SYLVA_EQ_GOMPERTZ, {50.0, 3.5, 0.25}};
  d.allocation = SYLVA_ALLOC_NONE;
  d.tropism[0] = 0.1, d.tropism[1] = -0.2, d.tropism[2] = 0.7;
  CHECK_INT(sylva_species_check(&d, NULL), 0);
  CHECK_INT(sylva_world_add_species(w, &d, "odd"), 0);
  sylva_world *r = snapshot_copy(w);
  if (r) {
    const sylva_species_def *e = sylva_world_species(r, 0);
    CHECK(e != NULL);
#define SAME(name, type, dflt, lo, hi, bounds, group, snap) \
  if (e) CHECK(e->name == d.name);
    SYLVA_SPECIES_FIELDS(SAME)
#undef SAME
    if (e) {
      CHECK(e->growth.kind == d.growth.kind && e->allocation == d.allocation);
      CHECK(memcmp(e->growth.p, d.growth.p, sizeof d.growth.p) == 0);
      CHECK(memcmp(e->tropism, d.tropism, sizeof d.tropism) == 0);
    }
  }
  sylva_world_destroy(r);
  sylva_world_destroy(w);
}

/* Heartwood alone sets the image's WOOD flag (32) with the three it implies, a
 * lateral reach the REACH flag (64) with all four, a wood density or biomass
 * allometry the CARBON flag (128) with all five; their places are read back; an
 * image with WOOD but not FOLIAGE, REACH but not WOOD, or CARBON but not REACH is
 * refused. A species without them keeps its images' flags. */
static void test_heartwood_snapshot(void) {
  for (int pass = 0; pass < 4; pass++) {
    sylva_world_def wd = sylva_default_world_def();
    sylva_world *w = NULL;
    CHECK_INT(sylva_world_create(&wd, &w), 0);
    sylva_species_def d = sylva_default_species_def();
    d.heartwood = pass == 1 ? 0.05 : 0.0;
    d.lateral_reach = pass == 2 ? 1.5 : 1.0;
    if (pass == 3) {
      d.wood_density = 520;
      d.biomass_form = 3;
      d.biomass_a = 0.113, d.biomass_b = 2.4572, d.biomass_c = 0.5;
      d.biomass_p = -4.0813, d.biomass_q = 5.8816, d.biomass_factor = 0.8;
    }
    CHECK_INT(sylva_world_add_species(w, &d, "h"), 0);
    uint8_t *img = NULL;
    size_t n = 0;
    CHECK_INT(sylva_snapshot_save(w, &img, &n), 0);
    if (img) {
      CHECK_INT(img[12], pass == 3   ? 4 | 8 | 16 | 32 | 64 | 128
                         : pass == 2 ? 4 | 8 | 16 | 32 | 64
                         : pass      ? 4 | 8 | 16 | 32
                                     : 0);
      sylva_world *r = NULL;
      CHECK_INT(sylva_snapshot_load(img, n, &r), 0);
      const sylva_species_def *e = r ? sylva_world_species(r, 0) : NULL;
      CHECK(e && e->heartwood == d.heartwood && e->lateral_reach == d.lateral_reach);
      CHECK(e && e->wood_density == d.wood_density && e->biomass_form == d.biomass_form &&
            e->biomass_a == d.biomass_a && e->biomass_b == d.biomass_b &&
            e->biomass_c == d.biomass_c && e->biomass_p == d.biomass_p &&
            e->biomass_q == d.biomass_q && e->biomass_factor == d.biomass_factor);
      sylva_world_destroy(r);
      if (pass) {
        img[12] &= (uint8_t)~(pass == 3 ? 64u : pass == 2 ? 32u : 16u);
        CHECK_INT(sylva_snapshot_load(img, n, &r), SYLVA_EBADIMAGE);
      }
    }
    sylva_free(img);
    sylva_world_destroy(w);
  }
}

/* Checks every stem's leaf_area against its nodes: leaf-bearing nodes (those whose
 * `leaves` is not 0, each with its species' leaf_density) x leaf_density x
 * SYLVA_LEAF_FILL x leaf_size^2; for a species without years a node bears leaves
 * exactly while the next iteration's age is at most leaf_age (docs/model.md,
 * "Foliage"). Returns the leaf-bearing nodes counted. */
static size_t check_leaf_area(const sylva_world *w) {
  enum { STEMS = 3 };
  size_t leafy[STEMS] = {0}, counted = 0;
  int iteration = sylva_world_iteration(w);
  CHECK_INT(sylva_world_stem_count(w), STEMS);
  for (size_t i = 0; i < sylva_world_node_count(w); i++) {
    sylva_node_info n;
    CHECK_INT(sylva_world_node_at(w, i, &n), 0);
    int k = sylva_world_stem_index(w, n.plant, n.stem);
    if (k < 0 || k >= STEMS) continue;
    const sylva_species_def *d = sylva_world_species(w, sylva_world_plant_species(w, n.plant));
    if (!d) continue;
    CHECK(n.leaves == 0 || n.leaves == d->leaf_density);
    if (!d->years) CHECK((n.leaves != 0) == (iteration + 1 - n.birth <= d->leaf_age));
    if (n.leaves) leafy[k]++, counted++;
  }
  for (int k = 0; k < STEMS; k++) {
    sylva_stem_stats st;
    CHECK_INT(sylva_world_stem_stats(w, k, &st), 0);
    const sylva_species_def *d = sylva_world_species(w, sylva_world_plant_species(w, st.plant));
    if (!d) continue;
    double want = (double)leafy[k] * d->leaf_density * SYLVA_LEAF_FILL * d->leaf_size * d->leaf_size;
    CHECK(fabs(st.leaf_area - want) <= 1e-12 * want);
    if (fabs(st.leaf_area - want) > 1e-12 * want)
      fprintf(stderr, "iteration %d stem %d: leaf_area %.17g, %zu leaf-bearing nodes give %.17g\n",
              iteration, k, st.leaf_area, leafy[k], want);
  }
  return counted;
}

/* leaf_area, every iteration of a shrub of the default species and a tree of a
 * species in years with its own foliage, and in a world read back from a snapshot. */
static void test_leaf_area(void) {
  sylva_world *w = small_world();
  CHECK(w != NULL);
  if (!w) return;
  sylva_species_def big = sylva_default_species_def();
  big.years = 1;
  big.leaf_size = 0.3;
  big.leaf_density = 4;
  big.leaf_colour = 0x2d5047;
  double root[1][3] = {{-1, 1, 0}};
  sylva_plant_def tree = {sylva_world_add_species(w, &big, "pine"), "tree",
                          (const double(*)[3])root, 1, 0, NULL, 0};
  CHECK(sylva_world_add_plant(w, &tree, NULL) >= 0);
  size_t counted = 0;
  for (int t = 1; t <= 14; t++) {
    CHECK_INT(sylva_world_step(w, NULL), 0);
    counted += check_leaf_area(w);
  }
  CHECK(counted > 0);
  sylva_world *r = snapshot_copy(w);
  if (r) {
    check_leaf_area(r);
    for (int k = 0; k < 3; k++) {
      sylva_stem_stats a, b;
      CHECK_INT(sylva_world_stem_stats(w, k, &a), 0);
      CHECK_INT(sylva_world_stem_stats(r, k, &b), 0);
      CHECK(a.leaf_area == b.leaf_area);
    }
  }
  sylva_world_destroy(r);
  sylva_world_destroy(w);
}

#ifndef NDEBUG
/* Breaks one invariant of a grown world in a child process and steps it: the phase
 * checks must abort the child. */
static void expect_abort(const char *what, void (*breaks)(sylva_world *)) {
  fflush(NULL);
  pid_t pid = fork();
  if (pid == 0) {
    freopen("/dev/null", "w", stderr);
    sylva_world *w = small_world();
    if (!w || sylva_world_step(w, NULL) != 0) _exit(2);
    breaks(w);
    sylva_world_step(w, NULL);
    _exit(0);
  }
  int status = 0;
  CHECK(pid > 0 && waitpid(pid, &status, 0) == pid);
  bool aborted = WIFSIGNALED(status) && WTERMSIG(status) == SIGABRT;
  if (!aborted) fprintf(stderr, "%s: the step was not stopped (status %d)\n", what, status);
  CHECK(aborted);
}

static void parent_after_child(sylva_world *w) { w->nodes.parent[1] = 2; }
static void live_count_off(sylva_world *w) { w->nodes.live--; }
static void doomed_left_on(sylva_world *w) { w->nodes.flags[2] |= SYLVA__NODE_DOOMED; }
static void link_one_way(sylva_world *w) { w->nodes.axis_child[0] = -1; }
static void occupancy_lost(sylva_world *w) {
  int v[3];
  sylva__node_voxel(w, 1, v);
  sylva__grid_vacate(&w->grid, v);
}

static void test_phase_checks(void) {
  expect_abort("a parent after its child", parent_after_child);
  expect_abort("a live count off by one", live_count_off);
  expect_abort("a transient flag left on", doomed_left_on);
  expect_abort("a link one way", link_one_way);
  expect_abort("a node without its voxel", occupancy_lost);
}
#endif

/* The world hash's definitions (docs/store.md, "The world hash"): hash 2 is the same
 * for a world on 1 and 3 threads and for its snapshot image loaded again; it sees
 * one node's radius; an unknown definition gives 0; both give the values pinned.
 * The shrubs are grown until they hold more slots than one piece of hash 2 (4,096). */
static void test_world_hash_versions(void) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&wd, &w), 0);
  if (!w) return;
  sylva_species_def sp = sylva_default_species_def();
  int s = sylva_world_add_species(w, &sp, "oak");
  double roots[6][3] = {{-2, -2, 0}, {0, -2, 0}, {2, -2, 0}, {-2, 2, 0}, {0, 2, 0}, {2, 2, 0}};
  sylva_plant_def pd = {s, "shrubs", (const double(*)[3])roots, 6, 0, NULL, 0};
  CHECK(s >= 0 && sylva_world_add_plant(w, &pd, NULL) >= 0);
  while (w->nodes.count <= 3 * 4096 && !sylva_world_finished(w))
    CHECK_INT(sylva_world_step(w, NULL), 0);
  CHECK(w->nodes.count > 3 * 4096);
  uint64_t h1 = sylva_world_hash_of(w, 1), h2 = sylva_world_hash_of(w, 2);
  /* the definitions pinned: stores keep these hashes, and restores of them in later
   * builds compare against them (a change of the model changes them with the golden
   * hashes; a change of a definition must be a new version) */
  CHECK(h1 == 0x055c94dd4f0a70dfULL && h2 == 0x8ffc766b5367dce9ULL);
  CHECK(h1 == sylva_world_hash(w) && h2 != h1 && h2 != 0);
  CHECK(sylva_world_hash_of(w, 0) == 0 && sylva_world_hash_of(w, 3) == 0);
  CHECK_INT(sylva_world_set_threads(w, 3), 0);
  CHECK(sylva_world_hash_of(w, 2) == h2 && sylva_world_hash_of(w, 1) == h1);
  uint8_t *img = NULL;
  size_t n = 0;
  sylva_world *r = NULL;
  CHECK_INT(sylva_snapshot_save(w, &img, &n), 0);
  if (img) CHECK_INT(sylva_snapshot_load(img, n, &r), 0);
  CHECK(r && sylva_world_hash_of(r, 2) == h2);
  free(img);
  sylva_world_destroy(r);
  w->nodes.radius[w->nodes.count - 1] *= 1.5f;
  CHECK(sylva_world_hash_of(w, 2) != h2 && sylva_world_hash_of(w, 1) != h1);
  sylva_world_destroy(w);
}

/* The light kept from one step's shedding for the next step's light phase
 * (docs/performance.md, "The light kept"): a change between the steps drops it. Each
 * edit is made to a world that keeps a pass and to its copy through a snapshot (which
 * keeps none, so its next step reads the grid); the two then grow the same world. */
typedef struct kept_edit {
  const char *what;
  int64_t (*edit)(sylva_world *w, int round);
} kept_edit;

static int64_t edit_roof(sylva_world *w, int round) {
  char label[32];
  snprintf(label, sizeof label, "roof%d", round);
  /* over the shrub's first stem, not its second (roots at x = 0 and 1) */
  sylva_obstacle_def roof = {label, {-5, -5, 11.0}, {0.5, 5, 11.2}, SYLVA_OBSTACLE_SOLID, {0}};
  return sylva_world_add_obstacle(w, &roof);
}

static int64_t edit_unroof(sylva_world *w, int round) {
  char label[32];
  snprintf(label, sizeof label, "roof%d", round - 1);
  int id = sylva_world_find_obstacle(w, label);
  return id < 0 ? id : sylva_world_remove_obstacle(w, id);
}

static int64_t edit_plant(sylva_world *w, int round) {
  double root[1][3] = {{-1.0 - 0.5 * round, 0.5, 0}};
  char label[32];
  snprintf(label, sizeof label, "late%d", round);
  sylva_plant_def pd = {0, label, (const double(*)[3])root, 1, 0, NULL, 0};
  return sylva_world_add_plant(w, &pd, NULL);
}

static int64_t edit_prune(sylva_world *w, int round) {
  (void)round;
  double lo[3] = {0.3, -5, 0.3}, hi[3] = {5, 5, 12};
  return sylva_world_prune(w, lo, hi, NULL, NULL);
}

static void test_light_kept(void) {
  static const kept_edit edits[] = {{"an obstacle added", edit_roof},
                                    {"an obstacle removed", edit_unroof},
                                    {"a plant added", edit_plant},
                                    {"a prune", edit_prune}};
  for (int round = 0; round < 4; round++) {
    const kept_edit *e = &edits[round];
    sylva_world *w = small_world();
    CHECK(w != NULL);
    if (!w) return;
    if (round == 1) CHECK(edit_roof(w, 0) >= 0); /* the roof the edit takes away */
    /* on to a step that shed, and so kept its last pass for the next */
    for (int k = 0; k < 12 && w->light_at != sylva_world_iteration(w) + 1; k++)
      CHECK_INT(sylva_world_step(w, NULL), 0);
    CHECK_INT(w->light_at, sylva_world_iteration(w) + 1);
    sylva_world *copy = snapshot_copy(w);
    if (!copy) {
      sylva_world_destroy(w);
      return;
    }
    CHECK_INT(copy->light_at, 0);
    int64_t a = e->edit(w, round), b = e->edit(copy, round);
    CHECK(a >= 0 && a == b);
    CHECK_INT(w->light_at, 0);
    for (int k = 0; k < 2; k++) {
      CHECK_INT(sylva_world_step(w, NULL), 0);
      CHECK_INT(sylva_world_step(copy, NULL), 0);
      if (sylva_world_hash(w) != sylva_world_hash(copy)) {
        fprintf(stderr, "light kept: after %s, step %d differs from the world that kept none\n",
                e->what, k + 1);
        CHECK(false);
      }
    }
    printf("light kept: %s at iteration %d, %zu nodes after\n", e->what,
           sylva_world_iteration(w) - 2, sylva_world_node_count(w));
    sylva_world_destroy(copy);
    sylva_world_destroy(w);
  }
}

/* Shared threads (pool.h): a loop posted while the pool runs another caller's runs
 * on its own caller alone, every index once. Thread A's loop holds the pool until
 * the main thread's loop has returned, so the main thread's must run alone. */
typedef struct busy_pool {
  sylva__pool *pool;
  atomic_int started, released;
  pthread_t main;
  atomic_int on_main, elsewhere, seen[100];
} busy_pool;

static void hold_piece(void *ctx, size_t begin, size_t end) {
  busy_pool *b = ctx;
  (void)begin, (void)end;
  atomic_fetch_add(&b->started, 1);
  while (!atomic_load(&b->released)) sched_yield();
}

static void *hold_pool(void *ctx) {
  busy_pool *b = ctx;
  sylva__pool_for(b->pool, 2, 1, hold_piece, b);
  return NULL;
}

static void count_piece(void *ctx, size_t begin, size_t end) {
  busy_pool *b = ctx;
  for (size_t i = begin; i < end; i++) atomic_fetch_add(&b->seen[i], 1);
  atomic_fetch_add(pthread_equal(pthread_self(), b->main) ? &b->on_main : &b->elsewhere, 1);
}

static void test_pool_busy(void) {
  static busy_pool b;
  CHECK_INT(sylva__pool_create(3, &b.pool), 0);
  if (!b.pool) return;
  b.main = pthread_self();
  pthread_t a;
  CHECK_INT(pthread_create(&a, NULL, hold_pool, &b), 0);
  while (atomic_load(&b.started) == 0) sched_yield(); /* A's loop is running */
  sylva__pool_for(b.pool, 100, 1, count_piece, &b);
  CHECK_INT(atomic_load(&b.elsewhere), 0);
  CHECK(atomic_load(&b.on_main) >= 1);
  for (int i = 0; i < 100; i++) CHECK_INT(atomic_load(&b.seen[i]), 1);
  atomic_store(&b.released, 1);
  pthread_join(a, NULL);
  /* free again: the next loop runs on the workers too, every index once */
  for (int i = 0; i < 100; i++) atomic_store(&b.seen[i], 0);
  sylva__pool_for(b.pool, 100, 1, count_piece, &b);
  for (int i = 0; i < 100; i++) CHECK_INT(atomic_load(&b.seen[i]), 1);
  sylva__pool_destroy(b.pool);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {
#ifndef NDEBUG
      CHECK_TEST(phase_checks),
#endif
      CHECK_TEST(bad_ids), CHECK_TEST(species_fields), CHECK_TEST(species_snapshot), CHECK_TEST(heartwood_snapshot), CHECK_TEST(measured_without_bad_root),
      CHECK_TEST(leaf_area), CHECK_TEST(world_hash_versions), CHECK_TEST(light_kept),
      CHECK_TEST(pool_busy)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("api");
}
