#include "files.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "server_error.h"
#include "sylva/status.h"

int files_read(const char *path, size_t max, char **data, size_t *len) {
  *data = NULL;
  *len = 0;
  FILE *f = fopen(path, "rb");
  if (!f) return errno;
  struct stat st;
  if (fstat(fileno(f), &st) != 0) {
    int e = errno;
    fclose(f);
    return e;
  }
  if (S_ISDIR(st.st_mode)) {
    fclose(f);
    return EISDIR;
  }
  /* The size from fstat is only a hint (pipes, growing files): read to the end. */
  size_t cap = S_ISREG(st.st_mode) && (size_t)st.st_size < max ? (size_t)st.st_size + 1 : 65536;
  size_t n = 0;
  char *buf = malloc(cap + 1);
  int rc = buf ? 0 : ENOMEM;
  while (!rc) {
    if (n == cap) {
      if (cap > max) {
        rc = EFBIG;
        break;
      }
      size_t bigger = cap * 2 > max + 1 ? max + 1 : cap * 2;
      char *grown = realloc(buf, bigger + 1);
      if (!grown) {
        rc = ENOMEM;
        break;
      }
      buf = grown;
      cap = bigger;
    }
    size_t got = fread(buf + n, 1, cap - n, f);
    n += got;
    if (got == 0) {
      if (ferror(f)) rc = errno ? errno : EIO;
      break;
    }
  }
  fclose(f);
  if (!rc && n > max) rc = EFBIG;
  if (rc) {
    free(buf);
    return rc;
  }
  buf[n] = '\0';
  *data = buf;
  *len = n;
  return 0;
}

int files_load_scenario(const char *path, unsigned flags, sylva_scenario **out, char *err,
                        size_t errlen) {
  *out = NULL;
  char *text;
  size_t len;
  int e = files_read(path, FILES_MAX_INPUT, &text, &len);
  if (e == EFBIG) {
    snprintf(err, errlen, "%s: larger than %u MiB", path, FILES_MAX_INPUT >> 20);
    return SERVER_EINPUT;
  }
  if (e) {
    snprintf(err, errlen, "%s: %s", path, strerror(e));
    return e == ENOMEM ? SERVER_ENOMEM : SERVER_EINPUT;
  }
  char why[1024];
  int rc = sylva_scenario_parse_ex(text, len, flags, out, why, sizeof why);
  free(text);
  if (rc < 0) {
    snprintf(err, errlen, "%s: %s", path, why);
    return rc == SYLVA_ENOMEM ? SERVER_ENOMEM : SERVER_EINPUT;
  }
  return SERVER_OK;
}

int files_build_world(const char *path, const sylva_scenario *s, sylva_world **out, char *err,
                      size_t errlen) {
  char why[1024];
  int rc = sylva_scenario_build(s, out, why, sizeof why);
  if (rc < 0) {
    snprintf(err, errlen, "%s: %s", path, why);
    return rc == SYLVA_ENOMEM ? SERVER_ENOMEM : SERVER_EINPUT;
  }
  return SERVER_OK;
}
