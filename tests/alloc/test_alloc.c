/* Allocation failures, in the manner of SQLite's malloc tests. One short run (a
 * scenario built with the proto parser, grown some iterations, saved, loaded, and
 * the loaded world grown some more) is repeated with the core's Nth allocation
 * failing, for every N from 1 until a run completes without reaching it. The
 * loaded world is also edited between steps (a board and a tree are added).
 *
 *  - transient: only the Nth allocation fails. The call that meets it must return
 *    SYLVA_ENOMEM and change nothing (the world's hash is the same, a failed build
 *    or load yields no world); the run retries the call and must end with the
 *    journals, stats and final snapshot bytes of a run without failures.
 *  - persistent: the Nth and every later allocation fail. The run must meet
 *    SYLVA_ENOMEM with the world unchanged, and a step retried then must fail the
 *    same way; the world is then destroyed (the sanitizer build finds any leak).
 *
 * A failure the library absorbs (a cache or a shrink it can do without) lets the
 * call succeed; the transient run must still end with the same bytes.
 *
 * With ALLOC_THREADS=n in the environment, the worlds grow on n threads (a world
 * whose pool could not be made grows on one: the same bytes).
 *
 *   test_alloc SCENARIO_DIR SCENARIO ITERATIONS_BEFORE_SAVE ITERATIONS_AFTER_LOAD [TEST] */
#include <stdint.h>
#include <string.h>
#include <time.h>

#include "../check.h"
#include "../scenario_file.h"
#include "sylva/scenario.h"
#include "sylva/sylva.h"

/* ---- the failing allocator ---------------------------------------------------- */

typedef struct faults {
  long calls;      /* allocations so far: malloc_fn and realloc_fn calls */
  long fail_at;    /* the allocation that fails, 0 for none */
  bool persistent; /* every allocation from fail_at on fails */
  long failed;     /* allocations refused */
  long reported;   /* refusals already answered by a SYLVA_ENOMEM */
} faults;

static bool refuse(faults *f) {
  f->calls++;
  bool fail =
      f->fail_at > 0 && (f->calls == f->fail_at || (f->persistent && f->calls > f->fail_at));
  f->failed += fail;
  return fail;
}

static void *f_malloc(size_t n, void *ctx) { return refuse(ctx) ? NULL : malloc(n); }
static void *f_realloc(void *p, size_t n, void *ctx) { return refuse(ctx) ? NULL : realloc(p, n); }
static void f_free(void *p, void *ctx) {
  (void)ctx;
  free(p);
}

/* The run of every test (main sets it from the command line and
 * ALLOC_THREADS). */
static struct {
  const char *name;
  sylva_scenario *sc;
  int before_save, after_load;
  int threads;
} cfg;

/* ---- what a run produced -------------------------------------------------------- */

typedef struct outcome {
  uint64_t digest; /* every journal and the final stats */
  uint8_t *image;  /* the final snapshot (sylva_free) */
  size_t image_size;
  int iteration;
  bool stopped; /* persistent failure: the run ended at its first failure */
  long enomem;  /* calls that returned SYLVA_ENOMEM */
} outcome;

static uint64_t fnv(uint64_t h, const void *data, size_t n) {
  const unsigned char *p = data;
  for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 0x100000001b3ULL;
  return h;
}

static uint64_t digest_stats(uint64_t h, const sylva_stem_stats *s) {
  h = fnv(h, &s->plant, sizeof s->plant);
  h = fnv(h, &s->stem, sizeof s->stem);
  double d[5] = {s->height, s->dbh, s->crown_width, s->crown_base, s->light};
  h = fnv(h, d, sizeof d);
  int64_t n[2] = {s->nodes, s->shed};
  h = fnv(h, n, sizeof n);
  h = fnv(h, &s->cap, sizeof s->cap);
  return fnv(h, &s->finished, sizeof s->finished);
}

static uint64_t digest_journal(uint64_t h, const sylva_journal *j) {
  h = fnv(h, &j->iteration, sizeof j->iteration);
  for (size_t i = 0; i < j->added_count; i++) {
    const sylva_node_info *n = &j->added[i];
    int32_t ints[5] = {n->id, n->parent, n->plant, n->stem, n->birth};
    float floats[4] = {n->x, n->y, n->z, n->radius};
    h = fnv(h, ints, sizeof ints);
    h = fnv(h, floats, sizeof floats);
  }
  for (size_t i = 0; i < j->radii_count; i++) {
    h = fnv(h, &j->radii[i].id, sizeof j->radii[i].id);
    h = fnv(h, &j->radii[i].radius, sizeof j->radii[i].radius);
  }
  h = fnv(h, j->shed, j->shed_count * sizeof *j->shed);
  h = fnv(h, j->order, j->stem_count * sizeof *j->order);
  for (size_t i = 0; i < j->stem_count; i++) h = digest_stats(h, &j->stats[i]);
  return h;
}

/* A call that failed: it must say SYLVA_ENOMEM, and only because an allocation was
 * refused since the last one that did (not a failure kept from before). */
static bool out_of_memory(int rc, faults *f, outcome *o) {
  CHECK_INT(rc, SYLVA_ENOMEM);
  CHECK(f->failed > f->reported);
  bool fresh = rc == SYLVA_ENOMEM && f->failed > f->reported;
  f->reported = f->failed;
  o->enomem++;
  return fresh;
}

/* Grows w by n iterations (fewer if it finishes), retrying a step that ran out of
 * memory; false when a persistent failure ended the run (w is then destroyed). */
static bool grow(sylva_world **wp, int n, faults *f, outcome *o) {
  sylva_world *w = *wp;
  for (int k = 0; k < n && !sylva_world_finished(w);) {
    uint64_t before = sylva_world_hash(w);
    int iteration = sylva_world_iteration(w);
    static const sylva_journal unset;
    const sylva_journal *j = &unset;
    int rc = sylva_world_step(w, &j);
    if (rc == SYLVA_OK) {
      o->digest = digest_journal(o->digest, j);
      k++;
      continue;
    }
    if (!out_of_memory(rc, f, o)) {
      sylva_world_destroy(w);
      *wp = NULL;
      return false;
    }
    /* the step changed nothing */
    CHECK(j == NULL);
    CHECK(sylva_world_hash(w) == before);
    CHECK_INT(sylva_world_iteration(w), iteration);
    if (f->persistent) {
      /* it keeps failing the same way, and changing nothing */
      out_of_memory(sylva_world_step(w, NULL), f, o);
      CHECK(sylva_world_hash(w) == before);
      sylva_world_destroy(w);
      *wp = NULL;
      return false;
    }
  }
  return true;
}

/* Saves w into (*image, *size), retrying while memory runs out (transient); false
 * when it gave up. */
static bool save(const sylva_world *w, uint8_t **image, size_t *size, faults *f, outcome *o) {
  for (;;) {
    int rc = sylva_snapshot_save(w, image, size);
    if (rc == SYLVA_OK) return true;
    CHECK(*image == NULL && *size == 0);
    if (!out_of_memory(rc, f, o) || f->persistent) return false;
  }
}

/* An edit between steps, as the daemon makes them: a board and a new tree in a
 * corner of the world, then a prune of a box over the middle of the world from a
 * fifth of its height up, each retried while memory runs out (transient). */
static bool edit(sylva_world *w, faults *f, outcome *o) {
  const sylva_world_def *d = sylva_world_get_def(w);
  double span[3], lo[3];
  for (int a = 0; a < 3; a++) span[a] = d->max[a] - d->min[a], lo[a] = d->min[a];
  sylva_obstacle_def board = {
      "board",
      {lo[0] + 0.05 * span[0], lo[1] + 0.05 * span[1], lo[2] + 0.8 * span[2]},
      {lo[0] + 0.15 * span[0], lo[1] + 0.15 * span[1], lo[2] + 0.82 * span[2]},
      SYLVA_OBSTACLE_SOLID, {0}};
  double root[1][3] = {{lo[0] + 0.25 * span[0], lo[1] + 0.25 * span[1], lo[2]}};
  sylva_plant_def tree = {0, "late", (const double(*)[3])root, 1, 0, NULL, 0};
  double cut_min[3] = {lo[0] + 0.4 * span[0], lo[1] + 0.4 * span[1], lo[2] + 0.2 * span[2]};
  double cut_max[3] = {lo[0] + 0.6 * span[0], lo[1] + 0.6 * span[1], lo[2] + span[2]};
  for (int k = 0; k < 3;) {
    uint64_t before = sylva_world_hash(w);
    int plants = sylva_world_plant_count(w), obstacles = sylva_world_obstacle_count(w);
    int64_t rc = k == 0   ? sylva_world_add_obstacle(w, &board)
                 : k == 1 ? sylva_world_add_plant(w, &tree, NULL)
                          : sylva_world_prune(w, cut_min, cut_max, NULL, NULL);
    if (rc >= 0) {
      k++;
      continue;
    }
    CHECK(sylva_world_hash(w) == before);
    CHECK_INT(sylva_world_plant_count(w), plants);
    CHECK_INT(sylva_world_obstacle_count(w), obstacles);
    if (!out_of_memory((int)rc, f, o) || f->persistent) return false;
  }
  return true;
}

/* The run: build, grow, save, load, edit and grow the loaded world, save it. A run that gives
 * up (persistent failures, or a failure of the test) destroys what it holds and is
 * marked stopped. */
static void run(const sylva_scenario *sc, int before_save, int after_load, faults *f, outcome *o) {
  memset(o, 0, sizeof *o);
  o->digest = 0xcbf29ce484222325ULL;
  sylva_world *w = NULL, *loaded = NULL;
  uint8_t *image = NULL;
  size_t size = 0;
  char err[512];
  int rc;
  while ((rc = sylva_scenario_build(sc, &w, err, sizeof err)) != 0) {
    CHECK(w == NULL);
    CHECK(strstr(err, "out of memory") != NULL);
    if (!out_of_memory(rc, f, o) || f->persistent) goto stopped;
  }
  (void)sylva_world_set_threads(w, cfg.threads);
  if (!grow(&w, before_save, f, o) || !save(w, &image, &size, f, o)) goto stopped;
  while ((rc = sylva_snapshot_load(image, size, &loaded)) != 0) {
    CHECK(loaded == NULL);
    if (!out_of_memory(rc, f, o) || f->persistent) goto stopped;
  }
  CHECK(sylva_world_hash(loaded) == sylva_world_hash(w));
  sylva_world_destroy(w);
  w = loaded;
  loaded = NULL;
  (void)sylva_world_set_threads(w, cfg.threads);
  if (!edit(w, f, o) || !grow(&w, after_load, f, o)) goto stopped;
  for (int k = 0; k < sylva_world_stem_count(w); k++) {
    sylva_stem_stats st;
    CHECK_INT(sylva_world_stem_stats(w, k, &st), 0);
    o->digest = digest_stats(o->digest, &st);
  }
  o->iteration = sylva_world_iteration(w);
  if (!save(w, &o->image, &o->image_size, f, o)) goto stopped;
  sylva_free(image);
  sylva_world_destroy(w);
  return;
stopped:
  sylva_free(image);
  sylva_world_destroy(loaded);
  sylva_world_destroy(w);
  o->stopped = true;
}

static double seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

/* Fails the Nth allocation for N = 1, 2, ... until a run no longer reaches it;
 * returns the number of failure points, and in *absorbed those at which no call
 * failed. */
static long sweep(const sylva_scenario *sc, int before_save, int after_load, bool persistent,
                  const outcome *ref, long *absorbed) {
  long n = 1;
  *absorbed = 0;
  for (;; n++) {
    faults f = {.fail_at = n, .persistent = persistent};
    sylva_allocator a = {f_malloc, f_realloc, f_free, &f};
    CHECK_INT(sylva_set_allocator(&a), 0);
    outcome o;
    int failed_before = check_failed;
    run(sc, before_save, after_load, &f, &o);
    CHECK_INT(sylva_set_allocator(NULL), 0);
    if (f.failed == 0) { /* the run did not reach allocation n: every point is covered */
      CHECK(!o.stopped && o.enomem == 0);
      sylva_free(o.image);
      break;
    }
    if (!persistent) {
      /* retried after every failure, the run ends exactly as one without */
      CHECK(!o.stopped);
      CHECK_INT(o.iteration, ref->iteration);
      CHECK(o.digest == ref->digest);
      CHECK(o.image_size == ref->image_size && o.image &&
            memcmp(o.image, ref->image, ref->image_size) == 0);
    } else {
      CHECK(o.stopped || o.enomem == 0);
    }
    if (o.enomem == 0) ++*absorbed;
    sylva_free(o.image);
    if (check_failed > failed_before) {
      fprintf(stderr, "%s failure at allocation %ld of %ld\n",
              persistent ? "persistent" : "transient", n, f.calls);
      if (check_failed > 20) break;
    }
  }
  return n - 1;
}

/* ---- the tests ----------------------------------------------------------------- */

/* The reference run: the failing allocator, nothing refused; made once. */
static outcome ref;
static long ref_calls = -1; /* its allocations */

static const outcome *reference(void) {
  if (ref_calls >= 0) return &ref;
  faults none = {0};
  sylva_allocator a = {f_malloc, f_realloc, f_free, &none};
  CHECK_INT(sylva_set_allocator(&a), 0);
  run(cfg.sc, cfg.before_save, cfg.after_load, &none, &ref);
  CHECK_INT(sylva_set_allocator(NULL), 0);
  CHECK(!ref.stopped && ref.enomem == 0 && ref.image != NULL);
  ref_calls = none.calls;
  printf("alloc: %s, %d + %d iterations: %ld allocations, %d iterations grown\n", cfg.name,
         cfg.before_save, cfg.after_load, ref_calls, ref.iteration);
  return &ref;
}

/* An allocator with a hook left out is refused and changes nothing. */
static void test_partial_allocator(void) {
  sylva_allocator partial = {f_malloc, NULL, f_free, NULL};
  CHECK_INT(sylva_set_allocator(&partial), SYLVA_EINVAL);
}

/* The reference run completes, and is the run of the C library's allocator. */
static void test_reference(void) {
  const outcome *r = reference();
  faults none = {0};
  outcome plain;
  run(cfg.sc, cfg.before_save, cfg.after_load, &none, &plain);
  CHECK(plain.digest == r->digest && plain.image_size == r->image_size &&
        memcmp(plain.image, r->image, r->image_size) == 0);
  sylva_free(plain.image);
}

/* Each allocation failing once: SYLVA_ENOMEM, no change, and retried the same bytes. */
static void test_transient(void) {
  const outcome *r = reference();
  double t0 = seconds();
  long absorbed = 0;
  long transient = sweep(cfg.sc, cfg.before_save, cfg.after_load, false, r, &absorbed);
  printf("alloc: transient failures at %ld points (%ld absorbed, the rest SYLVA_ENOMEM and "
         "retried), %.1f s\n",
         transient, absorbed, seconds() - t0);
  CHECK_INT(transient, ref_calls);
}

/* All allocations failing from one on: SYLVA_ENOMEM, no change, no leak once destroyed. */
static void test_persistent(void) {
  const outcome *r = reference();
  double t0 = seconds();
  long absorbed = 0;
  long persistent = sweep(cfg.sc, cfg.before_save, cfg.after_load, true, r, &absorbed);
  printf("alloc: persistent failures from %ld points (%ld absorbed to the end, the rest "
         "SYLVA_ENOMEM and destroyed), %.1f s\n",
         persistent, absorbed, seconds() - t0);
  CHECK_INT(persistent, ref_calls);
}

int main(int argc, char **argv) {
  if (argc != 5 && argc != 6) {
    fprintf(stderr, "usage: test_alloc SCENARIO_DIR SCENARIO BEFORE_SAVE AFTER_LOAD [TEST]\n");
    return 2;
  }
  cfg.name = argv[2];
  cfg.sc = scenario_file(argv[1], argv[2]);
  cfg.before_save = atoi(argv[3]), cfg.after_load = atoi(argv[4]);
  const char *threads = getenv("ALLOC_THREADS");
  cfg.threads = threads ? atoi(threads) : 1;
  static const check_test tests[] = {
      CHECK_TEST(partial_allocator), CHECK_TEST(reference), CHECK_TEST(transient),
      CHECK_TEST(persistent)};
  CHECK_RUN(argc, argv, 5, tests);
  sylva_free(ref.image);
  sylva_scenario_free(cfg.sc);
  return check_summary("alloc");
}
