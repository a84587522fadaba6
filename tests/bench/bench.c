/* sylva benchmark: grows the fig. 17b tree, the five-tree stand and a generated
 * stand of 100 trees to at least 1,000,000 live internodes, printing per iteration
 * the live and new internodes, the time of each phase and the memory, then a
 * summary; and measures the cost of shading one internode at several heights.
 *
 * With "store5" / "store100" the stands are grown while every iteration is stored
 * in an SQLite store (a temporary file) with the default snapshot interval, and
 * the time spent storing is compared with the time spent growing.
 *
 * "obstacles" reads the light at every cell of one horizontal slice of a
 * 4000 x 4000-voxel site holding 1,000 boxes (what a light_slice message asks), and
 * adds, finds by label, copies (a snapshot saved and loaded, as the daemon's edits
 * do) and removes by id --edits N obstacles (100,000 by default).
 *
 * "years" grows library species in years (issue 20): a street of ten trees and a
 * hectare of 400, each 40 years; "street10" the street alone.
 *
 *   bench [all|fig17b|stand5|stand100|shade|floor|store5|store100|obstacles|years|street10|thinning]
 *         [--scenarios DIR]
 *         [--edits N] [--threads N] */
#include <malloc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>
#include <time.h>

#include "../scenario_file.h"
#include "grid.h"
#include "world_impl.h"
#include "rng.h"
#include "store.h"
#include "sylva/encode.h"
#include "sylva/scenario.h"
#include "sylva/sylva.h"

static int bench_threads = 1; /* --threads N: the worlds grow on N threads */

static double now(void *ctx) {
  (void)ctx;
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static long peak_rss_kb(void) {
  struct rusage u;
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

typedef struct summary {
  const char *name;
  int iterations;
  size_t live, created;
  double seconds, phase[SYLVA_PHASE_COUNT];
  size_t peak_voxels, peak_skeleton, peak_other;
  double shade_us_per_node_early, shade_us_per_node_late;
  double last_ms[5]; /* the last five iterations' wall time, ms */
  double hash_ms[2];  /* the final world's hash by definitions 1 and 2 (docs/store.md) */
} summary;

static const char *phase_names[SYLVA_PHASE_COUNT] = {"light", "alloc", "shoots", "shade",
                                                     "radii", "shed", "stats"};

/* Grows w until finished, `limit` iterations, or `target` live internodes. */
static summary grow(const char *name, sylva_world *w, int limit, size_t target) {
  summary s = {.name = name};
  sylva_world_set_threads(w, bench_threads);
  printf("\n== %s (%d threads)\n%4s %9s %8s %8s", name, bench_threads, "T", "live", "new", "ms");
  for (int p = 0; p < SYLVA_PHASE_COUNT; p++) printf(" %7s", phase_names[p]);
  printf(" %9s %9s\n", "voxelMB", "skelMB");
  double t0 = now(NULL);
  const sylva_journal *j;
  double early_shade = 0, late_shade = 0;
  size_t early_nodes = 0, late_nodes = 0;
  while (!sylva_world_finished(w) && sylva_world_iteration(w) < limit) {
    double a = now(NULL);
    if (sylva_world_step(w, &j)) break;
    double ms = (now(NULL) - a) * 1e3;
    s.iterations = j->iteration;
    s.live = sylva_world_node_count(w);
    s.created += j->added_count;
    sylva_memory m;
    sylva_world_memory(w, &m);
    if (m.voxels > s.peak_voxels) s.peak_voxels = m.voxels;
    if (m.skeleton > s.peak_skeleton) s.peak_skeleton = m.skeleton;
    if (m.other > s.peak_other) s.peak_other = m.other;
    printf("%4d %9zu %8zu %8.1f", j->iteration, s.live, j->added_count, ms);
    memmove(s.last_ms, s.last_ms + 1, sizeof s.last_ms - sizeof *s.last_ms);
    s.last_ms[4] = ms;
    for (int p = 0; p < SYLVA_PHASE_COUNT; p++) {
      s.phase[p] += j->phase_seconds[p];
      printf(" %7.1f", j->phase_seconds[p] * 1e3);
    }
    printf(" %9.1f %9.1f\n", (double)m.voxels / 1048576.0, (double)m.skeleton / 1048576.0);
    /* shade cost per new internode while the trees are short vs tall */
    if (j->added_count > 1000) {
      if (j->iteration <= 10) {
        early_shade += j->phase_seconds[SYLVA_PHASE_SHADE];
        early_nodes += j->added_count;
      } else {
        late_shade += j->phase_seconds[SYLVA_PHASE_SHADE];
        late_nodes += j->added_count;
      }
    }
    if (target && s.live >= target) break;
  }
  s.seconds = now(NULL) - t0;
  for (int v = 1; v <= 2; v++) { /* what the store's row of an iteration costs */
    double h0 = now(NULL);
    volatile uint64_t h = sylva_world_hash_of(w, v);
    (void)h;
    s.hash_ms[v - 1] = (now(NULL) - h0) * 1e3;
  }
  s.shade_us_per_node_early = early_nodes ? early_shade * 1e6 / (double)early_nodes : 0;
  s.shade_us_per_node_late = late_nodes ? late_shade * 1e6 / (double)late_nodes : 0;
  return s;
}

static void report(const summary *s) {
  printf("-- %s: %d iterations, %zu live internodes (%zu grown), %.2f s wall, %.0f internodes/s\n",
         s->name, s->iterations, s->live, s->created, s->seconds,
         (double)s->created / (s->seconds > 0 ? s->seconds : 1));
  printf("   phases (s):");
  for (int p = 0; p < SYLVA_PHASE_COUNT; p++) printf(" %s %.2f", phase_names[p], s->phase[p]);
  printf("\n   peak memory: voxels %.1f MB, skeleton %.1f MB (%.1f bytes per live internode), "
         "scratch %.1f MB, process peak RSS %.1f MB\n",
         (double)s->peak_voxels / 1048576.0, (double)s->peak_skeleton / 1048576.0,
         s->live ? (double)s->peak_skeleton / (double)s->live : 0.0,
         (double)s->peak_other / 1048576.0, (double)peak_rss_kb() / 1024.0);
  printf("   shade per new internode: %.2f us (T <= 10), %.2f us (T > 10)\n",
         s->shade_us_per_node_early, s->shade_us_per_node_late);
  printf("   world hash of the last iteration: %.1f ms by definition 1, %.1f ms by 2\n",
         s->hash_ms[0], s->hash_ms[1]);
}

static sylva_world *from_file(const char *dir, const char *file, int *limit) {
  sylva_scenario *s = scenario_file(dir, file);
  char err[512];
  sylva_world *w;
  if (sylva_scenario_build(s, &w, err, sizeof err) < 0) {
    fprintf(stderr, "bench: %s/%s: %s\n", dir, file, err);
    exit(1);
  }
  *limit = s->iterations;
  sylva_scenario_free(s);
  return w;
}

/* scenarios/street.json under its site sky and, the light key dropped, under the
 * zenith sky: the site's cost per iteration and per grown internode, and the memory
 * of the site factors. The two skies grow different trees (the facades shade the
 * south sidewalk only under the sun), so the cost is compared per internode too. */
static void street(const char *dir) {
  summary r[2];
  size_t site_bytes = 0, voxels = 0;
  for (int k = 0; k < 2; k++) {
    sylva_scenario *s = scenario_file(dir, "street.json");
    if (k == 1) s->light.site = false;
    char err[512];
    sylva_world *w;
    if (sylva_scenario_build(s, &w, err, sizeof err) < 0) {
      fprintf(stderr, "bench: street.json: %s\n", err);
      exit(1);
    }
    sylva_world_set_clock(w, now, NULL);
    r[k] = grow(k ? "street.json, zenith sky" : "street.json, site sky (48 N)", w, s->iterations, 0);
    report(&r[k]);
    if (k == 0) {
      sylva_memory m;
      sylva_world_memory(w, &m);
      site_bytes = m.site;
      voxels = m.voxels;
    }
    sylva_world_destroy(w);
    sylva_scenario_free(s);
  }
  double per_it[2], per_node[2];
  for (int k = 0; k < 2; k++) {
    per_it[k] = r[k].seconds * 1e3 / (r[k].iterations ? r[k].iterations : 1);
    per_node[k] = r[k].seconds * 1e6 / (double)(r[k].created ? r[k].created : 1);
  }
  printf("-- street: site %.2f s, zenith %.2f s (%.2fx); per iteration %.1f ms vs %.1f ms; "
         "per grown internode %.1f us vs %.1f us (%.2fx); site factors %.2f MB of %.1f MB of "
         "voxels\n",
         r[0].seconds, r[1].seconds, r[0].seconds / r[1].seconds, per_it[0], per_it[1], per_node[0],
         per_node[1], per_node[0] / per_node[1], (double)site_bytes / 1048576.0,
         (double)voxels / 1048576.0);
}

/* A world of `rows` x `rows` trees of a preset `spacing` metres apart, `height`
 * metres high, at the preset's voxel rule (rho / 2). */
static sylva_world *stand_of(const char *preset, int rows, double spacing, double height) {
  sylva_species_def sp;
  if (sylva_preset_find(preset, &sp)) {
    fprintf(stderr, "bench: no preset %s\n", preset);
    exit(1);
  }
  sylva_world_def d = sylva_default_world_def();
  double half = rows * spacing / 2.0 + 3.0;
  d.min[0] = d.min[1] = -half;
  d.max[0] = d.max[1] = half;
  d.max[2] = height;
  d.voxel = sp.rho / 2.0;
  d.seed = 2024;
  d.clock = now;
  sylva_world *w;
  if (sylva_world_create(&d, &w)) exit(1);
  sp.tropism[2] = sp.tropism[2] < 0.0 ? sp.tropism[2] : 1.0; /* upright, as the scenarios */
  int s = sylva_world_add_species(w, &sp, preset);
  for (int i = 0; i < rows * rows; i++) {
    double root[1][3] = {{(i % rows - (rows - 1) / 2.0) * spacing, (i / rows - (rows - 1) / 2.0) * spacing, 0}};
    char label[16];
    snprintf(label, sizeof label, "t%d", i);
    sylva_plant_def p = {s, label, (const double(*)[3])root, 1, 0, NULL, 0};
    if (sylva_world_add_plant(w, &p, NULL) < 0) exit(1);
  }
  return w;
}

static sylva_world *single(const char *preset) {
  sylva_world_def d = sylva_default_world_def();
  d.min[0] = d.min[1] = -6;
  d.max[0] = d.max[1] = 6;
  d.max[2] = 12;
  d.clock = now;
  d.seed = 17;
  sylva_world *w;
  if (sylva_world_create(&d, &w)) exit(1);
  sylva_species_def sp;
  if (sylva_preset_find(preset, &sp)) exit(1);
  sp.tropism[2] = 1.0; /* upright, as the ready scenarios */
  int s = sylva_world_add_species(w, &sp, preset);
  double root[1][3] = {{0, 0, 0}};
  sylva_plant_def p = {s, "tree", (const double(*)[3])root, 1, 0, NULL, 0};
  if (sylva_world_add_plant(w, &p, NULL) < 0) exit(1);
  return w;
}

/* A world of `rows` x `rows` igm-fig17b trees `spacing` metres apart. */
static sylva_world *generated_stand(int rows, double spacing) {
  return stand_of("igm-fig17b", rows, spacing, 14.0);
}

/* What canopy cover and carbon add to an iteration (issue 32): the canopy pass and
 * the wood and carbon pass on the grown world, each timed over five calls, against
 * the mean of its last five iterations. The stats pass runs both once an iteration. */
static void gives_cost(sylva_world *w, const summary *s) {
  double a = now(NULL);
  for (int k = 0; k < 5; k++) sylva__canopy(w);
  double canopy = (now(NULL) - a) / 5 * 1e3;
  a = now(NULL);
  for (int k = 0; k < 5; k++) sylva__stats_loaded(w); /* wood, carbon and the canopy */
  double wood = (now(NULL) - a) / 5 * 1e3 - canopy;
  double it = 0;
  for (int k = 0; k < 5; k++) it += s->last_ms[k] / 5;
  printf("   what the trees give: canopy %.2f ms, wood and carbon %.2f ms an iteration, "
         "%.2f%% of the last iterations' %.1f ms (cover %.4f)\n",
         canopy, wood, 100 * (canopy + wood) / it, it, sylva_world_canopy_cover(w));
}

/* What the voxels hold: chunks of shade, chunks with a node, block sums. */
static void voxel_census(const sylva_world *w) {
  const sylva__grid *g = &w->grid;
  size_t n = (size_t)g->c[0] * (size_t)g->c[1] * (size_t)g->c[2], nonzero = 0, slots = 0, held = 0;
  for (size_t i = 0; i < n; i++) {
    if (g->occ[i]) slots += g->occ[i]->cap, held += g->occ[i]->count;
    const sylva__chunk *c = g->chunks[i];
    if (!c) continue;
    for (int k = 0; k < SYLVA__CHUNK_VOXELS; k++) nonzero += c->shade[k] != 0;
  }
  printf("   voxels: %zu chunks of shade of %zu, %zu with a node (%.1f MB of occupancy), %zu block "
         "sums; %.1f%% of shade entries nonzero\n", g->chunk_count, n, g->occ_count, (double)g->occ_bytes / 1048576.0,
         g->colsum_count, g->chunk_count ? 100.0 * (double)nonzero / (double)(g->chunk_count * 4096) : 0.0);
  printf("   occupancy: %zu voxels with a node in %zu slots (%.0f%% full)\n", held, slots,
         slots ? 100.0 * (double)held / (double)slots : 0.0);
}

/* Library species in years (issue 20): scenarios/street.json's street of library
 * trees, and a hectare of 400 trees 5 m apart, each grown 40 years; the time and the
 * peak memory of each. */
static void years(const char *dir, bool street_only) {
  int limit;
  sylva_world *w = from_file(dir, "street-ten.json", &limit);
  sylva_world_set_clock(w, now, NULL);
  summary s = grow("a street of 10 library trees, 40 years (scenarios/street-ten.json)", w, 40, 0);
  report(&s);
  gives_cost(w, &s);
  sylva_world_destroy(w);
  if (street_only) return;
  w = stand_of("utdb:NoEast:TICO", 20, 5.0, 30.0);
  s = grow("a hectare of 400 library trees (utdb:NoEast:TICO, 5 m apart), 40 years", w, 40, 0);
  report(&s);
  voxel_census(w);
  gives_cost(w, &s);
  sylva_world_destroy(w);
}

/* A stand that thins itself (issue 34, docs/model.md "Stands"): a hectare of 2,500
 * lindens 2 m apart grown 60 years (targets: under 10 minutes and 4 GB on 2 cores);
 * the time, the peak memory and the stand's end. */
static void thinning(void) {
  sylva_world *w = stand_of("utdb:NoEast:TICO", 50, 2.0, 30.0);
  summary s = grow("a hectare of 2,500 library trees (utdb:NoEast:TICO, 2 m apart), 60 years", w,
                   60, 0);
  report(&s);
  sylva_stand_stats st;
  sylva_world_stand(w, &st);
  printf("   stand at 60 years: %d of 2500 alive, %.0f stems/ha, QMD %.2f cm, SDI %.0f, "
         "dominant height %.2f m\n", st.alive, st.stems_per_ha, st.qmd, st.sdi,
         st.dominant_height);
  sylva_world_destroy(w);
}

/* Shading one internode at heights from 1 to 20 m: the cost must not grow. */
static void shade_by_height(void) {
  printf("\n== shade cost by height (pyramid depth 20, 5 cm voxels)\n");
  sylva__grid g;
  double mn[3] = {0, 0, 0}, mx[3] = {20, 20, 25};
  if (sylva__grid_init(&g, mn, mx, 0.05)) exit(1);
  sylva__pyramid shade = {.depth = 20};
  for (int q = 1; q <= 20; q++) {
    shade.w[q - 1] = (int64_t)(pow(2.0, -q) * SYLVA__SHADE_ONE);
    shade.half[q - 1] = q; /* the default shade_spread of 1 */
  }
  double heights[] = {1, 2, 5, 10, 20};
  for (size_t h = 0; h < sizeof heights / sizeof heights[0]; h++) {
    int n = 20000;
    double t0 = now(NULL);
    for (int i = 0; i < n; i++) {
      int v[3] = {100 + (i * 7) % 200, 100 + (i * 13) % 200, (int)(heights[h] / 0.05)};
      sylva__grid_stamp(&g, v, &shade, +1);
    }
    double t1 = now(NULL);
    printf("   at %4.1f m: %.2f us per internode\n", heights[h], (t1 - t0) * 1e6 / n);
  }
  sylva__grid_free(&g);
}

/* The engine against its shade floor (issue 35): a stand grown some iterations,
 * then the floor: every internode the run grew stamps its pyramid (the species' own,
 * as the engine cast it) into a dense grid of the same voxels, as plain C, once. The
 * engine also removes shade when it sheds and reads light; the floor only adds.
 *
 * "Every internode grown" counts those a shoot added and the same iteration shed
 * (a branch that died at once): the journal lists only the nodes alive at the end
 * of their iteration. The bench sees each stamp the engine adds through the
 * linker (-Wl,--wrap=sylva__grid_stamp, tests/bench/meson.build), so the floor
 * stamps what the engine stamped, and no hook sits in the engine. */
typedef struct floor_stamps {
  bool on;
  size_t n, cap;
  int (*v)[3];
  uint8_t *pyr; /* an index into kinds */
  sylva__pyramid kinds[256];
  int kind_count, last;
  int top; /* the highest layer a pyramid writes */
} floor_stamps;

static floor_stamps floor_rec;

static bool same_pyramid(const sylva__pyramid *a, const sylva__pyramid *b) {
  return a->depth == b->depth && a->column == b->column &&
         memcmp(a->w, b->w, (size_t)a->depth * sizeof a->w[0]) == 0 &&
         memcmp(a->half, b->half, (size_t)a->depth * sizeof a->half[0]) == 0;
}

int __real_sylva__grid_stamp(sylva__grid *g, const int v[3], const sylva__pyramid *p, int sign);
int __wrap_sylva__grid_stamp(sylva__grid *g, const int v[3], const sylva__pyramid *p, int sign);

int __wrap_sylva__grid_stamp(sylva__grid *g, const int v[3], const sylva__pyramid *p, int sign) {
  int rc = __real_sylva__grid_stamp(g, v, p, sign);
  floor_stamps *f = &floor_rec;
  if (rc || sign <= 0 || !f->on) return rc;
  if (f->n == f->cap) {
    f->cap = f->cap ? 2 * f->cap : 1 << 16;
    f->v = realloc(f->v, f->cap * sizeof *f->v);
    f->pyr = realloc(f->pyr, f->cap);
    if (!f->v || !f->pyr) exit(1);
  }
  int k = f->last;
  if (k >= f->kind_count || !same_pyramid(&f->kinds[k], p)) {
    for (k = 0; k < f->kind_count && !same_pyramid(&f->kinds[k], p); k++) continue;
    if (k == f->kind_count) {
      if (k == 256) {
        fprintf(stderr, "bench: more than 256 pyramids\n");
        exit(1);
      }
      f->kinds[f->kind_count++] = *p;
    }
    f->last = k;
  }
  memcpy(f->v[f->n], v, sizeof f->v[0]);
  f->pyr[f->n++] = (uint8_t)k;
  if (v[2] - 1 > f->top) f->top = v[2] - 1;
  return rc;
}

static void shade_floor_of(const char *title, sylva_world *w, int iterations) {
  sylva_world_set_threads(w, bench_threads);
  floor_stamps *f = &floor_rec;
  f->n = 0;
  f->kind_count = f->last = 0;
  f->top = -1;
  f->on = true;
  size_t kept = 0; /* alive at the end of their iteration: the journal's */
  const sylva_journal *j;
  double phase[SYLVA_PHASE_COUNT] = {0}, engine = 0;
  while (sylva_world_iteration(w) < iterations && !sylva_world_finished(w)) {
    double a = now(NULL);
    if (sylva_world_step(w, &j)) break;
    engine += now(NULL) - a;
    for (int p = 0; p < SYLVA_PHASE_COUNT; p++) phase[p] += j->phase_seconds[p];
    kept += j->added_count;
  }
  f->on = false;
  size_t n = f->n;
  printf("\n== %s, %d threads: %d iterations, %zu live internodes, %zu grown (%zu of them alive "
         "at their iteration's end) in %.2f s, %.0f grown per s\n   phases (s):",
         title, bench_threads, sylva_world_iteration(w), sylva_world_node_count(w), n, kept,
         engine, (double)n / engine);
  for (int p = 0; p < SYLVA_PHASE_COUNT; p++) printf(" %s %.2f", phase_names[p], phase[p]);
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  int dmin = 64, dmax = 0;
  for (int k = 0; k < f->kind_count; k++) {
    if (f->kinds[k].depth < dmin) dmin = f->kinds[k].depth;
    if (f->kinds[k].depth > dmax) dmax = f->kinds[k].depth;
  }
  printf("\n   world hash %016llx; %ld page faults so far; %d pyramids, %d to %d layers deep\n",
         (unsigned long long)sylva_world_hash(w), ru.ru_minflt + ru.ru_majflt, f->kind_count, dmin,
         dmax);
  voxel_census(w);
  const int *dim = w->grid.n;
  size_t plane = (size_t)dim[0] * (size_t)dim[1], layers = (size_t)(f->top + 1);
  /* the layers up to the highest a pyramid writes; its pages are first touched by
   * the stamps, inside its time, as the engine's chunks are inside the engine's (a
   * memset before the clock is dropped by the compiler: calloc's memory is zero) */
  int64_t *dense = calloc(plane * (layers ? layers : 1), sizeof *dense);
  if (!dense) exit(1);
  double t0 = now(NULL);
  for (size_t i = 0; i < n; i++) {
    const sylva__pyramid *p = &f->kinds[f->pyr[i]];
    const int *v = f->v[i];
    for (int q = 1; q <= p->depth && v[2] - q >= 0; q++) {
      int h = p->half[q - 1];
      int64_t *layer = dense + (size_t)(v[2] - q) * plane;
      int x0 = v[0] - h < 0 ? 0 : v[0] - h, x1 = v[0] + h >= dim[0] ? dim[0] - 1 : v[0] + h;
      int y0 = v[1] - h < 0 ? 0 : v[1] - h, y1 = v[1] + h >= dim[1] ? dim[1] - 1 : v[1] + h;
      for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) layer[(size_t)y * (size_t)dim[0] + (size_t)x] += p->w[q - 1];
    }
  }
  double floor_s = now(NULL) - t0;
  int64_t check = 0;
  for (size_t i = 0; i < plane * layers; i += 4099) check ^= dense[i];
  printf("-- shade floor: %zu internodes stamped into a dense %d x %d x %zu grid (%.0f MB) in "
         "%.2f s (%.0f per s; checksum %llx); the engine took %.2f s, %.2fx its floor\n",
         n, dim[0], dim[1], layers, (double)(plane * layers * sizeof *dense) / 1048576.0, floor_s,
         (double)n / floor_s, (unsigned long long)check, engine, engine / floor_s);
  free(dense);
  sylva_world_destroy(w);
}

/* The floors of issue 35: the 100 igm-fig13 trees 2.5 m apart, 30 iterations; and a
 * library species' stand, 36 lindens 5 m apart, 20 and 40 years. */
static void shade_floor(void) {
  shade_floor_of("100 igm-fig13 trees 2.5 m apart, 30 iterations",
                 stand_of("igm-fig13", 10, 2.5, 14.0), 30);
  shade_floor_of("36 lindens (utdb:NoEast:TICO) 5 m apart, 20 years",
                 stand_of("utdb:NoEast:TICO", 6, 5.0, 30.0), 20);
  shade_floor_of("36 lindens (utdb:NoEast:TICO) 5 m apart, 40 years",
                 stand_of("utdb:NoEast:TICO", 6, 5.0, 30.0), 40);
  free(floor_rec.v);
  free(floor_rec.pyr);
  floor_rec.v = NULL;
  floor_rec.pyr = NULL;
  floor_rec.cap = 0;
}

/* A site of 4000 x 4000 x 200 voxels: 200 m x 200 m x 10 m at 5 cm, nothing in it. */
static sylva_world *obstacle_site(void) {
  sylva_world_def d = sylva_default_world_def();
  d.min[0] = d.min[1] = -100;
  d.max[0] = d.max[1] = 100;
  d.min[2] = 0;
  d.max[2] = 10;
  d.voxel = 0.05;
  d.seed = 5;
  sylva_world *w;
  if (sylva_world_create(&d, &w)) exit(1);
  return w;
}

/* A random box: a corner anywhere in the site, sides of 0.05 m up to `side` m, at
 * most `thick` m tall, between 0.5 m and 9 m high. */
static void random_box(sylva__rng *r, double side, double thick, double mn[3], double mx[3]) {
  for (int a = 0; a < 2; a++) {
    mn[a] = -100 + 200 * sylva__rng_unit(r);
    mx[a] = mn[a] + 0.05 + (side - 0.05) * sylva__rng_unit(r);
  }
  mn[2] = 0.5 + 8.5 * sylva__rng_unit(r);
  mx[2] = mn[2] + 0.05 + (thick - 0.05) * sylva__rng_unit(r);
}

/* The light of every cell of the layer at 0.52 m (as sylva_msg_light_slice reads
 * it) with 1,000 boxes; then `edits` obstacles added, found by label, copied through
 * a snapshot and removed by id in the order they were added (the oldest first). */
/* The light of every cell of the layer at 0.52 m with 1,000 boxes, or (turned) the
 * same boxes as prisms turned by 30 degrees about their centres. */
static void light_slice(bool turned) {
  sylva_world *w = obstacle_site();
  sylva__rng r;
  sylva__rng_seed(&r, 99);
  double t_add = now(NULL), c = sqrt(3.0) / 2, s = 0.5; /* 30 degrees */
  for (int i = 0; i < 1000; i++) {
    char label[16];
    snprintf(label, sizeof label, "box%d", i);
    sylva_obstacle_def o = {label, {0}, {0}, SYLVA_OBSTACLE_SOLID, {0}};
    random_box(&r, 5.0, 2.0, o.min, o.max);
    double pts[4][2];
    int ring[1] = {4};
    if (turned) {
      double cx = (o.min[0] + o.max[0]) / 2, cy = (o.min[1] + o.max[1]) / 2;
      double hx = (o.max[0] - o.min[0]) / 2, hy = (o.max[1] - o.min[1]) / 2;
      const double corner[4][2] = {{-hx, -hy}, {hx, -hy}, {hx, hy}, {-hx, hy}};
      for (int k = 0; k < 4; k++) {
        pts[k][0] = cx + c * corner[k][0] - s * corner[k][1];
        pts[k][1] = cy + s * corner[k][0] + c * corner[k][1];
      }
      o.footprint = (sylva_footprint){(const double(*)[2])pts, 4, ring, 1};
    }
    if (sylva_world_add_obstacle(w, &o) < 0) exit(1);
  }
  int dims[3];
  sylva_world_dims(w, dims);
  double t0 = now(NULL), sum = 0;
  long dark = 0;
  for (int j = 0; j < dims[1]; j++)
    for (int i = 0; i < dims[0]; i++) {
      double p[3] = {-100 + (i + 0.5) * 0.05, -100 + (j + 0.5) * 0.05, 0.525};
      double l = sylva_world_light_at(w, p);
      sum += l;
      dark += l == 0.0;
    }
  double t1 = now(NULL);
  printf("   light slice %d x %d, 1,000 %s: %.3f s (%.1f ns per cell; %ld dark cells, "
         "light sum %.17g); added in %.3f s\n", dims[0], dims[1],
         turned ? "prisms at 30 degrees" : "boxes", t1 - t0,
         (t1 - t0) * 1e9 / ((double)dims[0] * dims[1]), dark, sum, t0 - t_add);
  sylva_world_destroy(w);
}

static void obstacles(int edits) {
  printf("\n== obstacles\n");
  light_slice(false);
  light_slice(true);
  sylva__rng r;
  sylva__rng_seed(&r, 99);
  for (int i = 0; i < 1000; i++) { /* the generator as the slices left it */
    double mn[3], mx[3];
    random_box(&r, 5.0, 2.0, mn, mx);
  }
  sylva_world *w;
  double t0, t1;

  w = obstacle_site();
  int *ids = malloc((size_t)edits * sizeof *ids);
  if (!ids) exit(1);
  t0 = now(NULL);
  for (int i = 0; i < edits; i++) {
    char label[16];
    snprintf(label, sizeof label, "o%d", i);
    sylva_obstacle_def o = {label, {0}, {0}, SYLVA_OBSTACLE_SOLID, {0}};
    random_box(&r, 1.0, 0.5, o.min, o.max);
    ids[i] = sylva_world_add_obstacle(w, &o);
    if (ids[i] < 0) exit(1);
  }
  t1 = now(NULL);
  int found = 0;
  for (int i = 0; i < edits; i++) {
    char label[16];
    snprintf(label, sizeof label, "o%d", i);
    found += sylva_world_find_obstacle(w, label) == ids[i];
  }
  double t2 = now(NULL);
  sylva_memory m;
  sylva_world_memory(w, &m);
  /* an edit of the daemon works on a copy: the world saved and loaded */
  double t3 = now(NULL);
  uint8_t *image;
  size_t size;
  sylva_world *copy;
  if (sylva_snapshot_save(w, &image, &size) || sylva_snapshot_load(image, size, &copy)) exit(1);
  sylva_free(image);
  sylva_world_destroy(copy);
  double t4 = now(NULL);
  int removed = 0;
  for (int i = 0; i < edits; i++) removed += sylva_world_remove_obstacle(w, ids[i]) == SYLVA_OK;
  double t5 = now(NULL);
  printf("   %d obstacles: added in %.3f s, found by label in %.3f s (%d found), saved and "
         "loaded in %.3f s, removed by id in %.3f s (%d removed, %d left); voxel memory with "
         "them %.1f MB\n",
         edits, t1 - t0, t2 - t1, found, t4 - t3, t5 - t4, removed,
         sylva_world_obstacle_count(w), (double)m.voxels / 1048576.0);
  free(ids);
  sylva_world_destroy(w);
}

/* Grows w, storing every iteration; reports store time against grow time. */
static void grow_stored(const char *name, sylva_world *w, int limit, size_t target) {
  char path[] = "/tmp/sylva-bench-XXXXXX";
  int fd = mkstemp(path);
  if (fd < 0) exit(1);
  close(fd);
  remove(path);
  store *st;
  int64_t run;
  if (store_open(path, true, &st) ||
      store_create_run(st, "bench", "{}", 1, limit, STORE_SNAPSHOT_EVERY, w, &run)) {
    fprintf(stderr, "bench: %s\n", st ? store_error(st) : store_open_error());
    exit(1);
  }
  printf("\n== %s, stored (a full snapshot every %d iterations)\n%4s %9s %10s %10s %7s\n", name,
         STORE_SNAPSHOT_EVERY, "T", "live", "grow ms", "store ms", "store%");
  double grow_s = 0, store_s = 0;
  const sylva_journal *j;
  while (!sylva_world_finished(w) && sylva_world_iteration(w) < limit) {
    double t0 = now(NULL);
    if (sylva_world_step(w, &j)) break;
    double t1 = now(NULL);
    bool last = sylva_world_finished(w) || j->iteration >= limit ||
                (target && sylva_world_node_count(w) >= target);
    if (store_save_iteration(st, run, w, j, last || j->iteration % STORE_SNAPSHOT_EVERY == 0)) {
      fprintf(stderr, "bench: %s\n", store_error(st));
      exit(1);
    }
    double t2 = now(NULL);
    grow_s += t1 - t0;
    store_s += t2 - t1;
    printf("%4d %9zu %10.1f %10.1f %6.1f%%\n", j->iteration, sylva_world_node_count(w),
           (t1 - t0) * 1e3, (t2 - t1) * 1e3, 100.0 * (t2 - t1) / (t1 - t0));
    if (last) break;
  }
  store_close(st);
  struct stat sb;
  long long bytes = stat(path, &sb) == 0 ? (long long)sb.st_size : -1;
  char wal[64];
  snprintf(wal, sizeof wal, "%s-wal", path);
  if (stat(wal, &sb) == 0) bytes += (long long)sb.st_size;
  printf("-- %s: growing %.2f s, storing %.2f s = %.1f%% of growing; store file %.1f MB\n", name,
         grow_s, store_s, 100.0 * store_s / grow_s, (double)bytes / 1048576.0);
  remove(path);
  remove(wal);
  snprintf(wal, sizeof wal, "%s-shm", path);
  remove(wal);
}

int main(int argc, char **argv) {
  mallopt(M_MMAP_THRESHOLD, 1 << 20); /* as the sylva program does (server/cli/main.c) */
  const char *what = "all", *dir = SOURCE_ROOT "/scenarios";
  int edits = 100000;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--scenarios") == 0 && i + 1 < argc)
      dir = argv[++i];
    else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc)
      bench_threads = atoi(argv[++i]);
    else if (strcmp(argv[i], "--edits") == 0 && i + 1 < argc)
      edits = atoi(argv[++i]);
    else
      what = argv[i];
  }
  bool all = strcmp(what, "all") == 0;
  if (all || strcmp(what, "shade") == 0) shade_by_height();
  if (all || strcmp(what, "floor") == 0) shade_floor();
  if (all || strcmp(what, "obstacles") == 0) obstacles(edits > 0 ? edits : 1);
  if (all || strcmp(what, "fig17b") == 0) {
    sylva_world *w = single("igm-fig17b");
    summary s = grow("fig. 17b tree", w, 40, 0);
    report(&s);
    sylva_world_destroy(w);
  }
  if (all || strcmp(what, "stand5") == 0) {
    int limit;
    sylva_world *w = from_file(dir, "stand.json", &limit);
    sylva_world_set_clock(w, now, NULL);
    summary s = grow("five-tree stand (scenarios/stand.json)", w, limit, 0);
    report(&s);
    sylva_world_destroy(w);
  }
  if (all || strcmp(what, "street") == 0) street(dir);
  if (strcmp(what, "hectare") == 0) {
    sylva_world *w = stand_of("utdb:NoEast:TICO", 20, 5.0, 30.0);
    summary s = grow("a hectare of 400 library trees (utdb:NoEast:TICO, 5 m apart), 40 years", w, 40, 0);
    report(&s);
    voxel_census(w);
    sylva_world_destroy(w);
  }
  if (all || strcmp(what, "years") == 0 || strcmp(what, "street10") == 0)
    years(dir, strcmp(what, "street10") == 0);
  if (all || strcmp(what, "thinning") == 0) thinning();
  if (all || strcmp(what, "store5") == 0) {
    int limit;
    sylva_world *w = from_file(dir, "stand.json", &limit);
    grow_stored("five-tree stand", w, limit, 0);
    sylva_world_destroy(w);
  }
  if (all || strcmp(what, "store100") == 0) {
    sylva_world *w = generated_stand(10, 2.0);
    grow_stored("100-tree stand", w, 60, 1000000);
    sylva_world_destroy(w);
  }
  if (all || strcmp(what, "stand100") == 0) {
    sylva_world *w = generated_stand(10, 2.0);
    summary s = grow("100-tree stand to 1,000,000 live internodes", w, 60, 1000000);
    report(&s);
    if (s.live < 1000000) printf("   (finished before 1,000,000 live internodes)\n");
    sylva_world_destroy(w);
  }
  return 0;
}
