/* TreeQSM .mat files through libmatio: TreeQSM 2.0's flat variables (Rad, Len,
 * Sta, Axe, CPar, BoC, TreeData) and the QSM structs of 2.3 and 2.4 (QSM, QSMs or
 * OptQSM; a struct array holds several models). */
#include <limits.h>
#include <math.h>
#include <matio.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "qsm.h"
#include "sylva/status.h"

/* ---- libmatio's log ---- */

/* libmatio reports a truncated or corrupt file only through its log (a variable
 * may come back half filled with zeros), so the read watches it: the log function
 * is process-wide, what it saw is per thread. */
static _Thread_local bool mat_log_bad;
static _Thread_local char mat_log_text[200];

static void mat_log(int level, char *message) {
  if (level & (MATIO_LOG_LEVEL_MESSAGE | MATIO_LOG_LEVEL_DEBUG)) return;
  const char *m = message ? message : "";
  /* HDF5 (MATLAB 7.3) reports a stack of errors, outermost first, each over
   * several lines; the innermost's "minor:" line says what is wrong ("File has
   * been truncated"). Otherwise the first message says enough. */
  const char *minor = strncmp(m, "HDF5", 4) == 0 ? strstr(m, "minor: ") : NULL;
  if (minor)
    snprintf(mat_log_text, sizeof mat_log_text, "HDF5: %s", minor + 7);
  else if (!mat_log_bad)
    snprintf(mat_log_text, sizeof mat_log_text, "%s", m);
  char *nl = strchr(mat_log_text, '\n');
  if (nl) *nl = '\0';
  mat_log_bad = true;
}

static void mat_log_reset(void) {
  mat_log_bad = false;
  mat_log_text[0] = '\0';
}

/* ---- Reading variables ---- */

typedef struct mat_reader {
  const char *path;
  char *err;
  size_t errlen;
  int status;
} mat_reader;

static int mat_fail(mat_reader *r, int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static int mat_fail(mat_reader *r, int status, const char *fmt, ...) {
  if (r->status) return r->status;
  r->status = status;
  if (r->err && r->errlen) {
    int k = snprintf(r->err, r->errlen, "%s: ", r->path);
    if (k >= 0 && (size_t)k < r->errlen) {
      va_list ap;
      va_start(ap, fmt);
      vsnprintf(r->err + k, r->errlen - (size_t)k, fmt, ap);
      va_end(ap);
    }
  }
  return status;
}

/* The kind of value v is, with its article: "a struct", "an empty value". */
static const char *class_name(enum matio_classes c) {
  switch (c) {
    case MAT_C_EMPTY:
      return "an empty value";
    case MAT_C_CELL:
      return "a cell array";
    case MAT_C_STRUCT:
      return "a struct";
    case MAT_C_OBJECT:
      return "an object";
    case MAT_C_CHAR:
      return "text";
    case MAT_C_SPARSE:
      return "a sparse matrix";
    case MAT_C_FUNCTION:
      return "a function handle";
    case MAT_C_OPAQUE:
      return "an opaque object";
    default:
      return "a numeric array";
  }
}

static size_t numel(const matvar_t *v) {
  if (!v->dims || v->rank <= 0) return 0;
  size_t n = 1;
  for (int i = 0; i < v->rank; i++) n *= v->dims[i];
  return n;
}

/* "169x3" */
static const char *shape(const matvar_t *v, char *buf, size_t len) {
  size_t at = 0;
  buf[0] = '\0';
  for (int i = 0; i < v->rank && v->dims; i++) {
    int w = snprintf(buf + at, len - at, "%s%zu", i ? "x" : "", v->dims[i]);
    if (w < 0 || (size_t)w >= len - at) break;
    at += (size_t)w;
  }
  if (at == 0) snprintf(buf, len, "0x0");
  return buf;
}

static bool is_numeric(const matvar_t *v) {
  return v->class_type >= MAT_C_DOUBLE && v->class_type <= MAT_C_UINT64 && !v->isComplex;
}

/* Element i of a numeric variable as a double. */
static double element(const matvar_t *v, size_t i) {
  switch (v->class_type) {
    case MAT_C_DOUBLE:
      return ((const double *)v->data)[i];
    case MAT_C_SINGLE:
      return ((const float *)v->data)[i];
    case MAT_C_INT8:
      return ((const int8_t *)v->data)[i];
    case MAT_C_UINT8:
      return ((const uint8_t *)v->data)[i];
    case MAT_C_INT16:
      return ((const int16_t *)v->data)[i];
    case MAT_C_UINT16:
      return ((const uint16_t *)v->data)[i];
    case MAT_C_INT32:
      return ((const int32_t *)v->data)[i];
    case MAT_C_UINT32:
      return ((const uint32_t *)v->data)[i];
    case MAT_C_INT64:
      return (double)((const int64_t *)v->data)[i];
    case MAT_C_UINT64:
      return (double)((const uint64_t *)v->data)[i];
    default:
      return NAN;
  }
}

/* Checks that v (named label) holds real numbers as a column or row of n values
 * (cols 1) or as n rows of cols values (n x cols); *n may be 0 to take it from v. */
static int numbers(mat_reader *r, const matvar_t *v, const char *label, size_t *n, size_t cols) {
  char dims[64];
  if (!is_numeric(v))
    return mat_fail(r, SYLVA_EINVAL, "%s is %s (%s), not an array of real numbers", label,
                    v->isComplex ? "a complex array" : class_name(v->class_type),
                    shape(v, dims, sizeof dims));
  size_t count = numel(v);
  bool ok = v->rank == 2;
  size_t rows = 0;
  if (ok && cols == 1) {
    ok = v->dims[0] == 1 || v->dims[1] == 1 || count == 0;
    rows = count;
  } else if (ok) {
    ok = v->dims[1] == cols;
    rows = v->dims[0];
  }
  if (ok && *n && rows != *n) ok = false;
  if (!ok) {
    if (cols == 1 && *n)
      return mat_fail(r, SYLVA_EINVAL, "%s has shape %s; expected %zux1 (one value per cylinder)",
                      label, shape(v, dims, sizeof dims), *n);
    if (cols == 1)
      return mat_fail(r, SYLVA_EINVAL,
                      "%s has shape %s; expected a column (one value per cylinder)", label,
                      shape(v, dims, sizeof dims));
    if (*n)
      return mat_fail(r, SYLVA_EINVAL, "%s has shape %s; expected %zux%zu (a row per cylinder)",
                      label, shape(v, dims, sizeof dims), *n, cols);
    return mat_fail(r, SYLVA_EINVAL, "%s has shape %s; expected Nx%zu (a row per cylinder)", label,
                    shape(v, dims, sizeof dims), cols);
  }
  if (count && !v->data)
    return mat_fail(r, SYLVA_EINVAL, "truncated or corrupt: %s has no data", label);
  *n = rows;
  return SYLVA_OK;
}

/* Field name of struct s, element index; NULL (and an error when required) if absent. */
static matvar_t *field(mat_reader *r, matvar_t *s, size_t index, const char *name,
                       const char *label, bool required) {
  unsigned nf = Mat_VarGetNumberOfFields(s);
  char *const *names = Mat_VarGetStructFieldnames(s);
  for (unsigned i = 0; names && i < nf; i++)
    if (names[i] && strcmp(names[i], name) == 0) {
      matvar_t *f = Mat_VarGetStructFieldByIndex(s, i, index);
      if (!f && required)
        mat_fail(r, SYLVA_EINVAL, "truncated or corrupt: %s.%s could not be read", label, name);
      return f;
    }
  if (required) mat_fail(r, SYLVA_EINVAL, "%s has no field '%s'", label, name);
  return NULL;
}

/* Reads variable name whole; NULL and an error if it cannot be read. */
static matvar_t *read_variable(mat_reader *r, mat_t *mat, const char *name) {
  mat_log_reset();
  matvar_t *v = Mat_VarRead(mat, name);
  if (!v || mat_log_bad) {
    mat_fail(r, SYLVA_EINVAL, "truncated or corrupt: variable '%s' could not be read%s%s%s", name,
             mat_log_text[0] ? " (libmatio: " : "", mat_log_text, mat_log_text[0] ? ")" : "");
    if (v) Mat_VarFree(v);
    return NULL;
  }
  return v;
}

/* ---- The cylinders ---- */

/* A whole number in lo..hi. */
static bool whole_in(double v, double lo, double hi) { return v == floor(v) && v >= lo && v <= hi; }

/* Fills parents (TreeQSM's, from 1; 0 for a root) from v. */
static int set_parents(mat_reader *r, sylva_qsm *q, const matvar_t *v, const char *label) {
  for (size_t i = 0; i < q->count; i++) {
    double p = element(v, i);
    if (!whole_in(p, 0, (double)q->count))
      return mat_fail(r, SYLVA_EINVAL, "%s(%zu) = %g is not a cylinder (1..%zu, or 0 for a root)",
                      label, i + 1, p, q->count);
    q->cyl[i].parent = (int)p - 1;
  }
  return SYLVA_OK;
}

/* Fills branch numbers or orders from column col of v (n rows). */
static int set_ints(mat_reader *r, sylva_qsm *q, const matvar_t *v, size_t col, const char *label,
                    bool order) {
  for (size_t i = 0; i < q->count; i++) {
    double b = element(v, col * q->count + i);
    if (!whole_in(b, 0, INT_MAX))
      return mat_fail(r, SYLVA_EINVAL, "%s(%zu) = %g is not a whole number of 0 or more", label,
                      i + 1, b);
    if (order)
      q->cyl[i].branch_order = (int)b;
    else
      q->cyl[i].branch = (int)b;
  }
  return SYLVA_OK;
}

static int alloc_cylinders(mat_reader *r, sylva_qsm *q, size_t n) {
  if (n > (size_t)INT_MAX) return mat_fail(r, SYLVA_ETOOBIG, "%zu cylinders: too many", n);
  q->cyl = calloc(n, sizeof *q->cyl);
  if (!q->cyl) return mat_fail(r, SYLVA_ENOMEM, "out of memory");
  q->count = n;
  return SYLVA_OK;
}

/* radius, length, start and axis of n cylinders from their variables. */
static void set_geometry(sylva_qsm *q, const matvar_t *rad, const matvar_t *len,
                         const matvar_t *sta, const matvar_t *axe) {
  size_t n = q->count;
  for (size_t i = 0; i < n; i++) {
    sylva_qsm_cylinder *c = &q->cyl[i];
    c->radius = element(rad, i);
    c->length = element(len, i);
    for (size_t k = 0; k < 3; k++) {
      /* MATLAB stores by columns: row i of column k. */
      c->start[k] = element(sta, k * n + i);
      c->axis[k] = element(axe, k * n + i);
    }
  }
}

static void no_treedata(sylva_qsm *q) {
  q->has_treedata = false;
  q->treedata = (sylva_qsm_treedata){NAN, NAN, NAN, NAN, NAN, NAN};
}

/* TreeQSM 2.0's TreeData: a vector (TotalVolume L, TrunkVolume, BranchVolume,
 * TreeHeight m, TrunkLength, BranchLength, NumberBranches, MaxBranchOrder,
 * TotalArea, DBHqsm in cm, ...), rounded to three figures. No TotalLength. */
static void treedata_vector(sylva_qsm *q, const matvar_t *v) {
  if (!is_numeric(v) || !v->data) return;
  size_t n = numel(v);
  if (n == 0) return;
  q->has_treedata = true;
  sylva_qsm_treedata *t = &q->treedata;
  if (n > 0) t->total_volume = element(v, 0);
  if (n > 3) t->height = element(v, 3);
  if (n > 6) t->branches = element(v, 6);
  if (n > 7) t->max_order = element(v, 7);
  if (n > 9) t->dbh = element(v, 9) / 100;
}

/* TreeQSM 2.3 and 2.4's treedata struct; each figure it lacks stays NaN. */
static void treedata_struct(mat_reader *r, sylva_qsm *q, matvar_t *t) {
  if (t->class_type != MAT_C_STRUCT) {
    treedata_vector(q, t);
    return;
  }
  if (numel(t) == 0) return;
  static const struct {
    const char *name;
    size_t offset;
  } figures[] = {
      {"TreeHeight", offsetof(sylva_qsm_treedata, height)},
      {"DBHqsm", offsetof(sylva_qsm_treedata, dbh)},
      {"TotalVolume", offsetof(sylva_qsm_treedata, total_volume)},
      {"TotalLength", offsetof(sylva_qsm_treedata, total_length)},
      {"NumberBranches", offsetof(sylva_qsm_treedata, branches)},
      {"MaxBranchOrder", offsetof(sylva_qsm_treedata, max_order)},
  };
  q->has_treedata = true;
  for (size_t i = 0; i < sizeof figures / sizeof figures[0]; i++) {
    const matvar_t *f = field(r, t, 0, figures[i].name, "treedata", false);
    if (f && is_numeric(f) && f->data && numel(f) >= 1)
      *(double *)((char *)&q->treedata + figures[i].offset) = element(f, 0);
  }
}

/* TreeQSM 2.3 and 2.4: element `model` of the struct (array) s, named name. */
static int read_struct_model(mat_reader *r, sylva_qsm *q, matvar_t *s, const char *name,
                             int model) {
  size_t models = numel(s);
  char label[160], what[200];
  if (models == 0) return mat_fail(r, SYLVA_EINVAL, "%s is an empty struct array: no models", name);
  if (models > (size_t)INT_MAX) return mat_fail(r, SYLVA_ETOOBIG, "%s: too many models", name);
  q->models = (int)models;
  if ((size_t)model > models)
    return mat_fail(r, SYLVA_ERANGE, "no model %d: %s holds %zu model%s", model, name, models,
                    models == 1 ? "" : "s");
  size_t e = model ? (size_t)model - 1 : 0;
  if (models == 1)
    snprintf(label, sizeof label, "%s", name);
  else
    snprintf(label, sizeof label, "%s(%zu)", name, e + 1);
  matvar_t *cyl = field(r, s, e, "cylinder", label, true);
  if (!cyl) return r->status;
  snprintf(what, sizeof what, "%s.cylinder", label);
  char dims[64];
  if (cyl->class_type != MAT_C_STRUCT || numel(cyl) != 1)
    return mat_fail(r, SYLVA_EINVAL, "%s is %s (%s), not a 1x1 struct", what,
                    class_name(cyl->class_type), shape(cyl, dims, sizeof dims));
  /* The cylinder fields, each a column of one value per cylinder (start and axis
   * a row of three). */
  static const char *const names[] = {"radius", "length", "start", "axis", "parent"};
  matvar_t *v[5];
  size_t n = 0;
  char fl[5][232];
  for (int k = 0; k < 5; k++) {
    snprintf(fl[k], sizeof fl[k], "%s.%s", what, names[k]);
    if (!(v[k] = field(r, cyl, 0, names[k], what, true))) return r->status;
    if (numbers(r, v[k], fl[k], &n, k == 2 || k == 3 ? 3 : 1)) return r->status;
    if (n == 0) return mat_fail(r, SYLVA_EINVAL, "%s is empty: no cylinders", fl[0]);
  }
  if (alloc_cylinders(r, q, n)) return r->status;
  set_geometry(q, v[0], v[1], v[2], v[3]);
  if (set_parents(r, q, v[4], fl[4])) return r->status;
  /* Branch numbers and orders, when the model has them. */
  static const char *const ints[] = {"branch", "BranchOrder"};
  for (int k = 0; k < 2; k++) {
    matvar_t *b = field(r, cyl, 0, ints[k], what, false);
    if (!b) continue;
    char bl[232];
    snprintf(bl, sizeof bl, "%s.%s", what, ints[k]);
    if (numbers(r, b, bl, &n, 1) || set_ints(r, q, b, 0, bl, k == 1)) return r->status;
  }
  matvar_t *t = field(r, s, e, "treedata", label, false);
  if (t) treedata_struct(r, q, t);
  return r->status;
}

/* TreeQSM 2.0: the model as variables of the file. */
static int read_flat_model(mat_reader *r, sylva_qsm *q, mat_t *mat, int model,
                           const char *const *vars, size_t nvars) {
  q->models = 1;
  if (model > 1)
    return mat_fail(r, SYLVA_ERANGE, "no model %d: the file holds 1 model (TreeQSM 2.0 variables)",
                    model);
  static const char *const names[] = {"Rad", "Len", "Sta", "Axe", "CPar"};
  matvar_t *v[5] = {0};
  matvar_t *boc = NULL, *td = NULL;
  size_t n = 0;
  for (int k = 0; k < 5 && !r->status; k++) {
    bool found = false;
    for (size_t i = 0; i < nvars && !found; i++) found = strcmp(vars[i], names[k]) == 0;
    if (!found) {
      mat_fail(r, SYLVA_EINVAL,
               "no variable '%s' (TreeQSM 2.0 keeps its model in Rad, Len, Sta, Axe and CPar)",
               names[k]);
      break;
    }
    if (!(v[k] = read_variable(r, mat, names[k]))) break;
    if (numbers(r, v[k], names[k], &n, k == 2 || k == 3 ? 3 : 1)) break;
    if (n == 0) mat_fail(r, SYLVA_EINVAL, "Rad is empty: no cylinders");
  }
  if (!r->status && !alloc_cylinders(r, q, n)) {
    set_geometry(q, v[0], v[1], v[2], v[3]);
    set_parents(r, q, v[4], "CPar");
  }
  for (size_t i = 0; i < nvars && !r->status; i++) {
    if (strcmp(vars[i], "BoC") == 0) {
      /* Branch of cylinder: the branch, its order and the position in it. */
      if (!(boc = read_variable(r, mat, "BoC"))) break;
      char dims[64];
      if (!is_numeric(boc) || boc->rank != 2 || boc->dims[0] != n || boc->dims[1] < 2 || !boc->data)
        mat_fail(r, SYLVA_EINVAL, "BoC has shape %s; expected %zux3 (branch, order, position)",
                 shape(boc, dims, sizeof dims), n);
      else if (!set_ints(r, q, boc, 0, "BoC(:,1)", false))
        set_ints(r, q, boc, 1, "BoC(:,2)", true);
    } else if (!td && (strcmp(vars[i], "TreeData") == 0 || strcmp(vars[i], "treedata") == 0)) {
      if ((td = read_variable(r, mat, vars[i]))) {
        if (td->class_type == MAT_C_STRUCT)
          treedata_struct(r, q, td);
        else
          treedata_vector(q, td);
      }
    }
  }
  for (int k = 0; k < 5; k++)
    if (v[k]) Mat_VarFree(v[k]);
  if (boc) Mat_VarFree(boc);
  if (td) Mat_VarFree(td);
  return r->status;
}

/* ---- The file ---- */

static const char *const struct_names[] = {"QSM", "QSMs", "OptQSM"};

/* Whether struct info v has a field named name. */
static bool has_field(const matvar_t *v, const char *name) {
  if (v->class_type != MAT_C_STRUCT) return false;
  unsigned nf = Mat_VarGetNumberOfFields((matvar_t *)v);
  char *const *names = Mat_VarGetStructFieldnames(v);
  for (unsigned i = 0; names && i < nf; i++)
    if (names[i] && strcmp(names[i], name) == 0) return true;
  return false;
}

int sylva__qsm_read_mat(const char *path, int model, sylva_qsm *q, char *err, size_t errlen) {
  memset(q, 0, sizeof *q);
  no_treedata(q);
  mat_reader r = {.path = path, .err = err, .errlen = errlen};
  Mat_LogInitFunc("sylva", mat_log);
  mat_log_reset();
  mat_t *mat = Mat_Open(path, MAT_ACC_RDONLY);
  if (!mat)
    return mat_fail(&r, SYLVA_EINVAL, "not a MATLAB MAT-file (libmatio cannot open it%s%s)",
                    mat_log_text[0] ? ": " : "", mat_log_text);
  enum mat_ft version = Mat_GetVersion(mat);
  char **vars = NULL;
  size_t nvars = 0, cap = 0;
  const char *chosen = NULL;
  matvar_t *s = NULL;
  if (mat_log_bad) {
    /* Opened, but HDF5 could not open a MATLAB 7.3 file behind its header. */
    mat_fail(&r, SYLVA_EINVAL, "truncated or corrupt (libmatio: %s)", mat_log_text);
    goto done;
  }
  if (version != MAT_FT_MAT5 && version != MAT_FT_MAT73) {
    /* MATLAB 4 files have no header: libmatio takes any bytes for one. */
    mat_fail(&r, SYLVA_EINVAL, "not a MATLAB 5 or 7.3 MAT-file (TreeQSM saves those)");
    goto done;
  }
  /* The variables by name, and which holds the model: a TreeQSM struct by its
   * name, else any struct with a cylinder field, else TreeQSM 2.0's Rad. */
  const char *any_struct = NULL;
  bool flat = false;
  for (;;) {
    mat_log_reset();
    matvar_t *info = Mat_VarReadNextInfo(mat);
    if (mat_log_bad) {
      mat_fail(&r, SYLVA_EINVAL, "truncated or corrupt %s%s%s (libmatio: %s)",
               nvars ? "after variable '" : "before its first variable",
               nvars ? vars[nvars - 1] : "", nvars ? "'" : "", mat_log_text);
      if (info) Mat_VarFree(info);
      goto done;
    }
    if (!info) break;
    if (info->name) {
      if (nvars == cap) {
        size_t m = cap ? 2 * cap : 16;
        char **g = realloc(vars, m * sizeof *g);
        if (!g) {
          Mat_VarFree(info);
          mat_fail(&r, SYLVA_ENOMEM, "out of memory");
          goto done;
        }
        vars = g;
        cap = m;
      }
      if (!(vars[nvars] = strdup(info->name))) {
        Mat_VarFree(info);
        mat_fail(&r, SYLVA_ENOMEM, "out of memory");
        goto done;
      }
      for (size_t k = 0; k < 3 && !chosen; k++)
        if (strcmp(info->name, struct_names[k]) == 0) chosen = vars[nvars];
      if (!any_struct && has_field(info, "cylinder")) any_struct = vars[nvars];
      if (strcmp(info->name, "Rad") == 0) flat = true;
      nvars++;
    }
    Mat_VarFree(info);
  }
  if (!chosen) chosen = any_struct;
  if (chosen) {
    if (!(s = read_variable(&r, mat, chosen))) goto done;
    char dims[64];
    if (s->class_type != MAT_C_STRUCT) {
      mat_fail(&r, SYLVA_EINVAL, "%s is %s (%s), not a TreeQSM struct", chosen,
               class_name(s->class_type), shape(s, dims, sizeof dims));
      goto done;
    }
    read_struct_model(&r, q, s, chosen, model);
  } else if (flat) {
    read_flat_model(&r, q, mat, model, (const char *const *)vars, nvars);
  } else {
    char list[256] = "";
    size_t at = 0;
    for (size_t i = 0; i < nvars && at < sizeof list; i++) {
      int w = snprintf(list + at, sizeof list - at, "%s%s", i ? ", " : "", vars[i]);
      if (w < 0) break;
      at += (size_t)w;
    }
    mat_fail(&r, SYLVA_EINVAL,
             "no TreeQSM model: no struct QSM, QSMs or OptQSM (or other with a 'cylinder' field) "
             "and no TreeQSM 2.0 variables (Rad, Len, Sta, Axe, CPar); the file holds %s%s",
             nvars ? "" : "no variables", list);
  }
  if (!r.status) {
    char msg[512];
    int rc = sylva__qsm_check_named(q, NULL, NULL, msg, sizeof msg);
    if (rc) {
      char where[160];
      if (!chosen)
        snprintf(where, sizeof where, "TreeQSM 2.0 variables");
      else if (q->models == 1)
        snprintf(where, sizeof where, "%s", chosen);
      else
        snprintf(where, sizeof where, "%s(%d)", chosen, model ? model : 1);
      mat_fail(&r, rc, "%s: %s", where, msg);
    }
  }

done:
  if (s) Mat_VarFree(s);
  for (size_t i = 0; i < nvars; i++) free(vars[i]);
  free(vars);
  Mat_Close(mat);
  if (r.status) {
    sylva_qsm_free(q);
    return r.status;
  }
  sylva__qsm_normalise(q);
  return SYLVA_OK;
}
