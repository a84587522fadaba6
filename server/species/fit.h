/* sylva species: calibration of a species in years to measured growth (`sylva fit`,
 * docs/model.md "Species in years", "Calibration").
 *
 *   targets (the database's chained curves, or curves fitted to a user's trees)
 *   -> the growth equation and the nursery years, fitted to the height curve (GSL
 *      nonlinear least squares), the crown lift from the crown ratio
 *   -> the crown's spread and the height's scale, searched with the simulation in
 *      the loop (GSL's Nelder-Mead simplex, the median of several seeds)
 *   -> the tip radius and pipe exponent from the grown trees' tip counts (a linear
 *      least-squares fit in log space), then r_tip rescaled exactly.
 *
 * Everything here is deterministic: the same targets and options give the same
 * species, bit for bit, whatever the number of threads. */
#ifndef SYLVA_SPECIES_FIT_H
#define SYLVA_SPECIES_FIT_H

#include <stdbool.h>
#include <stddef.h>

#include "sylva/params.h"
#include "utdb.h"

/** Most years a target curve or a grown tree spans. */
#define SYLVA_FIT_MAX_YEARS 120

/** Sizes at one age: height, crown diameter and crown height in m, dbh in cm. NAN
 *  where unknown (a curve the data lack, a tree below breast height). */
typedef struct sylva_fit_sizes {
  double height, dbh_cm, crown_dia, crown_ht;
} sylva_fit_sizes;

/** What a species should measure at each age 0..years (years + 1 entries). */
typedef struct sylva_fit_targets {
  int first, years; /**< ages first..years are within the data's range */
  sylva_fit_sizes at[SYLVA_FIT_MAX_YEARS + 1];
} sylva_fit_targets;

/** The database's chained curves of a species, clamped to where they apply, at ages
 *  0..min(age_max, SYLVA_FIT_MAX_YEARS). SYLVA_EINVAL (message in err) for a
 *  species without the four curves. */
int sylva_fit_targets_utdb(const sylva_utdb_species *s, sylva_fit_targets *out, char *err,
                           size_t errlen);

/** One measured tree of a user's data (a row of the CSV); NAN where empty. */
typedef struct sylva_fit_tree {
  double age, dbh_cm, height, crown_dia, crown_ht;
} sylva_fit_tree;

/** A user's measurements: the CSV header `age,dbh_cm,height_m,crown_diameter_m,
 *  crown_height_m` and one row per tree. Checks every value (numeric, not negative,
 *  age given) and the counts (at least SYLVA_FIT_MIN_TREES trees with a height);
 *  SYLVA_EINVAL with "line N, column C: ..." in err. *trees is malloc'd. */
#define SYLVA_FIT_MIN_TREES 8
int sylva_fit_read_csv(const char *text, size_t len, sylva_fit_tree **trees, int *count,
                       char *err, size_t errlen);

/** A measure's curve over age fitted to trees: the logistic of the model's growth
 *  equations, size = m / (1 + (m / s0 - 1) e^(-r age)). */
typedef struct sylva_fit_curve {
  bool present; /**< false: too few values of this measure to fit */
  double s0, m, r;
  int n;        /**< trees used */
  double r2;    /**< coefficient of determination */
} sylva_fit_curve;

/** The curves of height, dbh, crown diameter and crown height fitted to the trees
 *  (GSL nonlinear least squares), evaluated at ages 0..the oldest tree as targets.
 *  SYLVA_EINVAL when the heights cannot be fitted. */
int sylva_fit_targets_trees(const sylva_fit_tree *trees, int count, sylva_fit_targets *out,
                            sylva_fit_curve curves[4], char *err, size_t errlen);

/** How to calibrate. */
typedef struct sylva_fit_options {
  int seeds;     /**< grown per evaluation, medians taken (default 3) */
  int threads;   /**< at most this many trees grow at once (default 2) */
  int max_evals; /**< of the simplex search (default 40) */
  double rho;    /**< internode length of the species, also its ref_rho (0: 0.25 m, halved
                      for slow growth; see sylva_fit_calibrate) */
  /** Progress lines (may be NULL). */
  void (*progress)(void *ctx, const char *line);
  void *ctx;
} sylva_fit_options;

sylva_fit_options sylva_fit_default_options(void);

/** The species every calibration starts from: the years model's fixed choices. */
sylva_species_def sylva_fit_base_species(double rho);

/** A calibration's outcome. */
typedef struct sylva_fit_result {
  sylva_species_def def;
  sylva_fit_targets grown; /**< the median of the seeds, grown with def */
  int evaluations;         /**< trees grown in all (seeds included) */
  /** Largest relative error over the decades within the data, per measure:
   *  height, dbh, crown diameter, crown height. */
  double max_error[4];
} sylva_fit_result;

/** Calibrates a species to the targets. SYLVA_EINVAL (message in err) when the
 *  targets hold no heights. */
int sylva_fit_calibrate(const sylva_fit_targets *t, const sylva_fit_options *o,
                        sylva_fit_result *out, char *err, size_t errlen);

/** Grows the species alone in an open world from planting (age 0) for `years`
 *  seasons, `seeds` times (seeds 1..seeds), and gives the median sizes at each age
 *  0..years in out->at. threads as in the options. 0 or a negative status. */
int sylva_fit_grow(const sylva_species_def *def, int years, int seeds, int threads,
                   sylva_fit_targets *out);

/** Relative error of a grown size against a target (NAN when either is unknown). */
double sylva_fit_error(double grown, double target);

#endif
