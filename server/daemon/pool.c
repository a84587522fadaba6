/* syscall(SYS_gettid): a thread's own niceness */
#define _DEFAULT_SOURCE
#include "pool.h"

#include <errno.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

void pool_thread_nice(int steps) {
  /* below the main thread, the loop's, which nothing renices (PRIO_PROCESS with the
   * process id reads the main thread's own on Linux) */
  errno = 0;
  int base = getpriority(PRIO_PROCESS, (id_t)getpid());
  if (base == -1 && errno) return;
  int nice = base + steps > 19 ? 19 : base + steps;
  (void)setpriority(PRIO_PROCESS, (id_t)syscall(SYS_gettid), nice);
}

typedef struct world_threads_start {
  int count, nice;
  sylva_threads *made;
} world_threads_start;

static void *start_world_threads(void *arg) {
  world_threads_start *s = arg;
  pool_thread_nice(s->nice);
  if (sylva_threads_create(s->count, &s->made)) s->made = NULL;
  return NULL;
}

sylva_threads *pool_world_threads(int count, int nice) {
  world_threads_start s = {count < 1 ? 1 : count, nice, NULL};
  pthread_t starter;
  if (pthread_create(&starter, NULL, start_world_threads, &s)) return NULL;
  pthread_join(starter, NULL);
  return s.made;
}

static void *worker(void *arg) {
  pool *p = arg;
  pool_thread_nice(p->nice);
  pthread_mutex_lock(&p->lock);
  for (;;) {
    while (!p->queue && !p->stopping) pthread_cond_wait(&p->wake, &p->lock);
    if (!p->queue) break; /* stopping, nothing left */
    pool_task *t = p->queue;
    p->queue = t->next;
    if (!p->queue) p->queue_tail = NULL;
    p->running++;
    pthread_mutex_unlock(&p->lock);
    t->work(t);
    pthread_mutex_lock(&p->lock);
    p->running--;
    t->next = p->finished;
    p->finished = t;
    uv_async_send(&p->async);
  }
  pthread_mutex_unlock(&p->lock);
  return NULL;
}

void pool_report(pool *p, pool_task *t) {
  pthread_mutex_lock(&p->lock);
  if (!t->reported) {
    t->reported = true;
    t->next_report = p->reports;
    p->reports = t;
  }
  uv_async_send(&p->async);
  pthread_mutex_unlock(&p->lock);
}

/* Loop thread: the progress of running tasks, then the finished tasks, oldest
 * first. */
static void on_async(uv_async_t *a) {
  pool *p = a->data;
  for (;;) { /* one at a time: a worker may report its task again meanwhile */
    pthread_mutex_lock(&p->lock);
    pool_task *t = p->reports;
    if (t) {
      p->reports = t->next_report;
      t->reported = false;
    }
    pthread_mutex_unlock(&p->lock);
    if (!t) break;
    t->progress(t);
  }
  pthread_mutex_lock(&p->lock);
  pool_task *list = p->finished;
  p->finished = NULL;
  pthread_mutex_unlock(&p->lock);
  pool_task *ordered = NULL;
  while (list) { /* the list is newest first */
    pool_task *next = list->next;
    list->next = ordered;
    ordered = list;
    list = next;
  }
  while (ordered) {
    pool_task *next = ordered->next;
    ordered->done(ordered, false);
    ordered = next;
  }
}

int pool_init(pool *p, uv_loop_t *loop, int count, int nice) {
  *p = (pool){.count = 0, .nice = nice};
  if (pthread_mutex_init(&p->lock, NULL)) return -ENOMEM;
  if (pthread_cond_init(&p->wake, NULL)) {
    pthread_mutex_destroy(&p->lock);
    return -ENOMEM;
  }
  int rc = uv_async_init(loop, &p->async, on_async);
  if (rc) {
    pthread_cond_destroy(&p->wake);
    pthread_mutex_destroy(&p->lock);
    return rc;
  }
  p->async.data = p;
  p->threads = calloc((size_t)count, sizeof *p->threads);
  if (!p->threads) rc = -ENOMEM;
  for (int i = 0; !rc && i < count; i++) {
    if (pthread_create(&p->threads[i], NULL, worker, p)) rc = -EAGAIN;
    else p->count++;
  }
  if (rc) { /* the workers that started end at once; the handle closes */
    pool_stop(p);
    pool_close(p);
  }
  return rc;
}

void pool_submit(pool *p, pool_task *t) {
  t->next = NULL;
  pthread_mutex_lock(&p->lock);
  if (p->queue_tail) p->queue_tail->next = t;
  else p->queue = t;
  p->queue_tail = t;
  pthread_cond_signal(&p->wake);
  pthread_mutex_unlock(&p->lock);
}

void pool_stop(pool *p) {
  pthread_mutex_lock(&p->lock);
  pool_task *dropped = p->queue;
  p->queue = p->queue_tail = NULL;
  p->stopping = true;
  pthread_cond_broadcast(&p->wake);
  pthread_mutex_unlock(&p->lock);
  while (dropped) {
    pool_task *next = dropped->next;
    dropped->done(dropped, true);
    dropped = next;
  }
}

bool pool_idle(pool *p) {
  pthread_mutex_lock(&p->lock);
  bool idle = !p->running && !p->queue && !p->finished && !p->reports;
  pthread_mutex_unlock(&p->lock);
  return idle;
}

void pool_close(pool *p) {
  for (int i = 0; i < p->count; i++) pthread_join(p->threads[i], NULL);
  free(p->threads);
  p->threads = NULL;
  uv_close((uv_handle_t *)&p->async, NULL);
  pthread_cond_destroy(&p->wake);
  pthread_mutex_destroy(&p->lock);
}
