#include "utdb.h"

#include "table.h"

#include <assert.h>
#include <csv.h>
#include <errno.h>
#include <gsl/gsl_poly.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The tables built into the binary by embed.py (meson custom targets). */
extern const char sylva__utdb_ts6[];
extern const size_t sylva__utdb_ts6_len;
extern const char sylva__utdb_ts2[];
extern const size_t sylva__utdb_ts2_len;

#define TS6_FILE "TS6_Growth_coefficients.csv"
#define TS2_FILE "TS2_Regional_species_and_counts.csv"

/* A row with more fields than this is not one of the tables (they have 21 and 15). */

struct sylva_utdb {
  sylva_utdb_species *species;
  int count, cap;
};

/* ---- Equation forms (TS4 with the errata) ---- */

typedef enum form_family {
  FAMILY_POLY,          /* a + b x + c x² + d x³ + e x⁴ up to the degree */
  FAMILY_LOGLOG_INSIDE, /* loglogw1: exp(a + b ln(ln(x+1) + m/2)) */
  FAMILY_LOGLOG,        /* exp(a + b ln(ln(x+1)) + w m/2) */
  FAMILY_EXP            /* exp(a + b x + w m/2) */
} form_family;

typedef enum form_weight { WEIGHT_ONE, WEIGHT_SQRT, WEIGHT_X, WEIGHT_X2 } form_weight;

typedef struct form_def {
  const char *name;
  form_family family;
  int degree; /* polynomials: 1..4 */
  form_weight weight;
} form_def;

static const form_def forms[] = {
    {"lin", FAMILY_POLY, 1, WEIGHT_ONE},
    {"quad", FAMILY_POLY, 2, WEIGHT_ONE},
    {"cub", FAMILY_POLY, 3, WEIGHT_ONE},
    {"quart", FAMILY_POLY, 4, WEIGHT_ONE},
    {"loglogw1", FAMILY_LOGLOG_INSIDE, 0, WEIGHT_ONE},
    {"loglogw2", FAMILY_LOGLOG, 0, WEIGHT_SQRT},
    {"loglogw3", FAMILY_LOGLOG, 0, WEIGHT_X},
    {"loglogw4", FAMILY_LOGLOG, 0, WEIGHT_X2},
    {"expow1", FAMILY_EXP, 0, WEIGHT_ONE},
    {"expow2", FAMILY_EXP, 0, WEIGHT_SQRT},
    {"expow3", FAMILY_EXP, 0, WEIGHT_X},
    {"expow4", FAMILY_EXP, 0, WEIGHT_X2},
};

static const form_def *form_find(const char *name) {
  for (size_t i = 0; i < sizeof forms / sizeof forms[0]; i++)
    if (strcmp(forms[i].name, name) == 0) return &forms[i];
  return NULL;
}

/* How many of a..e a form needs: the log and exponential forms keep the MSE in c. */
static int form_coefficients(const form_def *f) {
  return f->family == FAMILY_POLY ? f->degree + 1 : 3;
}

static double weight_at(form_weight w, double x) {
  switch (w) {
  case WEIGHT_ONE: return 1.0;
  case WEIGHT_SQRT: return sqrt(x);
  case WEIGHT_X: return x;
  case WEIGHT_X2: return x * x;
  }
  return NAN;
}

static double form_eval(const form_def *f, const sylva_utdb_curve *c, double x) {
  switch (f->family) {
  case FAMILY_POLY: {
    /* Only the form's own coefficients: a cell the form does not use is not part of
     * the equation, whatever it holds. */
    double cc = f->degree >= 2 ? c->c : 0.0, d = f->degree >= 3 ? c->d : 0.0,
           e = f->degree >= 4 ? c->e : 0.0;
    return c->a + c->b * x + cc * x * x + d * x * x * x + e * x * x * x * x;
  }
  case FAMILY_LOGLOG_INSIDE: return exp(c->a + c->b * log(log(x + 1.0) + c->mse / 2.0));
  case FAMILY_LOGLOG:
    return exp(c->a + c->b * log(log(x + 1.0)) + weight_at(f->weight, x) * c->mse / 2.0);
  case FAMILY_EXP: return exp(c->a + c->b * x + weight_at(f->weight, x) * c->mse / 2.0);
  }
  return NAN;
}

double sylva_utdb_eval(const sylva_utdb_curve *c, double x) {
  if (!c || !c->present) return NAN;
  const form_def *f = form_find(c->form);
  return f ? form_eval(f, c, x) : NAN;
}

/* The points where the equation's slope is zero (maxima, minima or inflections; the
 * caller compares values, so a minimum among them does no harm). At most 3. */
static int stationary_points(const form_def *f, const sylva_utdb_curve *c, double out[3]) {
  switch (f->family) {
  case FAMILY_POLY:
    switch (f->degree) {
    case 2:
      if (c->c == 0.0) return 0;
      out[0] = -c->b / (2.0 * c->c);
      return 1;
    case 3: /* 3d x² + 2c x + b = 0; GSL takes a zero d as the linear case */
      return gsl_poly_solve_quadratic(3.0 * c->d, 2.0 * c->c, c->b, &out[0], &out[1]);
    case 4:
      if (c->e == 0.0)
        return gsl_poly_solve_quadratic(3.0 * c->d, 2.0 * c->c, c->b, &out[0], &out[1]);
      /* 4e x³ + 3d x² + 2c x + b = 0, made monic */
      return gsl_poly_solve_cubic(3.0 * c->d / (4.0 * c->e), 2.0 * c->c / (4.0 * c->e),
                                  c->b / (4.0 * c->e), &out[0], &out[1], &out[2]);
    default: return 0;
    }
  case FAMILY_LOGLOG_INSIDE:
    /* ln(ln(x+1) + m/2) rises with x: monotonic, the ends hold the extremes. */
    return 0;
  case FAMILY_LOGLOG:
    /* The slope has the sign of b + (m/2) w'(x) (x+1) ln(x+1), whose second term
     * rises from 0 for each weight: for m >= 0 a turn is a minimum, never a peak. */
    return 0;
  case FAMILY_EXP:
    switch (f->weight) {
    case WEIGHT_SQRT: /* b + m / (4 √x) = 0 */
      if (c->b == 0.0 || c->mse == 0.0) return 0;
      if ((c->b < 0.0) == (c->mse < 0.0)) return 0;
      out[0] = (c->mse / (4.0 * c->b)) * (c->mse / (4.0 * c->b));
      return 1;
    case WEIGHT_X2: /* b + m x = 0 */
      if (c->mse == 0.0) return 0;
      out[0] = -c->b / c->mse;
      return 1;
    case WEIGHT_ONE:
    case WEIGHT_X: return 0; /* a constant slope */
    }
    return 0;
  }
  return 0;
}

double sylva_utdb_eval_clamped(const sylva_utdb_curve *c, double x) {
  if (!c || !c->present || isnan(x)) return NAN;
  const form_def *f = form_find(c->form);
  if (!f) return NAN;
  double lo = c->x_min, hi = c->x_max;
  if (!(lo <= hi)) return NAN; /* a NAN or reversed range: nowhere applies */
  if (x < lo) x = lo;
  if (x > hi) x = hi;
  /* fmax ignores a NAN, so one undefined end does not hide the other's value. */
  double best = fmax(form_eval(f, c, lo), form_eval(f, c, x));
  double p[3];
  int n = stationary_points(f, c, p);
  for (int i = 0; i < n; i++)
    if (p[i] > lo && p[i] < x) best = fmax(best, form_eval(f, c, p[i]));
  return best;
}

int sylva_utdb_chain(const sylva_utdb_species *s, double age, bool clamp,
                     sylva_utdb_sizes *out) {
  assert(s && out);
  *out = (sylva_utdb_sizes){age, NAN, NAN, NAN, NAN, NAN};
  if (!isfinite(age) || age < 0.0) return SYLVA_ERANGE;
  double (*eval)(const sylva_utdb_curve *, double) =
      clamp ? sylva_utdb_eval_clamped : sylva_utdb_eval;
  double dbh = eval(&s->curve[SYLVA_UTDB_DBH], age);
  out->dbh_cm = dbh;
  out->height_m = eval(&s->curve[SYLVA_UTDB_HEIGHT], dbh);
  out->crown_dia_m = eval(&s->curve[SYLVA_UTDB_CROWN_DIA], dbh);
  out->crown_ht_m = eval(&s->curve[SYLVA_UTDB_CROWN_HT], dbh);
  out->leaf_area_m2 = eval(&s->curve[SYLVA_UTDB_LEAF_AREA], dbh);
  return SYLVA_OK;
}

bool sylva_utdb_complete(const sylva_utdb_species *s) {
  assert(s);
  return s->curve[SYLVA_UTDB_DBH].present && s->curve[SYLVA_UTDB_HEIGHT].present &&
         s->curve[SYLVA_UTDB_CROWN_DIA].present && s->curve[SYLVA_UTDB_CROWN_HT].present;
}

/* ---- TS2: species names ---- */

enum { TS2_REGION, TS2_SCIENTIFIC, TS2_COMMON, TS2_CODE, TS2_TYPE, TS2_COLUMNS };
_Static_assert(TS2_COLUMNS <= SYLVA__TABLE_MAX_COLUMNS, "columns.index too small for TS2");
static const char *const ts2_names[TS2_COLUMNS] = {"Region", "Scientific Name", "Common Name",
                                                   "SpCode", "Tree Type"};

typedef struct ts2_entry {
  char region[12], code[16], scientific[96], common[96], type[8];
  size_t line;
} ts2_entry;

typedef struct ts2_list {
  sylva__columns cols;
  ts2_entry *entry;
  size_t count, cap;
} ts2_list;

static int ts2_row(sylva__table *t, const char *const *field, size_t n) {
  ts2_list *l = t->ctx;
  if (t->rows == 0) return sylva__columns_header(t, &l->cols, field, n);
  int rc = sylva__columns_check_row(t, &l->cols, n);
  if (rc) return rc;
  if (l->count == l->cap) {
    size_t cap = l->cap ? 2 * l->cap : 512;
    ts2_entry *e = realloc(l->entry, cap * sizeof *e);
    if (!e) return sylva__table_nomem(t);
    l->entry = e;
    l->cap = cap;
  }
  ts2_entry *e = &l->entry[l->count];
  e->line = t->row_line;
  const sylva__columns *c = &l->cols;
  if ((rc = sylva__cell_text(t, c, field, TS2_REGION, true, e->region, sizeof e->region)) ||
      (rc = sylva__cell_text(t, c, field, TS2_CODE, true, e->code, sizeof e->code)) ||
      (rc = sylva__cell_text(t, c, field, TS2_SCIENTIFIC, false, e->scientific, sizeof e->scientific)) ||
      (rc = sylva__cell_text(t, c, field, TS2_COMMON, false, e->common, sizeof e->common)) ||
      (rc = sylva__cell_text(t, c, field, TS2_TYPE, false, e->type, sizeof e->type)))
    return rc;
  for (size_t i = 0; i < l->count; i++)
    if (strcmp(l->entry[i].region, e->region) == 0 && strcmp(l->entry[i].code, e->code) == 0)
      return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "species %s %s again (first on line %zu)",
                        e->region, e->code, l->entry[i].line);
  l->count++;
  return SYLVA_OK;
}

static const ts2_entry *ts2_find(const ts2_list *l, const char *region, const char *code) {
  for (size_t i = 0; i < l->count; i++)
    if (strcmp(l->entry[i].region, region) == 0 && strcmp(l->entry[i].code, code) == 0)
      return &l->entry[i];
  return NULL;
}

/* ---- TS6: the equations ---- */

enum {
  TS6_REGION,
  TS6_SCIENTIFIC,
  TS6_CODE,
  TS6_FROM,
  TS6_PREDICTS,
  TS6_FORM,
  TS6_A,
  TS6_B,
  TS6_C,
  TS6_D,
  TS6_E,
  TS6_APPS_MIN,
  TS6_APPS_MAX,
  TS6_N,
  TS6_R2,
  TS6_DATA_MIN,
  TS6_DATA_MAX,
  TS6_COLUMNS
};
_Static_assert(TS6_COLUMNS <= SYLVA__TABLE_MAX_COLUMNS, "columns.index too small for TS6");
static const char *const ts6_names[TS6_COLUMNS] = {
    "Region", "Scientific Name", "SpCode", "Independent variable", "Predicts component",
    "EqName", "a", "b", "c", "d", "e", "Apps min", "Apps max", "n", "adj R2",
    "Data min (from raw data)", "Data max (from raw data)"};

/* The equations TS6 holds: independent -> predicted variable, and the measure it is
 * kept as (-1: checked, then left out). */
static const struct {
  const char *from, *predicts;
  int measure;
} equations[] = {
    {"age", "dbh", SYLVA_UTDB_DBH},
    {"dbh", "tree ht", SYLVA_UTDB_HEIGHT},
    {"dbh", "crown dia", SYLVA_UTDB_CROWN_DIA},
    {"dbh", "crown ht", SYLVA_UTDB_CROWN_HT},
    {"dbh", "leaf area", SYLVA_UTDB_LEAF_AREA},
    {"dbh", "age", SYLVA_UTDB_AGE},
    {"cdia", "dbh", -1},
};

typedef struct ts6_state {
  sylva__columns cols;
  sylva_utdb *u;
  const ts2_list *names;
} ts6_state;

static sylva_utdb_species *species_get(sylva__table *t, ts6_state *st, const char *region,
                                       const char *code, const char *scientific) {
  sylva_utdb *u = st->u;
  /* A species' rows are together in TS6: the last one is nearly always it. */
  for (int i = u->count - 1; i >= 0; i--)
    if (strcmp(u->species[i].region, region) == 0 && strcmp(u->species[i].code, code) == 0)
      return &u->species[i];
  if (u->count == u->cap) {
    if (u->cap > INT_MAX / 2) {
      sylva__table_nomem(t);
      return NULL;
    }
    int cap = u->cap ? 2 * u->cap : 512;
    sylva_utdb_species *s = realloc(u->species, (size_t)cap * sizeof *s);
    if (!s) {
      sylva__table_nomem(t);
      return NULL;
    }
    u->species = s;
    u->cap = cap;
  }
  sylva_utdb_species *s = &u->species[u->count++];
  memset(s, 0, sizeof *s);
  /* Both buffers are the same size as TS6's cells, checked by sylva__cell_text. */
  memcpy(s->region, region, strlen(region) + 1);
  memcpy(s->code, code, strlen(code) + 1);
  const ts2_entry *e = ts2_find(st->names, region, code);
  if (e) {
    memcpy(s->scientific, e->scientific, sizeof s->scientific);
    memcpy(s->common, e->common, sizeof s->common);
    memcpy(s->type, e->type, sizeof s->type);
  } else {
    memcpy(s->scientific, scientific, strlen(scientific) + 1);
  }
  s->age_min = s->age_max = NAN;
  for (int m = 0; m < SYLVA_UTDB_MEASURES; m++)
    s->curve[m] = (sylva_utdb_curve){.apps_min = NAN, .apps_max = NAN, .data_min = NAN,
                                     .data_max = NAN, .r2 = NAN, .mse = NAN,
                                     .x_min = NAN, .x_max = NAN};
  return s;
}

static int ts6_row(sylva__table *t, const char *const *field, size_t n) {
  ts6_state *st = t->ctx;
  const sylva__columns *c = &st->cols;
  if (t->rows == 0) return sylva__columns_header(t, &st->cols, field, n);
  int rc = sylva__columns_check_row(t, c, n);
  if (rc) return rc;

  char region[sizeof ((sylva_utdb_species *)0)->region];
  char code[sizeof ((sylva_utdb_species *)0)->code];
  char scientific[sizeof ((sylva_utdb_species *)0)->scientific];
  char from[16], predicts[16];
  sylva_utdb_curve cv = {.present = true};
  if ((rc = sylva__cell_text(t, c, field, TS6_REGION, true, region, sizeof region)) ||
      (rc = sylva__cell_text(t, c, field, TS6_CODE, true, code, sizeof code)) ||
      (rc = sylva__cell_text(t, c, field, TS6_SCIENTIFIC, false, scientific, sizeof scientific)) ||
      (rc = sylva__cell_text(t, c, field, TS6_FROM, true, from, sizeof from)) ||
      (rc = sylva__cell_text(t, c, field, TS6_PREDICTS, true, predicts, sizeof predicts)) ||
      (rc = sylva__cell_text(t, c, field, TS6_FORM, true, cv.form, sizeof cv.form)))
    return rc;

  int measure = -2;
  for (size_t i = 0; i < sizeof equations / sizeof equations[0]; i++)
    if (strcmp(equations[i].from, from) == 0 && strcmp(equations[i].predicts, predicts) == 0)
      measure = equations[i].measure;
  if (measure == -2)
    return sylva__table_fail(t, t->row_line, SYLVA_EINVAL,
                      "columns %zu and %zu: no such equation as '%s' -> '%s'",
                      c->index[TS6_FROM] + 1, c->index[TS6_PREDICTS] + 1, from, predicts);
  const form_def *f = form_find(cv.form);
  if (!f)
    return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "column %zu (%s): unknown equation form '%s'",
                      c->index[TS6_FORM] + 1, c->names[TS6_FORM], cv.form);

  /* The form says which coefficients must be there; the others may be empty (0). */
  int needed = form_coefficients(f);
  double *coef[5] = {&cv.a, &cv.b, &cv.c, &cv.d, &cv.e};
  for (int k = 0; k < 5; k++) {
    if ((rc = sylva__cell_number(t, c, field, TS6_A + k, k < needed, coef[k]))) return rc;
    if (isnan(*coef[k])) *coef[k] = 0.0;
  }
  if (f->family != FAMILY_POLY) {
    if (cv.c < 0.0)
      return sylva__table_fail(t, t->row_line, SYLVA_EINVAL,
                        "column %zu (%s): the MSE of a %s equation is negative (%g)",
                        c->index[TS6_C] + 1, c->names[TS6_C], cv.form, cv.c);
    cv.mse = cv.c;
  } else {
    cv.mse = NAN;
  }
  if ((rc = sylva__cell_number(t, c, field, TS6_APPS_MIN, false, &cv.apps_min)) ||
      (rc = sylva__cell_number(t, c, field, TS6_APPS_MAX, false, &cv.apps_max)) ||
      (rc = sylva__cell_number(t, c, field, TS6_DATA_MIN, false, &cv.data_min)) ||
      (rc = sylva__cell_number(t, c, field, TS6_DATA_MAX, false, &cv.data_max)) ||
      (rc = sylva__cell_number(t, c, field, TS6_R2, false, &cv.r2)) ||
      (rc = sylva__cell_count(t, c, field, TS6_N, &cv.n)))
    return rc;
  cv.x_min = cv.x_max = NAN;

  sylva_utdb_species *s = species_get(t, st, region, code, scientific);
  if (!s) return t->status;
  if (measure < 0) return SYLVA_OK;
  if (s->curve[measure].present)
    return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "a second '%s' -> '%s' equation for %s %s",
                      from, predicts, region, code);
  s->curve[measure] = cv;
  return SYLVA_OK;
}

/* Where the equations apply (see sylva_utdb_parse in utdb.h). */
static void species_ranges(sylva_utdb_species *s) {
  const sylva_utdb_curve *age = &s->curve[SYLVA_UTDB_AGE];
  if (age->present && isfinite(age->apps_min) && isfinite(age->apps_max) &&
      age->apps_min <= age->apps_max) {
    s->age_min = age->apps_min;
    s->age_max = age->apps_max;
  }
  sylva_utdb_curve *dbh = &s->curve[SYLVA_UTDB_DBH];
  bool ages = !isnan(s->age_min);
  /* Without a known range only the sign is certain: ages and diameters are >= 0. */
  dbh->x_min = ages ? fmax(0.0, s->age_min) : 0.0;
  dbh->x_max = ages ? s->age_max : INFINITY;
  bool diameters = dbh->present && isfinite(dbh->apps_min) && isfinite(dbh->apps_max) &&
                   dbh->apps_min <= dbh->apps_max;
  for (int m = 0; m < SYLVA_UTDB_MEASURES; m++) {
    if (m == SYLVA_UTDB_DBH) continue;
    s->curve[m].x_min = diameters ? fmax(0.0, dbh->apps_min) : 0.0;
    s->curve[m].x_max = diameters ? dbh->apps_max : INFINITY;
  }
}

int sylva_utdb_parse(const char *ts6, size_t ts6_len, const char *ts2, size_t ts2_len,
                     sylva_utdb **out, char *err, size_t errlen) {
  assert(out && (ts6 || !ts6_len) && (ts2 || !ts2_len));
  *out = NULL;
  if (err && errlen) err[0] = '\0';
  ts2_list names = {.cols = {.names = ts2_names, .count = TS2_COLUMNS}};
  sylva__table t2 = {.file = TS2_FILE, .err = err, .errlen = errlen, .on_row = ts2_row, .ctx = &names};
  int rc = sylva__table_read(&t2, ts2 ? ts2 : "", ts2_len);
  sylva__table_release(&t2);
  if (rc) {
    free(names.entry);
    return rc;
  }
  sylva_utdb *u = calloc(1, sizeof *u);
  if (!u) {
    free(names.entry);
    if (err && errlen) snprintf(err, errlen, "out of memory");
    return SYLVA_ENOMEM;
  }
  ts6_state st = {.cols = {.names = ts6_names, .count = TS6_COLUMNS}, .u = u, .names = &names};
  sylva__table t6 = {.file = TS6_FILE, .err = err, .errlen = errlen, .on_row = ts6_row, .ctx = &st};
  rc = sylva__table_read(&t6, ts6 ? ts6 : "", ts6_len);
  sylva__table_release(&t6);
  free(names.entry);
  if (rc) {
    sylva_utdb_free(u);
    return rc;
  }
  for (int i = 0; i < u->count; i++) species_ranges(&u->species[i]);
  *out = u;
  return SYLVA_OK;
}

int sylva_utdb_builtin(sylva_utdb **out) {
  char err[256];
  return sylva_utdb_parse(sylva__utdb_ts6, sylva__utdb_ts6_len, sylva__utdb_ts2,
                          sylva__utdb_ts2_len, out, err, sizeof err);
}

void sylva_utdb_free(sylva_utdb *u) {
  if (!u) return;
  free(u->species);
  free(u);
}

int sylva_utdb_count(const sylva_utdb *u) {
  assert(u);
  return u->count;
}

const sylva_utdb_species *sylva_utdb_at(const sylva_utdb *u, int i) {
  assert(u);
  return i >= 0 && i < u->count ? &u->species[i] : NULL;
}

const sylva_utdb_species *sylva_utdb_find(const sylva_utdb *u, const char *region,
                                          const char *code) {
  assert(u);
  if (!region || !code) return NULL;
  for (int i = 0; i < u->count; i++)
    if (strcmp(u->species[i].region, region) == 0 && strcmp(u->species[i].code, code) == 0)
      return &u->species[i];
  return NULL;
}
