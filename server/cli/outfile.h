/* sylva server: output files of the command line, written whole or not at all:
 * the data goes to PATH.tmp, which is renamed over PATH once everything was
 * written, and removed otherwise. */
#ifndef SYLVA_SERVER_OUTFILE_H
#define SYLVA_SERVER_OUTFILE_H

#include <stdbool.h>
#include <stdio.h>

/** An output file being written. */
typedef struct cli_outfile {
  const char *path; /**< as given */
  char *tmp;        /**< PATH.tmp; NULL when writing to stdout */
  FILE *f;          /**< where to write */
} cli_outfile;

/** Creates PATH.tmp for writing; with allow_stdout, "-" means stdout. On failure
 *  prints "sylva: OPTION: cannot create PATH.tmp: reason" (option names the
 *  command's option, e.g. "-o") and returns the exit status (2; 1 when out of
 *  memory); 0 otherwise. */
int cli_outfile_open(cli_outfile *o, const char *option, const char *path, bool allow_stdout);

/** Ends the file with the command's status so far, rc: when rc is 0, flushes it,
 *  closes it and renames PATH.tmp over PATH; otherwise (or when that fails)
 *  removes PATH.tmp. A failure to write prints "sylva: PATH: reason". Returns the
 *  final exit status (rc, or 1 when writing failed). */
int cli_outfile_close(cli_outfile *o, int rc);

#endif
