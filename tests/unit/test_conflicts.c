/* Clearance zones, clearances and pruning (core/src/conflicts.c) against brute
 * forces, on a hand-built street: solid boxes and clearance zones among five stems
 * (three trees and a two-stemmed shrub).
 *
 * - zones change nothing: with or without them (zenith or site sky, zones added and
 *   removed mid-run) the world hash is the same at every iteration;
 * - the zone lines (nodes inside now, first iteration seen) and the clearances
 *   equal a count over every node and obstacle, after every step and edit;
 * - a schedule removes exactly the nodes inside its zone and their subtrees: the
 *   world equals a copy stepped without the schedule minus those subtrees, the
 *   pruned counts and the journal say so, and the grid equals one rebuilt from the
 *   live nodes; prune-now does the same for a box between steps (a box that is one
 *   point included), leaving a scar where it cut a lateral;
 * - a world that starts reporting by prune-now has its clearances at once;
 * - a stem pruned down to its root steps on (in a child process: a crash fails
 *   that test alone);
 * - snapshots taken at any iteration continue identically (hash, conflicts and
 *   pruned counts);
 * - images keep the old layout without zones, set the CONFLICTS flag with them,
 *   and a corrupted conflicts section is refused;
 * - schedules: bad ones refused, the iterations they name, a removed zone's;
 * - a plant whose trunk meets another stem's branches cuts exactly the nodes in its
 *   trunk's voxels and what they carry (counted as pruned; the grid as rebuilt); a
 *   root on another's root is refused with the world unchanged. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "../check.h"
#include "../conflicts_check.h"
#include "conflicts.h"
#include "sylva/sylva.h"
#include "world_impl.h"

enum { WITH_ZONES = 1, WITH_SOLIDS = 2, WITH_SKY = 4 };
enum { MAX_STEMS = 8, MAX_OBSTACLES = 16 };

/* A small sky: the zenith and four directions 60 degrees up. */
static const sylva_sky_dir sky5[] = {
    {{0, 0, 1}, 0.4},
    {{0.5, 0, 0.8660254037844386}, 0.15},
    {{-0.5, 0, 0.8660254037844386}, 0.15},
    {{0, 0.5, 0.8660254037844386}, 0.15},
    {{0, -0.5, 0.8660254037844386}, 0.15},
};

/* Solids and zones interleaved, so that ids of the one kind skip the other. */
static const sylva_obstacle_def layout[] = {
    {"wall-south", {-15, -4, 0}, {15, -3.6, 5}, SYLVA_OBSTACLE_SOLID, {0}},
    {"road", {-15, -1.4, 0}, {15, 1.4, 3.5}, SYLVA_OBSTACLE_ZONE, {0}},
    {"awning", {0.5, 1.0, 2.0}, {4, 1.3, 2.1}, SYLVA_OBSTACLE_SOLID, {0}},
    /* around tree b's root and first trunk node: entered at iteration 0 */
    {"trunk-zone", {-0.1, -2.1, 0}, {0.1, -1.9, 0.15}, SYLVA_OBSTACLE_ZONE, {0}},
    /* more than SYLVA_CLEARANCE_RANGE from tree a */
    {"east-post", {13.5, -0.5, 0}, {14, 0.5, 3}, SYLVA_OBSTACLE_SOLID, {0}},
    {"canopy", {-15, -4, 4}, {15, 4, 8}, SYLVA_OBSTACLE_ZONE, {0}},
};
#define LAYOUT_COUNT ((int)(sizeof layout / sizeof layout[0]))

static sylva_world *make_world(uint64_t seed, unsigned opts) {
  sylva_world_def wd = sylva_default_world_def();
  wd.min[0] = -15, wd.min[1] = -4, wd.min[2] = 0;
  wd.max[0] = 15, wd.max[1] = 4, wd.max[2] = 8;
  wd.seed = seed;
  if (opts & WITH_SKY) {
    wd.sky = sky5;
    wd.sky_count = 5;
  }
  sylva_world *w;
  if (sylva_world_create(&wd, &w)) return NULL;
  sylva_species_def sp = sylva_default_species_def();
  /* igm-fig13's tree on a shorter life: bushy by iteration 12, small enough to keep
   * the test fast */
  sp.growth.p[1] = 60;
  sp.tau = 5;
  sp.b_max = 2.3;
  sp.apical_flow = 0.01;
  int s = sylva_world_add_species(w, &sp, "x");
  for (int i = 0; i < LAYOUT_COUNT; i++) {
    bool zone = layout[i].kind == SYLVA_OBSTACLE_ZONE;
    if (!(opts & (zone ? WITH_ZONES : WITH_SOLIDS))) continue;
    if (sylva_world_add_obstacle(w, &layout[i]) < 0) {
      sylva_world_destroy(w);
      return NULL;
    }
  }
  static const double ra[1][3] = {{-12.5, -2, 0}}, rb[1][3] = {{0, -2, 0}},
                      rc[1][3] = {{2.2, 2.2, 0}}, rd[2][3] = {{-4, 2, 0}, {-4.5, 2.5, 0}};
  sylva_plant_def plants[] = {{s, "a", ra, 1, 0, NULL, 0}, {s, "b", rb, 1, 0, NULL, 0}, {s, "c", rc, 1, 0, NULL, 0}, {s, "d", rd, 2, 0, NULL, 0}};
  for (int i = 0; i < 4; i++)
    if (sylva_world_add_plant(w, &plants[i], NULL) < 0) {
      sylva_world_destroy(w);
      return NULL;
    }
  return w;
}

/* ---- brute force ------------------------------------------------------------ */

typedef struct node_list {
  sylva_node_info *n;
  int32_t *gstem; /* global stem index */
  size_t count;
} node_list;

static node_list nodes_of(const sylva_world *w) {
  node_list l;
  l.count = sylva_world_node_count(w);
  l.n = malloc((l.count + 1) * sizeof *l.n);
  l.gstem = malloc((l.count + 1) * sizeof *l.gstem);
  for (size_t i = 0; i < l.count; i++) {
    sylva_world_node_at(w, i, &l.n[i]);
    l.gstem[i] = sylva_world_stem_index(w, l.n[i].plant, l.n[i].stem);
  }
  return l;
}

static void nodes_free(node_list *l) {
  free(l->n);
  free(l->gstem);
}

/* The index of the node with this id in a list in id order, or -1. */
static long find_id(const node_list *l, int32_t id) {
  size_t lo = 0, hi = l->count;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (l->n[mid].id < id)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < l->count && l->n[lo].id == id ? (long)lo : -1;
}

/* First iteration each (stem, obstacle id) was seen with a node inside; -1 never. */
typedef struct tracker {
  int first[MAX_STEMS][MAX_OBSTACLES];
} tracker;

static void tracker_init(tracker *t) {
  for (int k = 0; k < MAX_STEMS; k++)
    for (int o = 0; o < MAX_OBSTACLES; o++) t->first[k][o] = -1;
}

static void tracker_note(tracker *t, int stem, int zone, int T) {
  if (t->first[stem][zone] < 0 || T < t->first[stem][zone]) t->first[stem][zone] = T;
}

/* Compares the world's conflicts with a count over every node and obstacle (noting
 * in t the zones entered now). Returns the mismatches (each also reported). */
static int check_conflicts(const sylva_world *w, tracker *t, const char *where) {
  return conflicts_brute_force(w, &t->first[0][0], MAX_OBSTACLES, true, where);
}

/* Zone lines with nodes inside now, and (stem, solid) pairs out of range. */
static void conflict_tally(const sylva_world *w, int64_t *inside, int *out_of_range) {
  sylva_conflicts c = sylva_world_conflicts(w);
  for (size_t i = 0; i < c.zone_count; i++) *inside += c.zones[i].nodes;
  int solids = 0;
  for (int i = 0; i < sylva_world_obstacle_count(w); i++) {
    sylva_obstacle_def od;
    sylva_world_obstacle_at(w, i, NULL, &od);
    solids += od.kind == SYLVA_OBSTACLE_SOLID;
  }
  *out_of_range += solids * sylva_world_stem_count(w) - (int)c.clearance_count;
}

/* ---- grids ------------------------------------------------------------------- */

/* Voxels whose shade or occupancy differ, over every chunk column either grid has
 * touched (elsewhere both are empty); *compared counts the voxels looked at. */
static long grids_differ(const sylva__grid *a, const sylva__grid *b, long *compared) {
  long bad = 0;
  for (int cy = 0; cy < a->c[1]; cy++)
    for (int cx = 0; cx < a->c[0]; cx++) {
      size_t col = (size_t)cy * (size_t)a->c[0] + (size_t)cx;
      bool any = a->colsum_top[col] || b->colsum_top[col];
      for (int cz = 0; cz < a->c[2] && !any; cz++) {
        size_t ci = ((size_t)cz * (size_t)a->c[1] + (size_t)cy) * (size_t)a->c[0] + (size_t)cx;
        any = a->chunks[ci] || b->chunks[ci];
      }
      if (!any) continue;
      for (int z = 0; z < a->n[2]; z++)
        for (int y = cy * 16; y < cy * 16 + 16 && y < a->n[1]; y++)
          for (int x = cx * 16; x < cx * 16 + 16 && x < a->n[0]; x++) {
            int v[3] = {x, y, z};
            (*compared)++;
            if (sylva__grid_shade_raw(a, v) != sylva__grid_shade_raw(b, v) ||
                sylva__grid_occ_word(a, v) != sylva__grid_occ_word(b, v))
              bad++;
          }
    }
  return bad;
}

static sylva_world *reload(const sylva_world *w) {
  uint8_t *img;
  size_t n;
  if (sylva_snapshot_save(w, &img, &n)) return NULL;
  sylva_world *r = NULL;
  int rc = sylva_snapshot_load(img, n, &r);
  free(img);
  return rc ? NULL : r;
}

/* The world's grid equals one stamped from its live nodes alone (a snapshot's
 * load), voxel for voxel. */
static void check_grid_restamped(const sylva_world *w) {
  sylva_world *r = reload(w);
  CHECK(r != NULL);
  if (!r) return;
  long compared = 0, bad = grids_differ(&w->grid, &r->grid, &compared);
  CHECK_INT(bad, 0);
  CHECK(compared > 100000);
  CHECK(sylva_world_hash(r) == sylva_world_hash(w));
  sylva_world_destroy(r);
}

/* ---- conflicts copies --------------------------------------------------------- */

typedef struct conflicts_copy {
  sylva_zone_stat *z;
  size_t nz;
  sylva_clearance_stat *c;
  size_t nc;
} conflicts_copy;

static conflicts_copy copy_conflicts(sylva_conflicts c) {
  conflicts_copy o = {malloc((c.zone_count + 1) * sizeof *o.z), c.zone_count,
                      malloc((c.clearance_count + 1) * sizeof *o.c), c.clearance_count};
  if (c.zone_count) memcpy(o.z, c.zones, c.zone_count * sizeof *o.z);
  if (c.clearance_count) memcpy(o.c, c.clearances, c.clearance_count * sizeof *o.c);
  return o;
}

static bool conflicts_equal(const conflicts_copy *a, sylva_conflicts b) {
  return conflicts_lists_equal(a->z, a->nz, a->c, a->nc, b);
}

/* ---- 1. zones change nothing ---------------------------------------------------- */

static void zones_change_nothing_case(unsigned base, uint64_t seed) {
  sylva_world *a = make_world(seed, base | WITH_ZONES), *b = make_world(seed, base);
  CHECK(a && b);
  if (!a || !b) return;
  CHECK(sylva_world_reports_conflicts(a));
  CHECK(!sylva_world_reports_conflicts(b));
  int mismatches = sylva_world_hash(a) != sylva_world_hash(b), steps = 0;
  int64_t inside = 0;
  int out_of_range = 0;
  for (int T = 1; T <= 16; T++) {
    if (T == 4) { /* a zone over tree c's crown, added mid-run */
      sylva_obstacle_def late = {"late", {1.5, 1.5, 0.5}, {3, 3, 2.5}, SYLVA_OBSTACLE_ZONE, {0}};
      CHECK(sylva_world_add_obstacle(a, &late) >= 0);
    }
    if (T == 9) /* and a zone removed */
      CHECK_INT(sylva_world_remove_obstacle(a, sylva_world_find_obstacle(a, "trunk-zone")), 0);
    mismatches += sylva_world_hash(a) != sylva_world_hash(b);
    const sylva_journal *ja, *jb;
    int ra = sylva_world_step(a, &ja), rb = sylva_world_step(b, &jb);
    CHECK_INT(ra, rb);
    if (ra || rb) break;
    steps++;
    mismatches += sylva_world_hash(a) != sylva_world_hash(b);
    mismatches += ja->added_count != jb->added_count || ja->shed_count != jb->shed_count ||
                  ja->radii_count != jb->radii_count;
    for (size_t k = 0; k < ja->stem_count; k++) mismatches += ja->stats[k].pruned != 0;
    CHECK_INT(jb->conflicts.zone_count, 0); /* b reports nothing, as before zones */
    CHECK_INT(jb->conflicts.clearance_count, 0);
    conflict_tally(a, &inside, &out_of_range);
  }
  CHECK_INT(steps, 16);
  CHECK_INT(mismatches, 0);
  CHECK(inside > 0); /* the zones held nodes: they were there to change something */
  /* the light everywhere the same */
  int light_diff = 0;
  for (double x = -14.75; x < 15; x += 0.5)
    for (double y = -3.75; y < 4; y += 0.5)
      for (double z = 0.05; z < 5; z += 0.35) {
        double p[3] = {x, y, z};
        light_diff += sylva_world_light_at(a, p) != sylva_world_light_at(b, p);
      }
  CHECK_INT(light_diff, 0);
  sylva_world_destroy(a);
  sylva_world_destroy(b);
}

static void test_zones_change_nothing(void) {
  zones_change_nothing_case(WITH_SOLIDS, 3);            /* zenith sky, among solids */
  zones_change_nothing_case(WITH_SOLIDS | WITH_SKY, 4); /* a site's sky */
  zones_change_nothing_case(WITH_SKY, 5);               /* zones the only obstacles */
  zones_change_nothing_case(0, 6);                      /* zenith, zones only */
}

/* ---- 2. zone lines and clearances equal a brute force ------------------------------ */

static void test_conflicts_brute_force(void) {
  sylva_world *w = make_world(11, WITH_ZONES | WITH_SOLIDS);
  CHECK(w != NULL);
  if (!w) return;
  tracker t;
  tracker_init(&t);
  int bad = check_conflicts(w, &t, "planted");
  /* tree b's root and first trunk node are in trunk-zone from the start */
  int tz = sylva_world_find_obstacle(w, "trunk-zone");
  CHECK_INT(t.first[1][tz], 0);
  sylva_conflicts c0 = sylva_world_stem_conflicts(w, 1);
  CHECK_INT(c0.zone_count, 1);
  if (c0.zone_count) CHECK_INT(c0.zones[0].nodes, 2);
  /* zones whose faces pass through tree b's root at (0, -2, 0): inside on every
   * face, min or max (each holds the root alone) */
  static const sylva_obstacle_def edges[] = {
      {"edge-max", {-1, -3, -1}, {0, -2, 0}, SYLVA_OBSTACLE_ZONE, {0}},
      {"edge-min", {0, -2, 0}, {1, -1, 0.05}, SYLVA_OBSTACLE_ZONE, {0}},
  };
  for (int i = 0; i < 2; i++) {
    int id = sylva_world_add_obstacle(w, &edges[i]);
    CHECK(id >= 0);
    sylva_conflicts c = sylva_world_stem_conflicts(w, 1);
    bool found = false;
    for (size_t z = 0; z < c.zone_count; z++)
      if (c.zones[z].obstacle == id) found = c.zones[z].nodes == 1 && c.zones[z].first == 0;
    CHECK(found);
  }
  bad += check_conflicts(w, &t, "edges");
  int64_t inside = 0;
  int out_of_range = 0;
  for (int T = 1; T <= 18; T++) {
    if (T == 3) { /* a tree planted on the road, its trunk inside the zone */
      static const double re[1][3] = {{6, 0, 0}};
      sylva_plant_def pd = {0, "e", re, 1, 0, NULL, 0};
      CHECK(sylva_world_add_plant(w, &pd, NULL) >= 0);
      bad += check_conflicts(w, &t, "planted e");
      CHECK_INT(t.first[5][sylva_world_find_obstacle(w, "road")], 2);
    }
    if (T == 6) { /* a zone added over nodes: they enter now */
      sylva_obstacle_def late = {"late", {1.5, 1.5, 0.5}, {3, 3, 2.5}, SYLVA_OBSTACLE_ZONE, {0}};
      int id = sylva_world_add_obstacle(w, &late);
      CHECK(id >= 0);
      bad += check_conflicts(w, &t, "zone added");
      CHECK_INT(t.first[2][id], 5);
    }
    if (T == 10) { /* a zone removed: its lines go */
      CHECK_INT(sylva_world_remove_obstacle(w, tz), 0);
      bad += check_conflicts(w, &t, "zone removed");
    }
    if (T == 12) { /* a solid added: clearances to it from now on */
      sylva_obstacle_def post = {"post", {-1, -1.5, 0}, {-0.8, -1.3, 2}, SYLVA_OBSTACLE_SOLID, {0}};
      CHECK(sylva_world_add_obstacle(w, &post) >= 0);
      bad += check_conflicts(w, &t, "solid added");
    }
    const sylva_journal *j;
    CHECK_INT(sylva_world_step(w, &j), 0);
    if (!j) break;
    /* the journal's conflicts are the world's */
    sylva_conflicts c = sylva_world_conflicts(w);
    CHECK(j->conflicts.zones == c.zones && j->conflicts.zone_count == c.zone_count);
    CHECK(j->conflicts.clearances == c.clearances &&
          j->conflicts.clearance_count == c.clearance_count);
    bad += check_conflicts(w, &t, "step");
    conflict_tally(w, &inside, &out_of_range);
  }
  CHECK_INT(bad, 0);
  CHECK(inside > 0);
  CHECK(out_of_range > 0); /* tree a is beyond the range of the east post */
  /* every stem of the layout ended up with a line or a clearance */
  sylva_conflicts all = sylva_world_conflicts(w);
  CHECK(all.zone_count >= 4);
  CHECK(all.clearance_count >= 6);
  int road = sylva_world_find_obstacle(w, "road"), canopy = sylva_world_find_obstacle(w, "canopy");
  int road_stems = 0, canopy_stems = 0;
  for (int k = 0; k < sylva_world_stem_count(w); k++) {
    road_stems += t.first[k][road] > 0;
    canopy_stems += t.first[k][canopy] > 0;
  }
  printf("brute force: %zu zone lines, %zu clearances, %d stems grew into the road, %d into the "
         "canopy zone\n",
         all.zone_count, all.clearance_count, road_stems, canopy_stems);
  CHECK(road_stems >= 1);
  CHECK(canopy_stems >= 1);
  sylva_world_destroy(w);
}

/* ---- 3. pruning on a schedule ----------------------------------------------------- */

static bool due(const sylva_prune_def *d, int T) {
  if (T < d->from) return false;
  if (d->every == 0) return T == d->from;
  return (T - d->from) % d->every == 0;
}

static void test_schedule_prunes(void) {
  sylva_world *w = make_world(13, WITH_ZONES | WITH_SOLIDS);
  CHECK(w != NULL);
  if (!w) return;
  int road = sylva_world_find_obstacle(w, "road"), canopy = sylva_world_find_obstacle(w, "canopy");
  sylva_prune_def sched[2] = {{road, 3, 5}, {canopy, 0, 15}};
  CHECK_INT(sylva_world_add_prune(w, &sched[0]), 0);
  CHECK_INT(sylva_world_add_prune(w, &sched[1]), 0);
  CHECK_INT(sylva_world_prune_count(w), 2);
  sylva_obstacle_def zdef[MAX_OBSTACLES];
  for (int i = 0; i < sylva_world_obstacle_count(w); i++) {
    int id;
    sylva_obstacle_def od;
    sylva_world_obstacle_at(w, i, &id, &od);
    zdef[id] = od;
  }
  tracker t;
  tracker_init(&t);
  int bad = check_conflicts(w, &t, "planted");
  int64_t total_pruned = 0;
  int pruning_steps = 0, grid_checks = 0, node_mismatch = 0, journal_mismatch = 0,
      stat_mismatch = 0, left_inside = 0, hash_mismatch = 0, scar_mismatch = 0, lateral_cuts = 0;
  for (int T = 1; T <= 18; T++) {
    /* the reference: a copy of the world without the schedules, stepped alike */
    sylva_world *r = reload(w);
    CHECK(r != NULL);
    if (!r) break;
    CHECK_INT(sylva_world_prune_count(r), 2);
    r->prunes.len = 0;
    const sylva_journal *jw, *jr;
    CHECK_INT(sylva_world_step(w, &jw), 0);
    CHECK_INT(sylva_world_step(r, &jr), 0);
    if (!jw || !jr) {
      sylva_world_destroy(r);
      break;
    }
    int due_zones[2], ndue = 0;
    for (int i = 0; i < 2; i++)
      if (due(&sched[i], T)) due_zones[ndue++] = sched[i].zone;
    /* what the schedules must remove: every node of the reference inside a due zone,
     * but a root, with its subtree */
    node_list ln = nodes_of(r), lw = nodes_of(w);
    char *doomed = calloc(ln.count + 1, 1);
    int64_t per_stem[MAX_STEMS] = {0};
    size_t cut_announced = 0, doomed_newborn = 0, ndoomed = 0;
    for (size_t i = 0; i < ln.count; i++) {
      const sylva_node_info *n = &ln.n[i];
      if (n->parent < 0) continue;
      long p = find_id(&ln, n->parent);
      CHECK(p >= 0 && (size_t)p < i);
      bool in = false;
      int zone_in = -1;
      for (int z = 0; z < ndue && !in; z++)
        if (conflicts_in_box(n, zdef[due_zones[z]].min, zdef[due_zones[z]].max)) {
          in = true;
          zone_in = due_zones[z];
        }
      if (p >= 0 && doomed[p]) {
        doomed[i] = 1;
      } else if (in) {
        doomed[i] = 2; /* the root of a cut subtree */
        tracker_note(&t, ln.gstem[i], zone_in, T);
        if (n->birth != T) {
          cut_announced++;
          bool listed = false;
          for (size_t k = 0; k < jw->shed_count; k++) listed |= jw->shed[k] == n->id;
          journal_mismatch += !listed;
        }
      }
      if (doomed[i]) {
        ndoomed++;
        per_stem[ln.gstem[i]]++;
        doomed_newborn += n->birth == T;
      }
    }
    /* the world is the reference without them, node for node */
    size_t k = 0;
    for (size_t i = 0; i < ln.count; i++) {
      if (doomed[i]) continue;
      const sylva_node_info *a = &ln.n[i], *b = k < lw.count ? &lw.n[k] : NULL;
      if (!b || a->id != b->id || a->parent != b->parent || a->plant != b->plant ||
          a->stem != b->stem || a->birth != b->birth || a->x != b->x || a->y != b->y ||
          a->z != b->z || a->radius != b->radius)
        node_mismatch++;
      k++;
    }
    node_mismatch += k != lw.count;
    /* a cut leaves its parent without the child: a lateral's parent with a scar
     * (its bud does not sprout again), a leader's parent as the axis's apex */
    for (size_t i = 0; i < ln.count; i++) {
      if (doomed[i] != 2) continue;
      long p = find_id(&ln, ln.n[i].parent), q = find_id(&lw, ln.n[i].parent);
      if (p < 0 || doomed[p] || q < 0) {
        scar_mismatch++;
        continue;
      }
      bool lateral = (r->nodes.flags[i] & SYLVA__NODE_LATERAL) != 0;
      lateral_cuts += lateral;
      scar_mismatch += (lateral ? r->nodes.lateral_child[p] : r->nodes.axis_child[p]) != (int32_t)i;
      if (lateral)
        scar_mismatch += w->nodes.lateral_child[q] != -1 || !(w->nodes.flags[q] & SYLVA__NODE_SCAR);
      else
        scar_mismatch += w->nodes.axis_child[q] != -1;
    }
    /* nothing of the world is left inside a zone pruned now, but roots */
    for (size_t i = 0; i < lw.count; i++)
      for (int z = 0; z < ndue; z++)
        left_inside += lw.n[i].parent >= 0 && conflicts_in_box(&lw.n[i], zdef[due_zones[z]].min,
                                                     zdef[due_zones[z]].max);
    /* pruned counts, node counts and the journal */
    for (int s = 0; s < sylva_world_stem_count(w); s++) {
      sylva_stem_stats sw, sr;
      sylva_world_stem_stats(w, s, &sw);
      sylva_world_stem_stats(r, s, &sr);
      stat_mismatch += sw.pruned != per_stem[s] || jw->stats[s].pruned != per_stem[s] ||
                       sr.pruned != 0 || sw.nodes != sr.nodes - per_stem[s] ||
                       sw.shed != sr.shed;
      total_pruned += sw.pruned;
    }
    journal_mismatch += jw->shed_count != jr->shed_count + cut_announced;
    for (size_t i = 0; i < jr->shed_count; i++) {
      bool listed = false;
      for (size_t q = 0; q < jw->shed_count; q++) listed |= jw->shed[q] == jr->shed[i];
      journal_mismatch += !listed;
    }
    journal_mismatch += jw->added_count != jr->added_count - doomed_newborn;
    if (ndue == 0 || ndoomed == 0) {
      hash_mismatch += sylva_world_hash(w) != sylva_world_hash(r);
    } else {
      pruning_steps++;
      if (grid_checks < 3) {
        check_grid_restamped(w);
        grid_checks++;
      }
    }
    if (ndue == 0) CHECK_INT(ndoomed, 0);
    bad += check_conflicts(w, &t, "prune");
    free(doomed);
    nodes_free(&ln);
    nodes_free(&lw);
    sylva_world_destroy(r);
  }
  printf("schedules: %lld nodes pruned over %d iterations, %d laterals cut\n",
         (long long)total_pruned, pruning_steps, lateral_cuts);
  CHECK_INT(node_mismatch, 0);
  CHECK_INT(journal_mismatch, 0);
  CHECK_INT(stat_mismatch, 0);
  CHECK_INT(left_inside, 0);
  CHECK_INT(hash_mismatch, 0);
  CHECK_INT(scar_mismatch, 0);
  CHECK_INT(bad, 0);
  CHECK(pruning_steps >= 3);
  CHECK(total_pruned > 0);
  sylva_world_destroy(w);
}

/* ---- 3b. prune now --------------------------------------------------------------- */

/* The slot of the node with this id (the skeleton is dense between steps). */
static size_t find_slot(const sylva_world *w, int32_t id) {
  for (size_t i = 0; i < w->nodes.count; i++)
    if (w->nodes.id[i] == id) return i;
  return 0;
}

static void test_prune_now(void) {
  sylva_world *w = make_world(21, WITH_SOLIDS);
  CHECK(w != NULL);
  if (!w) return;
  for (int T = 0; T < 12; T++) CHECK_INT(sylva_world_step(w, NULL), 0);
  CHECK(!sylva_world_reports_conflicts(w));
  /* a box that takes nothing: nothing changes, nothing reported */
  double far_min[3] = {10, 3, 6}, far_max[3] = {11, 3.5, 7};
  uint64_t h0 = sylva_world_hash(w);
  const int32_t *removed = NULL;
  size_t removed_count = 99;
  CHECK_INT(sylva_world_prune(w, far_min, far_max, &removed, &removed_count), 0);
  CHECK_INT(removed_count, 0);
  CHECK(sylva_world_hash(w) == h0);
  CHECK(!sylva_world_reports_conflicts(w));
  /* bad boxes */
  double nan_min[3] = {NAN, 0, 0};
  CHECK_INT(sylva_world_prune(w, nan_min, far_max, NULL, NULL), SYLVA_EINVAL);
  CHECK_INT(sylva_world_prune(w, far_max, far_min, NULL, NULL), SYLVA_EINVAL);
  /* a box through tree b's and tree c's crowns, and one over tree a's root */
  double mn[3] = {-1, -3, 0.9}, mx[3] = {3, 3, 1.6};
  node_list before = nodes_of(w);
  char *doomed = calloc(before.count + 1, 1);
  int64_t per_stem[MAX_STEMS] = {0}, expected = 0;
  int32_t cut[4096];
  size_t ncut = 0;
  for (size_t i = 0; i < before.count; i++) {
    const sylva_node_info *n = &before.n[i];
    if (n->parent < 0) continue;
    long p = find_id(&before, n->parent);
    if (doomed[p])
      doomed[i] = 1;
    else if (conflicts_in_box(n, mn, mx)) {
      doomed[i] = 2;
      if (ncut < 4096) cut[ncut++] = n->id;
    }
    if (doomed[i]) per_stem[before.gstem[i]]++, expected++;
  }
  CHECK(expected > 0);
  int64_t got = sylva_world_prune(w, mn, mx, &removed, &removed_count);
  CHECK_INT(got, expected);
  CHECK_INT(removed_count, ncut);
  int listed = 0;
  for (size_t i = 0; i < ncut && removed; i++)
    for (size_t q = 0; q < removed_count; q++) listed += removed[q] == cut[i];
  CHECK_INT(listed, ncut);
  CHECK(sylva_world_reports_conflicts(w));
  node_list after = nodes_of(w);
  CHECK_INT(after.count, before.count - (size_t)expected);
  size_t k = 0;
  int mismatch = 0, inside = 0;
  for (size_t i = 0; i < before.count; i++) {
    if (doomed[i]) continue;
    mismatch += k >= after.count || before.n[i].id != after.n[k].id ||
                memcmp(&before.n[i], &after.n[k], sizeof before.n[i]) != 0;
    k++;
  }
  for (size_t i = 0; i < after.count; i++)
    inside += after.n[i].parent >= 0 && conflicts_in_box(&after.n[i], mn, mx);
  CHECK_INT(mismatch, 0);
  CHECK_INT(inside, 0);
  for (int s = 0; s < sylva_world_stem_count(w); s++) {
    sylva_stem_stats st;
    sylva_world_stem_stats(w, s, &st);
    CHECK_INT(st.pruned, per_stem[s]);
    int64_t live = 0;
    for (size_t i = 0; i < after.count; i++) live += after.gstem[i] == s;
    CHECK_INT(st.nodes, live);
  }
  check_grid_restamped(w);
  /* roots stay: a box over tree a's root alone takes nothing */
  double root_min[3] = {-12.6, -2.1, -0.01}, root_max[3] = {-12.4, -1.9, 0.01};
  CHECK_INT(sylva_world_prune(w, root_min, root_max, NULL, NULL), 0);
  /* pruning on: the counts add up until the next step */
  double mn2[3] = {-13, -3, 0.5}, mx2[3] = {-12, -1, 1.0};
  sylva_stem_stats a0;
  sylva_world_stem_stats(w, 0, &a0);
  int64_t more = sylva_world_prune(w, mn2, mx2, NULL, NULL);
  CHECK(more > 0);
  sylva_stem_stats a1;
  sylva_world_stem_stats(w, 0, &a1);
  CHECK_INT(a1.pruned, a0.pruned + more);
  CHECK_INT(a1.nodes, a0.nodes - more);
  /* a box that is one point, the first node of a lateral branch: its parent keeps
   * a scar and never sprouts a lateral again */
  int32_t scarred = -1;
  for (size_t i = 0; i < w->nodes.count && scarred < 0; i++) {
    int32_t p = w->nodes.parent[i];
    if ((w->nodes.flags[i] & SYLVA__NODE_LATERAL) && p >= 0 && w->nodes.parent[p] >= 0 &&
        !(w->nodes.flags[p] & SYLVA__NODE_SCAR)) {
      double pt[3] = {w->nodes.x[i], w->nodes.y[i], w->nodes.z[i]};
      int32_t id = w->nodes.id[i];
      scarred = w->nodes.id[p];
      int32_t axis = w->nodes.axis_child[p] >= 0 ? w->nodes.id[w->nodes.axis_child[p]] : -1;
      CHECK(sylva_world_prune(w, pt, pt, &removed, &removed_count) >= 1);
      CHECK_INT(removed_count, 1);
      if (removed_count) CHECK_INT(removed[0], id);
      long q = -1;
      for (size_t k2 = 0; k2 < w->nodes.count; k2++)
        if (w->nodes.id[k2] == scarred) q = (long)k2;
      CHECK(q >= 0);
      if (q >= 0) {
        CHECK(w->nodes.flags[q] & SYLVA__NODE_SCAR);
        CHECK_INT(w->nodes.lateral_child[q], -1);
        CHECK_INT(w->nodes.axis_child[q] >= 0 ? w->nodes.id[w->nodes.axis_child[q]] : -1, axis);
      }
    }
  }
  CHECK(scarred >= 0);
  /* a snapshot now continues as the world does */
  sylva_world *r = reload(w);
  CHECK(r != NULL);
  int diverged = 0;
  for (int i = 0; i < 4 && r; i++) {
    const sylva_journal *j;
    CHECK_INT(sylva_world_step(w, &j), 0);
    CHECK_INT(sylva_world_step(r, NULL), 0);
    diverged += sylva_world_hash(w) != sylva_world_hash(r);
    for (size_t s = 0; j && s < j->stem_count; s++) CHECK_INT(j->stats[s].pruned, 0);
    for (size_t k2 = 0; j && k2 < j->added_count; k2++) CHECK(j->added[k2].parent != scarred ||
        !(w->nodes.flags[find_slot(w, j->added[k2].id)] & SYLVA__NODE_LATERAL));
  }
  CHECK_INT(diverged, 0);
  sylva_world_destroy(r);
  free(doomed);
  nodes_free(&before);
  nodes_free(&after);
  sylva_world_destroy(w);
}

/* A world without zones that did not report conflicts reports them once prune-now
 * removed nodes: its clearances are there at once, equal to a brute force and to a
 * copy loaded from its snapshot, and stay so after a step. */
static void test_prune_now_clearances(void) {
  sylva_world *w = make_world(23, WITH_SOLIDS);
  CHECK(w != NULL);
  if (!w) return;
  for (int T = 0; T < 10; T++) CHECK_INT(sylva_world_step(w, NULL), 0);
  CHECK(!sylva_world_reports_conflicts(w));
  double mn[3] = {-1, -3, 0.9}, mx[3] = {3, 3, 1.6};
  CHECK(sylva_world_prune(w, mn, mx, NULL, NULL) > 0);
  CHECK(sylva_world_reports_conflicts(w));
  for (int step = 0; step < 2; step++) {
    tracker t;
    tracker_init(&t);
    CHECK_INT(check_conflicts(w, &t, step ? "step after prune now" : "prune now"), 0);
    CHECK(sylva_world_conflicts(w).clearance_count > 0);
    sylva_world *copy = reload(w);
    CHECK(copy != NULL);
    if (copy) {
      conflicts_copy cc = copy_conflicts(sylva_world_conflicts(w));
      CHECK(conflicts_equal(&cc, sylva_world_conflicts(copy)));
      free(cc.z);
      free(cc.c);
      sylva_world_destroy(copy);
    }
    CHECK_INT(sylva_world_step(w, NULL), 0);
  }
  sylva_world_destroy(w);
}

/* ---- a stem pruned down to its root ------------------------------------------------ */

/* Runs fn in a child process, so that a crash in the core fails this test alone;
 * true when the child ran every check and none failed. (With SYLVA_TEST_NO_FORK
 * set, fn runs in this process, for a debugger.) */
static bool isolated(void (*fn)(void), const char *what) {
  fflush(stdout);
  fflush(stderr);
  if (getenv("SYLVA_TEST_NO_FORK")) {
    fn();
    return true;
  }
  pid_t pid = fork();
  if (pid == 0) {
    int failed = check_failed;
    fn();
    fflush(stdout);
    fflush(stderr);
    _exit(check_failed > failed ? 1 : 0);
  }
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) != pid) return false;
  if (WIFSIGNALED(status))
    fprintf(stderr, "%s: killed by signal %d\n", what, WTERMSIG(status));
  else if (WEXITSTATUS(status))
    fprintf(stderr, "%s: exit status %d\n", what, WEXITSTATUS(status));
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

/* The root stays and the stem goes on: it steps like any other, and a snapshot
 * continues it identically. */
static void steps_on(sylva_world *w, int stem) {
  sylva_world *r = reload(w);
  CHECK(r != NULL);
  for (int i = 0; i < 3 && r; i++) {
    int a = sylva_world_step(w, NULL), b = sylva_world_step(r, NULL);
    CHECK(a == 0 || a == SYLVA_EFINISHED);
    CHECK_INT(a, b);
    CHECK(sylva_world_hash(w) == sylva_world_hash(r));
  }
  sylva_stem_stats st;
  CHECK_INT(sylva_world_stem_stats(w, stem, &st), 0);
  CHECK(st.nodes >= 1);
  double root[3];
  CHECK_INT(sylva_world_stem_root(w, stem, root), 0);
  bool found = false;
  for (size_t i = 0; i < sylva_world_node_count(w); i++) {
    sylva_node_info n;
    sylva_world_node_at(w, i, &n);
    found |= n.parent < 0 && sylva_world_stem_index(w, n.plant, n.stem) == stem &&
             n.x == (float)root[0] && n.y == (float)root[1] && n.z == (float)root[2];
  }
  CHECK(found);
  sylva_world_destroy(r);
}

/* prune now with a box that is one point, the trunk node just above tree a's root */
static void prune_point_to_root(void) {
  sylva_world *w = make_world(21, WITH_SOLIDS);
  CHECK(w != NULL);
  if (!w) return;
  for (int T = 0; T < 6; T++) CHECK_INT(sylva_world_step(w, NULL), 0);
  node_list now = nodes_of(w);
  long second = -1;
  int64_t a_nodes = 0;
  for (size_t i = 0; i < now.count; i++) {
    a_nodes += now.gstem[i] == 0;
    long p = now.n[i].parent >= 0 ? find_id(&now, now.n[i].parent) : -1;
    if (now.gstem[i] == 0 && p >= 0 && now.n[p].parent < 0 && second < 0) second = (long)i;
  }
  CHECK(second >= 0);
  if (second >= 0) {
    double pt[3] = {now.n[second].x, now.n[second].y, now.n[second].z};
    const int32_t *removed = NULL;
    size_t removed_count = 0;
    CHECK_INT(sylva_world_prune(w, pt, pt, &removed, &removed_count), a_nodes - 1);
    CHECK_INT(removed_count, 1);
    if (removed_count) CHECK_INT(removed[0], now.n[second].id);
    sylva_stem_stats st;
    sylva_world_stem_stats(w, 0, &st);
    CHECK_INT(st.nodes, 1);
    CHECK_INT(st.pruned, a_nodes - 1);
    steps_on(w, 0);
  }
  nodes_free(&now);
  sylva_world_destroy(w);
}

/* a schedule on a zone through tree b's trunk base, from iteration 1 */
static void schedule_to_root(void) {
  sylva_world *w = make_world(22, WITH_SOLIDS | WITH_ZONES);
  CHECK(w != NULL);
  if (!w) return;
  sylva_prune_def d = {sylva_world_find_obstacle(w, "trunk-zone"), 2, 1};
  CHECK_INT(sylva_world_add_prune(w, &d), 0);
  const sylva_journal *j;
  CHECK_INT(sylva_world_step(w, &j), 0);
  sylva_stem_stats st;
  sylva_world_stem_stats(w, 1, &st);
  CHECK_INT(st.nodes, 1);
  CHECK(st.pruned >= 2);
  steps_on(w, 1);
  sylva_world_destroy(w);
}

static void test_prune_to_root(void) {
  CHECK(isolated(prune_point_to_root, "prune now to the root"));
  CHECK(isolated(schedule_to_root, "schedule to the root"));
}

/* ---- 4. snapshots continue ---------------------------------------------------- */

static void test_resume(void) {
  sylva_world *w = make_world(17, WITH_ZONES | WITH_SOLIDS);
  CHECK(w != NULL);
  if (!w) return;
  sylva_prune_def d1 = {sylva_world_find_obstacle(w, "road"), 3, 5};
  sylva_prune_def d2 = {sylva_world_find_obstacle(w, "canopy"), 4, 6};
  CHECK_INT(sylva_world_add_prune(w, &d1), 0);
  CHECK_INT(sylva_world_add_prune(w, &d2), 0);
  /* a snapshot at every iteration; those at 0, 4, 5, 7, 8 and 12 continue to the
   * end, the others four iterations */
  enum { N = 18 };
  static const bool to_end[N + 1] = {[0] = true, [4] = true, [5] = true,
                                     [7] = true, [8] = true, [12] = true};
  uint64_t ref[N + 1];
  conflicts_copy refc[N + 1];
  int64_t ref_pruned[N + 1][MAX_STEMS];
  uint8_t *img[N + 1] = {0};
  size_t len[N + 1] = {0};
  int last = 0, ns = 0, pruning_snapshots = 0;
  for (int T = 0; T <= N; T++) {
    ref[T] = sylva_world_hash(w);
    refc[T] = copy_conflicts(sylva_world_conflicts(w));
    for (int s = 0; s < sylva_world_stem_count(w); s++) {
      sylva_stem_stats st;
      sylva_world_stem_stats(w, s, &st);
      ref_pruned[T][s] = st.pruned;
    }
    last = T;
    CHECK_INT(sylva_snapshot_save(w, &img[T], &len[T]), 0);
    ns = T + 1;
    if (T == N || sylva_world_finished(w)) break;
    CHECK_INT(sylva_world_step(w, NULL), 0);
  }
  CHECK_INT(last, N);
  int64_t pruned = 0;
  for (int T = 0; T <= last; T++)
    for (int s = 0; s < sylva_world_stem_count(w); s++) {
      pruned += ref_pruned[T][s];
      pruning_snapshots += ref_pruned[T][s] > 0 && (s == 0 || ref_pruned[T][s - 1] == 0);
    }
  CHECK(pruned > 0);
  CHECK(pruning_snapshots > 0); /* an image carries pruned counts */
  int mismatches = 0, compared = 0;
  for (int i = 0; i < ns; i++) {
    sylva_world *r = NULL;
    CHECK_INT(sylva_snapshot_load(img[i], len[i], &r), 0);
    free(img[i]);
    if (!r) continue;
    CHECK_INT(sylva_world_prune_count(r), 2);
    int end = to_end[i] || i + 4 > last ? last : i + 4;
    for (int T = i; T <= end; T++) {
      if (T > i && sylva_world_step(r, NULL)) {
        mismatches++;
        break;
      }
      compared++;
      mismatches += sylva_world_hash(r) != ref[T];
      mismatches += !conflicts_equal(&refc[T], sylva_world_conflicts(r));
      for (int s = 0; s < sylva_world_stem_count(r); s++) {
        sylva_stem_stats st;
        sylva_world_stem_stats(r, s, &st);
        mismatches += st.pruned != ref_pruned[T][s];
      }
    }
    sylva_world_destroy(r);
  }
  CHECK_INT(mismatches, 0);
  CHECK(compared > 100);
  for (int T = 0; T <= last; T++) {
    free(refc[T].z);
    free(refc[T].c);
  }
  sylva_world_destroy(w);
}

/* ---- 5. snapshot images ---------------------------------------------------------- */

static uint32_t image_flags(const uint8_t *img) {
  return (uint32_t)img[12] | (uint32_t)img[13] << 8 | (uint32_t)img[14] << 16 |
         (uint32_t)img[15] << 24;
}

static uint32_t flags_of(const sylva_world *w, size_t *size) {
  uint8_t *img;
  size_t n;
  if (sylva_snapshot_save(w, &img, &n)) return 0xffffffffu;
  uint32_t f = image_flags(img);
  if (size) *size = n;
  free(img);
  return f;
}

/* Loads a copy of img with len bytes at `at` replaced (the checksum fixed). */
static int load_patched(const uint8_t *img, size_t n, size_t at, const void *bytes, size_t len) {
  uint8_t *b = malloc(n);
  memcpy(b, img, n);
  if (bytes) memcpy(b + at, bytes, len);
  uint64_t h = 0xcbf29ce484222325ULL;
  for (size_t i = 32; i < n; i++) h = (h ^ b[i]) * 0x100000001b3ULL;
  for (int i = 0; i < 8; i++) b[24 + i] = (uint8_t)(h >> (8 * i));
  sylva_world *r = NULL;
  int rc = sylva_snapshot_load(b, n, &r);
  sylva_world_destroy(r);
  free(b);
  return rc;
}

static void put32(uint8_t *b, int32_t v) {
  for (int i = 0; i < 4; i++) b[i] = (uint8_t)((uint32_t)v >> (8 * i));
}

static int32_t get32(const uint8_t *b) {
  return (int32_t)((uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 |
                   (uint32_t)b[3] << 24);
}

static void test_snapshot_format(void) {
  sylva_world *plain = make_world(31, WITH_SOLIDS),
              *zoned = make_world(31, WITH_SOLIDS | WITH_ZONES),
              *sky = make_world(31, WITH_SOLIDS | WITH_SKY),
              *sky_zoned = make_world(31, WITH_SOLIDS | WITH_ZONES | WITH_SKY);
  CHECK(plain && zoned && sky && sky_zoned);
  if (!plain || !zoned || !sky || !sky_zoned) return;
  /* a zone through every trunk: each stem enters it */
  sylva_obstacle_def trunks = {"trunks", {-15, -4, 0.3}, {15, 4, 0.6}, SYLVA_OBSTACLE_ZONE, {0}};
  CHECK(sylva_world_add_obstacle(zoned, &trunks) >= 0);
  for (int T = 0; T < 12; T++) {
    CHECK_INT(sylva_world_step(plain, NULL), 0);
    CHECK_INT(sylva_world_step(zoned, NULL), 0);
  }
  CHECK_INT(sylva_world_step(sky, NULL), 0);
  CHECK_INT(sylva_world_step(sky_zoned, NULL), 0);
  size_t plain_size = 0, zoned_size = 0;
  CHECK_INT(flags_of(plain, &plain_size), 0); /* the old format */
  CHECK_INT(flags_of(zoned, &zoned_size), 2); /* CONFLICTS */
  CHECK_INT(flags_of(sky, NULL), 1);
  CHECK_INT(flags_of(sky_zoned, NULL), 3);
  /* the zoned image is the plain one plus the zones' records, a kind byte per
   * obstacle, a pruned count per stem and the (empty) schedules */
  size_t zone_records = 0;
  int obstacles = sylva_world_obstacle_count(zoned);
  for (int i = 0; i < obstacles; i++) {
    sylva_obstacle_def od;
    sylva_world_obstacle_at(zoned, i, NULL, &od);
    if (od.kind == SYLVA_OBSTACLE_ZONE) zone_records += 4 + 4 + strlen(od.label) + 48;
  }
  size_t stems = (size_t)sylva_world_stem_count(zoned), entered = zoned->entered.len;
  CHECK(entered > 0);
  CHECK_INT(zoned_size, plain_size + zone_records + (size_t)obstacles + 8 * stems + 4 +
                            12 * entered + 4);
  /* a world that pruned without zones reports, and its image says so */
  double mn[3] = {-1, -3, 0.6}, mx[3] = {3, 3, 1.0};
  CHECK(sylva_world_prune(plain, mn, mx, NULL, NULL) > 0);
  CHECK_INT(flags_of(plain, NULL), 2);
  CHECK_INT(sylva_world_step(plain, NULL), 0); /* pruned counts back to 0: still reports */
  CHECK(sylva_world_reports_conflicts(plain));
  CHECK_INT(flags_of(plain, NULL), 2);
  sylva_world *r = reload(plain);
  CHECK(r && sylva_world_reports_conflicts(r));
  sylva_world_destroy(r);

  /* corruptions of the conflicts section of an image with entered zones and a
   * schedule */
  sylva_prune_def d = {sylva_world_find_obstacle(zoned, "road"), 3, 2};
  CHECK_INT(sylva_world_add_prune(zoned, &d), 0);
  uint8_t *img;
  size_t n;
  CHECK_INT(sylva_snapshot_save(zoned, &img, &n), 0);
  CHECK_INT(image_flags(img), 2);
  entered = zoned->entered.len;
  CHECK(entered >= 2);
  size_t prunes_at = n - 12, entered_at = n - 4 - 12 - 12 * entered; /* first pair */
  CHECK_INT(get32(img + prunes_at - 4), 1);
  CHECK_INT(get32(img + entered_at - 4), (int32_t)entered);
  CHECK_INT(get32(img + entered_at), zoned->entered.data[0].stem);
  CHECK_INT(get32(img + entered_at + 4), zoned->entered.data[0].zone);
  CHECK_INT(get32(img + entered_at + 8), zoned->entered.data[0].first);
  CHECK_INT(get32(img + prunes_at), d.zone);
  CHECK_INT(load_patched(img, n, 0, NULL, 0), 0); /* the patching itself is harmless */
  uint8_t v[12];
  size_t last_pair = entered_at + 12 * (entered - 1);
  put32(v, (int32_t)stems); /* a stem out of range, the pairs still in order */
  CHECK_INT(load_patched(img, n, last_pair, v, 4), SYLVA_EBADIMAGE);
  put32(v, (int32_t)stems - 1); /* the last stem: fine if still in order */
  CHECK_INT(load_patched(img, n, last_pair, v, 4),
            zoned->entered.data[entered - 1].stem <= (int32_t)stems - 1 ? 0 : SYLVA_EBADIMAGE);
  put32(v, -1);
  CHECK_INT(load_patched(img, n, entered_at, v, 4), SYLVA_EBADIMAGE);
  put32(v, sylva_world_find_obstacle(zoned, "wall-south")); /* a solid for a zone */
  CHECK_INT(load_patched(img, n, entered_at + 4, v, 4), SYLVA_EBADIMAGE);
  put32(v, zoned->grid.next_obstacle_id); /* an id never given */
  CHECK_INT(load_patched(img, n, entered_at + 4, v, 4), SYLVA_EBADIMAGE);
  put32(v, sylva_world_iteration(zoned) + 1); /* entered after the image's iteration */
  CHECK_INT(load_patched(img, n, entered_at + 8, v, 4), SYLVA_EBADIMAGE);
  put32(v, -1);
  CHECK_INT(load_patched(img, n, entered_at + 8, v, 4), SYLVA_EBADIMAGE);
  /* two pairs swapped: out of order */
  uint8_t swapped[24];
  memcpy(swapped, img + entered_at + 12, 12);
  memcpy(swapped + 12, img + entered_at, 12);
  CHECK_INT(load_patched(img, n, entered_at, swapped, 24), SYLVA_EBADIMAGE);
  /* the same pair twice */
  memcpy(swapped, img + entered_at, 12);
  memcpy(swapped + 12, img + entered_at, 12);
  CHECK_INT(load_patched(img, n, entered_at, swapped, 24), SYLVA_EBADIMAGE);
  /* schedules: from 0, every -1, a zone never given */
  put32(v, 0);
  CHECK_INT(load_patched(img, n, prunes_at + 8, v, 4), SYLVA_EBADIMAGE);
  put32(v, -1);
  CHECK_INT(load_patched(img, n, prunes_at + 4, v, 4), SYLVA_EBADIMAGE);
  put32(v, zoned->grid.next_obstacle_id);
  CHECK_INT(load_patched(img, n, prunes_at, v, 4), SYLVA_EBADIMAGE);
  /* an obstacle's kind byte (after its label and box) other than 0 or 1; and the
   * zone of the first entered pair made solid: a pair then names a solid */
  sylva_obstacle_def zdef;
  CHECK_INT(sylva_world_obstacle(zoned, zoned->entered.data[0].zone, &zdef), 0);
  const char *zl = zdef.label;
  uint8_t label[4 + SYLVA_LABEL_MAX];
  size_t ll = strlen(zl);
  put32(label, (int32_t)ll);
  memcpy(label + 4, zl, ll);
  uint8_t *at = NULL;
  for (size_t i = 32; i + 4 + ll <= n && !at; i++)
    if (memcmp(img + i, label, 4 + ll) == 0) at = img + i;
  CHECK(at != NULL);
  if (at) {
    size_t kind_at = (size_t)(at - img) + 4 + ll + 48;
    CHECK_INT(img[kind_at], 1);
    uint8_t two = 2, zero = 0;
    CHECK_INT(load_patched(img, n, kind_at, &two, 1), SYLVA_EBADIMAGE);
    CHECK_INT(load_patched(img, n, kind_at, &zero, 1), SYLVA_EBADIMAGE);
  }
  /* flags: an unknown bit, and the CONFLICTS bit taken away */
  uint8_t f = 2 | 8;
  CHECK_INT(load_patched(img, n, 12, &f, 1), SYLVA_EBADIMAGE);
  f = 0;
  CHECK(load_patched(img, n, 12, &f, 1) < 0);
  free(img);
  sylva_world_destroy(plain);
  sylva_world_destroy(zoned);
  sylva_world_destroy(sky);
  sylva_world_destroy(sky_zoned);
}

/* ---- schedules: bad ones, the iterations they name, removed zones ---------------- */

static void test_schedule_rules(void) {
  sylva_world *w = make_world(41, WITH_ZONES | WITH_SOLIDS);
  CHECK(w != NULL);
  if (!w) return;
  int road = sylva_world_find_obstacle(w, "road");
  int wall = sylva_world_find_obstacle(w, "wall-south");
  sylva_prune_def bad[] = {{wall, 3, 1}, {road, -1, 1}, {road, 3, 0}, {99, 3, 1}, {-1, 3, 1}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
    CHECK_INT(sylva_world_add_prune(w, &bad[i]), SYLVA_EINVAL);
  CHECK_INT(sylva_world_prune_count(w), 0);
  /* an obstacle by id: its kind and box; an id that is not there */
  sylva_obstacle_def od;
  CHECK_INT(sylva_world_obstacle(w, road, &od), 0);
  CHECK(od.kind == SYLVA_OBSTACLE_ZONE && strcmp(od.label, "road") == 0 && od.max[2] == 3.5);
  CHECK_INT(sylva_world_obstacle(w, wall, &od), 0);
  CHECK(od.kind == SYLVA_OBSTACLE_SOLID);
  CHECK_INT(sylva_world_obstacle(w, 99, &od), SYLVA_ENOTFOUND);
  CHECK_INT(sylva_world_obstacle(w, -1, &od), SYLVA_ENOTFOUND);
  sylva_prune_def out;
  CHECK_INT(sylva_world_prune_at(w, 0, &out), SYLVA_ENOTFOUND);
  sylva_prune_def once = {road, 0, 7}, every = {road, 4, 3};
  CHECK_INT(sylva_world_add_prune(w, &once), 0);
  CHECK_INT(sylva_world_add_prune(w, &every), 0);
  CHECK_INT(sylva_world_prune_at(w, 1, &out), 0);
  CHECK(out.zone == road && out.every == 4 && out.from == 3);
  CHECK_INT(sylva_world_prune_at(w, 2, &out), SYLVA_ENOTFOUND);
  CHECK_INT(sylva_world_prune_at(w, -1, &out), SYLVA_ENOTFOUND);
  /* the iterations named */
  int due_once = 0, due_every = 0;
  for (int T = 1; T <= 30; T++) {
    bool a = sylva__prune_due(&once, T), b = sylva__prune_due(&every, T);
    CHECK(a == due(&once, T));
    CHECK(b == due(&every, T));
    due_once += a;
    due_every += b;
  }
  CHECK_INT(due_once, 1);
  CHECK_INT(due_every, 7); /* 3, 7, 11, ..., 27 */
  /* a schedule whose zone is removed prunes nothing, and its image loads */
  for (int T = 0; T < 5; T++) CHECK_INT(sylva_world_step(w, NULL), 0);
  CHECK_INT(sylva_world_remove_obstacle(w, road), 0);
  /* the same label again is another zone, not scheduled */
  CHECK(sylva_world_add_obstacle(w, &layout[1]) > road);
  int64_t pruned = 0;
  for (int T = 5; T < 12; T++) {
    const sylva_journal *j;
    CHECK_INT(sylva_world_step(w, &j), 0);
    for (size_t s = 0; j && s < j->stem_count; s++) pruned += j->stats[s].pruned;
  }
  CHECK_INT(pruned, 0);
  sylva_world *r = reload(w);
  CHECK(r != NULL);
  if (r) {
    CHECK(sylva_world_hash(r) == sylva_world_hash(w));
    conflicts_copy c = copy_conflicts(sylva_world_conflicts(w));
    CHECK(conflicts_equal(&c, sylva_world_conflicts(r)));
    free(c.z);
    free(c.c);
    CHECK_INT(sylva_world_step(w, NULL), 0);
    CHECK_INT(sylva_world_step(r, NULL), 0);
    CHECK(sylva_world_hash(r) == sylva_world_hash(w));
    sylva_world_destroy(r);
  }
  sylva_world_destroy(w);
}

/* Two zones over the same box, one of them pruned every iteration: a node cut
 * the iteration it grew in dates the conflict in both, so every stem has the same
 * zone lines, first iterations included, for the two. */
static void test_prune_dates_every_zone(void) {
  sylva_world *w = make_world(43, WITH_SOLIDS);
  CHECK(w != NULL);
  if (!w) return;
  sylva_obstacle_def a = {"upper-a", {-15, -4, 1.2}, {15, 4, 8}, SYLVA_OBSTACLE_ZONE, {0}};
  sylva_obstacle_def b = {"upper-b", {-15, -4, 1.2}, {15, 4, 8}, SYLVA_OBSTACLE_ZONE, {0}};
  int ia = sylva_world_add_obstacle(w, &a), ib = sylva_world_add_obstacle(w, &b);
  CHECK(ia >= 0 && ib >= 0);
  sylva_prune_def every1 = {ia, 1, 1};
  CHECK_INT(sylva_world_add_prune(w, &every1), 0);
  int lines = 0, cuts = 0;
  for (int T = 1; T <= 14; T++) {
    const sylva_journal *j = NULL;
    CHECK_INT(sylva_world_step(w, &j), 0);
    sylva_conflicts c = sylva_world_conflicts(w);
    /* a stem cut at T had nodes inside at T: its line is dated T or before */
    for (size_t k = 0; j && k < j->stem_count; k++) {
      if (!j->stats[k].pruned) continue;
      cuts++;
      bool dated = false;
      for (size_t i = 0; i < c.zone_count; i++)
        dated |= c.zones[i].stem == (int32_t)k && c.zones[i].obstacle == ia && c.zones[i].first <= T;
      CHECK(dated);
    }
    for (size_t i = 0; i < c.zone_count; i++) {
      if (c.zones[i].obstacle != ia) continue;
      bool twin = false;
      for (size_t k = 0; k < c.zone_count; k++)
        twin |= c.zones[k].stem == c.zones[i].stem && c.zones[k].obstacle == ib &&
                c.zones[k].first == c.zones[i].first && c.zones[k].nodes == c.zones[i].nodes;
      CHECK(twin);
      lines++;
    }
  }
  CHECK(lines > 0 && cuts > 0);
  sylva_world_destroy(w);
}

/* A plant whose trunk meets another stem's branches cuts them with what they carry
 * (docs/model.md, "Species in years", nursery); another's root or trunk refuses it,
 * changing nothing. */
static void test_planting_cuts_branches(void) {
  sylva_world *w = make_world(21, WITH_SOLIDS);
  CHECK(w != NULL);
  if (!w) return;
  for (int T = 0; T < 12; T++) CHECK_INT(sylva_world_step(w, NULL), 0);
  const sylva_species_def *sp = sylva_world_species(w, 0);
  const double e = sylva_world_get_def(w)->voxel;
  const sylva__skeleton *s = &w->nodes;
  int b = sylva_world_stem_index(w, 1, 0); /* tree b, its root at (0, -2, 0) */
  /* a branch node of b well away from its trunk, its column free of obstacles */
  long pick = -1;
  for (size_t i = 0; i < s->count && pick < 0; i++)
    if ((s->flags[i] & SYLVA__NODE_ALIVE) && s->stem[i] == b && s->parent[i] >= 0 &&
        hypot(s->x[i], s->y[i] + 2) > 4 * e && s->z[i] + sp->rho * sp->initial_nodes < 3.5 &&
        s->y[i] > -3.4 && s->y[i] < 0.9)
      pick = (long)i;
  CHECK(pick >= 0);
  if (pick < 0) {
    sylva_world_destroy(w);
    return;
  }
  double at[3] = {s->x[pick], s->y[pick], s->z[pick]};
  int column[16][3];
  for (int k = 0; k <= sp->initial_nodes && k < 16; k++) {
    double p[3] = {at[0], at[1], at[2] + sp->rho * k};
    float f[3];
    CHECK(sylva__voxel_of(w, p, f, column[k]));
  }
  /* the nodes to go: those in the new trunk's voxels, and what they carry (parents
   * come before their children in slot order) */
  size_t n0 = sylva_world_node_count(w), expected = 0;
  char *doomed = calloc(s->count + 1, 1);
  int32_t *ids = malloc((s->count + 1) * sizeof *ids);
  size_t nids = 0;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE) || s->parent[i] < 0) continue;
    int v[3];
    sylva__node_voxel(w, (int32_t)i, v);
    doomed[i] = doomed[s->parent[i]];
    for (int k = 0; k <= sp->initial_nodes && k < 16; k++)
      if (v[0] == column[k][0] && v[1] == column[k][1] && v[2] == column[k][2]) doomed[i] = 1;
    if (doomed[i]) {
      expected++;
      ids[nids++] = s->id[i];
    }
  }
  CHECK(expected >= 1);
  static double root[1][3];
  memcpy(root[0], at, sizeof at);
  sylva_plant_def e_def = {0, "e", (const double(*)[3])root, 1, 0, NULL, 0};
  CHECK(sylva_world_add_plant(w, &e_def, NULL) >= 0);
  CHECK_INT((long)sylva_world_node_count(w), (long)(n0 - expected + (size_t)sp->initial_nodes + 1));
  sylva_stem_stats st;
  CHECK_INT(sylva_world_stem_stats(w, b, &st), 0);
  CHECK_INT(st.pruned, (long)expected);
  for (size_t k = 0; k < nids; k++) CHECK(sylva_world_node_index(w, ids[k]) < 0);
  check_grid_restamped(w);
  /* a root on b's root: refused, nothing changed */
  uint64_t h = sylva_world_hash(w);
  static const double on_b[1][3] = {{0, -2, 0}};
  sylva_plant_def f_def = {0, "f", on_b, 1, 0, NULL, 0};
  CHECK_INT(sylva_world_add_plant(w, &f_def, NULL), SYLVA_EOCCUPIED);
  CHECK(sylva_world_hash(w) == h);
  for (int T = 0; T < 3; T++) CHECK_INT(sylva_world_step(w, NULL), 0);
  free(doomed);
  free(ids);
  sylva_world_destroy(w);
}

int main(int argc, char **argv) {
  static const check_test tests[] = {
      CHECK_TEST(zones_change_nothing), CHECK_TEST(conflicts_brute_force),
      CHECK_TEST(schedule_prunes),      CHECK_TEST(prune_now),
      CHECK_TEST(prune_now_clearances), CHECK_TEST(prune_to_root),
      CHECK_TEST(resume),               CHECK_TEST(snapshot_format),
      CHECK_TEST(schedule_rules),       CHECK_TEST(prune_dates_every_zone),
      CHECK_TEST(planting_cuts_branches)};
  CHECK_RUN(argc, argv, 1, tests);
  return check_summary("conflicts");
}
