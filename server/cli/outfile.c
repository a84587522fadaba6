#include "outfile.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "options.h"

int cli_outfile_open(cli_outfile *o, const char *option, const char *path, bool allow_stdout) {
  *o = (cli_outfile){.path = path, .tmp = NULL, .f = stdout};
  if (allow_stdout && strcmp(path, "-") == 0) return CLI_EXIT_OK;
  size_t n = strlen(path) + 5;
  if (!(o->tmp = malloc(n))) {
    o->f = NULL;
    fprintf(stderr, "sylva: out of memory\n");
    return CLI_EXIT_FAILURE;
  }
  snprintf(o->tmp, n, "%s.tmp", path);
  if (!(o->f = fopen(o->tmp, "wb"))) {
    fprintf(stderr, "sylva: %s: cannot create %s: %s\n", option, o->tmp, strerror(errno));
    free(o->tmp);
    o->tmp = NULL;
    return CLI_EXIT_USAGE;
  }
  return CLI_EXIT_OK;
}

/* Prints why writing path failed (errno, or EIO when it was not set). */
static int write_failed(const char *path) {
  fprintf(stderr, "sylva: %s: %s\n", path, strerror(errno ? errno : EIO));
  return CLI_EXIT_FAILURE;
}

int cli_outfile_close(cli_outfile *o, int rc) {
  if (!o->f) return rc;
  if (rc == CLI_EXIT_OK && (ferror(o->f) || fflush(o->f) != 0)) rc = write_failed(o->path);
  if (o->tmp) {
    if (fclose(o->f) != 0 && rc == CLI_EXIT_OK) rc = write_failed(o->path);
    if (rc == CLI_EXIT_OK && rename(o->tmp, o->path) != 0) rc = write_failed(o->path);
    if (rc != CLI_EXIT_OK) remove(o->tmp);
    free(o->tmp);
    o->tmp = NULL;
  }
  o->f = NULL;
  return rc;
}
