#include "table.h"

#include <csv.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/status.h"

/* ---- Reading a CSV table (libcsv) row by row ---- */


/* Records the first failure: "FILE:LINE: message" in err. Returns status. */
int sylva__table_fail(sylva__table *t, size_t line, int status, const char *fmt, ...) {
  if (t->status) return t->status;
  t->status = status;
  if (t->err && t->errlen) {
    int k = line ? snprintf(t->err, t->errlen, "%s:%zu: ", t->file, line)
                 : snprintf(t->err, t->errlen, "%s: ", t->file);
    if (k >= 0 && (size_t)k < t->errlen) {
      va_list ap;
      va_start(ap, fmt);
      vsnprintf(t->err + k, t->errlen - (size_t)k, fmt, ap);
      va_end(ap);
    }
  }
  return status;
}

int sylva__table_nomem(sylva__table *t) {
  return sylva__table_fail(t, 0, SYLVA_ENOMEM, "out of memory");
}

static bool is_blank(char ch) { return ch == ' ' || ch == '\t'; }

/* libcsv: a field has ended. */
static void table_on_field(void *s, size_t len, void *data) {
  sylva__table *t = data;
  if (t->status) return;
  if (!t->row_open) {
    t->row_open = true;
    t->row_line = t->line;
  }
  const char *p = s ? s : "";
  /* Surrounding blanks are never part of a value here (the header's 'Predicts
   * component ', names with a trailing space), quoted or not. */
  while (len && is_blank(p[0])) p++, len--;
  while (len && is_blank(p[len - 1])) len--;
  if (memchr(p, '\0', len)) {
    sylva__table_fail(t, t->line, SYLVA_EINVAL, "column %zu: a NUL byte", t->nfields + 1);
    return;
  }
  if (t->nfields == SYLVA__TABLE_MAX_FIELDS) {
    sylva__table_fail(t, t->line, SYLVA_EINVAL, "more than %d fields", SYLVA__TABLE_MAX_FIELDS);
    return;
  }
  if (t->nfields == t->fields_cap) {
    size_t cap = t->fields_cap ? 2 * t->fields_cap : 32;
    size_t *start = realloc(t->start, cap * sizeof *start);
    if (!start) {
      sylva__table_nomem(t);
      return;
    }
    t->start = start;
    const char **field = realloc(t->field, cap * sizeof *field);
    if (!field) {
      sylva__table_nomem(t);
      return;
    }
    t->field = field;
    t->fields_cap = cap;
  }
  if (len + 1 > t->text_cap - t->text_len) {
    if (len + 1 > SIZE_MAX / 2 - t->text_len) {
      sylva__table_nomem(t);
      return;
    }
    size_t cap = t->text_cap ? t->text_cap : 1024;
    while (cap - t->text_len < len + 1) cap *= 2;
    char *text = realloc(t->text, cap);
    if (!text) {
      sylva__table_nomem(t);
      return;
    }
    t->text = text;
    t->text_cap = cap;
  }
  if (len) memcpy(t->text + t->text_len, p, len);
  t->text[t->text_len + len] = '\0';
  t->start[t->nfields++] = t->text_len;
  t->text_len += len + 1;
}

/* libcsv: a row has ended. */
static void table_on_row(int term, void *data) {
  (void)term;
  sylva__table *t = data;
  if (!t->status && t->row_open) {
    for (size_t i = 0; i < t->nfields; i++) t->field[i] = t->text + t->start[i];
    t->on_row(t, t->field, t->nfields);
    t->rows++;
  }
  t->row_open = false;
  t->nfields = 0;
  t->text_len = 0;
}

static int table_csv_error(sylva__table *t, struct csv_parser *p) {
  int e = csv_error(p);
  if (e == CSV_ENOMEM || e == CSV_ETOOBIG) return sylva__table_nomem(t);
  return sylva__table_fail(t, t->line, SYLVA_EINVAL,
                    "malformed quoting (a quote inside an unquoted field, text after a "
                    "closing quote, or a quoted field never closed)");
}

/* Reads data as CSV, handing each row to on_row. Returns the status. */
int sylva__table_read(sylva__table *t, const char *data, size_t len) {
  struct csv_parser p;
  if (csv_init(&p, CSV_STRICT | CSV_STRICT_FINI) != 0) return sylva__table_nomem(t);
  size_t pos = 0;
  if (len >= 3 && memcmp(data, "\xEF\xBB\xBF", 3) == 0) pos = 3; /* a UTF-8 byte order mark */
  t->line = 1;
  /* Fed a line at a time so that every row and error knows its line. */
  while (pos < len && !t->status) {
    const char *nl = memchr(data + pos, '\n', len - pos);
    size_t chunk = nl ? (size_t)(nl - (data + pos)) + 1 : len - pos;
    if (csv_parse(&p, data + pos, chunk, table_on_field, table_on_row, t) != chunk) {
      table_csv_error(t, &p);
      break;
    }
    pos += chunk;
    if (nl) t->line++;
  }
  if (!t->status && csv_fini(&p, table_on_field, table_on_row, t) != 0) table_csv_error(t, &p);
  csv_free(&p);
  if (!t->status && t->rows == 0) sylva__table_fail(t, 0, SYLVA_EINVAL, "empty: no header row");
  return t->status;
}

void sylva__table_release(sylva__table *t) {
  free(t->text);
  free(t->start);
  free(t->field);
}

/* ---- Columns ---- */


int sylva__columns_header(sylva__table *t, sylva__columns *cols, const char *const *field, size_t n) {
  cols->header_fields = n;
  for (int k = 0; k < cols->count; k++) {
    size_t i = 0;
    while (i < n && strcmp(field[i], cols->names[k]) != 0) i++;
    if (i == n)
      return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "the header has no column '%s'",
                        cols->names[k]);
    cols->index[k] = i;
  }
  return SYLVA_OK;
}

int sylva__columns_check_row(sylva__table *t, const sylva__columns *cols, size_t n) {
  if (n != cols->header_fields)
    return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "%zu fields where the header has %zu", n,
                      cols->header_fields);
  return SYLVA_OK;
}

/* A cell as text, copied into dst (size bytes); an empty one is an error if required. */
int sylva__cell_text(sylva__table *t, const sylva__columns *cols, const char *const *field, int k,
                     bool required, char *dst, size_t size) {
  const char *s = field[cols->index[k]];
  size_t len = strlen(s);
  if (required && len == 0)
    return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "column %zu (%s): empty",
                      cols->index[k] + 1, cols->names[k]);
  if (len >= size)
    return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "column %zu (%s): longer than %zu characters",
                      cols->index[k] + 1, cols->names[k], size - 1);
  memcpy(dst, s, len + 1);
  return SYLVA_OK;
}

/* A cell as a finite number; an empty one is NAN, or an error if required. */
int sylva__cell_number(sylva__table *t, const sylva__columns *cols, const char *const *field, int k,
                       bool required, double *out) {
  const char *s = field[cols->index[k]];
  *out = NAN;
  if (!*s) {
    if (!required) return SYLVA_OK;
    return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "column %zu (%s): empty",
                      cols->index[k] + 1, cols->names[k]);
  }
  char *end;
  /* An overflow is not finite and a denormal is still a number: errno adds nothing. */
  double v = strtod(s, &end);
  if (end == s || *end || !isfinite(v))
    return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "column %zu (%s): '%.40s' is not a number",
                      cols->index[k] + 1, cols->names[k], s);
  *out = v;
  return SYLVA_OK;
}

/* A cell as a count >= 0; an empty one is 0. */
int sylva__cell_count(sylva__table *t, const sylva__columns *cols, const char *const *field, int k,
                      int *out) {
  const char *s = field[cols->index[k]];
  *out = 0;
  if (!*s) return SYLVA_OK;
  char *end;
  errno = 0;
  long v = strtol(s, &end, 10);
  if (end == s || *end || errno || v < 0 || v > INT_MAX)
    return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "column %zu (%s): '%.40s' is not a count",
                      cols->index[k] + 1, cols->names[k], s);
  *out = (int)v;
  return SYLVA_OK;
}

