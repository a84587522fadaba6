/* The world's threads (pool.h): workers sleep on a condition variable until a loop
 * is posted, take pieces of it by an atomic counter, and the last one done wakes
 * the caller. A loop posted while another runs (worlds that share the pool, grown
 * on different threads) runs on its caller alone. */
#include "pool.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "alloc.h"
#include "sylva/status.h"

struct sylva__pool {
  int workers;
  pthread_t *tid;
  pthread_mutex_t lock;
  pthread_cond_t wake, done;
  uint64_t generation; /* one more for every loop posted (lock) */
  int busy;            /* workers still in the posted loop (lock) */
  bool stop;           /* lock */
  bool running;        /* a loop is posted and not yet done (lock) */
  /* the posted loop: written before generation moves, read after */
  sylva__range_fn fn;
  void *ctx;
  size_t n, grain;
  atomic_size_t next; /* the first index not taken yet */
};

static void run_pieces(sylva__pool *p) {
  for (;;) {
    size_t b = atomic_fetch_add_explicit(&p->next, p->grain, memory_order_relaxed);
    if (b >= p->n) return;
    size_t e = p->n - b < p->grain ? p->n : b + p->grain;
    p->fn(p->ctx, b, e);
  }
}

static void *worker(void *arg) {
  sylva__pool *p = arg;
  uint64_t seen = 0;
  for (;;) {
    pthread_mutex_lock(&p->lock);
    while (!p->stop && p->generation == seen) pthread_cond_wait(&p->wake, &p->lock);
    if (p->stop) {
      pthread_mutex_unlock(&p->lock);
      return NULL;
    }
    seen = p->generation;
    pthread_mutex_unlock(&p->lock);
    run_pieces(p);
    pthread_mutex_lock(&p->lock);
    if (--p->busy == 0) pthread_cond_signal(&p->done);
    pthread_mutex_unlock(&p->lock);
  }
}

static void stop_workers(sylva__pool *p, int started) {
  pthread_mutex_lock(&p->lock);
  p->stop = true;
  pthread_cond_broadcast(&p->wake);
  pthread_mutex_unlock(&p->lock);
  for (int i = 0; i < started; i++) pthread_join(p->tid[i], NULL);
}

int sylva__pool_create(int threads, sylva__pool **out) {
  *out = NULL;
  if (threads <= 1) return SYLVA_OK;
  sylva__pool *p = sylva__calloc(1, sizeof *p);
  if (!p) return SYLVA_ENOMEM;
  p->tid = sylva__calloc((size_t)threads - 1, sizeof *p->tid);
  if (!p->tid || pthread_mutex_init(&p->lock, NULL)) {
    sylva__free(p->tid);
    sylva__free(p);
    return SYLVA_ENOMEM;
  }
  pthread_cond_init(&p->wake, NULL);
  pthread_cond_init(&p->done, NULL);
  atomic_init(&p->next, 0);
  int started = 0;
  while (started < threads - 1 && pthread_create(&p->tid[started], NULL, worker, p) == 0) started++;
  if (started < threads - 1) { /* the system's limit: one thread, as without a pool */
    stop_workers(p, started);
    p->workers = 0;
    sylva__pool_destroy(p);
    return SYLVA_ENOMEM;
  }
  p->workers = started;
  *out = p;
  return SYLVA_OK;
}

void sylva__pool_destroy(sylva__pool *p) {
  if (!p) return;
  if (p->workers) stop_workers(p, p->workers);
  pthread_cond_destroy(&p->wake);
  pthread_cond_destroy(&p->done);
  pthread_mutex_destroy(&p->lock);
  sylva__free(p->tid);
  sylva__free(p);
}

int sylva__pool_threads(const sylva__pool *p) { return p ? p->workers + 1 : 1; }

void sylva__pool_for(sylva__pool *p, size_t n, size_t grain, sylva__range_fn fn, void *ctx) {
  if (grain == 0) grain = 1;
  if (!p || n <= grain) {
    if (n) fn(ctx, 0, n);
    return;
  }
  pthread_mutex_lock(&p->lock);
  if (p->running) { /* another world's loop: this one on its caller, the same results */
    pthread_mutex_unlock(&p->lock);
    fn(ctx, 0, n);
    return;
  }
  p->running = true;
  p->fn = fn;
  p->ctx = ctx;
  p->n = n;
  p->grain = grain;
  atomic_store_explicit(&p->next, 0, memory_order_relaxed);
  p->busy = p->workers;
  p->generation++;
  pthread_cond_broadcast(&p->wake);
  pthread_mutex_unlock(&p->lock);
  run_pieces(p);
  pthread_mutex_lock(&p->lock);
  while (p->busy) pthread_cond_wait(&p->done, &p->lock);
  p->running = false;
  pthread_mutex_unlock(&p->lock);
}
