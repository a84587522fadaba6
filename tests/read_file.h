/* Test helper: reads a whole file into a malloc'd, NUL-terminated buffer (*len
 * without the NUL); NULL when it cannot be opened or memory runs out. */
#ifndef SYLVA_TEST_READ_FILE_H
#define SYLVA_TEST_READ_FILE_H

#include <stdio.h>
#include <stdlib.h>

static char *read_file(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  size_t cap = 4096, n = 0;
  char *data = malloc(cap);
  while (data) {
    n += fread(data + n, 1, cap - 1 - n, f);
    if (n < cap - 1) break;
    char *bigger = realloc(data, cap * 2);
    if (!bigger) {
      free(data);
      data = NULL;
      break;
    }
    data = bigger;
    cap *= 2;
  }
  fclose(f);
  if (!data) return NULL;
  data[n] = 0;
  *len = n;
  return data;
}
#endif
