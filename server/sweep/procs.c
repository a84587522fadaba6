/* The pool of worker processes: fork per job, waitpid for the first to end, and the parent's
 * death signal so that no child outlives a killed pool. */
#include "procs.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static double now_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct worker {
  pid_t pid;
  int job;
  double since;
} worker;

int pool_run(const pool_def *def) {
  int n = def->workers > 0 ? def->workers : 1;
  worker *w = calloc((size_t)n, sizeof *w);
  if (!w) return -1;
  pid_t parent = getpid();
  int next = 0, running = 0, failed = 0, err = 0;
  fflush(NULL); /* a child must not write the parent's buffered output again */
  while (next < def->count || running > 0) {
    while (next < def->count && running < n) {
      int slot = 0;
      while (w[slot].pid) slot++;
      pid_t pid = fork();
      if (pid < 0) {
        err = errno;
        if (running == 0) {
          free(w);
          errno = err;
          return -1;
        }
        break; /* go on with the workers there are */
      }
      if (pid == 0) {
        /* dies with the parent; and the parent may have died before prctl */
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent) _exit(127);
        free(w); /* the parent's bookkeeping: a leak at the child's exit otherwise */
        int status = def->job(next, def->ctx);
        fflush(NULL);
        _exit(status & 0xff);
      }
      w[slot] = (worker){.pid = pid, .job = next, .since = now_seconds()};
      if (def->started) def->started(next, def->ctx);
      next++;
      running++;
    }
    int status;
    pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int slot = 0; slot < n; slot++) {
      if (w[slot].pid != pid) continue;
      int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      if (code) failed++;
      running--;
      w[slot].pid = 0;
      if (def->done) def->done(w[slot].job, code, now_seconds() - w[slot].since, def->ctx);
      break;
    }
  }
  free(w);
  return failed;
}
