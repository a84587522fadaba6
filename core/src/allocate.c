#include "allocate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sort.h"
#include "world_impl.h"

double sylva__bh_share(double lm, double ll, double lambda) {
  double den = lambda * lm + (1.0 - lambda) * ll;
  if (!(den > 0.0)) return 0.0;
  return (lm + ll) * (1.0 - lambda) * ll / den;
}

double sylva__priority_weight(int rank, int n, double k, double w1, double w2, double w3) {
  double r = (double)rank / (double)n;
  if (r < k || k >= 1.0) return w1;
  return w2 + (w3 - w2) * (r - k) / (1.0 - k);
}

static int cmp_ranked(const void *a, const void *b) {
  const sylva__ranked *x = a, *y = b;
  if (x->rbh > y->rbh) return -1;
  if (x->rbh < y->rbh) return 1;
  return (x->pos > y->pos) - (x->pos < y->pos);
}

/* One piece of the parallel allocation (sylva__allocate): its stems' scratch, each
 * of room the largest stem's live nodes (an axis, its ranking and the stack of
 * pending laterals never hold more), and the piece's own list of sprouts (room: its
 * stems' live nodes, as a node sprouts at most once). */
typedef struct axis_scratch {
  int32_t *axis, *work;
  double *light, *work_r;
  sylva__ranked *ranked;
  size_t axis_len, work_len, room;
  sylva__sprout *out;
  size_t out_len, out_room;
} axis_scratch;

static void push_sprout(axis_scratch *sc, int32_t slot, int32_t stem, int32_t n, double r, bool apex) {
  SYLVA_ASSERT(sc->out_len < sc->out_room);
  sc->out[sc->out_len++] = (sylva__sprout){slot, stem, n, r, apex};
}

/* The cap of a shoot off the trunk from node n: the reach graded by the node's depth
 * in the crown, f = 1 + (lateral_reach - 1) min(1, (top - z) / crown height), top the
 * stem's height at the season's start, and no more than the full reach's cap (the
 * rounded caps are not monotone in f; docs/model.md, "Species in years"). */
static int32_t graded_cap(const sylva_world *w, int32_t stem, int32_t n, int32_t full) {
  const sylva__stem *st = &w->stems[stem];
  const sylva__species *sp = &w->species[st->species];
  double reach = sp->def.lateral_reach;
  if (reach == 1.0) return full;
  double h = st->stats.height, depth = st->stats.crown_height;
  if (!(depth > 0.0)) depth = h;
  double below = st->root[2] + h - w->nodes.z[n];
  double share = depth > 0.0 ? below / depth : 1.0;
  share = share < 0.0 ? 0.0 : share > 1.0 ? 1.0 : share;
  int32_t c = sylva__clock_cap(sp, st->clock, w->clock_next.data[stem], 1.0 + (reach - 1.0) * share);
  return c < full ? c : full;
}

/* Distributes r_b over the axis starting at slot first; laterals go on the stack. */
static void allocate_axis(const sylva_world *w, axis_scratch *sc, int32_t stem, int32_t first,
                          double r_b, bool trunk, int local, int cap) {
  const sylva__skeleton *s = &w->nodes;
  const sylva__species *sp = &w->species[w->stems[stem].species];
  const sylva_species_def *d = &sp->def;
  /* The axis's nodes that carry a bud (every node, but with ref_rho one per ref_rho
   * of axis) and its apex; each stands for itself and the bud-less nodes below it
   * down to the previous one, whose light its free bud collects as its own
   * (docs/model.md, "Species in years"). */
  sc->axis_len = 0;
  double segment = 0.0;
  for (int32_t n = first; n >= 0; n = s->axis_child[n]) {
    segment += w->light[n];
    if (s->axis_child[n] >= 0 && s->lateral_child[n] < 0 && !sylva__has_bud(sp, s->depth[n]))
      continue;
    SYLVA_ASSERT(sc->axis_len < sc->room);
    sc->axis[sc->axis_len] = n;
    sc->light[sc->axis_len++] = segment;
    segment = 0.0;
  }
  int nb = (int)sc->axis_len;
  int32_t apex_depth = s->depth[sc->axis[nb - 1]];
  for (int i = 0; i < nb; i++) {
    int32_t n = sc->axis[i];
    double lm = s->axis_child[n] >= 0 ? w->q[s->axis_child[n]] : 0.0;
    double ll = s->lateral_child[n] >= 0 ? w->q[s->lateral_child[n]] : sc->light[i];
    /* a scar (shed branch) has no bud left to feed */
    double rbh = (s->flags[n] & SYLVA__NODE_SCAR) ? 0.0 : sylva__bh_share(lm, ll, d->lambda);
    /* Apical dominance: a free bud fewer than apical_zone internodes below the
     * axis's apex stays dormant and takes no share (docs/model.md, "Allocation"). */
    if (s->lateral_child[n] < 0 && i < nb - 1 && apex_depth - s->depth[n] < d->apical_zone)
      rbh = 0.0;
    sc->ranked[i] = (sylva__ranked){rbh, 0.0, i};
  }
  /* The trunk's apex continues the main flow: besides its own light it takes the
   * share apical_flow of what the BH shares of the other nodes leave of the axis's
   * light (docs/model.md, "Allocation"). */
  int32_t apex_node = sc->axis[nb - 1];
  if (trunk && s->lateral_child[apex_node] < 0 && d->apical_flow > 0.0) {
    double laterals = 0.0;
    for (int i = 0; i < nb - 1; i++) laterals += sc->ranked[i].rbh;
    double own = sc->ranked[nb - 1].rbh, rest = w->q[first] - laterals - own;
    if (rest > 0.0) sc->ranked[nb - 1].rbh = own + d->apical_flow * rest;
  }
  /* Apical control: the trunk's apex is ranked first while T <= tau. */
  bool apical = trunk && local <= d->tau;
  sylva__ranked *items = sc->ranked;
  int from = 0;
  if (apical) {
    sylva__ranked apex = items[nb - 1];
    for (int i = nb - 1; i > 0; i--) items[i] = items[i - 1];
    items[0] = apex;
    from = 1;
  }
  sylva__sort(items + from, (size_t)(nb - from), sizeof *items, cmp_ranked);
  double sum = 0.0;
  for (int rank = 0; rank < nb; rank++) {
    double wr = sylva__priority_weight(rank, nb, d->k, d->w1, d->w2, d->w3);
    items[rank].weighted = items[rank].rbh * wr;
    sum += items[rank].weighted;
  }
  for (int rank = 0; rank < nb; rank++) {
    int32_t n = sc->axis[items[rank].pos];
    double r_i = sum > 0.0 ? r_b * items[rank].weighted / sum : 0.0;
    bool apex = s->axis_child[n] < 0;
    if (s->lateral_child[n] >= 0) {
      SYLVA_ASSERT(sc->work_len < sc->room);
      sc->work[sc->work_len] = s->lateral_child[n];
      sc->work_r[sc->work_len++] = r_i;
    } else if (apex || !(s->flags[n] & SYLVA__NODE_SCAR)) {
      double y = floor(r_i / d->node_cost);
      int32_t c = trunk ? cap : graded_cap(w, stem, n, cap);
      int32_t grow = y < (double)c ? (int32_t)y : c;
      if (grow >= 1) push_sprout(sc, n, stem, grow, r_i, apex);
    }
  }
}

static void allocate_lgtm(const sylva_world *w, axis_scratch *sc, int32_t stem, int local, int cap,
                          int lateral_cap) {
  const sylva__skeleton *s = &w->nodes;
  int32_t root = w->stems[stem].root_slot;
  sc->work_len = 0;
  if (s->axis_child[root] < 0) return; /* pruned down to its root: a stump */
  allocate_axis(w, sc, stem, s->axis_child[root], w->q[root], true, local, cap);
  while (sc->work_len) {
    sc->work_len--;
    allocate_axis(w, sc, stem, sc->work[sc->work_len], sc->work_r[sc->work_len], false, local,
                  lateral_cap);
  }
}

static int cmp_sprout(const void *a, const void *b) {
  const sylva__sprout *x = a, *y = b;
  if (x->stem != y->stem) return (x->stem > y->stem) - (x->stem < y->stem);
  if (x->r > y->r) return -1;
  if (x->r < y->r) return 1;
  return (x->slot > y->slot) - (x->slot < y->slot);
}

/* The leader's answer to light (docs/model.md, "Stands"): the share of a season its
 * clock advances at light l = 1 - S in the voxel of its highest node, the plants'
 * shade alone, l (1 + K) / (l + K): 1 in full light and for K = 0, 0 in the dark. */
static double light_response(double l, double K) {
  if (!(K > 0.0) || l >= 1.0) return 1.0;
  if (!(l > 0.0)) return 0.0;
  return l * (1.0 + K) / (l + K);
}

/* Every stem's clock after this season into clock_next: its vigour times its
 * leader's answer to the light at its highest node. A dead stem's clock stands.
 * Committed by the step once it can no longer fail. */
static int season_clocks(sylva_world *w) {
  sylva__skeleton *s = &w->nodes;
  if (SYLVA__VEC_RESERVE(w->clock_next, (size_t)w->stem_count) ||
      SYLVA__VEC_RESERVE(w->stem_high, (size_t)w->stem_count))
    return SYLVA_ENOMEM;
  int32_t *high = w->stem_high.data;
  bool any = false;
  for (int k = 0; k < w->stem_count; k++) {
    high[k] = -1;
    any = any || w->species[w->stems[k].species].def.height_light > 0.0;
  }
  for (size_t i = 0; any && i < s->count; i++) {
    if (!(s->flags[i] & SYLVA__NODE_ALIVE)) continue;
    int32_t k = s->stem[i];
    if (high[k] < 0 || s->z[i] > s->z[high[k]]) high[k] = (int32_t)i;
  }
  for (int k = 0; k < w->stem_count; k++) {
    const sylva__stem *st = &w->stems[k];
    double f = 1.0;
    if (high[k] >= 0) {
      int v[3];
      sylva__node_voxel(w, high[k], v);
      /* the plants' shade alone: the database's street trees grew beside buildings,
       * so their curves hold a street's sky already */
      double l = 1.0 - (double)sylva__grid_shade_raw(&w->grid, v) / SYLVA__SHADE_ONE;
      f = light_response(l, w->species[st->species].def.height_light);
    }
    w->clock_next.data[k] = sylva__stem_dead(st) ? st->clock : st->clock + st->rate * f;
  }
  return SYLVA_OK;
}

/* The parallel allocation: pieces of consecutive stems, each with its own scratch. */
typedef struct alloc_ctx {
  sylva_world *w;
  int iteration;
  size_t pieces, room;
} alloc_ctx;

/* Piece p's stems: [p S / pieces, (p + 1) S / pieces). */
static size_t piece_stem(const alloc_ctx *c, size_t p) {
  return p * (size_t)c->w->stem_count / c->pieces;
}

/* Pieces [begin, end): each LGTM stem that grows distributes its resource alone
 * (reading the light, the skeleton and the caps, writing only its piece's scratch and
 * list), and sorts its sprouts. */
static void allocate_pieces(void *arg, size_t begin, size_t end) {
  const alloc_ctx *c = arg;
  sylva_world *w = c->w;
  const int32_t *caps = w->caps.data, *lateral = caps + w->stem_count;
  for (size_t piece = begin; piece < end; piece++) {
    size_t at = piece * c->room;
    sylva__piece_sprouts *list = &w->piece_sprouts.data[piece];
    axis_scratch sc = {.axis = w->axis.data + at, .work = w->work.data + at,
                       .light = w->work_light.data + at, .work_r = w->work_r.data + at,
                       .ranked = w->ranked.data + at, .room = c->room,
                       .out = list->data, .out_room = list->cap};
    for (size_t k = piece_stem(c, piece); k < piece_stem(c, piece + 1); k++) {
      const sylva__stem *st = &w->stems[k];
      if ((caps[k] <= 0 && lateral[k] <= 0) ||
          w->species[st->species].def.allocation != SYLVA_ALLOC_LGTM)
        continue;
      size_t from = sc.out_len;
      allocate_lgtm(w, &sc, (int32_t)k, sylva__stem_local(st, c->iteration), caps[k], lateral[k]);
      /* a stem's shoots grow in decreasing R_i (slot breaks ties) */
      sylva__sort(sc.out + from, sc.out_len - from, sizeof *sc.out, cmp_sprout);
    }
    list->len = sc.out_len;
  }
}

/* Room for the parallel allocation: each piece's list of sprouts (its stems' live
 * nodes) and scratch of room the most live nodes of a stem. Each piece keeps its own
 * block from step to step, so only the sprouts it writes are ever touched. */
static int reserve_pieces(sylva_world *w, alloc_ctx *c) {
  const sylva__skeleton *s = &w->nodes;
  size_t stems = (size_t)w->stem_count;
  if (SYLVA__VEC_RESERVE(w->stem_first, stems + 1)) return SYLVA_ENOMEM;
  int32_t *first = w->stem_first.data; /* the stems' live nodes, summed */
  for (size_t k = 0; k <= stems; k++) first[k] = 0;
  for (size_t i = 0; i < s->count; i++)
    if (s->flags[i] & SYLVA__NODE_ALIVE) first[s->stem[i] + 1]++;
  size_t room = 1;
  for (size_t k = 0; k < stems; k++) {
    if ((size_t)first[k + 1] > room) room = (size_t)first[k + 1];
    first[k + 1] += first[k];
  }
  /* a power of two, so that the pieces' stretches seldom move: each is touched only
   * as far as its longest axis and stack reach */
  size_t pow2 = 64;
  while (pow2 < room) pow2 *= 2;
  size_t pieces = 8 * (size_t)sylva__pool_threads(w->pool);
  c->pieces = pieces < stems ? pieces : stems;
  c->room = pow2;
  size_t had = w->piece_sprouts.cap;
  if (SYLVA__VEC_RESERVE(w->piece_sprouts, c->pieces)) return SYLVA_ENOMEM;
  for (size_t p = had; p < w->piece_sprouts.cap; p++)
    w->piece_sprouts.data[p] = (sylva__piece_sprouts){NULL, 0, 0};
  for (size_t p = 0; p < c->pieces; p++) {
    sylva__piece_sprouts *list = &w->piece_sprouts.data[p];
    list->len = 0;
    if (SYLVA__VEC_RESERVE(*list, (size_t)(first[piece_stem(c, p + 1)] - first[piece_stem(c, p)])))
      return SYLVA_ENOMEM;
  }
  size_t n = c->pieces * c->room;
  if (SYLVA__VEC_RESERVE(w->axis, n) || SYLVA__VEC_RESERVE(w->work, n) ||
      SYLVA__VEC_RESERVE(w->work_light, n) || SYLVA__VEC_RESERVE(w->work_r, n) ||
      SYLVA__VEC_RESERVE(w->ranked, n))
    return SYLVA_ENOMEM;
  return SYLVA_OK;
}

int sylva__allocate(sylva_world *w, int iteration) {
  sylva__skeleton *s = &w->nodes;
  w->sprouts.len = 0;
  /* the leaders' caps c(T) of the stems that grow this iteration (0: does not grow),
   * then their laterals' (docs/model.md, "Species in years": lateral_reach) */
  alloc_ctx c = {w, iteration, 0, 0};
  if (SYLVA__VEC_RESERVE(w->caps, 2 * (size_t)w->stem_count) || reserve_pieces(w, &c))
    return SYLVA_ENOMEM;
  int32_t *caps = w->caps.data, *lateral = caps + w->stem_count;
  bool any_none = false;
  int rc = season_clocks(w);
  if (rc) return rc;
  for (int k = 0; k < w->stem_count; k++) {
    const sylva__stem *st = &w->stems[k];
    const sylva__species *sp = &w->species[st->species];
    double t0 = st->clock, t1 = w->clock_next.data[k];
    bool grows = !st->finished && !sylva__stem_dead(st);
    caps[k] = grows ? sylva__clock_cap(sp, t0, t1, 1.0) : 0;
    lateral[k] = grows ? sylva__clock_cap(sp, t0, t1, sp->def.lateral_reach) : 0;
  }
  /* stems that stop at this iteration (phase 2) grow nothing */
  for (size_t i = 0; i < w->finishing.len; i++) {
    caps[w->finishing.data[i]] = 0;
    lateral[w->finishing.data[i]] = 0;
  }
  for (int k = 0; k < w->stem_count; k++)
    if (caps[k] > 0 && w->species[w->stems[k].species].def.allocation == SYLVA_ALLOC_NONE)
      any_none = true;
  /* Stems share no node: each distributes its resource on its own, on the world's
   * threads (docs/model.md, "Determinism"); then the pieces' lists join in stem order. */
  sylva__pool_for(w->pool, c.pieces, 1, allocate_pieces, &c);
  size_t total = 0;
  for (size_t p = 0; p < c.pieces; p++) total += w->piece_sprouts.data[p].len;
  if (SYLVA__VEC_RESERVE(w->sprouts, total + 1)) return SYLVA_ENOMEM;
  for (size_t p = 0; p < c.pieces; p++) {
    const sylva__piece_sprouts *list = &w->piece_sprouts.data[p];
    if (list->len) memcpy(w->sprouts.data + w->sprouts.len, list->data, list->len * sizeof *list->data);
    w->sprouts.len += list->len;
  }
  if (any_none) {
    /* Simplified IGM: every apex, and every free bud with enough light, grows c(T). */
    for (size_t i = 0; i < s->count; i++) {
      if (!(s->flags[i] & SYLVA__NODE_ALIVE) || s->parent[i] < 0) continue;
      int32_t k = s->stem[i];
      const sylva__species *spc = &w->species[w->stems[k].species];
      const sylva_species_def *d = &spc->def;
      if (caps[k] <= 0 || d->allocation != SYLVA_ALLOC_NONE) continue;
      bool apex = s->axis_child[i] < 0;
      if (!apex && (s->lateral_child[i] >= 0 || (s->flags[i] & SYLVA__NODE_SCAR) ||
                    !sylva__has_bud(spc, s->depth[i]) ||
                    !sylva__bears_leaves(d, s->birth[i], iteration)))
        continue;
      int v[3];
      sylva__node_voxel(w, (int32_t)i, v);
      double l = sylva__grid_light(&w->grid, v);
      if (!apex && l < d->sprout_light) continue;
      if (SYLVA__VEC_RESERVE(w->sprouts, w->sprouts.len + 1)) return SYLVA_ENOMEM;
      w->sprouts.data[w->sprouts.len++] = (sylva__sprout){(int32_t)i, k, caps[k], l, apex};
    }
    /* Shoots of a stem are appended in decreasing R_i (slot breaks ties): cmp_sprout
     * is a total order, so this is the list the stems' own sorts give, with these. */
    qsort(w->sprouts.data, w->sprouts.len, sizeof *w->sprouts.data, cmp_sprout);
  }
  const sylva__sprout *sp = w->sprouts.data;
  size_t at = 0;
  for (int k = 0; k <= w->stem_count; k++) {
    while (at < w->sprouts.len && sp[at].stem < k) at++;
    w->stem_first.data[k] = (int32_t)at;
  }
  return SYLVA_OK;
}
