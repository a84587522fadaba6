#include "shoot.h"

#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "world_impl.h"

#define SYLVA__DEG (3.14159265358979323846 / 180.0)

static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross(const double a[3], const double b[3], double o[3]) {
  o[0] = a[1] * b[2] - a[2] * b[1];
  o[1] = a[2] * b[0] - a[0] * b[2];
  o[2] = a[0] * b[1] - a[1] * b[0];
}

static bool normalize(double v[3]) {
  double n = sqrt(dot(v, v));
  if (!(n > 1e-12)) return false;
  v[0] /= n, v[1] /= n, v[2] /= n;
  return true;
}

/* Two unit vectors completing d (unit) to an orthonormal basis. */
static void basis(const double d[3], double e1[3], double e2[3]) {
  double ref[3] = {1.0, 0.0, 0.0};
  if (fabs(d[0]) > 0.9) ref[0] = 0.0, ref[1] = 1.0;
  cross(d, ref, e1);
  normalize(e1);
  cross(d, e1, e2);
}

void sylva__lateral_direction(const double d[3], double theta, double phi, double out[3]) {
  double e1[3], e2[3];
  basis(d, e1, e2);
  double cp = cos(phi * SYLVA__DEG), sp = sin(phi * SYLVA__DEG);
  double a[3] = {e1[0] * cp + e2[0] * sp, e1[1] * cp + e2[1] * sp, e1[2] * cp + e2[2] * sp};
  /* rotate d by theta around a (a is perpendicular to d): d cos + (a x d) sin */
  double axd[3];
  cross(a, d, axd);
  double ct = cos(theta * SYLVA__DEG), st = sin(theta * SYLVA__DEG);
  for (int i = 0; i < 3; i++) out[i] = d[i] * ct + axd[i] * st;
  normalize(out);
}

static void internode_direction(const sylva__skeleton *s, int32_t n, double d[3]) {
  int32_t p = s->parent[n];
  if (p < 0) {
    d[0] = 0.0, d[1] = 0.0, d[2] = 1.0;
    return;
  }
  d[0] = (double)s->x[n] - s->x[p];
  d[1] = (double)s->y[n] - s->y[p];
  d[2] = (double)s->z[n] - s->z[p];
  if (!normalize(d)) d[0] = 0.0, d[1] = 0.0, d[2] = 1.0;
}

/* ---- competition index: sprouting nodes in a dense grid of cells ------------- */

typedef struct index_ctx {
  double min[3], cell;
  int64_t dims[3];
} index_ctx;

int sylva__keyed_cmp(const void *a, const void *b) {
  const sylva__keyed *x = a, *y = b;
  if (x->key != y->key) return (x->key > y->key) - (x->key < y->key);
  return (x->item > y->item) - (x->item < y->item);
}

static int64_t cell_of(const index_ctx *ix, int a, double v) {
  double f = floor((v - ix->min[a]) / ix->cell);
  if (f < 0.0) return 0;
  if (f >= (double)ix->dims[a]) return ix->dims[a] - 1;
  return (int64_t)f;
}

/* Counting sort of the sprouts into cells of at least the longest marker cone over
 * their bounding box; positions are copied beside them for scanning. */
static int build_index(sylva_world *w, index_ctx *ix) {
  size_t n = w->sprouts.len;
  const sylva__skeleton *s = &w->nodes;
  double cell = 0.0;
  for (int k = 0; k < w->species_count; k++) {
    double c = w->species[k].def.cone_radius * w->species[k].def.rho;
    if (c > cell) cell = c;
  }
  double mn[3] = {0, 0, 0}, mx[3] = {0, 0, 0};
  for (size_t i = 0; i < n; i++) {
    int32_t slot = w->sprouts.data[i].slot;
    double p[3] = {s->x[slot], s->y[slot], s->z[slot]};
    for (int a = 0; a < 3; a++) {
      if (i == 0 || p[a] < mn[a]) mn[a] = p[a];
      if (i == 0 || p[a] > mx[a]) mx[a] = p[a];
    }
  }
  ix->cell = cell > 0.0 ? cell : 1.0;
  for (;;) {
    double cells = 1.0;
    for (int a = 0; a < 3; a++) cells *= floor((mx[a] - mn[a]) / ix->cell) + 1.0;
    if (cells <= (double)(1 << 22)) break;
    ix->cell *= 2.0; /* any cell size is correct; larger only scans more */
  }
  size_t ncells = 1;
  for (int a = 0; a < 3; a++) {
    ix->min[a] = mn[a];
    ix->dims[a] = (int64_t)floor((mx[a] - mn[a]) / ix->cell) + 1;
    ncells *= (size_t)ix->dims[a];
  }
  if (SYLVA__VEC_RESERVE(w->cell_first, ncells + 1) || SYLVA__VEC_RESERVE(w->cell_items, n + 1) ||
      SYLVA__VEC_RESERVE(w->cell_pos, 3 * n + 3) || SYLVA__VEC_RESERVE(w->cell_of, n + 1))
    return SYLVA_ENOMEM;
  int32_t *first = w->cell_first.data, *of = w->cell_of.data;
  /* Counting sort: first[c] counts cell c's items, then (summed) marks the end of
   * cell c; filling each cell from its end, last item first, keeps the items in order
   * and leaves first[c] at the cell's start. */
  for (size_t c = 0; c <= ncells; c++) first[c] = 0;
  for (size_t i = 0; i < n; i++) {
    int32_t slot = w->sprouts.data[i].slot;
    int64_t c = (cell_of(ix, 2, s->z[slot]) * ix->dims[1] + cell_of(ix, 1, s->y[slot])) *
                    ix->dims[0] + cell_of(ix, 0, s->x[slot]);
    of[i] = (int32_t)c;
    first[c]++;
  }
  for (size_t c = 1; c <= ncells; c++) first[c] += first[c - 1];
  for (size_t i = n; i-- > 0;) {
    int32_t at = --first[of[i]];
    int32_t slot = w->sprouts.data[i].slot;
    w->cell_items.data[at] = (int32_t)i;
    w->cell_pos.data[3 * at] = s->x[slot];
    w->cell_pos.data[3 * at + 1] = s->y[slot];
    w->cell_pos.data[3 * at + 2] = s->z[slot];
  }
  return SYLVA_OK;
}

/* True when a sprouting node other than self is closer to p than d2 (squared). */
static bool contested(const sylva_world *w, const index_ctx *ix, const double p[3], double d2,
                      int32_t self) {
  double d = sqrt(d2);
  int64_t lo[3], hi[3];
  for (int a = 0; a < 3; a++) {
    lo[a] = cell_of(ix, a, p[a] - d);
    hi[a] = cell_of(ix, a, p[a] + d);
  }
  const int32_t *first = w->cell_first.data, *items = w->cell_items.data;
  const float *pos = w->cell_pos.data;
  for (int64_t cz = lo[2]; cz <= hi[2]; cz++)
    for (int64_t cy = lo[1]; cy <= hi[1]; cy++) {
      int64_t row = (cz * ix->dims[1] + cy) * ix->dims[0];
      for (int32_t k = first[row + lo[0]]; k < first[row + hi[0] + 1]; k++) {
        double dx = pos[3 * k] - p[0], dy = pos[3 * k + 1] - p[1], dz = pos[3 * k + 2] - p[2];
        if (dx * dx + dy * dy + dz * dz < d2 && items[k] != self) return true;
      }
    }
  return false;
}

/* ---- the shoots' shade on a second thread ----------------------------------------

   With two threads or more, each shoot's shade is stamped on a second thread while
   the next shoots grow (docs/model.md, "Determinism"). The growing thread makes the
   stamp's blocks (so a stamp allocates nothing and cannot fail) and queues it;
   before it reads the shade of a voxel it waits for every queued stamp that writes
   an entry the voxel sums. Every read therefore sees the grid the one-thread order
   gives, and the stamps are exact integer sums: the same world on any number of
   threads.

   The stamps are written one at a time, in their order, by whichever thread holds
   the pen: the stamper while the queue has work, the growing thread when it must
   wait for a stamp (it writes the stamps up to it itself, so a stamper the system
   has not scheduled never stalls the growth). An idle stamper sleeps. */

#define SHADE_QUEUE 128 /* a power of two */
#define SHADE_SPINS 4096

typedef struct shade_queue {
  sylva_world *w;
  sylva__stamp item[SHADE_QUEUE];
  alignas(64) atomic_size_t head; /* stamps queued (the growing thread) */
  atomic_bool closed;             /* no stamp will be queued any more */
  alignas(64) atomic_size_t done; /* stamps written (whoever holds the pen) */
  atomic_bool pen;                /* held while a stamp is written */
  alignas(64) atomic_bool asleep; /* the stamper waits on wake */
  pthread_mutex_t lock;
  pthread_cond_t wake;
  int rc;          /* the growing thread's result */
  double waited; /* seconds the growing thread spent on the stamps */
} shade_queue;

static double clock_of(const sylva_world *w) {
  return w->def.clock ? w->def.clock(w->def.clock_ctx) : 0.0;
}

static void relax(unsigned spins) {
  if (spins % SHADE_SPINS == SHADE_SPINS - 1) sched_yield();
}

/* With the pen: writes the queued stamps while fewer than n are written. Returns
 * false when another thread holds the pen. */
static bool write_stamps(shade_queue *q, size_t n) {
  if (atomic_exchange_explicit(&q->pen, true, memory_order_acquire)) return false;
  size_t done = atomic_load_explicit(&q->done, memory_order_relaxed);
  size_t head = atomic_load_explicit(&q->head, memory_order_acquire);
  for (; done < n && done < head; done++) {
    const sylva__stamp *it = &q->item[done & (SHADE_QUEUE - 1)];
    sylva__grid_stamp_prepared(&q->w->grid, it->v, it->p, +1);
    atomic_store_explicit(&q->done, done + 1, memory_order_release);
  }
  atomic_store_explicit(&q->pen, false, memory_order_release);
  return true;
}

/* The growing thread: returns once at least n stamps (all queued) are written. */
static void queue_wait(shade_queue *q, size_t n) {
  if (atomic_load_explicit(&q->done, memory_order_acquire) >= n) return;
  double t0 = clock_of(q->w);
  for (unsigned spins = 0; atomic_load_explicit(&q->done, memory_order_acquire) < n; spins++)
    if (!write_stamps(q, n)) relax(spins);
  q->waited += clock_of(q->w) - t0;
}

/* Before the shade of voxel v is read: the stamps queued that touch it written. */
static void queue_settle(shade_queue *q, const int v[3]) {
  if (!q) return;
  size_t head = atomic_load_explicit(&q->head, memory_order_relaxed);
  size_t done = atomic_load_explicit(&q->done, memory_order_acquire);
  for (size_t i = head; i-- > done;) {
    const sylva__stamp *it = &q->item[i & (SHADE_QUEUE - 1)];
    if (sylva__grid_stamp_touches(it->v, it->p, v)) {
      queue_wait(q, i + 1);
      return;
    }
  }
}

static void wake_stamper(shade_queue *q) {
  if (!atomic_load(&q->asleep)) return; /* sequentially consistent with the stamper's */
  pthread_mutex_lock(&q->lock);
  pthread_cond_signal(&q->wake);
  pthread_mutex_unlock(&q->lock);
}

/* Queues the shade of a grown node, its blocks made; SYLVA_ENOMEM queues nothing. */
static int queue_push(shade_queue *q, const int v[3], const sylva__pyramid *p) {
  int rc = sylva__grid_stamp_prepare(&q->w->grid, v, p);
  if (rc) return rc;
  size_t head = atomic_load_explicit(&q->head, memory_order_relaxed);
  queue_wait(q, head + 1 > SHADE_QUEUE ? head + 1 - SHADE_QUEUE : 0); /* a free place */
  sylva__stamp *it = &q->item[head & (SHADE_QUEUE - 1)];
  memcpy(it->v, v, sizeof it->v);
  it->p = p;
  atomic_store(&q->head, head + 1);
  wake_stamper(q);
  return SYLVA_OK;
}

/* The growing thread, done: the rest written (by the stamper or itself). */
static void queue_close(shade_queue *q) {
  queue_wait(q, atomic_load_explicit(&q->head, memory_order_relaxed));
  atomic_store(&q->closed, true);
  wake_stamper(q);
}

/* The stamper: writes the queued stamps until the queue is closed. */
static void queue_drain(shade_queue *q) {
  for (unsigned spins = 0;;) {
    size_t done = atomic_load_explicit(&q->done, memory_order_acquire);
    if (done < atomic_load_explicit(&q->head, memory_order_acquire)) {
      if (write_stamps(q, done + 1)) spins = 0;
      continue;
    }
    if (atomic_load_explicit(&q->closed, memory_order_acquire)) return;
    if (++spins < SHADE_SPINS) continue;
    /* idle: sleep until a stamp is queued or the queue closes; asleep is set before
     * head is looked at, and the growing thread sets head before it looks at asleep */
    pthread_mutex_lock(&q->lock);
    atomic_store(&q->asleep, true);
    while (atomic_load(&q->head) == done && !atomic_load(&q->closed))
      pthread_cond_wait(&q->wake, &q->lock);
    atomic_store(&q->asleep, false);
    pthread_mutex_unlock(&q->lock);
    spins = 0;
  }
}

/* ---- one shoot ----------------------------------------------------------------- */

/* Optimal direction Vo = normalise(sum of l_j v_j): unit vectors to the usable marker
 * points, drawn uniformly in the cone (spherical sector) around vd, weighted by their
 * light. */
static void optimal_direction(sylva_world *w, shade_queue *q, const index_ctx *ix,
                              const sylva_species_def *d, int markers, const double tip[3],
                              const double vd[3], int32_t self, double vo[3]) {
  vo[0] = vo[1] = vo[2] = 0.0;
  if (markers <= 0) return;
  double e1[3], e2[3];
  basis(vd, e1, e2);
  double cos_a = cos(d->cone_angle * SYLVA__DEG);
  double len = d->cone_radius * d->rho;
  for (int m = 0; m < markers; m++) {
    double u1 = sylva__rng_unit(&w->rng), u2 = sylva__rng_unit(&w->rng),
           u3 = sylva__rng_unit(&w->rng);
    double c = 1.0 - u1 * (1.0 - cos_a);
    double sn = sqrt(fmax(0.0, 1.0 - c * c));
    double psi = 2.0 * 3.14159265358979323846 * u2;
    double r = len * cbrt(u3);
    double dir[3];
    for (int i = 0; i < 3; i++) dir[i] = c * vd[i] + sn * (cos(psi) * e1[i] + sin(psi) * e2[i]);
    double p[3] = {tip[0] + r * dir[0], tip[1] + r * dir[1], tip[2] + r * dir[2]};
    int v[3];
    if (!sylva__grid_voxel(&w->grid, p[0], p[1], p[2], v)) continue;
    if (w->grid.obstacle_count && sylva__grid_blocked(&w->grid, v)) continue;
    queue_settle(q, v);
    double l = sylva__grid_free_light(&w->grid, v);
    if (l < 0.0) continue; /* occupied */
    if (contested(w, ix, p, r * r, self)) continue;
    for (int i = 0; i < 3; i++) vo[i] += l * dir[i];
  }
  /* only the direction counts: mu weighs it against Vd and Vt whatever the number
   * of markers (docs/model.md, "Shoots") */
  if (!normalize(vo)) vo[0] = vo[1] = vo[2] = 0.0;
}

static int grow_shoot(sylva_world *w, shade_queue *q, const index_ctx *ix, int32_t item,
                      int iteration) {
  const sylva__sprout *sp = &w->sprouts.data[item];
  sylva__skeleton *s = &w->nodes;
  sylva__stem *st = &w->stems[sp->stem];
  const sylva_species_def *d = &w->species[st->species].def;
  int local = sylva__stem_local(st, iteration);
  int markers = d->m0 - local;
  if (markers < d->m_min) markers = d->m_min;
  /* the crown's widest reach for the stem's height (docs/model.md, "Species in years") */
  double reach = INFINITY;
  if (d->crown_max > 0.0) {
    double h = st->stats.height > d->rho ? st->stats.height : d->rho;
    reach = 0.5 * d->crown_max * pow(h, d->crown_max_exp);
  }
  w->shoot.len = 0;
  int32_t tip = sp->slot;
  for (int32_t k = 0; k < sp->n; k++) {
    double vd[3];
    internode_direction(s, tip, vd);
    bool lateral = k == 0 && !sp->apex;
    if (lateral) {
      double axis[3] = {vd[0], vd[1], vd[2]};
      /* successive buds of an axis stand divergence apart */
      int32_t bud = s->depth[tip] / w->species[st->species].bud_every;
      sylva__lateral_direction(axis, d->theta, (double)bud * d->divergence, vd);
    }
    double p0[3] = {s->x[tip], s->y[tip], s->z[tip]};
    double vo[3];
    optimal_direction(w, q, ix, d, markers, p0, vd, item, vo);
    double vu[3];
    for (int i = 0; i < 3; i++) vu[i] = vd[i] + d->mu * vo[i] + d->gamma * d->tropism[i];
    if (!normalize(vu)) memcpy(vu, vd, sizeof vu);
    double p[3] = {p0[0] + d->rho * vu[0], p0[1] + d->rho * vu[1], p0[2] + d->rho * vu[2]};
    double dx = p[0] - st->root[0], dy = p[1] - st->root[1];
    if (dx * dx + dy * dy > reach * reach) break; /* beyond the crown's reach: stops */
    int32_t slot = sylva__add_node(w, tip, lateral, p, sp->stem, iteration);
    if (slot == SYLVA_ENOMEM) return SYLVA_ENOMEM;
    if (slot < 0) break; /* outside, obstacle or another stem's voxel: the shoot stops */
    if (SYLVA__VEC_RESERVE(w->shoot, w->shoot.len + 1)) return SYLVA_ENOMEM;
    w->shoot.data[w->shoot.len++] = slot;
    tip = slot;
  }
  return SYLVA_OK;
}

/* The shade of a node the current iteration grew: its species' pyramid is made. */
static const sylva__pyramid *new_shade(const sylva_world *w, int32_t slot) {
  const sylva__stem *st = &w->stems[w->nodes.stem[slot]];
  return sylva__species_shade_at(&w->species[st->species], w->nodes.birth[slot] - st->born);
}

/* The shoots in the iteration's stem order, each shoot's shade stamped before the
 * next shoot grows (on the stamper's thread when q is not NULL). */
static int grow_all(sylva_world *w, shade_queue *q, const index_ctx *ix, int iteration,
                    double *shade_time) {
  for (size_t o = 0; o < w->order.len; o++) {
    int32_t stem = w->order.data[o];
    for (int32_t i = w->stem_first.data[stem]; i < w->stem_first.data[stem + 1]; i++) {
      int rc = grow_shoot(w, q, ix, i, iteration);
      if (rc) return rc;
      double t0 = q ? 0.0 : clock_of(w);
      for (size_t k = 0; k < w->shoot.len; k++) {
        int32_t slot = w->shoot.data[k];
        int v[3];
        sylva__node_voxel(w, slot, v);
        rc = q ? queue_push(q, v, new_shade(w, slot))
               : sylva__grid_stamp(&w->grid, v, new_shade(w, slot), +1);
        if (rc) return rc;
        w->mark.shaded = (size_t)slot + 1; /* queued: written before the phase returns */
      }
      if (!q) *shade_time += clock_of(w) - t0;
    }
  }
  return SYLVA_OK;
}

typedef struct pipeline {
  shade_queue *q;
  const index_ctx *ix;
  int iteration;
} pipeline;

/* The pool's two pieces: 0 grows the shoots, 1 stamps their shade. Whichever thread
 * takes a piece, the other piece runs beside it or after it: the growing thread
 * waits only for stamps already queued, and the stamper only for the queue. */
static void grow_or_stamp(void *ctx, size_t begin, size_t end) {
  pipeline *pl = ctx;
  for (size_t k = begin; k < end; k++) {
    if (k == 1) {
      queue_drain(pl->q);
      continue;
    }
    double unused = 0.0;
    pl->q->rc = grow_all(pl->q->w, pl->q, pl->ix, pl->iteration, &unused);
    queue_close(pl->q);
  }
}

int sylva__shoots(sylva_world *w, int iteration) {
  index_ctx ix;
  int rc = build_index(w, &ix);
  if (rc) return rc;
  if (SYLVA__VEC_RESERVE(w->order, (size_t)w->stem_count + 1)) return SYLVA_ENOMEM;
  /* the pyramids of this iteration's nodes, made before any shoot grows */
  for (int k = 0; k < w->stem_count; k++) {
    const sylva__stem *st = &w->stems[k];
    rc = sylva__species_shade_reserve(&w->species[st->species], iteration - st->born);
    if (rc) return rc;
  }
  sylva__rng_permutation(&w->rng, w->order.data, w->stem_count);
  w->order.len = (size_t)w->stem_count;
  double shade_time = 0.0;
  if (sylva__pool_threads(w->pool) < 2) {
    rc = grow_all(w, NULL, &ix, iteration, &shade_time);
  } else {
    shade_queue queue, *q = &queue;
    q->w = w;
    atomic_init(&q->head, 0);
    atomic_init(&q->done, 0);
    atomic_init(&q->closed, false);
    atomic_init(&q->pen, false);
    atomic_init(&q->asleep, false);
    pthread_mutex_init(&q->lock, NULL);
    pthread_cond_init(&q->wake, NULL);
    q->rc = SYLVA_OK;
    q->waited = 0.0;
    pipeline pl = {q, &ix, iteration};
    sylva__pool_for(w->pool, 2, 1, grow_or_stamp, &pl);
    rc = q->rc;
    shade_time = q->waited; /* the shade's share of the phase: the shoots' waits */
    pthread_cond_destroy(&q->wake);
    pthread_mutex_destroy(&q->lock);
  }
  w->journal.phase_seconds[SYLVA_PHASE_SHADE] = shade_time;
  return rc;
}
