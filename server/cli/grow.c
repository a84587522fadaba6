#include "grow.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "options.h"
#include "sylva/encode.h"
#include "sylva/status.h"

static double now_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

/* Progress on stderr; `width` remembers what to clear. */
typedef struct progress {
  bool enabled;
  int width;
} progress;

static void progress_show(progress *pr, int iteration, int limit, size_t nodes) {
  if (!pr->enabled) return;
  int n = fprintf(stderr, "\r iteration %d/%d  nodes %zu", iteration, limit, nodes);
  if (n > 0 && n - 1 < pr->width) fprintf(stderr, "%*s", pr->width - (n - 1), "");
  if (n > 0 && n - 1 > pr->width) pr->width = n - 1;
  fflush(stderr);
}

static void progress_clear(progress *pr) {
  if (!pr->enabled || pr->width == 0) return;
  fprintf(stderr, "\r%*s\r", pr->width + 1, "");
  fflush(stderr);
  pr->width = 0;
}

bool grow_put_line(const char *line) {
  if (fputs(line, stdout) == EOF || fputc('\n', stdout) == EOF) return false;
  return fflush(stdout) == 0;
}

void grow_set_threads(sylva_world *w, int threads) {
  if (sylva_world_set_threads(w, threads))
    fprintf(stderr, "sylva: warning: cannot start %d threads; growing on one (the same "
                    "world)\n", threads);
}

int grow_run(grow_job *job) {
  sylva_world *w = job->w;
  if (job->threads > 0) grow_set_threads(w, job->threads);
  progress pr = {.enabled = job->progress, .width = 0};
  int rc = CLI_EXIT_OK;
  job->reason = NULL;
  while (!job->reason) {
    if (sylva_world_finished(w)) {
      job->reason = "finished";
      break;
    }
    if (sylva_world_iteration(w) >= job->limit) {
      job->reason = "limit";
      break;
    }
    const sylva_journal *j;
    double t0 = now_ms();
    int status = sylva_world_step(w, &j);
    double elapsed = now_ms() - t0;
    if (status < 0) {
      progress_clear(&pr);
      fprintf(stderr, "sylva: %s: iteration %d: %s\n", job->label, sylva_world_iteration(w) + 1,
              sylva_strerror(status));
      rc = CLI_EXIT_FAILURE;
      break;
    }
    if (job->st) {
      int it = j->iteration;
      if (store_save_step(job->st, job->run, w, j, job->snapshot_every, job->limit)) {
        progress_clear(&pr);
        fprintf(stderr, "sylva: %s\n", store_error(job->st));
        fprintf(stderr, "sylva: %s: stopped after iteration %d; what was stored before is "
                "intact ('sylva resume' continues)\n", job->label, it - 1);
        rc = CLI_EXIT_FAILURE;
        break;
      }
    }
    if (!job->silent) {
      char *line = sylva_encode_stats_line(w, j, elapsed, job->start_year);
      bool nomem = !line, ok = line && grow_put_line(line);
      free(line);
      if (!ok) {
        progress_clear(&pr);
        fprintf(stderr, "sylva: %s\n", nomem ? "out of memory" : "cannot write to stdout");
        rc = CLI_EXIT_FAILURE;
        break;
      }
    }
    progress_show(&pr, sylva_world_iteration(w), job->limit, sylva_world_node_count(w));
  }
  progress_clear(&pr);
  if (job->st) {
    /* best effort: after a failure of the disk this may fail too, and the run can
     * still be resumed from what was stored */
    if (rc == CLI_EXIT_OK)
      rc = store_set_status(job->st, job->run, SYLVA_RUN_FINISHED, job->reason, 0) ? CLI_EXIT_FAILURE : rc;
    else
      store_set_status(job->st, job->run, SYLVA_RUN_FAILED, NULL, 0);
    if (rc != CLI_EXIT_OK && job->reason) fprintf(stderr, "sylva: %s\n", store_error(job->st));
  }
  if (rc == CLI_EXIT_OK && !job->silent) {
    char *done = sylva_encode_done_line(sylva_world_iteration(w), job->reason);
    if (!done || !grow_put_line(done)) {
      fprintf(stderr, "sylva: %s\n", done ? "cannot write to stdout" : "out of memory");
      rc = CLI_EXIT_FAILURE;
    }
    free(done);
  } else if (rc != CLI_EXIT_OK) {
    job->reason = NULL;
  }
  return rc;
}
