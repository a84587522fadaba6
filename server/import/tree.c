/* A cylinder model turned into a sylva tree (tree.h): pieces, axes, resampling,
 * branches, births, stages. */
#include "tree.h"

#include <assert.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/status.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

void sylva_tree_free(sylva_tree *t) {
  if (!t) return;
  free(t->node);
  memset(t, 0, sizeof *t);
}

static double dist3(const double a[3], const double b[3]) {
  double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return sqrt(dx * dx + dy * dy + dz * dz);
}

static void cyl_end(const sylva_qsm_cylinder *c, double e[3]) {
  for (int j = 0; j < 3; j++) e[j] = c->start[j] + c->axis[j] * c->length;
}

/* ---- the summary ---- */

int sylva_tree_summarise(sylva_tree *t) {
  t->height = 0;
  t->dbh = NAN;
  t->volume = 0;
  t->length = 0;
  t->branches = 0;
  t->max_order = 0;
  t->stems = 0;
  if (t->count == 0) return SYLVA_OK;
  int *order = malloc(t->count * sizeof *order);
  int *next = malloc(t->count * sizeof *next); /* each node's axis child, -1 if none */
  if (!order || !next) {
    free(order);
    free(next);
    return SYLVA_ENOMEM;
  }
  double zmax = -INFINITY;
  for (size_t i = 0; i < t->count; i++) {
    const sylva_tree_node *n = &t->node[i];
    next[i] = -1;
    if (n->p[2] > zmax) zmax = n->p[2];
    if (n->parent < 0) {
      order[i] = 0;
      t->stems++;
      continue;
    }
    const sylva_tree_node *p = &t->node[n->parent];
    double len = dist3(n->p, p->p);
    t->length += len;
    t->volume += M_PI * n->radius * n->radius * len;
    order[i] = order[n->parent] + (n->lateral ? 1 : 0);
    if (order[i] > t->max_order) t->max_order = order[i];
    if (n->lateral) t->branches++;
    else next[n->parent] = (int)i;
  }
  t->height = zmax - t->base[2];
  /* DBH: the first stem's main axis, the internode that reaches breast height */
  for (int i = next[0]; i >= 0; i = next[i])
    if (t->node[i].p[2] - t->base[2] >= 1.3) {
      t->dbh = 2.0 * t->node[i].radius;
      break;
    }
  free(order);
  free(next);
  return SYLVA_OK;
}

/* ---- building ---- */

/* An axis: a chain of cylinders, order[cyl_begin .. cyl_begin + cyl_count), and the
 * nodes resampled on it, node[node_begin .. node_begin + node_count). */
typedef struct axis {
  int parent; /* the parent axis, -1 for a stem's first axis */
  size_t cyl_begin, cyl_count;
  size_t node_begin, node_count;
} axis;

typedef struct builder {
  const sylva_qsm *q;
  const sylva_tree_options *o;
  size_t *child_start; /* children of cylinder i: child[child_start[i] .. child_start[i+1]) */
  int *child;
  int *order;          /* cylinders in axis order */
  size_t order_n;
  axis *axes;
  size_t axes_n, axes_cap;
  sylva_tree_node *node;
  size_t node_n, node_cap;
  bool *has_lateral;
  double *cum;         /* arc length at each joint of an axis (see resample_axis) */
  double *joint;       /* an axis's joints, x y z each */
  bool branch_numbers; /* the file numbers its branches */
} builder;

static int push_axis(builder *b, int parent, int first_cyl) {
  if (b->axes_n == b->axes_cap) {
    size_t cap = b->axes_cap ? 2 * b->axes_cap : 64;
    axis *a = realloc(b->axes, cap * sizeof *a);
    if (!a) return SYLVA_ENOMEM;
    b->axes = a;
    b->axes_cap = cap;
  }
  /* the first cylinder's place in order[] is given when the axis is walked; keep the
   * cylinder in cyl_begin until then */
  b->axes[b->axes_n++] = (axis){.parent = parent, .cyl_begin = (size_t)first_cyl};
  return SYLVA_OK;
}

/* The child of cylinder c that continues its axis, or -1. */
static int continuation(const builder *b, int c) {
  const sylva_qsm_cylinder *cyl = b->q->cyl;
  int best = -1;
  double best_dot = -INFINITY;
  for (size_t k = b->child_start[c]; k < b->child_start[c + 1]; k++) {
    int ch = b->child[k];
    if (b->branch_numbers) {
      if (cyl[ch].branch == cyl[c].branch) return ch;
      continue;
    }
    double dot = cyl[ch].axis[0] * cyl[c].axis[0] + cyl[ch].axis[1] * cyl[c].axis[1] +
                 cyl[ch].axis[2] * cyl[c].axis[2];
    if (dot > best_dot) {
      best_dot = dot;
      best = ch;
    }
  }
  return best;
}

/* Walks the axes of the stem whose first axis is axes[first]: each axis's chain of
 * cylinders into order[], every other child a new axis, breadth first. */
static int walk_stem(builder *b, size_t first) {
  for (size_t a = first; a < b->axes_n; a++) {
    int c = (int)b->axes[a].cyl_begin;
    b->axes[a].cyl_begin = b->order_n;
    while (c >= 0) {
      b->order[b->order_n++] = c;
      int next = continuation(b, c);
      for (size_t k = b->child_start[c]; k < b->child_start[c + 1]; k++)
        if (b->child[k] != next && push_axis(b, (int)a, b->child[k])) return SYLVA_ENOMEM;
      c = next;
    }
    b->axes[a].cyl_count = b->order_n - b->axes[a].cyl_begin;
  }
  return SYLVA_OK;
}

static int push_node(builder *b, const double p[3], double radius, int parent, int lateral) {
  if (b->node_n == b->node_cap) {
    size_t cap = b->node_cap ? 2 * b->node_cap : 1024;
    sylva_tree_node *n = realloc(b->node, cap * sizeof *n);
    if (!n) return SYLVA_ENOMEM;
    b->node = n;
    bool *h = realloc(b->has_lateral, cap * sizeof *h);
    if (!h) return SYLVA_ENOMEM;
    b->has_lateral = h;
    b->node_cap = cap;
  }
  sylva_tree_node *n = &b->node[b->node_n];
  memcpy(n->p, p, sizeof n->p);
  n->radius = radius;
  n->parent = parent;
  n->lateral = lateral;
  n->birth = 0;
  b->has_lateral[b->node_n] = false;
  if (lateral) b->has_lateral[parent] = true;
  b->node_n++;
  return SYLVA_OK;
}

/* The node nearest to p among node[lo..hi) with no lateral child (any node when
 * free_only is false), or -1. */
static int nearest_node(const builder *b, size_t lo, size_t hi, const double p[3],
                        bool free_only) {
  int best = -1;
  double best_d = INFINITY;
  for (size_t i = lo; i < hi; i++) {
    if (free_only && b->has_lateral[i]) continue;
    double d = dist3(b->node[i].p, p);
    if (d < best_d) {
      best_d = d;
      best = (int)i;
    }
  }
  return best;
}

/* Resamples axis a (see tree.h); stem_begin is the stem's first node. */
static int resample_axis(builder *b, sylva_tree *t, size_t a, size_t stem_begin) {
  const sylva_qsm_cylinder *cyl = b->q->cyl;
  axis *ax = &b->axes[a];
  const int *oc = b->order + ax->cyl_begin;
  size_t m = ax->cyl_count;
  /* The axis as a line through its joints: TreeQSM's consecutive cylinders of a
   * branch rarely meet (their ends are some centimetres apart, mostly sideways: 2.6 cm
   * on average in the ITSMe tree of 3791 cylinders, up to 0.7 m), so each joint is
   * the midpoint of one cylinder's end and the next one's start. Walking the
   * cylinders themselves would add a zigzag at every joint, which a short rho turns
   * into length and volume (+16% and +9% at rho 0.01 m on that tree). Segment j,
   * joint[j] to joint[j + 1], has cylinder j's radius. */
  double *jt = b->joint;
  for (size_t j = 0; j <= m; j++) {
    double e[3];
    if (j > 0) cyl_end(&cyl[oc[j - 1]], e);
    for (int d = 0; d < 3; d++)
      jt[3 * j + (size_t)d] = j == 0   ? cyl[oc[0]].start[d]
                              : j == m ? e[d]
                                       : 0.5 * (e[d] + cyl[oc[j]].start[d]);
  }
  b->cum[0] = 0;
  for (size_t j = 0; j < m; j++) b->cum[j + 1] = b->cum[j] + dist3(jt + 3 * j, jt + 3 * j + 3);
  double len = b->cum[m], rho = b->o->rho;
  ax->node_begin = b->node_n;
  int parent = -1, lateral = 0;
  if (ax->parent >= 0) {
    /* A branch: its first node hangs from the nearest node of its parent axis that
     * carries no lateral yet (tree.h, "Branches"). */
    const axis *pa = &b->axes[ax->parent];
    const double *start = cyl[oc[0]].start;
    size_t lo = pa->node_begin, hi = pa->node_begin + pa->node_count;
    parent = nearest_node(b, lo, hi, start, false);
    if (b->has_lateral[parent]) {
      parent = nearest_node(b, lo, hi, start, true);
      if (parent >= 0) {
        t->laterals_moved++;
      } else {
        /* each axis adds a free node, so the stem always has one */
        parent = nearest_node(b, stem_begin, b->node_n, start, true);
        assert(parent >= 0);
        t->laterals_off_axis++;
      }
    }
    lateral = 1;
  }
  /* points at k rho, k from 0 on a stem's first axis and from 1 on a branch */
  size_t j = 0;
  for (size_t k = ax->parent >= 0 ? 1 : 0;; k++) {
    double s = (double)k * rho;
    if (!(s < len - SYLVA_TREE_MERGE)) break;
    while (j + 1 < m && s > b->cum[j + 1]) j++;
    double seg = b->cum[j + 1] - b->cum[j], f = seg > 0 ? (s - b->cum[j]) / seg : 0, p[3];
    for (int d = 0; d < 3; d++)
      p[d] = jt[3 * j + (size_t)d] + (jt[3 * j + 3 + (size_t)d] - jt[3 * j + (size_t)d]) * f;
    int rc = push_node(b, p, cyl[oc[j]].radius, parent, lateral);
    if (rc) return rc;
    parent = (int)b->node_n - 1;
    lateral = 0;
  }
  int rc = push_node(b, jt + 3 * m, cyl[oc[m - 1]].radius, parent, lateral);
  if (rc) return rc;
  ax->node_count = b->node_n - ax->node_begin;
  return SYLVA_OK;
}

static void builder_free(builder *b) {
  free(b->child_start);
  free(b->child);
  free(b->order);
  free(b->axes);
  free(b->node);
  free(b->has_lateral);
  free(b->cum);
  free(b->joint);
}

/* The first year t (0..age) at which the scaled curve reaches h. */
static int year_reaching(const double *heights, int age, double scale, double h) {
  for (int a = 0; a < age; a++)
    if (heights[a] * scale >= h) return a;
  return age;
}

/* Births from the path length to the tips (tree.h, sylva_tree_build). */
static int estimate_births(sylva_tree *t, const sylva_tree_options *o) {
  if (!o->heights || t->count == 0) return SYLVA_OK;
  double *d = calloc(t->count, sizeof *d);
  if (!d) return SYLVA_ENOMEM;
  for (size_t i = t->count; i-- > 0;) {
    const sylva_tree_node *n = &t->node[i];
    if (n->parent < 0) continue;
    double down = d[i] + dist3(n->p, t->node[n->parent].p);
    if (down > d[n->parent]) d[n->parent] = down;
  }
  double h = t->height;
  double scale = h / o->heights[t->age];
  for (size_t i = 0; i < t->count; i++) {
    sylva_tree_node *n = &t->node[i];
    /* born once the tree was as tall as the node stands and as the node's own
     * subtree reaches below the top (docs/model.md, "Measured trees") */
    int by_tips = year_reaching(o->heights, t->age, scale, h - d[i]);
    int by_height = year_reaching(o->heights, t->age, scale, n->p[2] - t->base[2]);
    n->birth = (by_tips > by_height ? by_tips : by_height) - t->age;
    if (n->parent >= 0 && n->birth < t->node[n->parent].birth) n->birth = t->node[n->parent].birth;
  }
  free(d);
  return SYLVA_OK;
}

static int check_options(const sylva_tree_options *o, char *err, size_t errlen) {
  if (!(isfinite(o->rho) && o->rho > 0))
    return server_fail(err, errlen, SYLVA_EINVAL, "rho %g is not a length above 0", o->rho);
  for (int j = 0; j < 3; j++)
    if (!isfinite(o->base[j]))
      return server_fail(err, errlen, SYLVA_EINVAL, "the base is not a finite point");
  if (!o->heights) {
    if (o->age < 0)
      return server_fail(err, errlen, SYLVA_EINVAL, "age %d is negative", o->age);
    return SYLVA_OK;
  }
  if (o->years < 0)
    return server_fail(err, errlen, SYLVA_EINVAL, "the height curve has no years");
  if (o->age < 0 || o->age > o->years)
    return server_fail(err, errlen, SYLVA_EINVAL,
                           "age %d is outside the height curve's ages 0 to %d", o->age, o->years);
  for (int a = 0; a <= o->years; a++) {
    if (!(isfinite(o->heights[a]) && o->heights[a] >= 0))
      return server_fail(err, errlen, SYLVA_EINVAL,
                             "the height curve at age %d is %g, not a height", a, o->heights[a]);
    if (a > 0 && o->heights[a] < o->heights[a - 1])
      return server_fail(err, errlen, SYLVA_EINVAL,
                             "the height curve decreases at age %d (%g m after %g m)", a,
                             o->heights[a], o->heights[a - 1]);
  }
  return SYLVA_OK;
}

int sylva_tree_build(const sylva_qsm *q, const sylva_tree_options *o, sylva_tree *t, char *err,
                     size_t errlen) {
  if (err && errlen) err[0] = '\0';
  memset(t, 0, sizeof *t);
  int rc = check_options(o, err, errlen);
  if (rc) return rc;
  if (!q->count) return server_fail(err, errlen, SYLVA_EINVAL, "the model has no cylinders");
  if (q->count > (size_t)INT32_MAX)
    return server_fail(err, errlen, SYLVA_ETOOBIG, "%zu cylinders: too many", q->count);
  size_t n = q->count;
  builder b = {.q = q, .o = o};
  b.child_start = calloc(n + 1, sizeof *b.child_start);
  b.child = malloc(n * sizeof *b.child);
  b.order = malloc(n * sizeof *b.order);
  b.cum = malloc((n + 1) * sizeof *b.cum);
  b.joint = malloc(3 * (n + 1) * sizeof *b.joint);
  int *piece = malloc(n * sizeof *piece); /* each cylinder's root */
  if (!b.child_start || !b.child || !b.order || !b.cum || !b.joint || !piece) {
    rc = SYLVA_ENOMEM;
    goto fail;
  }
  /* children in file order */
  for (size_t i = 0; i < n; i++) {
    if (q->cyl[i].parent >= 0) b.child_start[q->cyl[i].parent + 1]++;
    if (q->cyl[i].branch != 0) b.branch_numbers = true;
  }
  for (size_t i = 0; i < n; i++) b.child_start[i + 1] += b.child_start[i];
  {
    /* a second pass with a cursor per parent keeps the file order */
    size_t *cursor = malloc((n + 1) * sizeof *cursor);
    if (!cursor) {
      rc = SYLVA_ENOMEM;
      goto fail;
    }
    memcpy(cursor, b.child_start, (n + 1) * sizeof *cursor);
    for (size_t i = 0; i < n; i++)
      if (q->cyl[i].parent >= 0) b.child[cursor[q->cyl[i].parent]++] = (int)i;
    free(cursor);
  }
  /* pieces: each cylinder's root, by walking down from the roots (parents are in
   * range and acyclic, sylva_qsm_check) */
  {
    size_t done = 0;
    for (size_t i = 0; i < n; i++) piece[i] = -1;
    for (size_t r = 0; r < n; r++) {
      if (q->cyl[r].parent >= 0) continue;
      size_t head = done;
      b.order[done++] = (int)r;
      piece[r] = (int)r;
      for (; head < done; head++) {
        int c = b.order[head];
        for (size_t k = b.child_start[c]; k < b.child_start[c + 1]; k++) {
          piece[b.child[k]] = (int)r;
          b.order[done++] = b.child[k];
        }
      }
    }
    assert(done == n);
  }
  /* the ground: the lowest root; its piece's horizontal extent is the footprint */
  int lowest = -1;
  for (size_t r = 0; r < n; r++)
    if (q->cyl[r].parent < 0 && (lowest < 0 || q->cyl[r].start[2] < q->cyl[lowest].start[2]))
      lowest = (int)r;
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (size_t i = 0; i < n; i++) {
    if (piece[i] != lowest) continue;
    double e[3];
    cyl_end(&q->cyl[i], e);
    for (int j = 0; j < 2; j++) {
      lo[j] = fmin(lo[j], fmin(q->cyl[i].start[j], e[j]));
      hi[j] = fmax(hi[j], fmax(q->cyl[i].start[j], e[j]));
    }
  }
  /* the stems, in file order: walk each one's axes */
  b.order_n = 0;
  int first_root = -1;
  for (size_t r = 0; r < n; r++) {
    const sylva_qsm_cylinder *c = &q->cyl[r];
    if (c->parent >= 0) continue;
    bool stem = (int)r == lowest ||
                (c->start[2] - q->cyl[lowest].start[2] <= SYLVA_TREE_STEM_RISE &&
                 c->start[0] >= lo[0] && c->start[0] <= hi[0] && c->start[1] >= lo[1] &&
                 c->start[1] <= hi[1]);
    if (!stem) {
      t->pieces_dropped++;
      continue;
    }
    if (first_root < 0) first_root = (int)r;
    size_t first = b.axes_n;
    if ((rc = push_axis(&b, -1, (int)r)) || (rc = walk_stem(&b, first))) goto fail;
  }
  t->cylinders = b.order_n;
  t->cylinders_dropped = n - b.order_n;
  /* Too many nodes is known before any is placed: an axis's line through its joints
   * is no longer than its cylinders and the gaps between them. */
  double reach = 0;
  for (size_t i = 0; i < b.order_n; i++) {
    const sylva_qsm_cylinder *c = &q->cyl[b.order[i]];
    t->cylinder_volume += M_PI * c->radius * c->radius * c->length;
    reach += c->length;
    if (c->parent >= 0) {
      double e[3];
      cyl_end(&q->cyl[c->parent], e);
      reach += dist3(e, c->start);
    }
  }
  if (reach / o->rho + 2.0 * (double)b.axes_n > (double)SYLVA_TREE_MAX_NODES) {
    rc = server_fail(err, errlen, SYLVA_ETOOBIG,
                         "more than %zu nodes: rho %g m is too short for %.1f m of cylinders",
                         SYLVA_TREE_MAX_NODES, o->rho, reach);
    goto fail;
  }
  /* resample, stem by stem (a stem's axes are contiguous, its first axis first) */
  {
    size_t stem_begin = 0;
    for (size_t a = 0; a < b.axes_n; a++) {
      if (b.axes[a].parent < 0) stem_begin = b.node_n;
      if ((rc = resample_axis(&b, t, a, stem_begin))) goto fail;
    }
  }
  /* the first root at the base */
  double shift[3];
  for (int j = 0; j < 3; j++) shift[j] = o->base[j] - q->cyl[first_root].start[j];
  for (size_t i = 0; i < b.node_n; i++)
    for (int j = 0; j < 3; j++) b.node[i].p[j] += shift[j];
  t->node = b.node;
  t->count = b.node_n;
  b.node = NULL;
  memcpy(t->base, o->base, sizeof t->base);
  if ((rc = sylva_tree_summarise(t))) goto fail;
  t->age = o->age;
  if (o->heights) {
    if (t->age == 0) {
      t->age = o->years;
      for (int a = 0; a <= o->years; a++)
        if (o->heights[a] >= t->height) {
          t->age = a;
          break;
        }
    }
    if (!(o->heights[t->age] > 0)) {
      rc = server_fail(err, errlen, SYLVA_EINVAL,
                           "the height curve is 0 at age %d: it cannot be scaled", t->age);
      goto fail;
    }
  }
  if ((rc = estimate_births(t, o))) goto fail;
  builder_free(&b);
  free(piece);
  return SYLVA_OK;

fail:
  if (rc == SYLVA_ENOMEM && err && errlen && !err[0])
    server_fail(err, errlen, rc, "out of memory");
  builder_free(&b);
  free(piece);
  sylva_tree_free(t);
  return rc;
}

/* ---- stages ---- */

/* Tips in each node's subtree: tips[i] over node[0..count). */
static void count_tips(const sylva_tree_node *node, size_t count, const int *keep, double *tips) {
  for (size_t i = 0; i < count; i++) tips[i] = 0;
  for (size_t i = count; i-- > 0;) {
    if (keep && !keep[i]) continue;
    if (tips[i] == 0) tips[i] = 1;
    if (node[i].parent >= 0) tips[node[i].parent] += tips[i];
  }
}

int sylva_tree_stage(const sylva_tree *t, int years_before, double pipe_exponent,
                     sylva_tree *out) {
  assert(out != t);
  sylva_tree_free(out);
  if (years_before < 0 || years_before > t->age || !(pipe_exponent > 0)) return SYLVA_ERANGE;
  size_t n = t->count;
  int *keep = calloc(n ? n : 1, sizeof *keep); /* the new index + 1, 0 if not kept */
  double *tips0 = malloc((n ? n : 1) * sizeof *tips0);
  double *tipsn = malloc((n ? n : 1) * sizeof *tipsn);
  size_t kept = 0;
  int rc = SYLVA_OK;
  if (!keep || !tips0 || !tipsn) {
    rc = SYLVA_ENOMEM;
    goto done;
  }
  for (size_t i = 0; i < n; i++) {
    const sylva_tree_node *v = &t->node[i];
    keep[i] = 0;
    if (v->birth > -years_before) continue;
    /* births never decrease from parent to child, so the stage is closed */
    assert(v->parent < 0 || keep[v->parent] > 0);
    keep[i] = (int)++kept;
  }
  count_tips(t->node, n, NULL, tips0);
  count_tips(t->node, n, keep, tipsn);
  *out = *t;
  out->node = malloc((kept ? kept : 1) * sizeof *out->node);
  if (!out->node) {
    memset(out, 0, sizeof *out);
    rc = SYLVA_ENOMEM;
    goto done;
  }
  out->count = kept;
  out->age = t->age - years_before;
  for (size_t i = 0; i < n; i++) {
    if (!keep[i]) continue;
    sylva_tree_node *v = &out->node[keep[i] - 1];
    *v = t->node[i];
    v->parent = v->parent < 0 ? -1 : keep[v->parent] - 1;
    v->birth += years_before;
    if (tipsn[i] != tips0[i]) v->radius *= pow(tipsn[i] / tips0[i], 1.0 / pipe_exponent);
  }
  rc = sylva_tree_summarise(out);
  if (rc) sylva_tree_free(out);

done:
  free(keep);
  free(tips0);
  free(tipsn);
  return rc;
}
