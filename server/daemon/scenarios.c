#include "scenarios.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "files.h"
#include "sylva/protocol.h"
#include "sylva/scenario.h"

bool scenarios_name_ok(const char *name) {
  size_t n = strlen(name);
  if (n == 0 || n > SCENARIOS_MAX_NAME || name[0] == '.') return false;
  for (const char *c = name; *c; c++)
    if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
          *c == '_' || *c == '-' || *c == '.'))
      return false;
  return true;
}

bool scenarios_path(const char *dir, const char *name, char *path, size_t size) {
  if (!scenarios_name_ok(name)) return false;
  int n = snprintf(path, size, "%s/%s.json", dir, name);
  return n > 0 && (size_t)n < size;
}

/* One listing: asked on the loop, built on a worker, answered on the loop. */
typedef struct list_job {
  uv_work_t work;
  client_set *clients;
  uint64_t client;
  char *dir, *ref;
  char *text; /* the message (malloc'd), NULL when memory ran out */
} list_job;

typedef struct entry {
  char *name, *title;
} entry;

static int by_name(const void *a, const void *b) {
  return strcmp(((const entry *)a)->name, ((const entry *)b)->name);
}

/* The title of dir/name.json, or NULL when it is not a scenario sylva serves. */
static char *read_title(const char *dir, const char *name) {
  char path[4096];
  if (!scenarios_path(dir, name, path, sizeof path)) return NULL;
  char *data = NULL, err[256];
  size_t len = 0;
  if (files_read(path, SCENARIOS_MAX_FILE, &data, &len)) return NULL;
  sylva_scenario *s = NULL;
  char *title = NULL;
  if (sylva_scenario_parse(data, len, &s, err, sizeof err) == 0) title = strdup(s->name);
  sylva_scenario_free(s);
  free(data);
  return title;
}

static void list_work(uv_work_t *req) {
  list_job *j = req->data;
  entry *found = calloc(SCENARIOS_MAX_LISTED, sizeof *found);
  size_t n = 0;
  DIR *dh = found && j->dir ? opendir(j->dir) : NULL;
  struct dirent *e;
  while (dh && n < SCENARIOS_MAX_LISTED && (e = readdir(dh))) {
    size_t len = strlen(e->d_name);
    if (len < 6 || strcmp(e->d_name + len - 5, ".json") != 0) continue;
    char *name = strndup(e->d_name, len - 5);
    char *title = name ? read_title(j->dir, name) : NULL;
    if (!title) {
      free(name);
      continue;
    }
    found[n++] = (entry){name, title};
  }
  if (dh) closedir(dh);
  if (n) qsort(found, n, sizeof *found, by_name);
  const char *names[SCENARIOS_MAX_LISTED], *titles[SCENARIOS_MAX_LISTED];
  for (size_t i = 0; i < n; i++) {
    names[i] = found[i].name;
    titles[i] = found[i].title;
  }
  j->text = found ? sylva_msg_scenarios(names, titles, n, j->ref) : NULL;
  for (size_t i = 0; i < n; i++) {
    free(found[i].name);
    free(found[i].title);
  }
  free(found);
}

static void list_done(uv_work_t *req, int status) {
  (void)status;
  list_job *j = req->data;
  client *c = client_find(j->clients, j->client);
  if (c)
    client_send_text(c, j->text); /* takes it; NULL sends an out-of-memory error */
  else
    free(j->text);
  free(j->dir);
  free(j->ref);
  free(j);
}

void scenarios_list(uv_loop_t *loop, client_set *clients, client *c, const char *dir,
                    const char *ref) {
  list_job *j = calloc(1, sizeof *j);
  if (!j || (dir && !(j->dir = strdup(dir))) || (ref && !(j->ref = strdup(ref)))) {
    if (j) free(j->dir);
    free(j);
    client_send_text(c, NULL);
    return;
  }
  j->clients = clients;
  j->client = c->serial;
  j->work.data = j;
  if (uv_queue_work(loop, &j->work, list_work, list_done) != 0) {
    free(j->dir);
    free(j->ref);
    free(j);
    client_send_text(c, NULL);
  }
}
