/* sylva server: the per-stem stats of a stored run as CSV (RFC 4180), one header
 * line, then one row per stem and iteration. */
#ifndef SYLVA_SERVER_CSV_H
#define SYLVA_SERVER_CSV_H

#include <stdint.h>
#include <stdio.h>

#include "store.h"

/** Writes the stats of run up to iteration `to`; 0, or -1 (a write error leaves
 *  ferror(f) set, otherwise store_error(st) says what failed). */
int csv_write_stats(FILE *f, store *st, int64_t run, int to);

/** Writes one field, quoted as RFC 4180 quotes a field that holds a comma, a quote
 *  or a line break. */
void csv_write_text(FILE *f, const char *s);
#endif
