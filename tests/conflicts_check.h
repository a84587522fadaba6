/* Test helpers for the conflicts of sylva/world.h: two lists compared element by
 * element, and a world's zone lines and clearances against a count over every node
 * and obstacle (docs/model.md, "Zones, clearance and pruning"). */
#ifndef SYLVA_TESTS_CONFLICTS_CHECK_H
#define SYLVA_TESTS_CONFLICTS_CHECK_H

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "sylva/world.h"

/* Whether two lists of conflicts are the same (distances exactly: the same world
 * gives the same bits). */
static inline bool conflicts_lists_equal(const sylva_zone_stat *z, size_t nz,
                                         const sylva_clearance_stat *c, size_t nc,
                                         sylva_conflicts b) {
  if (nz != b.zone_count || nc != b.clearance_count) return false;
  for (size_t i = 0; i < nz; i++)
    if (z[i].stem != b.zones[i].stem || z[i].obstacle != b.zones[i].obstacle ||
        z[i].nodes != b.zones[i].nodes || z[i].first != b.zones[i].first)
      return false;
  for (size_t i = 0; i < nc; i++)
    if (c[i].stem != b.clearances[i].stem || c[i].obstacle != b.clearances[i].obstacle ||
        c[i].distance != b.clearances[i].distance)
      return false;
  return true;
}

/* Is node n inside the box [mn, mx], faces included? */
static inline bool conflicts_in_box(const sylva_node_info *n, const double mn[3],
                                    const double mx[3]) {
  double p[3] = {n->x, n->y, n->z};
  for (int a = 0; a < 3; a++)
    if (!(mn[a] <= p[a] && p[a] <= mx[a])) return false;
  return true;
}

/* Euclidean distance from node n to the box [mn, mx] (0 inside). */
static inline double conflicts_box_distance(const sylva_node_info *n, const double mn[3],
                                            const double mx[3]) {
  double p[3] = {n->x, n->y, n->z}, d2 = 0.0;
  for (int a = 0; a < 3; a++) {
    double d = fmax(0.0, fmax(mn[a] - p[a], p[a] - mx[a]));
    d2 += d * d;
  }
  return sqrt(d2);
}

/* Compares w's conflicts with a count over every node and obstacle. first holds,
 * per stem k and obstacle id, first[k * ids + id]: the first iteration a count found
 * a node of k inside (-1 never), and is updated here. With exact_first a stem has a
 * zone line exactly when it was ever found inside, with that first iteration;
 * without (nodes pruned before a count saw them) a line may be older than the
 * count knows. Clearances: exactly the solids within SYLVA_CLEARANCE_RANGE, within
 * 1e-9 m. Both lists ordered by stem, then obstacle id. Returns the mismatches,
 * each reported on stderr after `where`. */
static inline int conflicts_brute_force(const sylva_world *w, int *first, int ids,
                                        bool exact_first, const char *where) {
  int bad = 0, T = sylva_world_iteration(w), nob = sylva_world_obstacle_count(w);
  int nstems = sylva_world_stem_count(w);
  size_t n = sylva_world_node_count(w);
  sylva_node_info *nodes = malloc((n + 1) * sizeof *nodes);
  int *stem = malloc((n + 1) * sizeof *stem);
  if (!nodes || !stem) abort();
  for (size_t i = 0; i < n; i++) {
    sylva_world_node_at(w, i, &nodes[i]);
    stem[i] = sylva_world_stem_index(w, nodes[i].plant, nodes[i].stem);
  }
  sylva_conflicts all = sylva_world_conflicts(w);
  for (size_t i = 1; i < all.zone_count; i++) {
    const sylva_zone_stat *a = &all.zones[i - 1], *b = &all.zones[i];
    if (!(a->stem < b->stem || (a->stem == b->stem && a->obstacle < b->obstacle))) bad++;
  }
  for (size_t i = 1; i < all.clearance_count; i++) {
    const sylva_clearance_stat *a = &all.clearances[i - 1], *b = &all.clearances[i];
    if (!(a->stem < b->stem || (a->stem == b->stem && a->obstacle < b->obstacle))) bad++;
  }
  size_t zsum = 0, csum = 0;
  for (int k = 0; k < nstems; k++) {
    sylva_conflicts c = sylva_world_stem_conflicts(w, k);
    zsum += c.zone_count;
    csum += c.clearance_count;
    size_t zi = 0, ci = 0;
    for (int o = 0; o < nob; o++) {
      int id;
      sylva_obstacle_def od;
      sylva_world_obstacle_at(w, o, &id, &od);
      if (id >= ids) abort(); /* the caller's table is too small */
      if (od.kind == SYLVA_OBSTACLE_ZONE) {
        int64_t inside = 0;
        for (size_t i = 0; i < n; i++)
          inside += stem[i] == k && conflicts_in_box(&nodes[i], od.min, od.max);
        int *f = &first[k * ids + id];
        if (inside > 0 && *f < 0) *f = T;
        bool line = zi < c.zone_count && c.zones[zi].obstacle == id;
        bool ok = line ? c.zones[zi].stem == k && c.zones[zi].nodes == inside &&
                             (exact_first ? c.zones[zi].first == *f
                                          : *f < 0 || c.zones[zi].first <= *f)
                       : (exact_first ? *f < 0 : inside == 0);
        if (!ok) {
          bad++;
          fprintf(stderr, "%s T=%d: stem %d zone %s: expected %lld nodes, first %d; got ", where,
                  T, k, od.label, (long long)inside, *f);
          if (line)
            fprintf(stderr, "%lld nodes, first %d\n", (long long)c.zones[zi].nodes,
                    c.zones[zi].first);
          else
            fprintf(stderr, "no line\n");
        }
        zi += line;
      } else {
        double best = INFINITY;
        for (size_t i = 0; i < n; i++)
          if (stem[i] == k) best = fmin(best, conflicts_box_distance(&nodes[i], od.min, od.max));
        if (!(best <= SYLVA_CLEARANCE_RANGE)) continue;
        if (ci >= c.clearance_count || c.clearances[ci].stem != k ||
            c.clearances[ci].obstacle != id || !(fabs(c.clearances[ci].distance - best) <= 1e-9)) {
          bad++;
          fprintf(stderr, "%s T=%d: stem %d solid %s: expected clearance %.12g, got %.12g\n",
                  where, T, k, od.label, best,
                  ci < c.clearance_count ? c.clearances[ci].distance : NAN);
        }
        ci++;
      }
    }
    if (zi != c.zone_count || ci != c.clearance_count) {
      bad++;
      fprintf(stderr, "%s T=%d: stem %d has %zu zone lines and %zu clearances, expected %zu, %zu\n",
              where, T, k, c.zone_count, c.clearance_count, zi, ci);
    }
  }
  if (zsum != all.zone_count || csum != all.clearance_count) bad++;
  free(nodes);
  free(stem);
  return bad;
}

#endif
