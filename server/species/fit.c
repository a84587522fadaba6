/* Calibration of a species in years to measured growth (fit.h; docs/model.md,
 * "Calibration"). */
#include "fit.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_fit.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_multimin.h>
#include <gsl/gsl_vector.h>
#include <stdarg.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/world.h"
#include "table.h"

#define MAX_SEEDS 16

sylva_fit_options sylva_fit_default_options(void) {
  return (sylva_fit_options){.seeds = 3, .threads = 2, .max_evals = 40, .rho = 0.0};
}

/* The base species' shedding threshold and column shade (the crown base's control
 * moves both, set_crown). */
#define R_S 0.5
#define SHADE_COLUMN 0.002

sylva_species_def sylva_fit_base_species(double rho) {
  /* The years model's fixed choices, each measured (docs/model.md, "Species in
   * years"): counts that act as lengths, shedding against the stem's own light,
   * buds that break the season after they form, and leaves on the last three
   * seasons' shoots. */
  sylva_species_def d = sylva_default_species_def();
  d.rho = rho;
  d.ref_rho = rho;
  d.years = 1;
  d.acclimation = 1.0;
  d.r_s = R_S;
  d.shade_column = SHADE_COLUMN;
  d.apical_zone = 1;
  d.leaf_age = 3;
  d.tau = 0;
  d.initial_nodes = 2;
  d.growth.kind = SYLVA_EQ_LOGISTIC;
  d.growth.p[0] = 2.0;
  d.growth.p[1] = 60.0;
  d.growth.p[2] = 0.1;
  d.gamma = 0.3;
  d.r_tip = 0.005;
  d.pipe_exponent = 2.5;
  return d;
}

double sylva_fit_error(double grown, double target) {
  if (!isfinite(grown) || !isfinite(target) || target <= 0.0) return NAN;
  return grown / target - 1.0;
}

static double measure_of(const sylva_fit_sizes *s, int m) {
  switch (m) {
  case 0: return s->height;
  case 1: return s->dbh_cm;
  case 2: return s->crown_dia;
  default: return s->crown_ht;
  }
}

static void fail(char *err, size_t errlen, const char *msg) {
  if (err && errlen) snprintf(err, errlen, "%s", msg);
}

/* ---- targets -------------------------------------------------------------------- */

int sylva_fit_targets_utdb(const sylva_utdb_species *s, sylva_fit_targets *out, char *err,
                           size_t errlen) {
  if (!sylva_utdb_complete(s)) {
    if (err && errlen)
      snprintf(err, errlen, "%s:%s lacks one of the curves of dbh, height, crown diameter "
               "and crown height", s->region, s->code);
    return SYLVA_EINVAL;
  }
  double lo = isfinite(s->age_min) && s->age_min > 0.0 ? ceil(s->age_min) : 0.0;
  double hi = isfinite(s->age_max) ? floor(s->age_max) : 60.0;
  if (hi > SYLVA_FIT_MAX_YEARS) hi = SYLVA_FIT_MAX_YEARS;
  if (hi < lo + 5.0) {
    if (err && errlen)
      snprintf(err, errlen, "%s:%s: its age range (%g to %g years) is too short to fit",
               s->region, s->code, s->age_min, s->age_max);
    return SYLVA_EINVAL;
  }
  memset(out, 0, sizeof *out);
  out->first = (int)lo;
  out->years = (int)hi;
  for (int a = 0; a <= out->years; a++) {
    sylva_utdb_sizes z;
    /* ages below the data's first are held at it: the clamped chain */
    int rc = sylva_utdb_chain(s, (double)a, true, &z);
    if (rc) return rc;
    out->at[a] = (sylva_fit_sizes){z.height_m, z.dbh_cm, z.crown_dia_m, z.crown_ht_m};
  }
  return SYLVA_OK;
}

/* ---- nonlinear least squares (GSL) --------------------------------------------- */

typedef int (*residual_fn)(const gsl_vector *x, void *ctx, gsl_vector *f);

/* Minimises the sum of squared residuals over x (p parameters, n residuals), from x;
 * returns that sum, or NAN when the fit fails. */
static double least_squares(residual_fn fn, void *ctx, size_t n, size_t p, double *x) {
  gsl_multifit_nlinear_fdf fdf = {.f = fn, .df = NULL, .fvv = NULL, .n = n, .p = p, .params = ctx};
  gsl_multifit_nlinear_parameters params = gsl_multifit_nlinear_default_parameters();
  gsl_multifit_nlinear_workspace *w =
      gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &params, n, p);
  if (!w) return NAN;
  gsl_vector_view xv = gsl_vector_view_array(x, p);
  double sse = NAN;
  int info = 0;
  if (gsl_multifit_nlinear_init(&xv.vector, &fdf, w) == GSL_SUCCESS) {
    int rc = gsl_multifit_nlinear_driver(200, 1e-10, 1e-10, 1e-10, NULL, NULL, &info, w);
    /* too many iterations still leaves the best point found */
    if (rc == GSL_SUCCESS || rc == GSL_EMAXITER) {
      const gsl_vector *f = gsl_multifit_nlinear_residual(w);
      double s = 0.0;
      for (size_t i = 0; i < n; i++) s += gsl_vector_get(f, i) * gsl_vector_get(f, i);
      memcpy(x, gsl_multifit_nlinear_position(w)->data, p * sizeof *x);
      sse = s;
    }
  }
  gsl_multifit_nlinear_free(w);
  return sse;
}

/* The logistic with a fixed start: X(t) = m / (1 + (m / x0 - 1) e^(-r t)). */
static double logistic(double x0, double m, double r, double t) {
  return m / (1.0 + (m / x0 - 1.0) * exp(-r * t));
}

/* ---- the user's trees ------------------------------------------------------------- */

static const char *const csv_names[] = {"age", "dbh_cm", "height_m", "crown_diameter_m",
                                        "crown_height_m"};
enum { CSV_COLUMNS = 5 };

typedef struct csv_state {
  sylva__columns cols;
  sylva_fit_tree *trees;
  int count, cap;
} csv_state;

static int csv_row(sylva__table *t, const char *const *field, size_t n) {
  csv_state *st = t->ctx;
  if (t->rows == 0) {
    /* the header exactly: a column named otherwise is a wrong file, not a guess */
    if (n != CSV_COLUMNS)
      return sylva__table_fail(t, t->row_line, SYLVA_EINVAL,
                               "the header must be age,dbh_cm,height_m,crown_diameter_m,"
                               "crown_height_m (%zu columns found)", n);
    for (size_t i = 0; i < n; i++)
      if (strcmp(field[i], csv_names[i]) != 0)
        return sylva__table_fail(t, t->row_line, SYLVA_EINVAL,
                                 "column %zu of the header is '%.40s', expected '%s'", i + 1,
                                 field[i], csv_names[i]);
    return sylva__columns_header(t, &st->cols, field, n);
  }
  int rc = sylva__columns_check_row(t, &st->cols, n);
  if (rc) return rc;
  double v[CSV_COLUMNS];
  for (int k = 0; k < CSV_COLUMNS; k++) {
    rc = sylva__cell_number(t, &st->cols, field, k, k == 0, &v[k]);
    if (rc) return rc;
    if (v[k] < 0.0)
      return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "column %d (%s): %g is negative",
                               k + 1, csv_names[k], v[k]);
  }
  if (v[0] > SYLVA_FIT_MAX_YEARS)
    return sylva__table_fail(t, t->row_line, SYLVA_EINVAL, "column 1 (age): %g is older than %d "
                             "years", v[0], SYLVA_FIT_MAX_YEARS);
  if (st->count == st->cap) {
    int cap = st->cap ? 2 * st->cap : 64;
    sylva_fit_tree *p = realloc(st->trees, (size_t)cap * sizeof *p);
    if (!p) return sylva__table_nomem(t);
    st->trees = p;
    st->cap = cap;
  }
  st->trees[st->count++] = (sylva_fit_tree){v[0], v[1], v[2], v[3], v[4]};
  return SYLVA_OK;
}

int sylva_fit_read_csv(const char *text, size_t len, sylva_fit_tree **trees, int *count,
                       char *err, size_t errlen) {
  csv_state st = {.cols = {.names = csv_names, .count = CSV_COLUMNS}};
  sylva__table t = {.file = "data", .err = err, .errlen = errlen, .on_row = csv_row, .ctx = &st};
  int rc = sylva__table_read(&t, text, len);
  sylva__table_release(&t);
  int heights = 0;
  for (int i = 0; !rc && i < st.count; i++) heights += isfinite(st.trees[i].height);
  if (!rc && heights == 0) {
    fail(err, errlen, "data: no tree has a height (height_m is empty in every row)");
    rc = SYLVA_EINVAL;
  } else if (!rc && heights < SYLVA_FIT_MIN_TREES) {
    if (err && errlen)
      snprintf(err, errlen, "data: %d trees with a height; at least %d are needed to fit a curve",
               heights, SYLVA_FIT_MIN_TREES);
    rc = SYLVA_EINVAL;
  }
  if (rc) {
    free(st.trees);
    return rc;
  }
  *trees = st.trees;
  *count = st.count;
  return SYLVA_OK;
}

typedef struct curve_fit {
  const double *age, *value;
  size_t n;
} curve_fit;

/* x = ln s0, ln m, ln r: positive by construction */
static int curve_residuals(const gsl_vector *x, void *ctx, gsl_vector *f) {
  const curve_fit *c = ctx;
  double s0 = exp(gsl_vector_get(x, 0)), m = exp(gsl_vector_get(x, 1)),
         r = exp(gsl_vector_get(x, 2));
  for (size_t i = 0; i < c->n; i++)
    gsl_vector_set(f, i, logistic(s0, m, r, c->age[i]) - c->value[i]);
  return GSL_SUCCESS;
}

/* Fits measure k of the trees (dbh, height, crown diameter, crown height). */
static sylva_fit_curve fit_curve(const sylva_fit_tree *trees, int count, int k, double *age,
                                 double *value) {
  sylva_fit_curve out = {0};
  size_t n = 0;
  double youngest = INFINITY, young_v = NAN, top = 0.0, sum = 0.0;
  for (int i = 0; i < count; i++) {
    const double vals[4] = {trees[i].height, trees[i].dbh_cm, trees[i].crown_dia,
                            trees[i].crown_ht};
    double v = vals[k];
    if (!isfinite(v) || v <= 0.0) continue;
    age[n] = trees[i].age;
    value[n] = v;
    sum += v;
    if (trees[i].age < youngest) youngest = trees[i].age, young_v = v;
    if (v > top) top = v;
    n++;
  }
  if (n < SYLVA_FIT_MIN_TREES) return out;
  curve_fit c = {age, value, n};
  double x[3] = {log(young_v * 0.8), log(top * 1.2), log(0.1)};
  double sse = least_squares(curve_residuals, &c, n, 3, x);
  if (!isfinite(sse)) return out;
  double mean = sum / (double)n, sst = 0.0;
  for (size_t i = 0; i < n; i++) sst += (value[i] - mean) * (value[i] - mean);
  out = (sylva_fit_curve){true, exp(x[0]), exp(x[1]), exp(x[2]), (int)n,
                          sst > 0.0 ? 1.0 - sse / sst : 0.0};
  return out;
}

int sylva_fit_targets_trees(const sylva_fit_tree *trees, int count, sylva_fit_targets *out,
                            sylva_fit_curve curves[4], char *err, size_t errlen) {
  double *age = malloc((size_t)(count ? count : 1) * sizeof *age);
  double *value = malloc((size_t)(count ? count : 1) * sizeof *value);
  if (!age || !value) {
    free(age);
    free(value);
    fail(err, errlen, "out of memory");
    return SYLVA_ENOMEM;
  }
  for (int k = 0; k < 4; k++) curves[k] = fit_curve(trees, count, k, age, value);
  free(age);
  free(value);
  if (!curves[0].present) {
    fail(err, errlen, "data: the heights could not be fitted by a growth curve");
    return SYLVA_EINVAL;
  }
  double oldest = 0.0, youngest = INFINITY;
  for (int i = 0; i < count; i++) {
    if (trees[i].age > oldest) oldest = trees[i].age;
    if (trees[i].age < youngest) youngest = trees[i].age;
  }
  memset(out, 0, sizeof *out);
  out->first = (int)ceil(youngest);
  out->years = (int)floor(oldest);
  if (out->years < out->first + 5) {
    fail(err, errlen, "data: the trees' ages span less than 5 years");
    return SYLVA_EINVAL;
  }
  for (int a = 0; a <= out->years; a++) {
    double v[4];
    for (int k = 0; k < 4; k++)
      v[k] = curves[k].present ? logistic(curves[k].s0, curves[k].m, curves[k].r, a) : NAN;
    out->at[a] = (sylva_fit_sizes){v[0], v[1], v[2], v[3]};
  }
  return SYLVA_OK;
}

/* ---- growing ----------------------------------------------------------------------- */

typedef struct grow_job {
  const sylva_species_def *def;
  int years;
  uint64_t seed;
  sylva_fit_sizes *at; /* years + 1 */
  int rc;
} grow_job;

static sylva_fit_sizes sizes_of(const sylva_stem_stats *s) {
  return (sylva_fit_sizes){s->height, s->dbh * 100.0, s->crown_width,
                           isfinite(s->crown_height) ? s->crown_height : 0.0};
}

static void *grow_one(void *arg) {
  grow_job *j = arg;
  const sylva_species_def *d = j->def;
  sylva_equation eq = d->growth;
  double reach = sylva_equation_value(&eq, (double)(d->nursery + j->years)) *
                 (d->ref_rho > 0.0 ? d->ref_rho : d->rho);
  /* Bounds in whole metres: the voxels then stand where they stand in any open world
   * so bounded around the root (scripts/fidelity's, the species tests'), and the tree
   * grows there as here, bit for bit. */
  sylva_world_def wd = sylva_default_world_def();
  double half = ceil(0.75 * reach + 3.0);
  wd.min[0] = wd.min[1] = -half;
  wd.max[0] = wd.max[1] = half;
  wd.min[2] = 0.0;
  wd.max[2] = ceil(1.3 * reach + 3.0);
  wd.voxel = d->rho / 2.0;
  wd.seed = j->seed;
  sylva_world *w = NULL;
  j->rc = sylva_world_create(&wd, &w);
  if (j->rc) return NULL;
  double root[1][3] = {{0, 0, 0}};
  int sp = sylva_world_add_species(w, d, "fit");
  sylva_plant_def pd = {.species = sp, .label = "tree", .roots = (const double(*)[3])root, .root_count = 1};
  j->rc = sp < 0 ? sp : sylva_world_add_plant(w, &pd, NULL);
  if (j->rc >= 0) {
    j->rc = SYLVA_OK;
    sylva_stem_stats st;
    sylva_world_stem_stats(w, 0, &st);
    j->at[0] = sizes_of(&st);
    for (int a = 1; a <= j->years && !j->rc; a++) {
      const sylva_journal *jr;
      j->rc = sylva_world_step(w, &jr);
      if (!j->rc) j->at[a] = sizes_of(&jr->stats[0]);
    }
  }
  sylva_world_destroy(w);
  return NULL;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Median of the finite values (NAN when there are none). */
static double median(double *v, int n) {
  int k = 0;
  for (int i = 0; i < n; i++)
    if (isfinite(v[i])) v[k++] = v[i];
  if (!k) return NAN;
  qsort(v, (size_t)k, sizeof *v, cmp_double);
  return k % 2 ? v[k / 2] : 0.5 * (v[k / 2 - 1] + v[k / 2]);
}

int sylva_fit_grow(const sylva_species_def *def, int years, int seeds, int threads,
                   sylva_fit_targets *out) {
  if (years < 0 || years > SYLVA_FIT_MAX_YEARS || seeds < 1 || seeds > MAX_SEEDS)
    return SYLVA_EINVAL;
  if (threads < 1) threads = 1;
  sylva_fit_sizes *at = calloc((size_t)seeds * (size_t)(years + 1), sizeof *at);
  if (!at) return SYLVA_ENOMEM;
  grow_job jobs[MAX_SEEDS];
  for (int s = 0; s < seeds; s++)
    jobs[s] = (grow_job){def, years, (uint64_t)(s + 1), at + (size_t)s * (size_t)(years + 1), 0};
  int rc = SYLVA_OK;
  /* each tree grows in a world of its own: the threads share nothing but def */
  for (int s0 = 0; s0 < seeds; s0 += threads) {
    pthread_t tid[MAX_SEEDS];
    bool started[MAX_SEEDS] = {false};
    for (int s = s0; s < seeds && s < s0 + threads; s++)
      started[s] = pthread_create(&tid[s], NULL, grow_one, &jobs[s]) == 0;
    for (int s = s0; s < seeds && s < s0 + threads; s++) {
      if (started[s])
        pthread_join(tid[s], NULL);
      else
        grow_one(&jobs[s]);
      if (jobs[s].rc && !rc) rc = jobs[s].rc;
    }
  }
  if (!rc) {
    memset(out, 0, sizeof *out);
    out->years = years;
    double v[MAX_SEEDS];
    for (int a = 0; a <= years; a++) {
      double m[4];
      for (int k = 0; k < 4; k++) {
        for (int s = 0; s < seeds; s++) v[s] = measure_of(&jobs[s].at[a], k);
        m[k] = median(v, seeds);
      }
      out->at[a] = (sylva_fit_sizes){m[0], m[1], m[2], m[3]};
    }
  }
  free(at);
  return rc;
}

/* ---- calibration ------------------------------------------------------------------- */

/* The ages a calibration compares: every 5 years within the data, from 5. */
static int check_ages(const sylva_fit_targets *t, int years, int *ages) {
  int n = 0;
  for (int a = 5; a <= years; a += 5)
    if (a >= t->first) ages[n++] = a;
  return n;
}

typedef struct growth_fit {
  const sylva_fit_targets *t;
  double scale; /* internodes per metre of target height */
  int nursery, years;
  double per_metre; /* internodes per metre of path */
  double top;       /* the tallest target, internodes */
} growth_fit;

/* The liner's height X0 from its parameter: a whip of LINER_MIN to LINER_MAX metres. */
#define LINER_MIN 0.5
#define LINER_MAX 4.0
static double liner(double p, double scale) {
  return (LINER_MIN + (LINER_MAX - LINER_MIN) / (1.0 + exp(-p))) * scale;
}

/* The limit Xm from its parameter: from just above the tallest target to five times
 * it (an unbounded Xm with a tiny r is a straight line that never bends over). */
static double limit_of(double p, double top) {
  return top * (1.02 + 3.98 / (1.0 + exp(-p)));
}

/* x = the liner's parameter, the limit's, ln r: the path length at t = nursery + age
 * against the target height */
static int growth_residuals(const gsl_vector *x, void *ctx, gsl_vector *f) {
  const growth_fit *g = ctx;
  double x0 = liner(gsl_vector_get(x, 0), g->per_metre);
  double m = limit_of(gsl_vector_get(x, 1), g->top), r = exp(gsl_vector_get(x, 2));
  for (int a = 0; a <= g->years; a++) {
    double y = g->t->at[a].height * g->scale;
    double v = m > x0 ? logistic(x0, m, r, (double)(g->nursery + a)) : 1e9;
    gsl_vector_set(f, (size_t)a, v - y);
  }
  return GSL_SUCCESS;
}

/* Fits the logistic of the path length (in internodes of rho) to k times the target
 * heights, with the nursery years: the liner's X0 internodes grow to the height of
 * age 0 in the nursery. Tries every nursery from NURSERY_MIN to NURSERY_MAX years
 * (or only *nursery when it is above 0) and keeps the best; returns 0 or
 * SYLVA_EINVAL. */
enum { NURSERY_MIN = 2, NURSERY_MAX = 8 };
static int fit_growth(const sylva_fit_targets *t, int years, double rho, double k, int *nursery,
                      sylva_equation *out) {
  double best = INFINITY;
  int lo = *nursery > 0 ? *nursery : NURSERY_MIN, hi = *nursery > 0 ? *nursery : NURSERY_MAX;
  for (int n = lo; n <= hi; n++) {
    growth_fit g = {t, k / rho, n, years, 1.0 / rho, 0.0};
    for (int a = 0; a <= years; a++)
      if (t->at[a].height * g.scale > g.top) g.top = t->at[a].height * g.scale;
    double x[3] = {-1.0, -1.0, log(0.1)};
    double sse = least_squares(growth_residuals, &g, (size_t)years + 1, 3, x);
    if (isfinite(sse) && sse < best) {
      best = sse;
      *nursery = n;
      out->kind = SYLVA_EQ_LOGISTIC;
      out->p[0] = liner(x[0], g.per_metre);
      out->p[1] = limit_of(x[1], g.top);
      out->p[2] = exp(x[2]);
    }
  }
  return isfinite(best) ? SYLVA_OK : SYLVA_EINVAL;
}

typedef struct search {
  const sylva_fit_targets *t;
  const sylva_fit_options *o;
  sylva_species_def def; /* the species being searched */
  int years, nursery;
  int ages[SYLVA_FIT_MAX_YEARS / 5 + 1], nages;
  int evals, trees;
  int rc;
  double best;
  double k;     /* the height's scale, found apart from the search (scale_height) */
  double crown; /* the crown base's control (set_crown), from 0 */
} search;

/* The crown base's control c: the shedding threshold r_s = R_S e^(2c). The lift is
 * the managers' (set from the data's crown ratio), and the crown base above it is
 * the tree's: a crown whose lower branches die too soon for the data keeps them
 * longer, one that keeps them too long sheds them sooner. */
#define CROWN_GAIN 1.5 /* per (grown - target crown height) / target height */
#define CROWN_MIN (-2.0)
#define CROWN_MAX 0.5
static void set_crown(sylva_species_def *d, double c) {
  if (c < CROWN_MIN) c = CROWN_MIN;
  if (c > CROWN_MAX) c = CROWN_MAX;
  d->r_s = R_S * exp(2.0 * c);
  d->shade_column = SHADE_COLUMN * exp(2.0 * c);
}

/* Builds the species for a point of the search: the tropism's weight (below 0: the
 * tropism points down, for crowns wider than tall), and the height's scale. */
static int species_at(search *s, double gamma, double k, sylva_species_def *d) {
  *d = s->def;
  d->gamma = fabs(gamma);
  d->tropism[2] = gamma < 0.0 ? -1.0 : 1.0;
  int n = s->nursery;
  int rc = fit_growth(s->t, s->years, d->rho, k, &n, &d->growth);
  d->nursery = n;
  d->initial_nodes = (int)floor(d->growth.p[0] + 0.5);
  return rc;
}

/* Grows the species at the search's point (its tropism's signed weight, the height's
 * scale s->k) over the seeds: the species in d, the trees' sizes in g. */
static int grow_at(search *s, double gamma, sylva_species_def *d, sylva_fit_targets *g) {
  int rc = species_at(s, gamma, s->k, d);
  if (!rc) rc = sylva_fit_grow(d, s->years, s->o->seeds, s->o->threads, g);
  s->trees += s->o->seeds;
  return rc;
}

/* Weighted mean squared log error of the crown diameter over the check ages: the
 * decades up to 40 years, which planners ask about most, count four times as much
 * as the other ages. */
static double search_error(const sylva_fit_targets *t, const sylva_fit_targets *g,
                           const int *ages, int nages) {
  double e = 0.0, n = 0.0;
  for (int i = 0; i < nages; i++) {
    double want = t->at[ages[i]].crown_dia, got = g->at[ages[i]].crown_dia;
    if (!isfinite(want) || want <= 0.0) continue;
    double l = log((got > 1e-3 ? got : 1e-3) / want);
    double w = ages[i] % 10 == 0 && ages[i] <= 40 ? 4.0 : 1.0;
    e += w * l * l;
    n += w;
  }
  return n > 0.0 ? e / n : 0.0;
}

/* The tropism's signed weight searched: from down (-1) to three times up. */
#define GAMMA_MIN (-1.0)
#define GAMMA_MAX 3.0

static double search_f(const gsl_vector *x, void *ctx) {
  search *s = ctx;
  double gamma = gsl_vector_get(x, 0), mu = gsl_vector_get(x, 1);
  /* outside the box the error grows with the distance: the simplex turns back */
  double penalty = 0.0;
  if (gamma < GAMMA_MIN) penalty += (GAMMA_MIN - gamma) * (GAMMA_MIN - gamma) * 10.0, gamma = GAMMA_MIN;
  if (gamma > GAMMA_MAX) penalty += (gamma - GAMMA_MAX) * (gamma - GAMMA_MAX) * 10.0, gamma = GAMMA_MAX;
  if (mu < 0.2) penalty += (0.2 - mu) * (0.2 - mu) * 10.0, mu = 0.2;
  if (mu > 4.0) penalty += (mu - 4.0) * (mu - 4.0) * 10.0, mu = 4.0;
  sylva_species_def d;
  sylva_fit_targets g;
  s->def.mu = mu;
  int rc = grow_at(s, gamma, &d, &g);
  s->evals++;
  if (rc) {
    if (!s->rc && rc == SYLVA_ENOMEM) s->rc = rc;
    return 1e6;
  }
  double e = search_error(s->t, &g, s->ages, s->nages) + penalty;
  if (e < s->best) s->best = e;
  if (s->o->progress) {
    char line[160];
    snprintf(line, sizeof line, "fit: search %d/%d: gamma %.3f, mu %.3f: error %.4f (best %.4f)",
             s->evals, s->o->max_evals, gamma, mu, e, s->best);
    s->o->progress(s->o->ctx, line);
  }
  return e;
}

/* Tip radius and pipe exponent from grown trees' dbh at r_tip r0 and exponent v0:
 * a tree's dbh is 2 r_tip N^(1/v) for N tips above breast height, so ln(dbh / 2) is
 * linear in ln N = v0 ln(dbh0 / (2 r0)). */
static void fit_pipe(const sylva_fit_targets *t, const sylva_fit_targets *g, const int *ages,
                     int nages, double r0, double v0, double *r_tip, double *v) {
  double x[SYLVA_FIT_MAX_YEARS], y[SYLVA_FIT_MAX_YEARS];
  size_t n = 0;
  for (int i = 0; i < nages; i++) {
    double grown = g->at[ages[i]].dbh_cm / 100.0, target = t->at[ages[i]].dbh_cm / 100.0;
    if (!(grown > 0.0) || !(target > 0.0)) continue;
    x[n] = v0 * log(grown / (2.0 * r0));
    y[n] = log(target / 2.0);
    n++;
  }
  *r_tip = r0;
  *v = v0;
  if (n == 0) return;
  double slope = 1.0 / v0;
  if (n >= 3) {
    double c0, c1, cov00, cov01, cov11, sumsq;
    if (gsl_fit_linear(x, 1, y, 1, n, &c0, &c1, &cov00, &cov01, &cov11, &sumsq) == GSL_SUCCESS &&
        c1 > 0.0)
      slope = c1;
  }
  *v = 1.0 / slope;
  if (*v < 2.0) *v = 2.0;
  if (*v > 3.5) *v = 3.5;
  double mean = 0.0;
  for (size_t i = 0; i < n; i++) mean += y[i] - x[i] / *v;
  *r_tip = exp(mean / (double)n);
}

/* Largest |error| per measure over the decades within the targets. */
static void decade_errors(const sylva_fit_targets *t, const sylva_fit_targets *g, int years,
                          double out[4]) {
  for (int m = 0; m < 4; m++) {
    out[m] = 0.0;
    for (int a = 10; a <= years; a += 10) {
      if (a < t->first) continue;
      double e = sylva_fit_error(measure_of(&g->at[a], m), measure_of(&t->at[a], m));
      if (isfinite(e) && fabs(e) > out[m]) out[m] = fabs(e);
      if (!isfinite(e) && isfinite(measure_of(&t->at[a], m))) out[m] = INFINITY;
    }
  }
}

static void progress(const sylva_fit_options *o, const char *fmt, ...);

/* The height's scale k and the crown base's control. The path grows k times the
 * target height, as much as the leader's bends and its share of the light take off
 * it; the shedding threshold sets the crown base above the lift. Each round grows the
 * trees, multiplies k by the median over the check ages of target / grown height,
 * and raises the control by the median of (grown - target crown height) / target
 * height. */
static int scale_height(search *s, double gamma, int rounds) {
  for (int i = 0; i < rounds; i++) {
    sylva_species_def d;
    sylva_fit_targets g;
    int rc = grow_at(s, gamma, &d, &g);
    if (rc) return rc;
    double ratio[SYLVA_FIT_MAX_YEARS / 5 + 1], shift[SYLVA_FIT_MAX_YEARS / 5 + 1];
    int n = 0, m = 0;
    for (int a = 0; a < s->nages; a++) {
      const sylva_fit_sizes *grown = &g.at[s->ages[a]], *target = &s->t->at[s->ages[a]];
      if (grown->height > 0.0 && target->height > 0.0) ratio[n++] = target->height / grown->height;
      if (target->height > 0.0 && isfinite(target->crown_ht) && isfinite(grown->crown_ht))
        shift[m++] = (grown->crown_ht - target->crown_ht) / target->height;
    }
    double f = n ? median(ratio, n) : 1.0, longer = m ? median(shift, m) : 0.0;
    s->k *= f;
    if (s->k < 0.5) s->k = 0.5;
    if (s->k > 2.5) s->k = 2.5;
    s->crown += CROWN_GAIN * longer;
    set_crown(&s->def, s->crown);
    progress(s->o, "fit: height's scale %.3f (grown / target %.3f), lift %.3f, r_s %.3f", s->k,
             1.0 / f, s->def.lift, s->def.r_s);
  }
  return SYLVA_OK;
}

/* The crown's widest reach: the data's crown diameter against height at the check
 * ages, the power law a H^b fitted in logs (GSL's linear least squares, b within
 * 0..2), with CROWN_ROOM to spare: an open-grown tree of a height is as wide as the
 * data and no wider (docs/model.md, "Species in years"). */
#define CROWN_ROOM 1.05
static void crown_limit(const sylva_fit_targets *t, const int *ages, int nages,
                        sylva_species_def *d) {
  double lx[SYLVA_FIT_MAX_YEARS / 5 + 1], ly[SYLVA_FIT_MAX_YEARS / 5 + 1];
  size_t n = 0;
  for (int i = 0; i < nages; i++) {
    const sylva_fit_sizes *z = &t->at[ages[i]];
    if (z->height > 0.0 && isfinite(z->crown_dia) && z->crown_dia > 0.0) {
      lx[n] = log(z->height);
      ly[n++] = log(z->crown_dia);
    }
  }
  if (!n) return; /* no crown diameter in the data: no limit */
  double c0 = 0.0, b = 1.0, cov00, cov01, cov11, sumsq;
  if (n >= 2 && gsl_fit_linear(lx, 1, ly, 1, n, &c0, &b, &cov00, &cov01, &cov11, &sumsq) == GSL_SUCCESS &&
      isfinite(b))
    b = b < 0.0 ? 0.0 : b > 2.0 ? 2.0 : b;
  else
    b = 1.0;
  double mean = 0.0; /* ln a for that exponent: the mean of ln CD - b ln H */
  for (size_t i = 0; i < n; i++) mean += ly[i] - b * lx[i];
  d->crown_max = CROWN_ROOM * exp(mean / (double)n);
  d->crown_max_exp = b;
}

/* The tolerances of docs/species.md, "Species fidelity": height, dbh, crown diameter,
 * crown height. The last stages of the fit aim at them: the largest error over the
 * decades up to 40 years (within the data) in units of its measure's tolerance. */
static const double TOLERANCE[4] = {0.15, 0.20, 0.20, 0.25};
#define DECADES_MAX 40

/* The largest error over those decades in tolerances, of the measures in mask (bit m
 * for measure m). */
static double tolerance_error(const sylva_fit_targets *t, const sylva_fit_targets *g, int years,
                              unsigned mask) {
  double worst = 0.0;
  for (int a = 10; a <= years && a <= DECADES_MAX; a += 10) {
    if (a < t->first) continue;
    for (int m = 0; m < 4; m++) {
      if (!(mask & (1u << m)) || !isfinite(measure_of(&t->at[a], m))) continue;
      double e = sylva_fit_error(measure_of(&g->at[a], m), measure_of(&t->at[a], m));
      double x = isfinite(e) ? fabs(e) / TOLERANCE[m] : INFINITY;
      if (x > worst) worst = x;
    }
  }
  return worst;
}

/* The trunk's scale that balances the dbh's largest errors over those decades: with
 * u = grown / target, f = 2 / (min u + max u) makes the largest error over and the
 * largest under equal. 1 without dbh in the data. */
static double trunk_scale(const sylva_fit_targets *t, const sylva_fit_targets *g, int years) {
  double lo = INFINITY, hi = 0.0;
  for (int a = 10; a <= years && a <= DECADES_MAX; a += 10) {
    if (a < t->first) continue;
    double grown = g->at[a].dbh_cm, target = t->at[a].dbh_cm;
    if (!(grown > 0.0) || !(target > 0.0)) continue;
    double u = grown / target;
    if (u < lo) lo = u;
    if (u > hi) hi = u;
  }
  return hi > 0.0 ? 2.0 / (lo + hi) : 1.0;
}

/* The dbh's largest error once the trunk's scale balances it: (max u - min u) /
 * (max u + min u) over the decades, u = grown / target. */
static double balanced_dbh_error(const sylva_fit_targets *t, const sylva_fit_targets *g, int years) {
  double f = trunk_scale(t, g, years), worst = 0.0;
  for (int a = 10; a <= years && a <= DECADES_MAX; a += 10) {
    if (a < t->first) continue;
    double grown = g->at[a].dbh_cm, target = t->at[a].dbh_cm;
    if (!(grown > 0.0) || !(target > 0.0)) continue;
    double e = fabs(f * grown / target - 1.0);
    if (e > worst) worst = e;
  }
  return worst;
}

/* The heartwood tried after the pipe model (docs/model.md, "Calibration", step 7): the
 * least whose balanced dbh error is at least HEARTWOOD_GAIN below the pipe model's and
 * every smaller one's is kept. */
static const double HEARTWOOD[] = {0.02, 0.05, 0.1, 0.2};
#define HEARTWOOD_GAIN 0.01
static int fit_heartwood(const sylva_fit_targets *t, int years, const sylva_fit_options *o,
                         sylva_species_def *d, sylva_fit_targets *g, int *trees) {
  double best = balanced_dbh_error(t, g, years);
  for (size_t i = 0; i < sizeof HEARTWOOD / sizeof HEARTWOOD[0]; i++) {
    sylva_species_def e = *d;
    sylva_fit_targets h;
    e.heartwood = HEARTWOOD[i];
    int rc = sylva_fit_grow(&e, years, o->seeds, o->threads, &h);
    *trees += o->seeds;
    if (rc) return rc;
    double err = balanced_dbh_error(t, &h, years);
    progress(o, "fit: heartwood %.2f: dbh's largest error %.0f%% (was %.0f%%)", e.heartwood,
             100 * err, 100 * best);
    if (err <= best - HEARTWOOD_GAIN) {
      best = err;
      *d = e;
      *g = h;
    }
  }
  return SYLVA_OK;
}

/* The dbh's largest error once the pipe fit (fit_pipe) and the trunk's scale balance
 * it, predicted from trees grown at r_tip r0 and exponent v0 without growing them
 * again: each dbh becomes 2 r_tip (dbh0 / (2 r0))^(v0 / v). */
static double fitted_dbh_error(const sylva_fit_targets *t, const sylva_fit_targets *g,
                               const search *s, const sylva_species_def *d) {
  double r, v;
  fit_pipe(t, g, s->ages, s->nages, d->r_tip, d->pipe_exponent, &r, &v);
  sylva_fit_targets p = *g;
  for (int a = 0; a <= s->years; a++)
    if (p.at[a].dbh_cm > 0.0)
      p.at[a].dbh_cm = 200.0 * r * pow(p.at[a].dbh_cm / (200.0 * d->r_tip), d->pipe_exponent / v);
  return balanced_dbh_error(t, &p, s->years);
}

/* Grows the species at the search's point and measures its largest error of height,
 * crown diameter and crown height, in tolerances; with dbh, also fitted_dbh_error's in
 * its tolerance. */
static int grow_error(search *s, double gamma, double *e, double *dbh) {
  sylva_species_def d;
  sylva_fit_targets g;
  int rc = grow_at(s, gamma, &d, &g);
  if (rc) return rc;
  *e = tolerance_error(s->t, &g, s->years, 1u | 4u | 8u);
  if (dbh) *dbh = fitted_dbh_error(s->t, &g, s, &d) / TOLERANCE[1];
  return SYLVA_OK;
}

/* The crown base's control, last: the rounds of scale_height centre the crown height's
 * errors on their median; this tries the control a few steps either side and keeps
 * the one whose largest error of height, crown diameter and crown height, in
 * tolerances, is least (the present one on a tie). */
#define POLISH_STEP 0.15
#define POLISH_STEPS 3
static int polish_crown(search *s, double gamma, double *error) {
  double c0 = s->crown, best_c = c0, best = INFINITY;
  for (int i = 0; i <= 2 * POLISH_STEPS; i++) {
    /* 0 first, then -1, +1, -2, +2, ... steps */
    int k = (i + 1) / 2 * (i % 2 ? -1 : 1);
    double c = c0 + POLISH_STEP * k;
    if (c < CROWN_MIN || c > CROWN_MAX) continue;
    set_crown(&s->def, c);
    double e;
    int rc = grow_error(s, gamma, &e, NULL);
    if (rc) return rc;
    progress(s->o, "fit: crown control %+.2f: largest error %.2f tolerances", c, e);
    if (e < best) best = e, best_c = c;
  }
  s->crown = best_c;
  set_crown(&s->def, best_c);
  *error = best;
  return SYLVA_OK;
}

/* The laterals' reach (docs/model.md, "Calibration", step 6): a young crown that the
 * leader's cap keeps narrower than the data may let its laterals grow further. Tried
 * only when the largest error of height, crown diameter and crown height after
 * polish_crown (polished, in tolerances) exceeds REACH_FROM: the trials grow the
 * largest trees of the calibration, and over all species they doubled its time. Each
 * reach is tried with the height's scale and the crown's control found again for it
 * (REACH_ROUNDS rounds of scale_height). Its error is the largest of height, crown
 * diameter and crown height, in tolerances, and of the dbh as the trunk's fit would
 * leave it (fitted_dbh_error): more laterals make more tips, and a crown that fills
 * its reach early stops adding them. The least is kept if it is at least REACH_GAIN
 * below the leader's cap's. */
static const double REACH[] = {1.5, 2.0, 3.0};
#define REACH_GAIN 0.02
#define REACH_ROUNDS 2
#define REACH_FROM 0.8
static int fit_reach(search *s, double gamma, double polished) {
  if (!(polished > REACH_FROM)) return SYLVA_OK;
  double e, dbh;
  int rc = grow_error(s, gamma, &e, &dbh);
  if (rc) return rc;
  double best = e > dbh ? e : dbh, least = best;
  double k0 = s->k, c0 = s->crown, best_k = k0, best_c = c0, best_f = 1.0;
  for (size_t i = 0; i < sizeof REACH / sizeof REACH[0]; i++) {
    s->def.lateral_reach = REACH[i];
    s->k = k0;
    s->crown = c0;
    set_crown(&s->def, c0);
    rc = scale_height(s, gamma, REACH_ROUNDS);
    if (!rc) rc = grow_error(s, gamma, &e, &dbh);
    if (rc) return rc;
    double err = e > dbh ? e : dbh;
    progress(s->o, "fit: lateral reach %.1f: largest error %.2f tolerances (dbh %.2f; leader's cap %.2f)",
             REACH[i], err, dbh, best);
    if (err < least) least = err, best_f = REACH[i], best_k = s->k, best_c = s->crown;
  }
  if (!(least <= best - REACH_GAIN)) best_f = 1.0, best_k = k0, best_c = c0;
  s->def.lateral_reach = best_f;
  s->k = best_k;
  s->crown = best_c;
  set_crown(&s->def, best_c);
  return SYLVA_OK;
}

static void progress(const sylva_fit_options *o, const char *fmt, ...) {
  if (!o->progress) return;
  char line[240];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(line, sizeof line, fmt, ap);
  va_end(ap);
  o->progress(o->ctx, line);
}

/* The internode length when none is given: 0.25 m, halved while the height grows
 * less than half an internode a season over the first 40 years (or the data's): a
 * cap rounds to whole internodes, and a tree whose caps are mostly 0 stands still
 * (docs/model.md, "Calibration"). */
static double default_rho(const sylva_fit_targets *t) {
  int a0 = t->first > 0 ? t->first : 0, a = t->years < a0 + 40 ? t->years : a0 + 40;
  double rate = a > a0 ? (t->at[a].height - t->at[a0].height) / (double)(a - a0) : 0.0, rho = 0.25;
  while (rho > 0.07 && isfinite(rate) && rate < 0.5 * rho) rho *= 0.5;
  return rho;
}

int sylva_fit_calibrate(const sylva_fit_targets *t, const sylva_fit_options *opt,
                        sylva_fit_result *out, char *err, size_t errlen) {
  sylva_fit_options o = *opt;
  if (o.seeds < 1 || o.seeds > MAX_SEEDS) o.seeds = 3;
  if (o.threads < 1) o.threads = 1;
  if (o.max_evals < 1) o.max_evals = 40;
  if (!(o.rho > 0.0)) o.rho = default_rho(t);
  int years = t->years < 60 ? t->years : 60; /* the decades a planner asks about */
  if (!(t->at[years].height > 0.0)) {
    fail(err, errlen, "the targets hold no height");
    return SYLVA_EINVAL;
  }
  search s = {.t = t, .o = &o, .def = sylva_fit_base_species(o.rho), .years = years,
              .best = INFINITY, .k = 1.0};
  s.nages = check_ages(t, years, s.ages);
  /* The crown's lift: street trees are lifted for clearance, so the database's crown
   * ratio is the managers' as much as the tree's (docs/model.md, "Species in years"). */
  double ratios[SYLVA_FIT_MAX_YEARS / 5 + 1];
  int nr = 0;
  for (int i = 0; i < s.nages; i++) {
    const sylva_fit_sizes *z = &t->at[s.ages[i]];
    if (z->height > 0.0 && isfinite(z->crown_ht)) ratios[nr++] = 1.0 - z->crown_ht / z->height;
  }
  double lift = nr ? median(ratios, nr) : 0.3;
  s.def.lift = lift < 0.0 ? 0.0 : lift > 0.6 ? 0.6 : lift;
  crown_limit(t, s.ages, s.nages, &s.def);
  /* the nursery years, once, from the height curve as the data give it */
  int rc = fit_growth(t, years, o.rho, 1.0, &s.nursery, &s.def.growth);
  if (rc) {
    fail(err, errlen, "the height curve could not be fitted by the logistic");
    return rc;
  }
  progress(&o, "fit: nursery %d years; logistic X0 %g, Xm %.2f, r %.4f (internodes of %g m); "
           "lift %.3f", s.nursery, s.def.growth.p[0], s.def.growth.p[1], s.def.growth.p[2],
           o.rho, s.def.lift);
  /* the height's scale, then the crown's spread with the simulation in the loop, then
   * the height's scale again for that spread */
  rc = scale_height(&s, s.def.gamma, 3);
  if (rc) {
    fail(err, errlen, rc == SYLVA_ENOMEM ? "out of memory" : "growing the species failed");
    return rc;
  }
  gsl_multimin_function fn = {.f = search_f, .n = 2, .params = &s};
  gsl_multimin_fminimizer *m = gsl_multimin_fminimizer_alloc(gsl_multimin_fminimizer_nmsimplex2, 2);
  gsl_vector *x = gsl_vector_alloc(2), *step = gsl_vector_alloc(2);
  if (!m || !x || !step) {
    gsl_multimin_fminimizer_free(m);
    gsl_vector_free(x);
    gsl_vector_free(step);
    fail(err, errlen, "out of memory");
    return SYLVA_ENOMEM;
  }
  gsl_vector_set(x, 0, s.def.gamma);
  gsl_vector_set(x, 1, s.def.mu);
  gsl_vector_set(step, 0, 0.25);
  gsl_vector_set(step, 1, 0.5);
  gsl_multimin_fminimizer_set(m, &fn, x, step);
  while (s.evals < o.max_evals && !s.rc) {
    if (gsl_multimin_fminimizer_iterate(m) != GSL_SUCCESS) break;
    if (gsl_multimin_test_size(gsl_multimin_fminimizer_size(m), 0.01) == GSL_SUCCESS) break;
  }
  double gamma = gsl_vector_get(m->x, 0), mu = gsl_vector_get(m->x, 1);
  gsl_multimin_fminimizer_free(m);
  gsl_vector_free(x);
  gsl_vector_free(step);
  if (s.rc) {
    fail(err, errlen, "out of memory");
    return s.rc;
  }
  if (gamma < GAMMA_MIN) gamma = GAMMA_MIN;
  if (gamma > GAMMA_MAX) gamma = GAMMA_MAX;
  s.def.mu = mu < 0.2 ? 0.2 : mu > 4.0 ? 4.0 : mu;
  rc = scale_height(&s, gamma, 3);
  double polished = INFINITY;
  if (!rc) rc = polish_crown(&s, gamma, &polished);
  if (!rc) rc = fit_reach(&s, gamma, polished);
  sylva_species_def d;
  if (!rc) rc = species_at(&s, gamma, s.k, &d);
  /* the trunk: tip radius and pipe exponent, then r_tip rescaled (dbh is linear in it)
   * to balance the largest errors of the decades */
  sylva_fit_targets g;
  if (!rc) rc = sylva_fit_grow(&d, years, o.seeds, o.threads, &g);
  if (!rc) {
    double r_tip, v;
    fit_pipe(t, &g, s.ages, s.nages, d.r_tip, d.pipe_exponent, &r_tip, &v);
    d.r_tip = r_tip;
    d.pipe_exponent = v;
    rc = sylva_fit_grow(&d, years, o.seeds, o.threads, &g);
  }
  if (!rc) rc = fit_heartwood(t, years, &o, &d, &g, &s.trees);
  if (!rc) {
    d.r_tip *= trunk_scale(t, &g, years);
    if (d.r_tip > 0.05) d.r_tip = 0.05;
    rc = sylva_fit_grow(&d, years, o.seeds, o.threads, &g);
  }
  s.trees += 3 * o.seeds;
  if (rc) {
    fail(err, errlen, rc == SYLVA_ENOMEM ? "out of memory" : "growing the species failed");
    return rc;
  }
  out->def = d;
  out->grown = g;
  out->grown.first = t->first;
  out->evaluations = s.trees;
  decade_errors(t, &g, years, out->max_error);
  progress(&o, "fit: gamma %.3f, mu %.3f, height x%.3f, lateral reach %.1f, r_tip %.4f m, pipe exponent %.2f, "
           "heartwood %.2f; largest error over the decades: height %.0f%%, dbh %.0f%%, crown diameter %.0f%%, "
           "crown height %.0f%%",
           d.gamma * d.tropism[2], d.mu, s.k, d.lateral_reach, d.r_tip, d.pipe_exponent, d.heartwood,
           100 * out->max_error[0], 100 * out->max_error[1],
           100 * out->max_error[2], 100 * out->max_error[3]);
  return SYLVA_OK;
}
