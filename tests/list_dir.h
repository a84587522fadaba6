/* Test helper: the names of a directory's entries that keep() accepts, sorted
 * with strcmp, so that every suite reads its input files in one fixed order. */
#ifndef SYLVA_TEST_LIST_DIR_H
#define SYLVA_TEST_LIST_DIR_H

#include <dirent.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

static inline void list_dir_free(char **names, size_t count) {
  for (size_t i = 0; i < count; i++) free(names[i]);
  free(names);
}

static inline int list_dir_cmp(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Names ending in ".json". */
static inline bool list_dir_json(const char *name) {
  size_t n = strlen(name);
  return n > 5 && strcmp(name + n - 5, ".json") == 0;
}

/* A malloc'd array of *count malloc'd names (list_dir_free() frees them); NULL,
 * *count 0, when dir cannot be opened or memory runs out. */
static inline char **list_dir(const char *dir, bool (*keep)(const char *name), size_t *count) {
  *count = 0;
  DIR *d = opendir(dir);
  if (!d) return NULL;
  size_t n = 0, cap = 16;
  char **names = malloc(cap * sizeof *names);
  for (struct dirent *e; names && (e = readdir(d));) {
    if (!keep(e->d_name)) continue;
    if (n == cap) {
      char **bigger = realloc(names, 2 * cap * sizeof *names);
      if (!bigger) {
        list_dir_free(names, n);
        names = NULL;
        break;
      }
      names = bigger;
      cap *= 2;
    }
    if (!(names[n] = strdup(e->d_name))) {
      list_dir_free(names, n);
      names = NULL;
      break;
    }
    n++;
  }
  closedir(d);
  if (!names) return NULL;
  qsort(names, n, sizeof *names, list_dir_cmp);
  *count = n;
  return names;
}

#endif
