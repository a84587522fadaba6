/* Threads (docs/model.md, "Determinism"): the number of threads never changes what
 * grows. Each case grows one world on 1, 2 and 4 threads in lockstep and, after every
 * step, checks that the three agree: the step's status, the world's hash and the whole
 * journal (every array, field by field, numbers by their bits); every few steps and at
 * the end, the snapshot's bytes and the light on a lattice of voxels. A world resumed
 * from a snapshot saved on one thread and grown on four agrees with one grown on two
 * throughout. The cases: the IGM stand, a pruned street under a site's sky, a dense
 * stand that thins (deaths by light and by chance, snags that fall), and a world edited
 * between steps as the daemon edits one (obstacles and zones added and removed, a
 * plant added, a prune by hand, a schedule added, threads changed); and two worlds
 * that share one set of threads, grown at once. */
#include <pthread.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../check.h"
#include "../scenario_file.h"
#include "sylva/sylva.h"

/* The journal's records are compared whole where they have no padding, field by field
 * where they have; a field added to one of them changes its size and stops the build
 * here until the comparison below covers it. */
_Static_assert(sizeof(sylva_node_info) == 6 * sizeof(int32_t) + 4 * sizeof(float),
               "sylva_node_info changed: compare its new fields");
_Static_assert(sizeof(sylva_radius_change) == 8, "sylva_radius_change changed");
_Static_assert(sizeof(sylva_leaf_change) == 8, "sylva_leaf_change changed");
_Static_assert(sizeof(sylva_stem_stats) == 176, "sylva_stem_stats changed: compare its new fields");
_Static_assert(sizeof(sylva_stand_stats) == 72, "sylva_stand_stats changed: compare its new fields");
_Static_assert(sizeof(sylva_zone_stat) == 24, "sylva_zone_stat changed: compare its new fields");
_Static_assert(sizeof(sylva_clearance_stat) == 16, "sylva_clearance_stat changed");
_Static_assert(sizeof(sylva_journal) == 264, "sylva_journal changed: compare its new fields");

/* The worlds of a case: threads_of[i] threads; world 0 is the reference. */
enum { NW = 3 };
static const int threads_of[NW] = {1, 2, 4};

/* ---- comparisons: true when equal, else false with the first difference in `why` */

static bool same_double(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

static bool differ(char *why, size_t n, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(why, n, fmt, ap);
  va_end(ap);
  return false;
}

#define SAME_INT(what, k, a, b)                                                          \
  do {                                                                                   \
    if ((a) != (b))                                                                      \
      return differ(why, n, "%s[%zu]: %lld != %lld", what, (size_t)(k), (long long)(a), \
                    (long long)(b));                                                     \
  } while (0)
#define SAME_DOUBLE(what, k, a, b)                                                          \
  do {                                                                                      \
    if (!same_double((a), (b)))                                                             \
      return differ(why, n, "%s[%zu]: %.17g != %.17g", what, (size_t)(k), (double)(a), \
                    (double)(b));                                                           \
  } while (0)
#define SAME_COUNT(what, a, b)                                                           \
  do {                                                                                   \
    if ((a) != (b)) return differ(why, n, "%s: %zu != %zu", what, (size_t)(a), (size_t)(b)); \
  } while (0)

/* Records without padding, compared as bytes (floats by their bits). */
static bool same_records(const char *what, const void *a, const void *b, size_t count,
                         size_t size, char *why, size_t n) {
  if (count == 0) return true;
  if (!a || !b) return differ(why, n, "%s: NULL array with %zu records", what, count);
  for (size_t k = 0; k < count; k++)
    if (memcmp((const char *)a + k * size, (const char *)b + k * size, size) != 0)
      return differ(why, n, "%s[%zu]: records differ", what, k);
  return true;
}

static bool same_stem(size_t k, const sylva_stem_stats *x, const sylva_stem_stats *y, char *why,
                      size_t n) {
  SAME_INT("stats.plant", k, x->plant, y->plant);
  SAME_INT("stats.stem", k, x->stem, y->stem);
  SAME_DOUBLE("stats.height", k, x->height, y->height);
  SAME_DOUBLE("stats.dbh", k, x->dbh, y->dbh);
  SAME_DOUBLE("stats.crown_width", k, x->crown_width, y->crown_width);
  SAME_DOUBLE("stats.crown_base", k, x->crown_base, y->crown_base);
  SAME_DOUBLE("stats.light", k, x->light, y->light);
  SAME_DOUBLE("stats.crown_height", k, x->crown_height, y->crown_height);
  SAME_INT("stats.age", k, x->age, y->age);
  SAME_DOUBLE("stats.leaf_area", k, x->leaf_area, y->leaf_area);
  SAME_DOUBLE("stats.crown_area", k, x->crown_area, y->crown_area);
  SAME_DOUBLE("stats.wood_volume", k, x->wood_volume, y->wood_volume);
  SAME_DOUBLE("stats.biomass", k, x->biomass, y->biomass);
  SAME_DOUBLE("stats.biomass_model", k, x->biomass_model, y->biomass_model);
  SAME_DOUBLE("stats.carbon", k, x->carbon, y->carbon);
  SAME_DOUBLE("stats.co2", k, x->co2, y->co2);
  SAME_DOUBLE("stats.co2_sequestered", k, x->co2_sequestered, y->co2_sequestered);
  SAME_INT("stats.nodes", k, x->nodes, y->nodes);
  SAME_INT("stats.shed", k, x->shed, y->shed);
  SAME_INT("stats.pruned", k, x->pruned, y->pruned);
  SAME_INT("stats.cap", k, x->cap, y->cap);
  SAME_INT("stats.finished", k, x->finished, y->finished);
  SAME_INT("stats.alive", k, x->alive, y->alive);
  SAME_INT("stats.died", k, x->died, y->died);
  SAME_INT("stats.fallen", k, x->fallen, y->fallen);
  SAME_DOUBLE("stats.vigour", k, x->vigour, y->vigour);
  return true;
}

static bool same_stand(const sylva_stand_stats *x, const sylva_stand_stats *y, char *why,
                       size_t n) {
  SAME_DOUBLE("stand.area", 0, x->area, y->area);
  SAME_INT("stand.alive", 0, x->alive, y->alive);
  SAME_INT("stand.died", 0, x->died, y->died);
  SAME_DOUBLE("stand.stems_per_ha", 0, x->stems_per_ha, y->stems_per_ha);
  SAME_DOUBLE("stand.basal_area", 0, x->basal_area, y->basal_area);
  SAME_DOUBLE("stand.qmd", 0, x->qmd, y->qmd);
  SAME_DOUBLE("stand.dominant_height", 0, x->dominant_height, y->dominant_height);
  SAME_DOUBLE("stand.sdi", 0, x->sdi, y->sdi);
  SAME_DOUBLE("stand.cv_height", 0, x->cv_height, y->cv_height);
  SAME_DOUBLE("stand.cv_dbh", 0, x->cv_dbh, y->cv_dbh);
  return true;
}

static bool same_conflicts(const sylva_conflicts *x, const sylva_conflicts *y, char *why,
                           size_t n) {
  SAME_COUNT("conflicts.zone_count", x->zone_count, y->zone_count);
  for (size_t k = 0; k < x->zone_count; k++) {
    SAME_INT("conflicts.zones.stem", k, x->zones[k].stem, y->zones[k].stem);
    SAME_INT("conflicts.zones.obstacle", k, x->zones[k].obstacle, y->zones[k].obstacle);
    SAME_INT("conflicts.zones.nodes", k, x->zones[k].nodes, y->zones[k].nodes);
    SAME_INT("conflicts.zones.first", k, x->zones[k].first, y->zones[k].first);
  }
  SAME_COUNT("conflicts.clearance_count", x->clearance_count, y->clearance_count);
  for (size_t k = 0; k < x->clearance_count; k++) {
    SAME_INT("conflicts.clearances.stem", k, x->clearances[k].stem, y->clearances[k].stem);
    SAME_INT("conflicts.clearances.obstacle", k, x->clearances[k].obstacle,
             y->clearances[k].obstacle);
    SAME_DOUBLE("conflicts.clearances.distance", k, x->clearances[k].distance,
                y->clearances[k].distance);
  }
  return true;
}

/* A journal's array and its count, a and b the journals. */
#define SAME_ARRAY(array, count)                                                         \
  do {                                                                                   \
    SAME_COUNT(#count, a->count, b->count);                                              \
    if (!same_records(#array, a->array, b->array, a->count, sizeof *a->array, why, n)) \
      return false;                                                                      \
  } while (0)

/* Every field of the journal but phase_seconds (only with a clock, which these
 * worlds have not). */
static bool same_journal(const sylva_journal *a, const sylva_journal *b, char *why, size_t n) {
  if (!a || !b) return differ(why, n, "journal: %s", a ? "second NULL" : "first NULL");
  SAME_INT("iteration", 0, a->iteration, b->iteration);
  SAME_ARRAY(added, added_count);
  SAME_ARRAY(radii, radii_count);
  SAME_ARRAY(leaves, leaves_count);
  SAME_ARRAY(shed, shed_count);
  SAME_COUNT("stem_count", a->stem_count, b->stem_count);
  for (size_t k = 0; k < a->stem_count; k++)
    if (!same_stem(k, &a->stats[k], &b->stats[k], why, n)) return false;
  if (!same_records("order", a->order, b->order, a->stem_count, sizeof *a->order, why, n))
    return false;
  if (!same_conflicts(&a->conflicts, &b->conflicts, why, n)) return false;
  SAME_DOUBLE("canopy_cover", 0, a->canopy_cover, b->canopy_cover);
  return same_stand(&a->stand, &b->stand, why, n);
}

/* What the world answers outside a journal after an edit: stand, cover, conflicts. */
static bool same_queries(const sylva_world *a, const sylva_world *b, char *why, size_t n) {
  sylva_stand_stats x, y;
  sylva_world_stand(a, &x);
  sylva_world_stand(b, &y);
  if (!same_stand(&x, &y, why, n)) return false;
  SAME_DOUBLE("canopy_cover", 0, sylva_world_canopy_cover(a), sylva_world_canopy_cover(b));
  sylva_conflicts ca = sylva_world_conflicts(a), cb = sylva_world_conflicts(b);
  if (!same_conflicts(&ca, &cb, why, n)) return false;
  SAME_COUNT("node_count", sylva_world_node_count(a), sylva_world_node_count(b));
  return true;
}

static bool same_snapshot(const sylva_world *a, const sylva_world *b, char *why, size_t n) {
  uint8_t *x = NULL, *y = NULL;
  size_t nx = 0, ny = 0;
  int rx = sylva_snapshot_save(a, &x, &nx), ry = sylva_snapshot_save(b, &y, &ny);
  bool same = rx == 0 && ry == 0 && nx == ny && memcmp(x, y, nx) == 0;
  if (!same) {
    size_t at = 0;
    while (rx == 0 && ry == 0 && at < nx && at < ny && x[at] == y[at]) at++;
    differ(why, n, "snapshot: status %d, %d; %zu and %zu bytes, first difference at byte %zu",
           rx, ry, nx, ny, at);
  }
  sylva_free(x);
  sylva_free(y);
  return same;
}

/* The light, by its bits, at every live node and, under the paper's light from above,
 * at the centre of every fourth voxel along each axis (under a site's sky a voxel's
 * light needs its site factor, found by tracing the sky: too slow for a lattice). */
static bool same_light(const sylva_world *a, const sylva_world *b, char *why, size_t n) {
  for (size_t i = 0; i < sylva_world_node_count(a); i++) {
    sylva_node_info info;
    sylva_world_node_at(a, i, &info);
    double p[3] = {info.x, info.y, info.z};
    double la = sylva_world_light_at(a, p), lb = sylva_world_light_at(b, p);
    if (!same_double(la, lb))
      return differ(why, n, "light at node %d: %.17g != %.17g", info.id, la, lb);
  }
  const sylva_world_def *d = sylva_world_get_def(a);
  if (d->sky_count) return true;
  int dims[3];
  sylva_world_dims(a, dims);
  for (int k = 0; k < dims[2]; k += 4)
    for (int j = 0; j < dims[1]; j += 4)
      for (int i = 0; i < dims[0]; i += 4) {
        double p[3] = {d->min[0] + (i + 0.5) * d->voxel, d->min[1] + (j + 0.5) * d->voxel,
                       d->min[2] + (k + 0.5) * d->voxel};
        double la = sylva_world_light_at(a, p), lb = sylva_world_light_at(b, p);
        if (!same_double(la, lb))
          return differ(why, n, "light at voxel (%d, %d, %d): %.17g != %.17g", i, j, k, la, lb);
      }
  return true;
}

/* ---- lockstep */

/* Worlds grown together. After the first difference a case stops (one report). */
typedef struct lockstep {
  const char *name;
  sylva_world *w[NW];
  int count; /* worlds in use */
  bool broken;
  int steps;     /* steps grown, for the report */
  int64_t pruned; /* nodes the steps pruned (by schedule), world 0 */
} lockstep;

static void report(lockstep *ls, int k, const char *what, const char *why) {
  ls->broken = true;
  check_failed++;
  fprintf(stderr, "%s: iteration %d, %s: %d threads differ from %d threads: %s\n", ls->name,
          sylva_world_iteration(ls->w[k]), what, sylva_world_threads(ls->w[k]),
          sylva_world_threads(ls->w[0]), why);
}

/* The worlds' hashes, snapshots (when `deep`, with the light) and queries agree. */
static void compare_state(lockstep *ls, bool deep) {
  char why[512];
  for (int k = 1; k < ls->count && !ls->broken; k++) {
    if (sylva_world_hash(ls->w[k]) != sylva_world_hash(ls->w[0])) {
      snprintf(why, sizeof why, "%016llx != %016llx",
               (unsigned long long)sylva_world_hash(ls->w[k]),
               (unsigned long long)sylva_world_hash(ls->w[0]));
      report(ls, k, "hash", why);
    } else if (!same_queries(ls->w[k], ls->w[0], why, sizeof why)) {
      report(ls, k, "queries", why);
    } else if (deep && !same_snapshot(ls->w[k], ls->w[0], why, sizeof why)) {
      report(ls, k, "snapshot", why);
    } else if (deep && !same_light(ls->w[k], ls->w[0], why, sizeof why)) {
      report(ls, k, "light", why);
    } else {
      check_passed++;
    }
  }
}

/* One step of every world; their statuses and journals agree. Returns the status. */
static int step_all(lockstep *ls) {
  const sylva_journal *j[NW] = {0};
  int rc[NW] = {0};
  for (int k = 0; k < ls->count; k++) rc[k] = sylva_world_step(ls->w[k], &j[k]);
  char why[512];
  for (int k = 1; k < ls->count && !ls->broken; k++) {
    if (rc[k] != rc[0]) {
      snprintf(why, sizeof why, "%s != %s", sylva_err_name(rc[k]), sylva_err_name(rc[0]));
      report(ls, k, "status", why);
    } else if (rc[0] == SYLVA_OK && !same_journal(j[k], j[0], why, sizeof why)) {
      report(ls, k, "journal", why);
    } else {
      check_passed++;
    }
  }
  ls->steps++;
  if (rc[0] == SYLVA_OK)
    for (size_t k = 0; k < j[0]->stem_count; k++) ls->pruned += j[0]->stats[k].pruned;
  return rc[0];
}

/* Grows `steps` iterations, comparing after each (deeply every `deep` steps and at the
 * last); false when the worlds differ or one fails. */
static bool grow(lockstep *ls, int steps, int deep) {
  for (int s = 1; s <= steps && !ls->broken; s++) {
    int rc = step_all(ls);
    if (rc != SYLVA_OK) {
      CHECK_INT(rc, SYLVA_OK);
      return false;
    }
    compare_state(ls, s == steps || (deep > 0 && s % deep == 0));
  }
  return !ls->broken;
}

static void lockstep_free(lockstep *ls) {
  for (int k = 0; k < ls->count; k++) sylva_world_destroy(ls->w[k]);
}

/* The worlds of a scenario, each on its number of threads. */
static lockstep lockstep_of(const char *name, const sylva_scenario *s) {
  lockstep ls = {.name = name, .count = NW};
  for (int k = 0; k < NW; k++) {
    ls.w[k] = scenario_world(s);
    CHECK_INT(sylva_world_set_threads(ls.w[k], threads_of[k]), 0);
    CHECK_INT(sylva_world_threads(ls.w[k]), threads_of[k]);
  }
  compare_state(&ls, true);
  return ls;
}

static sylva_scenario *scenario_named(const char *name) {
  return scenario_file(SOURCE_ROOT "/scenarios", name);
}

/* Grows a scenario `steps` iterations in lockstep on 1, 2 and 4 threads. */
static void grow_scenario(const char *name, const sylva_scenario *s, int steps, int deep) {
  lockstep ls = lockstep_of(name, s);
  grow(&ls, steps, deep);
  printf("%s: %d steps, %zu nodes\n", name, ls.steps, sylva_world_node_count(ls.w[0]));
  lockstep_free(&ls);
}

/* Grows k steps on one thread and on two, saves the first, loads the image, sets four
 * threads on the loaded world and grows it on beside the two-thread world to `steps`:
 * the two agree after the load and after every step. */
static void grow_resumed(const char *name, const sylva_scenario *s, int k, int steps) {
  lockstep ls = {.name = name, .count = 2};
  ls.w[0] = scenario_world(s);
  ls.w[1] = scenario_world(s);
  CHECK_INT(sylva_world_set_threads(ls.w[1], 2), 0);
  if (!grow(&ls, k, 0)) {
    lockstep_free(&ls);
    return;
  }
  uint8_t *img = NULL;
  size_t len = 0;
  CHECK_INT(sylva_snapshot_save(ls.w[0], &img, &len), 0);
  sylva_world *r = NULL;
  CHECK_INT(sylva_snapshot_load(img, len, &r), 0);
  sylva_free(img);
  if (!r) {
    lockstep_free(&ls);
    return;
  }
  CHECK_INT(sylva_world_threads(r), 1); /* a loaded image starts on one thread */
  CHECK_INT(sylva_world_set_threads(r, 4), 0);
  CHECK_INT(sylva_world_threads(r), 4);
  sylva_world_destroy(ls.w[0]);
  ls.w[0] = r; /* the reference is the resumed world now: 4 threads against 2 */
  compare_state(&ls, true);
  grow(&ls, steps - k, 3);
  printf("%s: resumed at %d, grown to %d\n", name, k, sylva_world_iteration(ls.w[0]));
  lockstep_free(&ls);
}

/* ---- the cases */

/* (a) The IGM stand (five trees 2 m apart, the paper's light from above). */
static void test_igm_stand(void) {
  sylva_scenario *s = scenario_named("stand.json");
  grow_scenario("igm-stand", s, 15, 4);
  sylva_scenario_free(s);
}

/* (b) A street of library planes under a site's sky: facades, an awning, clearance
 * zones pruned every 3 years from year 6 (three prunes); resumed at 5 across two. */
static void test_street(void) {
  sylva_scenario *s = scenario_named("street-pruned.json");
  CHECK(s->light.site && s->management_count == 3);
  grow_scenario("street-pruned", s, 12, 3);
  grow_resumed("street-pruned-resumed", s, 5, 10);
  sylva_scenario_free(s);
}

/* (c) 16 lindens 1.5 m apart that die of shade after 2 seasons below 0.3 and by chance
 * (2% a season), whose snags fall after 2: the first die at about 6 years. Resumed
 * after deaths, with snags standing. */
static sylva_scenario *thinning_scenario(void) {
  char json[8192];
  int len = snprintf(json, sizeof json,
                     "{\"format\": \"sylva.scenario/1\", \"seed\": 7, \"iterations\": 30,"
                     " \"world\": {\"min\": [-7, -7, 0], \"max\": [7, 7, 16]},"
                     " \"species\": {\"s\": {\"preset\": \"utdb:NoEast:TICO\","
                     " \"mortality_light\": 0.3, \"mortality_years\": 2, \"snag_years\": 2,"
                     " \"mortality\": 0.02}}, \"plants\": [");
  for (int i = 0; i < 16; i++)
    len += snprintf(json + len, sizeof json - (size_t)len,
                    "%s{\"id\": \"t%d\", \"species\": \"s\", \"roots\": [[%g, %g, 0]]}",
                    i ? ", " : "", i, (i % 4 - 1.5) * 1.5, (i / 4 - 1.5) * 1.5);
  snprintf(json + len, sizeof json - (size_t)len, "]}");
  sylva_scenario *s = NULL;
  char err[512];
  if (sylva_scenario_parse(json, strlen(json), &s, err, sizeof err) < 0) {
    fprintf(stderr, "thinning scenario: %s\n", err);
    exit(1);
  }
  return s;
}

static void test_thinning(void) {
  sylva_scenario *s = thinning_scenario();
  lockstep ls = lockstep_of("thinning", s);
  grow(&ls, 14, 4);
  sylva_stand_stats st;
  sylva_world_stand(ls.w[0], &st);
  int fallen = 0;
  for (int k = 0; k < sylva_world_stem_count(ls.w[0]); k++) {
    sylva_stem_stats x;
    sylva_world_stem_stats(ls.w[0], k, &x);
    fallen += x.fallen >= 0;
  }
  printf("thinning: %d of 16 alive, %d fallen after %d steps\n", st.alive, fallen, ls.steps);
  CHECK(st.alive < 14 && fallen > 0); /* the case grows what it is meant to */
  lockstep_free(&ls);
  grow_resumed("thinning-resumed", s, 8, 14);
  sylva_scenario_free(s);
}

/* (d) The daemon's edits between steps, the same in every world: a board over a tree
 * added and removed, a zone beside the crowns added (over nodes) and pruned on a
 * schedule, then removed, a prism, a prune by hand, a plant, and the 4-thread world
 * moved to 3 threads. Three lindens 3 m apart; the worlds are made with
 * sylva_world_create and def.threads. */
static int edit_all(lockstep *ls, const char *what, int (*edit)(sylva_world *, const void *),
                    const void *ctx) {
  int rc[NW] = {0};
  for (int k = 0; k < ls->count; k++) rc[k] = edit(ls->w[k], ctx);
  for (int k = 1; k < ls->count && !ls->broken; k++) {
    if (rc[k] != rc[0]) {
      char why[128];
      snprintf(why, sizeof why, "%d != %d", rc[k], rc[0]);
      report(ls, k, what, why);
    }
  }
  compare_state(ls, true);
  return rc[0];
}

static int add_obstacle(sylva_world *w, const void *ctx) {
  return sylva_world_add_obstacle(w, ctx);
}
static int remove_obstacle(sylva_world *w, const void *ctx) {
  return sylva_world_remove_obstacle(w, *(const int *)ctx);
}
static int add_plant(sylva_world *w, const void *ctx) {
  return sylva_world_add_plant(w, ctx, NULL);
}
static int add_prune(sylva_world *w, const void *ctx) { return sylva_world_add_prune(w, ctx); }

/* A prune by hand in every world: the nodes removed and the removed roots' ids agree.
 * Returns the nodes removed. */
static int64_t prune_all(lockstep *ls, const double min[3], const double max[3]) {
  int64_t nodes[NW] = {0};
  int32_t *ids[NW] = {0};
  size_t count[NW] = {0};
  for (int k = 0; k < ls->count; k++) {
    const int32_t *removed = NULL;
    nodes[k] = sylva_world_prune(ls->w[k], min, max, &removed, &count[k]);
    ids[k] = malloc(count[k] * sizeof *ids[k] + 1);
    if (count[k]) memcpy(ids[k], removed, count[k] * sizeof *ids[k]);
  }
  char why[512];
  for (int k = 1; k < ls->count && !ls->broken; k++) {
    size_t n = sizeof why;
    bool same = true;
    if (nodes[k] != nodes[0])
      same = differ(why, n, "nodes removed: %lld != %lld", (long long)nodes[k], (long long)nodes[0]);
    else if (count[k] != count[0])
      same = differ(why, n, "removed roots: %zu != %zu", count[k], count[0]);
    else
      same = same_records("removed", ids[k], ids[0], count[0], sizeof *ids[0], why, n);
    if (!same) report(ls, k, "prune", why);
  }
  for (int k = 0; k < ls->count; k++) free(ids[k]);
  compare_state(ls, true);
  return nodes[0];
}

static void test_edits(void) {
  sylva_world *proto = json_world(
      "{\"format\": \"sylva.scenario/1\", \"seed\": 5, \"iterations\": 30,"
      " \"world\": {\"min\": [-8, -6, 0], \"max\": [8, 6, 16]},"
      " \"species\": {\"lin\": {\"preset\": \"utdb:NoEast:TICO\"}}, \"plants\": []}");
  const sylva_world_def *pd = sylva_world_get_def(proto);
  lockstep ls = {.name = "edits", .count = NW};
  for (int k = 0; k < NW; k++) {
    sylva_world_def def = *pd;
    def.threads = threads_of[k];
    CHECK_INT(sylva_world_create(&def, &ls.w[k]), 0);
    CHECK_INT(sylva_world_threads(ls.w[k]), threads_of[k]);
    CHECK_INT(sylva_world_add_species(ls.w[k], sylva_world_species(proto, 0), "lin"), 0);
    for (int p = 0; p < 3; p++) {
      char label[8];
      snprintf(label, sizeof label, "t%d", p);
      const double root[1][3] = {{3.0 * (p - 1), 0, 0}};
      sylva_plant_def plant = {.species = 0, .label = label, .roots = root, .root_count = 1};
      CHECK_INT(sylva_world_add_plant(ls.w[k], &plant, NULL), p);
    }
  }
  sylva_world_destroy(proto);
  compare_state(&ls, true);
  grow(&ls, 2, 0);
  sylva_obstacle_def board = {.label = "board", .min = {-4, -1, 9}, .max = {-2, 1, 9.1}};
  int board_id = edit_all(&ls, "add board", add_obstacle, &board);
  CHECK(board_id >= 0);
  sylva_obstacle_def zone = {.label = "zone", .min = {4, -2, 1}, .max = {6, 2, 5},
                             .kind = SYLVA_OBSTACLE_ZONE};
  int zone_id = edit_all(&ls, "add zone", add_obstacle, &zone);
  CHECK(zone_id >= 0);
  grow(&ls, 2, 0);
  /* the branches of t0 (at x = -3) that reach west, its trunk spared */
  CHECK(prune_all(&ls, (const double[3]){-8, -6, 1}, (const double[3]){-3.5, 6, 10}) > 0);
  sylva_prune_def schedule = {.zone = zone_id, .every = 2, .from = sylva_world_iteration(ls.w[0]) + 1};
  CHECK_INT(edit_all(&ls, "add schedule", add_prune, &schedule), 0);
  grow(&ls, 2, 0);
  CHECK_INT(edit_all(&ls, "remove board", remove_obstacle, &board_id), 0);
  const double late_root[1][3] = {{-6.5, -3.5, 0}};
  sylva_plant_def late = {.species = 0, .label = "late", .roots = late_root, .root_count = 1};
  CHECK_INT(edit_all(&ls, "add plant", add_plant, &late), 3);
  const double ring[4][2] = {{3.5, -2}, {6, -2}, {6, 2}, {3.5, 2}};
  const int ring_size[1] = {4};
  sylva_obstacle_def prism = {.label = "prism", .min = {0, 0, 11}, .max = {0, 0, 11.2},
                              .footprint = {.points = ring, .point_count = 4,
                                            .ring_sizes = ring_size, .ring_count = 1}};
  CHECK(edit_all(&ls, "add prism", add_obstacle, &prism) >= 0);
  grow(&ls, 2, 0);
  CHECK_INT(sylva_world_set_threads(ls.w[2], 3), 0); /* from now on */
  CHECK_INT(sylva_world_threads(ls.w[2]), 3);
  grow(&ls, 3, 0);
  sylva_conflicts c = sylva_world_conflicts(ls.w[0]);
  size_t zone_entries = c.zone_count;
  CHECK_INT(edit_all(&ls, "remove zone", remove_obstacle, &zone_id), 0);
  grow(&ls, 3, 0);
  c = sylva_world_conflicts(ls.w[0]);
  printf("edits: %d steps, %zu nodes, %d stems, %lld pruned on schedule, %zu zone entries, %zu clearances\n",
         ls.steps, sylva_world_node_count(ls.w[0]), sylva_world_stem_count(ls.w[0]),
         (long long)ls.pruned, zone_entries, c.clearance_count);
  CHECK(zone_entries > 0 && ls.pruned > 0 && c.clearance_count > 0); /* the edits did what they are for */
  lockstep_free(&ls);
}

/* The threads a world is given, and what it refuses; the most threads grow a small
 * world as one does. */
static void test_threads_api(void) {
  sylva_world_def def = sylva_default_world_def();
  sylva_world *w = NULL;
  CHECK_INT(sylva_world_create(&def, &w), 0);
  CHECK_INT(sylva_world_threads(w), 1); /* the default: the caller's thread alone */
  CHECK_INT(sylva_world_set_threads(w, 3), 0);
  CHECK_INT(sylva_world_threads(w), 3);
  CHECK_INT(sylva_world_set_threads(w, 3), 0); /* the same again */
  CHECK_INT(sylva_world_threads(w), 3);
  CHECK_INT(sylva_world_set_threads(w, SYLVA_MAX_THREADS + 1), SYLVA_EINVAL);
  CHECK_INT(sylva_world_threads(w), 3);
  CHECK_INT(sylva_world_set_threads(w, -1), SYLVA_EINVAL);
  CHECK_INT(sylva_world_threads(w), 3);
  CHECK_INT(sylva_world_set_threads(w, 0), 0);
  CHECK_INT(sylva_world_threads(w), 1);
  CHECK_INT(sylva_world_set_threads(w, 1), 0);
  CHECK_INT(sylva_world_threads(w), 1);
  CHECK_INT(sylva_world_set_threads(w, 2), 0);
  CHECK_INT(sylva_world_threads(w), 2);
  sylva_world_destroy(w);

  int bad[] = {-1, SYLVA_MAX_THREADS + 1, -1000};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    def.threads = bad[i];
    w = NULL;
    CHECK_INT(sylva_world_create(&def, &w), SYLVA_EINVAL);
    CHECK(w == NULL);
    CHECK_INT(sylva_world_def_check(&def), SYLVA_EINVAL);
  }
  for (int t = 0; t <= 4; t++) {
    def.threads = t;
    w = NULL;
    CHECK_INT(sylva_world_create(&def, &w), 0);
    CHECK_INT(sylva_world_threads(w), t <= 1 ? 1 : t);
    sylva_world_destroy(w);
  }

  /* SYLVA_MAX_THREADS, more threads than work, against one thread */
  sylva_scenario *s = scenario_named("stand.json");
  lockstep ls = {.name = "most-threads", .count = 2};
  ls.w[0] = scenario_world(s);
  ls.w[1] = scenario_world(s);
  CHECK_INT(sylva_world_set_threads(ls.w[1], SYLVA_MAX_THREADS), 0);
  CHECK_INT(sylva_world_threads(ls.w[1]), SYLVA_MAX_THREADS);
  grow(&ls, 6, 3);
  lockstep_free(&ls);
  sylva_scenario_free(s);
}

/* (e) Threads that worlds share (sylva_threads), as the daemon's runs do: two pruned
 * streets of other seeds share four, each grown on a thread of its own at the same
 * time, so that one world's loops find the threads busy with the other's and run on
 * their caller (2 to 14 of their loops did in three runs on two cores). Every step's hash, and
 * the snapshot at the end, are those of the same world grown alone on one thread. */
enum { SHARED_STEPS = 12 };

typedef struct shared_grower {
  sylva_world *w;
  uint64_t hash[SHARED_STEPS];
  int rc;
} shared_grower;

static void *grow_shared(void *arg) {
  shared_grower *g = arg;
  for (int k = 0; k < SHARED_STEPS && !g->rc; k++) {
    g->rc = sylva_world_step(g->w, NULL);
    g->hash[k] = sylva_world_hash(g->w);
  }
  return NULL;
}

static void test_shared_threads(void) {
  sylva_threads *t = NULL;
  CHECK_INT(sylva_threads_create(0, &t), SYLVA_EINVAL);
  CHECK(t == NULL);
  CHECK_INT(sylva_threads_create(SYLVA_MAX_THREADS + 1, &t), SYLVA_EINVAL);
  CHECK_INT(sylva_threads_create(1, &t), 0);
  CHECK_INT(sylva_threads_count(t), 1);
  sylva_threads_destroy(t);
  CHECK_INT(sylva_threads_create(4, &t), 0);
  if (!t) return;
  CHECK_INT(sylva_threads_count(t), 4);

  const char *names[2] = {"street-pruned.json", "street-pruned.json (seed + 1)"};
  sylva_scenario *sc[2];
  shared_grower g[2], alone[2];
  pthread_t th[2];
  for (int i = 0; i < 2; i++) {
    sc[i] = scenario_named("street-pruned.json");
    sc[i]->seed += (uint64_t)i;
    g[i] = (shared_grower){.w = scenario_world(sc[i])};
    alone[i] = (shared_grower){.w = scenario_world(sc[i])};
    sylva_world_share_threads(g[i].w, t);
    CHECK(sylva_world_shared_threads(g[i].w) == t);
    CHECK_INT(sylva_world_threads(g[i].w), 4);
  }
  for (int i = 0; i < 2; i++) CHECK_INT(pthread_create(&th[i], NULL, grow_shared, &g[i]), 0);
  for (int i = 0; i < 2; i++) grow_shared(&alone[i]);
  for (int i = 0; i < 2; i++) pthread_join(th[i], NULL);
  for (int i = 0; i < 2; i++) {
    CHECK_INT(g[i].rc, 0);
    for (int k = 0; k < SHARED_STEPS; k++)
      if (g[i].hash[k] != alone[i].hash[k]) {
        fprintf(stderr, "%s on shared threads: step %d hash %016llx, alone %016llx\n", names[i],
                k + 1, (unsigned long long)g[i].hash[k], (unsigned long long)alone[i].hash[k]);
        CHECK(false);
        break;
      }
    char why[256] = "";
    if (!same_snapshot(g[i].w, alone[i].w, why, sizeof why)) {
      fprintf(stderr, "%s on shared threads: %s\n", names[i], why);
      CHECK(false);
    }
    printf("%s: %d steps on shared threads, %zu nodes\n", names[i], SHARED_STEPS,
           sylva_world_node_count(g[i].w));
  }
  /* threads of its own leave the shared ones; NULL leaves them for the caller's */
  CHECK_INT(sylva_world_set_threads(g[0].w, 2), 0);
  CHECK(sylva_world_shared_threads(g[0].w) == NULL);
  CHECK_INT(sylva_world_threads(g[0].w), 2);
  sylva_world_share_threads(g[1].w, NULL);
  CHECK(sylva_world_shared_threads(g[1].w) == NULL);
  CHECK_INT(sylva_world_threads(g[1].w), 1);
  sylva_world_share_threads(g[0].w, t); /* destroyed while sharing them */
  for (int i = 0; i < 2; i++) {
    sylva_world_destroy(g[i].w);
    sylva_world_destroy(alone[i].w);
    sylva_scenario_free(sc[i]);
  }
  sylva_threads_destroy(t);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {CHECK_TEST(threads_api), CHECK_TEST(igm_stand),
                                     CHECK_TEST(street), CHECK_TEST(thinning),
                                     CHECK_TEST(edits), CHECK_TEST(shared_threads)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("threads");
}
