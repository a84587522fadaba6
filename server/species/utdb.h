/* sylva species: the USDA Urban Tree Database (McPherson, van Doorn and Peper 2016,
 * https://doi.org/10.2737/RDS-2016-0005) as a C library. Its growth equations (table
 * TS6: age -> dbh, dbh -> height, crown diameter, crown height, leaf area and age for
 * each species of 17 US climate regions), joined with the species' names (TS2), are
 * evaluated as published or clamped to where they apply. The two tables are built
 * into the binary; data/utdb/README.md has the citation, the units, the equation
 * forms and the pitfalls of the data.
 *
 * Units: age in years since planting, dbh in cm, heights and crown diameter in m,
 * leaf area in m². Functions that can fail return SYLVA_OK (0) or a negative
 * sylva_status (sylva/status.h). */
#ifndef SYLVA_SPECIES_UTDB_H
#define SYLVA_SPECIES_UTDB_H

#include <stdbool.h>
#include <stddef.h>

#include "sylva/status.h"

/** The equations held for each species: what each predicts and from what. */
typedef enum sylva_utdb_measure {
  SYLVA_UTDB_DBH,       /**< age (years) -> dbh (cm) */
  SYLVA_UTDB_HEIGHT,    /**< dbh (cm) -> tree height (m) */
  SYLVA_UTDB_CROWN_DIA, /**< dbh (cm) -> crown diameter (m) */
  SYLVA_UTDB_CROWN_HT,  /**< dbh (cm) -> crown height (m), height minus crown base */
  SYLVA_UTDB_LEAF_AREA, /**< dbh (cm) -> leaf area (m²) */
  SYLVA_UTDB_AGE,       /**< dbh (cm) -> age (years); its Apps are the age range */
  SYLVA_UTDB_MEASURES   /**< the number of measures */
} sylva_utdb_measure;

/** One published equation (one TS6 row). The table's empty cells are NAN, except
 *  the coefficients a..e, which are 0 where the form does not use them and the
 *  table leaves them empty, and n, which is 0 where the table has no count. */
typedef struct sylva_utdb_curve {
  bool present;  /**< false: the table has no such equation for the species */
  char form[12]; /**< TS4's EqName: lin, quad, cub, quart, loglogw1..4, expow1..4 */
  double a, b, c, d, e; /**< the coefficients as published */
  double mse; /**< for the log and exponential forms the MSE (column c, kept in c too,
                   never negative); NAN for the polynomials */
  double apps_min, apps_max; /**< range of the predicted value where the equation applies */
  double data_min, data_max; /**< measured range of the predicted value */
  int n;                     /**< trees measured for this equation */
  double r2;                 /**< adjusted R² of the fit */
  /** The x range in which the equation applies, the one sylva_utdb_eval_clamped()
   *  clamps to; set by sylva_utdb_parse() (see there), set it yourself for a curve
   *  you build. x_max may be INFINITY. */
  double x_min, x_max;
} sylva_utdb_curve;

/** One species in one region. */
typedef struct sylva_utdb_species {
  char region[12];     /**< region code, as in TS6 ("NoEast") */
  char code[16];       /**< species code within the region ("PLAC") */
  char scientific[96]; /**< scientific name from TS2 (from TS6 where TS2 lacks the species) */
  char common[96];     /**< common name from TS2; "" where TS2 lacks the species */
  char type[8];        /**< TS2's tree type ("BDL": broadleaf deciduous large); "" if none */
  sylva_utdb_curve curve[SYLVA_UTDB_MEASURES]; /**< indexed by sylva_utdb_measure */
  /** The ages in which the equations apply: the Apps of the dbh -> age equation;
   *  NAN when the species has none. */
  double age_min, age_max;
} sylva_utdb_species;

/** A parsed database: the species in the order of TS6 (by region, then code). */
typedef struct sylva_utdb sylva_utdb;

/** Parses TS6 (growth coefficients) and TS2 (species and counts) as CSV text (quoted
 *  fields, CRLF or LF line ends, surrounding spaces trimmed; columns found by their
 *  header names) and joins them on region and species code. Every cell an equation
 *  needs is checked: on bad input the result is SYLVA_EINVAL and err (when errlen > 0)
 *  names the file, line and column ("TS6_Growth_coefficients.csv:12: column 9 (a):
 *  'x' is not a number"); SYLVA_ENOMEM when out of memory. On success *out is a new
 *  database for sylva_utdb_free(); on failure *out is NULL.
 *
 *  The rows predicting dbh from crown diameter are checked and left out. x ranges
 *  (sylva_utdb_curve.x_min, x_max): the age -> dbh equation applies over
 *  age_min..age_max (0..INFINITY when the species has no dbh -> age equation); the
 *  dbh -> X equations, dbh -> age included, over the age -> dbh equation's Apps, the
 *  dbh at the first and last applicable age (0..INFINITY when it has none). */
int sylva_utdb_parse(const char *ts6, size_t ts6_len, const char *ts2, size_t ts2_len,
                     sylva_utdb **out, char *err, size_t errlen);

/** Parses the tables built into the binary (data/utdb/, the archive's of 21 January
 *  2020), anew on each call: SYLVA_OK and *out, or SYLVA_ENOMEM. */
int sylva_utdb_builtin(sylva_utdb **out);

/** Frees a database and with it every species pointer it gave; NULL is allowed. */
void sylva_utdb_free(sylva_utdb *u);

/** The number of species (one per region and code). */
int sylva_utdb_count(const sylva_utdb *u);

/** The species at index i (0 <= i < count), in TS6 order; NULL for another i. Valid
 *  until sylva_utdb_free(u). */
const sylva_utdb_species *sylva_utdb_at(const sylva_utdb *u, int i);

/** The species of a region and code, matched exactly (case-sensitive); NULL if none.
 *  Valid until sylva_utdb_free(u). */
const sylva_utdb_species *sylva_utdb_find(const sylva_utdb *u, const char *region,
                                          const char *code);

/** The equation at x, as published, without clamping: NAN for an absent curve or an
 *  unknown form. With m = mse: loglogw1 exp(a + b ln(ln(x+1) + m/2)) (the term inside
 *  the inner log, as TS4 prints it and as the archive's Apps are computed);
 *  loglogw2..4 exp(a + b ln(ln(x+1)) + w m/2) and expow1..4 exp(a + b x + w m/2),
 *  where the weight w (√x, x, x² for loglogw2..4; 1, √x, x, x² for expow1..4)
 *  multiplies m/2 as the errata corrected; lin, quad, cub, quart the polynomial in x
 *  with a..e. */
double sylva_utdb_eval(const sylva_utdb_curve *c, double x);

/** The equation held to where it applies: x is clamped to x_min..x_max, and the
 *  result is the largest value of the equation over x_min..x (the running maximum),
 *  so that a quadratic or cubic that turns over inside its range (their coefficients
 *  are rounded to 5 decimals) is held at its peak and sizes never shrink as a tree
 *  ages or thickens. The maximum is exact: the equation is compared at x_min, x and
 *  its stationary points between (polynomial roots by GSL; the log and exponential
 *  forms' in closed form; loglogw1 and loglogw2..4 have no maximum inside their
 *  range for an mse >= 0, which sylva_utdb_parse() ensures). NAN for an absent curve
 *  or a NAN x. */
double sylva_utdb_eval_clamped(const sylva_utdb_curve *c, double x);

/** Sizes of a tree at one age, from the chained equations. */
typedef struct sylva_utdb_sizes {
  double age;          /**< years since planting, as asked */
  double dbh_cm;       /**< diameter at breast height (1.37 m), cm */
  double height_m;     /**< total height, m */
  double crown_dia_m;  /**< crown diameter, m */
  double crown_ht_m;   /**< crown height (height minus crown base), m */
  double leaf_area_m2; /**< leaf area, m² */
} sylva_utdb_sizes;

/** A species' sizes at an age: dbh from the age -> dbh equation, then height, crown
 *  diameter, crown height and leaf area from that dbh. With clamp each step is
 *  sylva_utdb_eval_clamped() (ages held to age_min..age_max, dbh to the dbh range,
 *  nothing shrinking), without it sylva_utdb_eval() as published. A missing equation
 *  gives NAN (and a missing age -> dbh equation NAN for all). SYLVA_ERANGE, and all
 *  NAN, for an age that is negative or not finite; else SYLVA_OK. */
int sylva_utdb_chain(const sylva_utdb_species *s, double age, bool clamp,
                     sylva_utdb_sizes *out);

/** Whether the species has the four equations a growing tree needs: age -> dbh and
 *  dbh -> height, crown diameter and crown height. */
bool sylva_utdb_complete(const sylva_utdb_species *s);

#endif
