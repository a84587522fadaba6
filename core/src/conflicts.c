/* Conflicts between stems and obstacles (docs/model.md, "Zones, clearance and
 * pruning"): the nodes of each stem inside each clearance zone and the iteration
 * one first entered it, the least distance from a stem's nodes to each solid
 * obstacle near it, and pruning, which removes every node inside a box together
 * with its subtree as shedding removes a branch. */
#include <math.h>
#include <string.h>

#include "conflicts.h"

/* ---- geometry ------------------------------------------------------------------ */

/* Whether a point lies in an obstacle (a box, or a prism: its z range and footprint,
 * boundaries included). */
static bool inside(const sylva__obstacle *o, double x, double y, double z) {
  if (!(x >= o->min[0] && x <= o->max[0] && y >= o->min[1] && y <= o->max[1] &&
        z >= o->min[2] && z <= o->max[2]))
    return false;
  return !o->fp || sylva__footprint_inside(o->fp, x, y);
}

/* Squared distance from a point to an obstacle: a box [min, max], or a prism, whose
 * distance is the footprint's across and its z range's along. */
static double dist2_point(const sylva__obstacle *o, const double p[3]) {
  double d2 = 0.0;
  for (int a = o->fp ? 2 : 0; a < 3; a++) {
    double d = p[a] < o->min[a] ? o->min[a] - p[a] : p[a] > o->max[a] ? p[a] - o->max[a] : 0.0;
    d2 += d * d;
  }
  return o->fp ? d2 + sylva__footprint_dist2(o->fp, p[0], p[1]) : d2;
}

/* Squared distance between two boxes. */
static double dist2_boxes(const double amn[3], const double amx[3], const double bmn[3],
                          const double bmx[3]) {
  double d2 = 0.0;
  for (int a = 0; a < 3; a++) {
    double d = amx[a] < bmn[a] ? bmn[a] - amx[a] : bmx[a] < amn[a] ? amn[a] - bmx[a] : 0.0;
    d2 += d * d;
  }
  return d2;
}

/* ---- entered zones ------------------------------------------------------------- */

/* Index of (stem, zone) in w->entered, or where it would go (*found false). */
static size_t entered_find(const sylva_world *w, int32_t stem, int32_t zone, bool *found) {
  size_t lo = 0, hi = w->entered.len;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    const sylva__entered *e = &w->entered.data[mid];
    if (e->stem < stem || (e->stem == stem && e->zone < zone))
      lo = mid + 1;
    else
      hi = mid;
  }
  *found = lo < w->entered.len && w->entered.data[lo].stem == stem &&
           w->entered.data[lo].zone == zone;
  return lo;
}

/* Notes that a node of stem entered zone at iteration T, unless one did before
 * (room reserved by sylva__conflicts_reserve). */
static void enter(sylva_world *w, int32_t stem, int32_t zone, int T) {
  bool found;
  size_t at = entered_find(w, stem, zone, &found);
  if (found) return;
  SYLVA_ASSERT(w->entered.len < w->entered.cap);
  memmove(w->entered.data + at + 1, w->entered.data + at,
          (w->entered.len - at) * sizeof *w->entered.data);
  w->entered.data[at] = (sylva__entered){stem, zone, T};
  w->entered.len++;
}

int sylva__entered_add(sylva_world *w, int32_t stem, int32_t zone, int32_t first) {
  if (w->entered.len && (w->entered.data[w->entered.len - 1].stem > stem ||
                         (w->entered.data[w->entered.len - 1].stem == stem &&
                          w->entered.data[w->entered.len - 1].zone >= zone)))
    return SYLVA_EINVAL; /* a snapshot's pairs come in order */
  if (SYLVA__VEC_RESERVE(w->entered, w->entered.len + 1)) return SYLVA_ENOMEM;
  w->entered.data[w->entered.len++] = (sylva__entered){stem, zone, first};
  return SYLVA_OK;
}

/* ---- the conflicts ----------------------------------------------------------- */

bool sylva__conflicts_any(const sylva_world *w) {
  /* a world that does not report conflicts spends nothing on them */
  return w->reports && (w->grid.obstacle_count > 0 || w->entered.len > 0 ||
                        w->zone_stats.len > 0 || w->clear_stats.len > 0);
}

int sylva__conflicts_reserve(sylva_world *w, int first_stem) {
  w->candidates.len = 0;
  if (!sylva__conflicts_any(w)) return SYLVA_OK;
  const sylva__skeleton *s = &w->nodes;
  size_t nstems = (size_t)w->stem_count;
  if (SYLVA__VEC_RESERVE(w->stem_box, nstems) || SYLVA__VEC_RESERVE(w->stem_nodes, s->count) ||
      SYLVA__VEC_RESERVE(w->stem_nodes_first, nstems + 1))
    return SYLVA_ENOMEM;
  /* each stem's live nodes, grouped by stem in slot order, and its box */
  sylva__group_by_stem(w);
  const int32_t *first = w->stem_nodes_first.data;
  for (size_t k = 0; k < nstems; k++)
    w->stem_box.data[k] = (sylva__box){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    sylva__box *b = &w->stem_box.data[s->stem[i]];
    double p[3] = {s->x[i], s->y[i], s->z[i]};
    for (int a = 0; a < 3; a++) {
      if (p[a] < b->min[a]) b->min[a] = p[a];
      if (p[a] > b->max[a]) b->max[a] = p[a];
    }
  }
  /* the obstacles that may touch each stem: zones its box meets, solids within range */
  size_t zones = 0, solids = 0;
  double range2 = SYLVA_CLEARANCE_RANGE * SYLVA_CLEARANCE_RANGE;
  for (int k = first_stem; k < w->stem_count; k++) {
    const sylva__box *b = &w->stem_box.data[k];
    if (first[k + 1] == first[k]) continue;
    for (int o = 0; o < w->grid.obstacle_slots; o++) {
      const sylva__obstacle *ob = &w->grid.obstacles[o];
      if (!ob->live) continue;
      double d2 = dist2_boxes(b->min, b->max, ob->min, ob->max);
      if (ob->zone ? d2 > 0.0 : d2 > range2) continue;
      if (SYLVA__VEC_RESERVE(w->candidates, w->candidates.len + 1)) return SYLVA_ENOMEM;
      w->candidates.data[w->candidates.len++] = (sylva__candidate){k, o, 0, 0.0};
      if (ob->zone)
        zones++;
      else
        solids++;
    }
  }
  /* room for the results: the stems before first_stem keep theirs */
  size_t keep_z = 0, keep_c = 0;
  while (keep_z < w->zone_stats.len && w->zone_stats.data[keep_z].stem < first_stem) keep_z++;
  while (keep_c < w->clear_stats.len && w->clear_stats.data[keep_c].stem < first_stem) keep_c++;
  if (SYLVA__VEC_RESERVE(w->entered, w->entered.len + zones) ||
      SYLVA__VEC_RESERVE(w->zone_stats, keep_z + w->entered.len + zones) ||
      SYLVA__VEC_RESERVE(w->clear_stats, keep_c + solids))
    return SYLVA_ENOMEM;
  w->conflicts_from = first_stem;
  return SYLVA_OK;
}

void sylva__conflicts(sylva_world *w, int T) {
  const sylva__skeleton *s = &w->nodes;
  int from = w->conflicts_from;
  size_t nz = 0, nc = 0;
  while (nz < w->zone_stats.len && w->zone_stats.data[nz].stem < from) nz++;
  while (nc < w->clear_stats.len && w->clear_stats.data[nc].stem < from) nc++;
  w->zone_stats.len = nz;
  w->clear_stats.len = nc;
  if (!sylva__conflicts_any(w)) return;
  const int32_t *first = w->stem_nodes_first.data, *nodes = w->stem_nodes.data;
  size_t c = 0;
  for (int k = from; k < w->stem_count; k++) {
    /* this stem's candidates, counted (zones) and measured (solids) */
    size_t c0 = c;
    while (c < w->candidates.len && w->candidates.data[c].stem == k) c++;
    for (size_t j = c0; j < c; j++) {
      const sylva__obstacle *ob = &w->grid.obstacles[w->candidates.data[j].slot];
      int64_t count = 0;
      double best = INFINITY;
      for (int32_t n = first[k]; n < first[k + 1]; n++) {
        int32_t i = nodes[n];
        if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue; /* pruned since */
        if (ob->zone) {
          count += inside(ob, s->x[i], s->y[i], s->z[i]);
        } else {
          double p[3] = {s->x[i], s->y[i], s->z[i]};
          double d2 = dist2_point(ob, p);
          if (d2 < best) best = d2;
        }
      }
      w->candidates.data[j].count = count;
      w->candidates.data[j].dist2 = best;
      if (ob->zone && count > 0) enter(w, k, ob->id, T);
    }
    /* one zone line per zone the stem ever entered, in zone id order */
    bool found;
    for (size_t e = entered_find(w, k, -1, &found);
         e < w->entered.len && w->entered.data[e].stem == k; e++) {
      int32_t zone = w->entered.data[e].zone;
      if (sylva__grid_obstacle_slot(&w->grid, zone) < 0) continue; /* removed since */
      int64_t count = 0;
      for (size_t j = c0; j < c; j++)
        if (w->grid.obstacles[w->candidates.data[j].slot].id == zone)
          count = w->candidates.data[j].count;
      w->zone_stats.data[w->zone_stats.len++] =
          (sylva_zone_stat){k, zone, count, w->entered.data[e].first};
    }
    for (size_t j = c0; j < c; j++) {
      const sylva__obstacle *ob = &w->grid.obstacles[w->candidates.data[j].slot];
      double d2 = w->candidates.data[j].dist2;
      if (ob->zone || d2 > SYLVA_CLEARANCE_RANGE * SYLVA_CLEARANCE_RANGE) continue;
      w->clear_stats.data[w->clear_stats.len++] = (sylva_clearance_stat){k, ob->id, sqrt(d2)};
    }
  }
}

int sylva__conflicts_update(sylva_world *w, int first_stem) {
  int rc = sylva__conflicts_reserve(w, first_stem);
  if (rc) return rc;
  sylva__conflicts(w, w->iteration);
  return SYLVA_OK;
}

/* ---- pruning ------------------------------------------------------------------- */

/* Removes every node hit() picks and its subtree (roots stay), as sylva__prune. */
static size_t cut(sylva_world *w, bool (*hit)(const sylva_world *w, size_t i, const void *ctx),
                  const void *ctx, int T, bool announced_only, int32_t *roots,
                  size_t *root_count) {
  sylva__skeleton *s = &w->nodes;
  size_t doomed = 0;
  for (size_t i = 0; i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    int32_t p = s->parent[i];
    if (p < 0) continue; /* a root stays: the stem goes on */
    if (s->flags[p] & SYLVA__NODE_DOOMED) {
      s->flags[i] |= SYLVA__NODE_DOOMED;
      doomed++;
      continue;
    }
    if (!hit(w, i, ctx)) continue;
    s->flags[i] |= SYLVA__NODE_DOOMED;
    doomed++;
    /* a cut: a lateral leaves a scar on its parent, whose bud does not sprout again;
     * a cut leader leaves its parent as the axis's apex */
    if (s->flags[i] & SYLVA__NODE_LATERAL) {
      s->lateral_child[p] = -1;
      s->flags[p] |= SYLVA__NODE_SCAR;
    } else {
      s->axis_child[p] = -1;
    }
    /* a branch born at T in a step was never announced: nor is its removal */
    if (!announced_only || s->birth[i] != T) roots[(*root_count)++] = s->id[i];
  }
  if (!doomed) return 0;
  sylva__remove_doomed(w, true);
  return doomed;
}

static bool in_box(const sylva_world *w, size_t i, const void *ctx) {
  return inside(ctx, w->nodes.x[i], w->nodes.y[i], w->nodes.z[i]);
}

size_t sylva__prune(sylva_world *w, const sylva__obstacle *box, int T, bool announced_only,
                    int32_t *roots, size_t *root_count) {
  return cut(w, in_box, box, T, announced_only, roots, root_count);
}

typedef struct voxel_list {
  int (*v)[3];
  size_t n;
} voxel_list;

static bool in_voxels(const sylva_world *w, size_t i, const void *ctx) {
  const voxel_list *l = ctx;
  int v[3];
  sylva__node_voxel(w, (int32_t)i, v);
  for (size_t k = 0; k < l->n; k++)
    if (l->v[k][0] == v[0] && l->v[k][1] == v[1] && l->v[k][2] == v[2]) return true;
  return false;
}

size_t sylva__cut_voxels(sylva_world *w, int (*voxels)[3], size_t n, int T, int32_t *roots,
                         size_t *root_count) {
  voxel_list l = {voxels, n};
  return cut(w, in_voxels, &l, T, false, roots, root_count);
}

bool sylva__prune_due(const sylva_prune_def *d, int T) {
  if (T < d->from) return false;
  return d->every == 0 ? T == d->from : (T - d->from) % d->every == 0;
}
