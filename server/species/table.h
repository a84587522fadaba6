/* sylva species: reading a CSV table row by row (libcsv), its columns by name and
 * its cells as numbers, each failure named "FILE:LINE: message". Shared by the
 * Urban Tree Database tables and a user's measurements. */
#ifndef SYLVA_SPECIES_TABLE_H
#define SYLVA_SPECIES_TABLE_H

#include <stdbool.h>
#include <stddef.h>

/** Most fields a row may have. */
#define SYLVA__TABLE_MAX_FIELDS 256

typedef struct sylva__table sylva__table;
/* Called with each row; returns 0 or a status (after calling sylva__table_fail). */
typedef int (*sylva__table_row_fn)(sylva__table *t, const char *const *field, size_t n);

struct sylva__table {
  const char *file;
  char *err;
  size_t errlen;
  int status;      /* the first failure, or SYLVA_OK */
  size_t line;     /* the physical line being read, from 1 */
  size_t row_line; /* the line of the row being assembled */
  bool row_open;
  size_t rows;     /* rows handed over, the header included */
  char *text;      /* the row's fields, each NUL-terminated */
  size_t text_len, text_cap;
  size_t *start; /* offset of each field in text */
  const char **field;
  size_t nfields, fields_cap;
  sylva__table_row_fn on_row;
  void *ctx;
};

/* The columns a table needs, found by name in its header. */
#define SYLVA__TABLE_MAX_COLUMNS 24
typedef struct sylva__columns {
  const char *const *names;
  int count;
  size_t index[SYLVA__TABLE_MAX_COLUMNS]; /* field index of each name */
  size_t header_fields;
} sylva__columns;

/** Records the first failure, "FILE:LINE: message" in t->err (no line when 0); returns status. */
int sylva__table_fail(sylva__table *t, size_t line, int status, const char *fmt, ...);
/** Records SYLVA_ENOMEM. */
int sylva__table_nomem(sylva__table *t);
/** Reads data as CSV (a UTF-8 byte order mark skipped), handing each row to t->on_row; returns t->status. */
int sylva__table_read(sylva__table *t, const char *data, size_t len);
/** Frees what reading held (not t itself). */
void sylva__table_release(sylva__table *t);
/** Finds each of cols->names in the header row; an error names a missing one. */
int sylva__columns_header(sylva__table *t, sylva__columns *cols, const char *const *field, size_t n);
/** A row must have as many fields as the header. */
int sylva__columns_check_row(sylva__table *t, const sylva__columns *cols, size_t n);
/** Column k of a row as text copied into dst (size bytes); empty is an error when required. */
int sylva__cell_text(sylva__table *t, const sylva__columns *cols, const char *const *field, int k,
                     bool required, char *dst, size_t size);
/** Column k as a finite number; empty is NAN, or an error when required. */
int sylva__cell_number(sylva__table *t, const sylva__columns *cols, const char *const *field, int k,
                       bool required, double *out);
/** Column k as a count >= 0; empty is 0. */
int sylva__cell_count(sylva__table *t, const sylva__columns *cols, const char *const *field, int k,
                      int *out);

#endif
