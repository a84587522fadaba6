/* The text readers: TreeQSM's save_model_text (whitespace-separated numbers, a
 * header row in its newer form) and SimpleForest's CSV (named columns, libcsv).
 * Rows in messages are the file's lines, counted from 1 with the header. */
#include <csv.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "qsm.h"
#include "sylva/status.h"

/* A whole number that fits an int (TreeQSM writes them as floats: "12", "1e+06"). */
static bool whole_int(double v) { return v == floor(v) && v >= INT_MIN && v <= INT_MAX; }

/* The whole token s as a number. */
static bool parse_number(const char *s, double *out) {
  if (!*s) return false;
  char *end;
  *out = strtod(s, &end);
  return end != s && *end == '\0';
}

/* Names a cylinder by its row: rows[i] is the line of cylinder i. */
static void name_row(const void *ctx, size_t i, char *buf, size_t len) {
  const size_t *rows = ctx;
  snprintf(buf, len, "row %zu", rows[i]);
}

/* ---- TreeQSM text ---- */

/* Columns of save_model_text: 17 since TreeQSM 2.4 (version 1.1.0 of the
 * function, with a header row), 15 before (no header). The first 12 agree. */
static const char *const text_columns17[17] = {"radius",
                                               "length",
                                               "start x",
                                               "start y",
                                               "start z",
                                               "axis x",
                                               "axis y",
                                               "axis z",
                                               "parent",
                                               "extension",
                                               "branch",
                                               "branch_order",
                                               "position_in_branch",
                                               "mad",
                                               "SurfCov",
                                               "added",
                                               "UnmodRadius"};
static const char *const text_columns15[15] = {"radius",
                                               "length",
                                               "start x",
                                               "start y",
                                               "start z",
                                               "axis x",
                                               "axis y",
                                               "axis z",
                                               "parent",
                                               "extension",
                                               "branch",
                                               "branch_order",
                                               "position_in_branch",
                                               "added",
                                               "UnmodRadius"};

enum { TEXT_MAX_COLUMNS = 17 };

int sylva__qsm_read_text(const char *path, int model, sylva_qsm *q, char *err, size_t errlen) {
  memset(q, 0, sizeof *q);
  if (model > 1)
    return server_fail(err, errlen, SYLVA_ERANGE,
                           "%s: no model %d: a TreeQSM text file holds 1", path, model);
  FILE *f = fopen(path, "r");
  if (!f) return server_fail(err, errlen, SYLVA_EINVAL, "%s: %s", path, strerror(errno));
  int rc = SYLVA_OK;
  char *line = NULL;
  size_t line_cap = 0, cap = 0, line_no = 0, rows_cap = 0;
  size_t *rows = NULL; /* the line of each cylinder */
  double *parent = NULL;
  int columns = 0;
  bool header = false;
  const char *const *names = text_columns17;
  ssize_t got;
  while ((got = getline(&line, &line_cap, f)) != -1) {
    line_no++;
    if (memchr(line, '\0', (size_t)got)) {
      rc = server_fail(err, errlen, SYLVA_EINVAL,
                           "%s: row %zu: a NUL byte: binary data, not TreeQSM text", path, line_no);
      break;
    }
    char *tok[TEXT_MAX_COLUMNS + 1];
    int n = 0;
    char *save = NULL;
    for (char *t = strtok_r(line, " \t\r\n\f\v", &save); t;
         t = strtok_r(NULL, " \t\r\n\f\v", &save)) {
      if (n <= TEXT_MAX_COLUMNS) tok[n] = t;
      n++;
    }
    if (n == 0) continue; /* a blank line */
    double v[TEXT_MAX_COLUMNS];
    if (!columns && !header && q->count == 0 && !parse_number(tok[0], &v[0])) {
      /* TreeQSM's header row names 13 of the 17 columns (start and axis take one
       * name for three): it only tells that the numbers begin below it. */
      header = true;
      continue;
    }
    if (!columns) {
      if (n != 17 && n != 15) {
        rc = server_fail(
            err, errlen, SYLVA_EINVAL,
            "%s: row %zu: %d columns: TreeQSM text has 17 (radius, length, start, "
            "axis, parent, extension, branch, branch_order, position_in_branch, "
            "mad, SurfCov, added, UnmodRadius) or 15 (older, without mad and SurfCov)",
            path, line_no, n);
        break;
      }
      columns = n;
      names = n == 17 ? text_columns17 : text_columns15;
    } else if (n != columns) {
      rc = server_fail(err, errlen, SYLVA_EINVAL,
                           "%s: row %zu: %d columns where the rows above have %d", path, line_no, n,
                           columns);
      break;
    }
    for (int k = 0; k < n; k++)
      if (!parse_number(tok[k], &v[k])) {
        rc = server_fail(err, errlen, SYLVA_EINVAL,
                             "%s: row %zu, column %d (%s): '%.40s' is not a number", path, line_no,
                             k + 1, names[k], tok[k]);
        break;
      }
    if (rc) break;
    for (int k = 10; k <= 11; k++)
      if (!whole_int(v[k])) {
        rc = server_fail(err, errlen, SYLVA_EINVAL,
                             "%s: row %zu, column %d (%s): %s is not a whole number", path, line_no,
                             k + 1, names[k], tok[k]);
        break;
      }
    if (rc) break;
    if ((rc = sylva__qsm_grow(q, &cap))) break;
    if (q->count == rows_cap) {
      size_t m = rows_cap ? rows_cap * 2 : 256;
      size_t *r = realloc(rows, m * sizeof *r);
      double *p = r ? realloc(parent, m * sizeof *p) : NULL;
      if (r) rows = r;
      if (p) parent = p;
      if (!r || !p) {
        rc = SYLVA_ENOMEM;
        break;
      }
      rows_cap = m;
    }
    sylva_qsm_cylinder *c = &q->cyl[q->count];
    c->radius = v[0];
    c->length = v[1];
    for (int k = 0; k < 3; k++) {
      c->start[k] = v[2 + k];
      c->axis[k] = v[5 + k];
    }
    c->parent = -1;
    c->branch = (int)v[10];
    c->branch_order = (int)v[11];
    parent[q->count] = v[8];
    rows[q->count] = line_no;
    q->count++;
  }
  if (!rc && ferror(f))
    rc = server_fail(err, errlen, SYLVA_EINVAL, "%s: %s", path, strerror(errno));
  if (rc == SYLVA_ENOMEM) server_fail(err, errlen, rc, "%s: out of memory", path);
  free(line);
  fclose(f);
  if (!rc && q->count == 0)
    rc = server_fail(err, errlen, SYLVA_EINVAL, "%s: no cylinders%s", path,
                         header ? " below the header row" : ": an empty model");
  /* Parents count from 1 in the file, 0 for a root. */
  for (size_t i = 0; !rc && i < q->count; i++) {
    double p = parent[i];
    if (!whole_int(p) || p < 0 || p > (double)q->count)
      rc = server_fail(
          err, errlen, SYLVA_EINVAL,
          "%s: row %zu, column 9 (parent): %g is not a cylinder (1..%zu, or 0 for a root)", path,
          rows[i], p, q->count);
    else
      q->cyl[i].parent = (int)p - 1;
  }
  if (!rc) {
    char msg[512];
    rc = sylva__qsm_check_named(q, name_row, rows, msg, sizeof msg);
    if (rc) server_fail(err, errlen, rc, "%s: %s", path, msg);
  }
  free(rows);
  free(parent);
  if (rc) {
    sylva_qsm_free(q);
    return rc;
  }
  sylva__qsm_normalise(q);
  q->models = 1;
  return SYLVA_OK;
}

/* ---- SimpleForest CSV ---- */

/* The columns read, by name: the first nine are required. */
enum {
  COL_ID,
  COL_PARENT,
  COL_SX,
  COL_SY,
  COL_SZ,
  COL_EX,
  COL_EY,
  COL_EZ,
  COL_RADIUS,
  COL_REQUIRED,
  COL_LENGTH = COL_REQUIRED,
  COL_AX,
  COL_AY,
  COL_AZ,
  COL_BRANCH,
  COL_ORDER,
  COL_COUNT
};
static const char *const csv_names[COL_COUNT] = {
    "ID",     "parentID", "startX", "startY", "startZ", "endX",     "endY",       "endZ",
    "radius", "length",   "axisX",  "axisY",  "axisZ",  "branchID", "branchOrder"};

typedef struct csv_reader {
  const char *path;
  char *err;
  size_t errlen;
  int status;
  size_t line;     /* the line being fed */
  size_t row_line; /* the line where the row being assembled began */
  bool row_open;
  bool have_header;
  /* The row's fields, each NUL-terminated in text at start[k]. */
  char *text;
  size_t text_len, text_cap;
  size_t *start;
  size_t nfields, fields_cap;
  size_t header_fields;
  long col[COL_COUNT]; /* field index of each column; -1 when absent */
  bool exact;          /* length and axis columns all present */
  /* The model and, per cylinder, its line, ID and parent ID. */
  sylva_qsm *q;
  size_t cap, meta_cap;
  size_t *rows;
  double *id, *parent_id;
} csv_reader;

static void csv_fail_nomem(csv_reader *r) {
  if (r->status) return;
  r->status = server_fail(r->err, r->errlen, SYLVA_ENOMEM, "%s: out of memory", r->path);
}

static bool blank(char ch) { return ch == ' ' || ch == '\t' || ch == '\r'; }

static void csv_on_field(void *s, size_t len, void *data) {
  csv_reader *r = data;
  if (r->status) return;
  if (!r->row_open) {
    r->row_open = true;
    r->row_line = r->line;
  }
  const char *p = s ? s : "";
  /* SimpleForest writes ", parentID, startX": blanks around a name are not part of it. */
  while (len && blank(p[0])) p++, len--;
  while (len && blank(p[len - 1])) len--;
  if (r->nfields == r->fields_cap) {
    size_t cap = r->fields_cap ? 2 * r->fields_cap : 32;
    if (cap > 4096) {
      r->status = server_fail(r->err, r->errlen, SYLVA_EINVAL,
                                  "%s: row %zu: more than 4096 fields", r->path, r->row_line);
      return;
    }
    size_t *start = realloc(r->start, cap * sizeof *start);
    if (!start) {
      csv_fail_nomem(r);
      return;
    }
    r->start = start;
    r->fields_cap = cap;
  }
  if (len + 1 > r->text_cap - r->text_len) {
    size_t cap = r->text_cap ? r->text_cap : 1024;
    while (cap - r->text_len < len + 1) {
      if (cap > SIZE_MAX / 4) {
        csv_fail_nomem(r);
        return;
      }
      cap *= 2;
    }
    char *text = realloc(r->text, cap);
    if (!text) {
      csv_fail_nomem(r);
      return;
    }
    r->text = text;
    r->text_cap = cap;
  }
  if (memchr(p, '\0', len)) {
    r->status = server_fail(r->err, r->errlen, SYLVA_EINVAL,
                                "%s: row %zu: a NUL byte: binary data, not CSV", r->path, r->line);
    return;
  }
  if (len) memcpy(r->text + r->text_len, p, len);
  r->text[r->text_len + len] = '\0';
  r->start[r->nfields++] = r->text_len;
  r->text_len += len + 1;
}

static const char *csv_field(const csv_reader *r, size_t k) { return r->text + r->start[k]; }

static void csv_header(csv_reader *r) {
  r->header_fields = r->nfields;
  for (int c = 0; c < COL_COUNT; c++) {
    r->col[c] = -1;
    for (size_t k = 0; k < r->nfields; k++)
      if (strcmp(csv_field(r, k), csv_names[c]) == 0) {
        r->col[c] = (long)k;
        break;
      }
    if (c < COL_REQUIRED && r->col[c] < 0) {
      r->status = server_fail(r->err, r->errlen, SYLVA_EINVAL,
                                  "%s: row %zu: the header has no column '%s' (a SimpleForest CSV "
                                  "needs ID, parentID, startX, startY, startZ, endX, endY, endZ "
                                  "and radius)",
                                  r->path, r->row_line, csv_names[c]);
      return;
    }
  }
  r->exact =
      r->col[COL_LENGTH] >= 0 && r->col[COL_AX] >= 0 && r->col[COL_AY] >= 0 && r->col[COL_AZ] >= 0;
  r->have_header = true;
}

/* Column c of the row as a number (whole when asked); sets r->status if not. */
static double csv_number(csv_reader *r, int c, bool whole) {
  size_t k = (size_t)r->col[c];
  const char *s = csv_field(r, k);
  double v = 0;
  if (!*s)
    r->status =
        server_fail(r->err, r->errlen, SYLVA_EINVAL, "%s: row %zu, column %zu (%s): empty",
                        r->path, r->row_line, k + 1, csv_names[c]);
  else if (!parse_number(s, &v))
    r->status = server_fail(r->err, r->errlen, SYLVA_EINVAL,
                                "%s: row %zu, column %zu (%s): '%.40s' is not a number", r->path,
                                r->row_line, k + 1, csv_names[c], s);
  else if (whole && !whole_int(v))
    r->status = server_fail(r->err, r->errlen, SYLVA_EINVAL,
                                "%s: row %zu, column %zu (%s): '%.40s' is not a whole number",
                                r->path, r->row_line, k + 1, csv_names[c], s);
  return v;
}

static void csv_data_row(csv_reader *r) {
  if (r->nfields != r->header_fields) {
    r->status = server_fail(r->err, r->errlen, SYLVA_EINVAL,
                                "%s: row %zu: %zu fields where the header has %zu", r->path,
                                r->row_line, r->nfields, r->header_fields);
    return;
  }
  double v[COL_COUNT] = {0};
  for (int c = 0; c < COL_COUNT && !r->status; c++)
    if (r->col[c] >= 0 && (c < COL_REQUIRED || c >= COL_BRANCH || r->exact))
      v[c] = csv_number(r, c, c == COL_ID || c == COL_PARENT || c >= COL_BRANCH);
  if (r->status) return;
  sylva_qsm *q = r->q;
  if (sylva__qsm_grow(q, &r->cap)) {
    csv_fail_nomem(r);
    return;
  }
  if (q->count == r->meta_cap) {
    size_t m = r->meta_cap ? 2 * r->meta_cap : 256;
    size_t *rows = realloc(r->rows, m * sizeof *rows);
    if (rows) r->rows = rows;
    double *id = rows ? realloc(r->id, m * sizeof *id) : NULL;
    if (id) r->id = id;
    double *pid = id ? realloc(r->parent_id, m * sizeof *pid) : NULL;
    if (pid) r->parent_id = pid;
    if (!pid) {
      csv_fail_nomem(r);
      return;
    }
    r->meta_cap = m;
  }
  sylva_qsm_cylinder *c = &q->cyl[q->count];
  memset(c, 0, sizeof *c);
  c->radius = v[COL_RADIUS];
  double d[3];
  for (int k = 0; k < 3; k++) {
    c->start[k] = v[COL_SX + k];
    d[k] = v[COL_EX + k] - v[COL_SX + k];
  }
  if (r->exact) {
    c->length = v[COL_LENGTH];
    for (int k = 0; k < 3; k++) c->axis[k] = v[COL_AX + k];
  } else {
    c->length = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    /* A zero length leaves a zero axis, which the check names after the length. */
    for (int k = 0; k < 3; k++) c->axis[k] = c->length > 0 ? d[k] / c->length : 0;
  }
  c->parent = -1;
  c->branch = (int)v[COL_BRANCH];
  c->branch_order = (int)v[COL_ORDER];
  r->rows[q->count] = r->row_line;
  r->id[q->count] = v[COL_ID];
  r->parent_id[q->count] = v[COL_PARENT];
  q->count++;
}

static void csv_on_row(int term, void *data) {
  (void)term;
  csv_reader *r = data;
  if (!r->status && r->row_open) {
    if (!r->have_header)
      csv_header(r);
    else
      csv_data_row(r);
  }
  r->row_open = false;
  r->nfields = 0;
  r->text_len = 0;
}

/* A cylinder's ID and index, sorted by ID to find parents. */
typedef struct id_index {
  double id;
  size_t i;
} id_index;

static int cmp_id(const void *a, const void *b) {
  const id_index *x = a, *y = b;
  if (x->id != y->id) return (x->id > y->id) - (x->id < y->id);
  return (x->i > y->i) - (x->i < y->i);
}

/* Turns IDs and parent IDs into parent indices. */
static int csv_link(csv_reader *r) {
  sylva_qsm *q = r->q;
  id_index *by_id = malloc(q->count * sizeof *by_id);
  if (!by_id) {
    csv_fail_nomem(r);
    return r->status;
  }
  for (size_t i = 0; i < q->count; i++) by_id[i] = (id_index){r->id[i], i};
  qsort(by_id, q->count, sizeof *by_id, cmp_id);
  size_t id_col = (size_t)r->col[COL_ID] + 1, parent_col = (size_t)r->col[COL_PARENT] + 1;
  for (size_t k = 1; k < q->count && !r->status; k++)
    if (by_id[k].id == by_id[k - 1].id)
      r->status =
          server_fail(r->err, r->errlen, SYLVA_EINVAL,
                          "%s: row %zu, column %zu (ID): ID %.0f is also on row %zu", r->path,
                          r->rows[by_id[k].i], id_col, by_id[k].id, r->rows[by_id[k - 1].i]);
  for (size_t i = 0; i < q->count && !r->status; i++) {
    double p = r->parent_id[i];
    if (p == -1) continue; /* a root */
    size_t lo = 0, hi = q->count;
    while (lo < hi) {
      size_t mid = lo + (hi - lo) / 2;
      if (by_id[mid].id < p)
        lo = mid + 1;
      else
        hi = mid;
    }
    if (lo == q->count || by_id[lo].id != p)
      r->status =
          server_fail(r->err, r->errlen, SYLVA_EINVAL,
                          "%s: row %zu, column %zu (parentID): no row has ID %.0f (-1 for a root)",
                          r->path, r->rows[i], parent_col, p);
    else
      q->cyl[i].parent = (int)by_id[lo].i;
  }
  free(by_id);
  return r->status;
}

typedef struct csv_names_ctx {
  const size_t *rows;
  const double *id;
} csv_names_ctx;

static void name_csv_row(const void *ctx, size_t i, char *buf, size_t len) {
  const csv_names_ctx *c = ctx;
  snprintf(buf, len, "row %zu (ID %.0f)", c->rows[i], c->id[i]);
}

int sylva__qsm_read_csv(const char *path, int model, sylva_qsm *q, char *err, size_t errlen) {
  memset(q, 0, sizeof *q);
  if (model > 1)
    return server_fail(err, errlen, SYLVA_ERANGE,
                           "%s: no model %d: a SimpleForest CSV file holds 1", path, model);
  FILE *f = fopen(path, "r");
  if (!f) return server_fail(err, errlen, SYLVA_EINVAL, "%s: %s", path, strerror(errno));
  csv_reader r = {.path = path, .err = err, .errlen = errlen, .q = q};
  struct csv_parser p;
  if (csv_init(&p, CSV_STRICT | CSV_STRICT_FINI) != 0) {
    fclose(f);
    return server_fail(err, errlen, SYLVA_ENOMEM, "%s: out of memory", path);
  }
  char *line = NULL;
  size_t line_cap = 0;
  ssize_t got;
  bool first = true;
  /* Fed a line at a time so that each row knows its line. */
  while (!r.status && (got = getline(&line, &line_cap, f)) != -1) {
    r.line++;
    const char *s = line;
    size_t n = (size_t)got;
    if (first && n >= 3 && memcmp(s, "\xEF\xBB\xBF", 3) == 0)
      s += 3, n -= 3; /* a byte order mark */
    first = false;
    if (csv_parse(&p, s, n, csv_on_field, csv_on_row, &r) != n && !r.status) {
      r.status =
          csv_error(&p) == CSV_ENOMEM || csv_error(&p) == CSV_ETOOBIG
              ? server_fail(err, errlen, SYLVA_ENOMEM, "%s: out of memory", path)
              : server_fail(err, errlen, SYLVA_EINVAL, "%s: row %zu: malformed quoting (%s)",
                                path, r.line, csv_strerror(csv_error(&p)));
    }
  }
  if (!r.status && ferror(f))
    r.status = server_fail(err, errlen, SYLVA_EINVAL, "%s: %s", path, strerror(errno));
  if (!r.status && csv_fini(&p, csv_on_field, csv_on_row, &r) != 0 && !r.status)
    r.status = server_fail(err, errlen, SYLVA_EINVAL,
                               "%s: row %zu: a quoted field never closed", path, r.line);
  csv_free(&p);
  free(line);
  fclose(f);
  if (!r.status && !r.have_header)
    r.status = server_fail(err, errlen, SYLVA_EINVAL, "%s: empty: no header row", path);
  if (!r.status && q->count == 0)
    r.status = server_fail(err, errlen, SYLVA_EINVAL,
                               "%s: no cylinders below the header row: an empty model", path);
  if (!r.status) csv_link(&r);
  if (!r.status) {
    char msg[512];
    csv_names_ctx names = {r.rows, r.id};
    r.status = sylva__qsm_check_named(q, name_csv_row, &names, msg, sizeof msg);
    if (r.status) server_fail(err, errlen, r.status, "%s: %s", path, msg);
  }
  free(r.text);
  free(r.start);
  free(r.rows);
  free(r.id);
  free(r.parent_id);
  if (r.status) {
    sylva_qsm_free(q);
    return r.status;
  }
  sylva__qsm_normalise(q);
  q->models = 1;
  return SYLVA_OK;
}
