/* The Slurm array script of a sweep, and its submission. */
/* realpath (X/Open) */
#define _XOPEN_SOURCE 700
#include "slurm.h"

#include <errno.h>
#include <limits.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

/* Writes s single-quoted for sh: 'it'\''s'. */
static void put_quoted(FILE *f, const char *s) {
  fputc('\'', f);
  for (; *s; s++) {
    if (*s == '\'') fputs("'\\''", f);
    else fputc(*s, f);
  }
  fputc('\'', f);
}

static char *absolute(const char *path) {
  char *r = realpath(path, NULL);
  return r;
}

int slurm_write_script(const slurm_script *s, char **path, char *err, size_t errlen) {
  *path = NULL;
  if (mkdir(s->dir, 0777) && errno != EEXIST) {
    snprintf(err, errlen, "--slurm %s: %s", s->dir, strerror(errno));
    return -1;
  }
  char *dir = absolute(s->dir), *exe = absolute(s->exe), *plan = absolute(s->plan);
  int rc = -1;
  if (!dir || !exe || !plan) {
    snprintf(err, errlen, "%s: %s", !dir ? s->dir : !exe ? s->exe : s->plan, strerror(errno));
    goto done;
  }
  size_t n = strlen(dir) + sizeof SLURM_SCRIPT + 2;
  *path = malloc(n);
  if (!*path) {
    snprintf(err, errlen, "out of memory");
    goto done;
  }
  snprintf(*path, n, "%s/%s", dir, SLURM_SCRIPT);
  char tmp[PATH_MAX + 8];
  snprintf(tmp, sizeof tmp, "%s.tmp", *path);
  FILE *f = fopen(tmp, "w");
  if (!f) {
    snprintf(err, errlen, "%s: %s", tmp, strerror(errno));
    goto done;
  }
  fprintf(f,
          "#!/bin/sh\n"
          "# Written by `sylva sweep --slurm`: the plan's %d runs as %d array tasks.\n"
          "# Task K grows the runs at positions K, K + %d, ... of the plan into its own\n"
          "# store, task-K.db in this folder. Merge them afterwards with\n"
          "#   sylva sweep PLAN --merge DIR --db OUT.db\n"
          "#SBATCH --job-name=sylva-sweep\n"
          "#SBATCH --array=0-%d\n"
          "#SBATCH --cpus-per-task=%d\n"
          "#SBATCH --output=\"%s/task-%%a.log\"\n" /* sbatch takes the quotes off */
          "exec ",
          s->runs, s->tasks, s->tasks, s->tasks - 1, s->jobs * s->threads, dir);
  put_quoted(f, exe);
  fputs(" sweep ", f);
  put_quoted(f, plan);
  fprintf(f, " --task \"$SLURM_ARRAY_TASK_ID\" --tasks %d --jobs %d --threads %d%s"
             " --quiet-progress \\\n  --db ", s->tasks, s->jobs, s->threads,
             s->force ? " --force" : "");
  put_quoted(f, dir);
  fputs("\"/task-$SLURM_ARRAY_TASK_ID.db\"\n", f);
  bool ok = !ferror(f);
  ok = fclose(f) == 0 && ok;
  if (!ok || chmod(tmp, 0755) || rename(tmp, *path)) {
    snprintf(err, errlen, "%s: %s", *path, strerror(errno));
    unlink(tmp);
    goto done;
  }
  rc = 0;
done:
  if (rc) {
    free(*path);
    *path = NULL;
  }
  free(dir);
  free(exe);
  free(plan);
  return rc;
}

int slurm_script_tasks(const char *dir, int *tasks, char *err, size_t errlen) {
  char path[PATH_MAX];
  snprintf(path, sizeof path, "%s/%s", dir, SLURM_SCRIPT);
  FILE *f = fopen(path, "r");
  if (!f) {
    snprintf(err, errlen, "%s: %s (write it with sylva sweep PLAN --slurm %s)", path,
             strerror(errno), dir);
    return -1;
  }
  char line[512];
  int last = -1;
  while (fgets(line, sizeof line, f))
    if (sscanf(line, "#SBATCH --array=0-%d", &last) == 1) break;
  fclose(f);
  if (last < 0) {
    snprintf(err, errlen, "%s: no #SBATCH --array=0-N line (not written by sylva sweep)", path);
    return -1;
  }
  *tasks = last + 1;
  return 0;
}

char *slurm_task_store(const char *dir, int k) {
  size_t n = strlen(dir) + 32;
  char *p = malloc(n);
  if (p) snprintf(p, n, "%s/task-%d.db", dir, k);
  return p;
}

int slurm_submit(const char *script, char *jobid, size_t idlen, char *err, size_t errlen) {
  int out[2];
  if (pipe(out)) {
    snprintf(err, errlen, "sbatch: %s", strerror(errno));
    return -1;
  }
  fflush(NULL);
  pid_t pid = fork();
  if (pid < 0) {
    snprintf(err, errlen, "sbatch: %s", strerror(errno));
    close(out[0]);
    close(out[1]);
    return -1;
  }
  if (pid == 0) {
    dup2(out[1], STDOUT_FILENO);
    close(out[0]);
    close(out[1]);
    execlp("sbatch", "sbatch", "--parsable", script, (char *)NULL);
    fprintf(stderr, "sylva: sbatch: %s (is Slurm installed, and sbatch on the PATH?)\n",
            strerror(errno));
    _exit(127);
  }
  close(out[1]);
  size_t len = 0;
  ssize_t got;
  while ((got = read(out[0], jobid + len, idlen - 1 - len)) > 0 && len + 1 < idlen)
    len += (size_t)got;
  close(out[0]);
  jobid[len] = '\0';
  int status;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  /* --parsable prints "jobid" or "jobid;cluster" */
  jobid[strcspn(jobid, ";\n")] = '\0';
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !jobid[0]) {
    snprintf(err, errlen, "sbatch %s failed (status %d)", script,
             WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    return -1;
  }
  return 0;
}
