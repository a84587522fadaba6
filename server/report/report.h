/* sylva server: the planner's comparison of a store's runs (`sylva report`,
 * docs/cli.md "report"). A report is gathered once from the store (report_load) and
 * then written as CSV (report_csv.c), HTML (report_html.c) or PDF (report_pdf.c):
 *
 *   rows      one per run, stem and reported year: the stats row of that stem at
 *             iteration = year, with the pruned nodes summed up to it (and its
 *             run's tree shade that year, with a shade day);
 *   summary   per axis value (seeds pooled) and species, at each reported year: the
 *             median and range of height, dbh, crown diameter and crown height, and
 *             of the first conflict year with each clearance zone;
 *   stand     with the rows, their run's stand at that year (a run with stands);
 *   series    every stored stats row's height and crown diameter, for the plots;
 *   finals    each stem's last stored stats row, for the first-conflict chart.
 *
 * Every number a report shows is a stored stats value, or a median, minimum or
 * maximum of such values; nothing is re-measured but the tree shade of a plan's
 * shade day (shade.h, on the stored iterations regrown). Functions that can fail return
 * SERVER_OK or a negative server_error (server_error.h) with err naming what and
 * where. */
#ifndef SYLVA_SERVER_REPORT_H
#define SYLVA_SERVER_REPORT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "fit.h"
#include "render.h"
#include "server_error.h"
#include "shade.h"
#include "store.h"

/** Most reported years. */
#define REPORT_MAX_YEARS 64
/** The years reported when none are asked for. */
#define REPORT_DEFAULT_YEARS "10,20,40"
/** The greatest reported year (the scenarios' iteration limit). */
#define REPORT_MAX_YEAR 100000
/** A first-conflict year that never happened. */
#define REPORT_NEVER INT32_MIN

/** Output formats, by the extension of -o. */
typedef enum report_format { REPORT_CSV, REPORT_HTML, REPORT_PDF } report_format;
/** The extensions, for messages. */
#define REPORT_FORMAT_NAMES ".csv, .html or .pdf"

/** The format of a file name by its extension (.csv, .html or .htm, .pdf; any case);
 *  false for anything else. */
bool report_format_from_path(const char *path, report_format *out);

/** Parses a list of years "10,20,40" (decimal integers 1 to REPORT_MAX_YEAR, comma
 *  separated, at most REPORT_MAX_YEARS) into years[], sorted, duplicates dropped.
 *  false with err saying what is wrong ("'x' is not a whole number of years"). */
bool report_parse_years(const char *text, int years[REPORT_MAX_YEARS], int *count, char *err,
                        size_t errlen);

/** The stand's figures a report gives per run and reported year (docs/cli.md, "report";
 *  docs/model.md, "Stands"), in their order. */
typedef enum report_stand_figure {
  REPORT_STEMS_PER_HA,
  REPORT_BASAL_AREA,      /**< m^2/ha */
  REPORT_QMD,             /**< cm */
  REPORT_DOMINANT_HEIGHT, /**< m */
  REPORT_SDI,
  REPORT_CV_DBH,
  REPORT_DIED,            /**< stems that died in iterations 1 to the year */
  REPORT_STAND_FIGURES
} report_stand_figure;

/** Their CSV columns ("stems_per_ha", ..., "died"). */
extern const char *const report_stand_columns[REPORT_STAND_FIGURES];
/** Their heads in the HTML and PDF stand table ("stems/ha", ...). */
extern const char *const report_stand_heads[REPORT_STAND_FIGURES];

/** An (index, value) pair of a row: a zone's first conflict year, an obstacle's
 *  clearance or tree shade hours. */
typedef struct report_kv {
  int index;
  double value;
} report_kv;

/** A run's tree shade at one reported year, on the plan's shade day (shade.h): the
 *  mean hours of direct sun its plants take (mean_added, open - with). */
typedef struct report_shade {
  double ground;         /**< on the ground's cells; NAN when not computed (the run has
                              not reached the year, or its light has no latitude) */
  report_kv *obstacles;  /**< index into report.shade_obstacles and the mean over all
                              that obstacle's face cells; only obstacles with cells */
  int nobstacles;
} report_shade;

/** A run of the report. */
typedef struct report_run {
  int64_t id;
  char *name;
  int position;       /**< in its sweep; -1 outside one */
  char **values;      /**< per axis of the report, the run's value as labelled */
  int start_year;     /**< the scenario's start_year; 0 when none */
  bool years;         /**< a species counts in years */
  bool conflicts;     /**< the run reports conflicts (zones, clearance, pruned) */
  bool stand;         /**< its stats carry the stand's (store_run.stand) */
  int last_iteration; /**< its last stored iteration */
  report_shade *shade; /**< per reported year when report.shade, else NULL */
} report_run;

/** A species, as labelled in the report. */
typedef struct report_species {
  char *label;              /**< a library name ("utdb:NoEast:PLAC"), "KEY#k" for a
                                 species object of a sweep's axis, else the
                                 scenario's species key */
  sylva_fit_targets *utdb;  /**< the database's open-grown curves of a library
                                 species (sylva_fit_targets_utdb), else NULL */
  int age0;                 /**< the median age at planting of its stems (0 without
                                 years): the plots' curves are at age = year + age0 */
  int picture_run;          /**< the run drawn for it: the first with such a plant */
} report_species;

/** A stem at one iteration. */
typedef struct report_row {
  int run;            /**< index into report.runs */
  int species;        /**< index into report.species */
  int key;            /**< the plant's species key, index into report.keys */
  int plant;          /**< the plant's id, index into report.plants */
  int stem;           /**< its index within the plant */
  int year;           /**< index into report.years; -1 for a final row */
  int iteration, age; /**< age -1 where not stored */
  double height, dbh, crown_diameter, crown_height; /**< NAN where not stored */
  double leaf_area;   /**< m^2; NAN where not stored (a store before schema 5) */
  double co2, co2_sequestered; /**< kg CO2 stored and sequestered since planting; NAN
                                    where not stored (docs/model.md, "Wood and carbon") */
  double canopy_cover; /**< the run's share of open ground under leaves at this
                            iteration; NAN where not stored */
  double shade_ground; /**< its run's report_shade.ground at this year; NAN in final
                            rows and without a shade day */
  double stand[REPORT_STAND_FIGURES]; /**< its run's stand at this iteration, the same
                                           on each of its rows; NAN where not stored
                                           (a run without stands, rows before
                                           schema 7) */
  int64_t pruned;     /**< nodes pruned up to this iteration; -1 without conflicts */
  report_kv *first;   /**< zone index and its stored `first` (a calendar year with a
                           start year, else an iteration) */
  int nfirst;
  report_kv *clearance; /**< obstacle index and its least clearance (m) */
  int nclearance;
} report_row;

/** One value of the plots: a stored stats row's height and crown diameter. */
typedef struct report_sample {
  int species, iteration;
  double height, crown_diameter;
} report_sample;

/** Median, minimum and maximum of n values (n == 0: no value; the others NAN). */
typedef struct report_stat {
  int n;
  double median, min, max;
} report_stat;

/** The measures the summary gives, in its order. The per-stem ones pool one value
 *  per stem of a group, the per-run ones (report_measure_per_run) one per run. */
typedef enum report_measure {
  REPORT_HEIGHT,
  REPORT_DBH,
  REPORT_CROWN_DIAMETER,
  REPORT_CROWN_HEIGHT,
  REPORT_CO2,          /**< kg CO2 stored in the stem */
  REPORT_CANOPY_COVER, /**< the run's canopy cover at that iteration */
  REPORT_SHADE_GROUND, /**< the run's tree shade hours on the ground (shown only with a
                            shade day: report_measures_shown) */
  REPORT_MEASURES
} report_measure;

/** Whether measure m is one value per run and iteration (repeated on its stems' rows)
 *  rather than one per stem. */
bool report_measure_per_run(report_measure m);

/** One line of the summary: an axis value and a species at a reported year. */
typedef struct report_group {
  int axis;           /**< index into report.axes; -1: all runs (no axis but seeds) */
  const char *value;  /**< the axis value ("all runs" for axis -1) */
  int species;
  int year;           /**< index into report.years */
  int n;              /**< stems (rows) pooled */
  int runs;           /**< runs pooled (the per-run measures' count) */
  report_stat measure[REPORT_MEASURES];
  report_stat *first; /**< per zone: the first conflict years of the stems that met
                           it (n of them) */
  report_stat stand[REPORT_STAND_FIGURES]; /**< one value per run (runs of them) */
} report_group;

/** A gathered report. Every string and array is owned by it (report_free). */
typedef struct report {
  char *db;              /**< the store's path, for titles */
  char *sweep;           /**< the sweep reported, or NULL for the runs of a store
                              without sweeps */
  int years[REPORT_MAX_YEARS];
  int nyears;
  bool calendar;         /**< the CSV's column is `year` (runs in years or with a
                              start year), not `iteration` */
  bool multi_stem;       /**< a plant has several stems: the CSV has a `stem` column */
  bool conflicts;        /**< a run reports conflicts */
  bool stand;            /**< a run has stands: the CSV's stand columns and the stand
                              table */
  int common_start_year; /**< every run's start year when they share one, else 0 */
  char **axes;           /**< the sweep's axes ("species/KEY", "seed", "variant") */
  int naxes;
  report_run *runs;
  int nruns;
  report_species *species;
  int nspecies;
  char **keys, **plants, **zones, **obstacles; /**< names, in order of appearance */
  int nkeys, nplants, nzones, nobstacles;
  report_row *rows;      /**< by run, then year, then stem */
  size_t nrows;
  report_row *finals;    /**< each stem's last stored row (year -1) */
  size_t nfinals;
  report_sample *samples;
  size_t nsamples;
  int max_iteration;     /**< the longest run's last iteration */
  report_group *groups;
  size_t ngroups;
  bool shade;            /**< the sweep's plan names a shade day (sweep_plan_shade) */
  shade_day shade_day;   /**< that day (year 0: each run's own) */
  char **shade_obstacles; /**< the solid obstacles of the runs' scenarios, in order of
                               appearance: the shade_ columns */
  int nshade_obstacles;
} report;

/** How many of the measures the summary shows: all of them with a shade day, else
 *  all but REPORT_SHADE_GROUND (the last). */
int report_measures_shown(const report *r);

/** What to report. */
typedef struct report_request {
  const char *db;       /**< the store's path, for messages and titles */
  const char *sweep;    /**< the sweep to report; NULL: the store's only sweep, or every
                             run of a store without sweeps */
  const int *years;     /**< sorted, distinct, 1 to REPORT_MAX_YEAR */
  int nyears;
  void (*warn)(const char *msg); /**< told of a damaged snapshot passed over and of runs
                                      whose tree shade cannot be computed (may be NULL) */
} report_request;

/** Gathers the report q asks for from st (one pass over each run's stats) and its
 *  summary. With a shade day in the sweep's plan, each run's world is regrown at each
 *  reported year it reached and its tree shade computed once (shade_compute); runs
 *  whose light has no latitude get none, and q->warn is told so in one message. SERVER_EINPUT when the store has no such sweep, several sweeps and no
 *  --sweep, or no runs; SERVER_EFAIL when the store fails; SERVER_ENOMEM. On
 *  failure *out is NULL and err says why. */
int report_load(store *st, const report_request *q, report **out, char *err, size_t errlen);

/** Frees a report; NULL is fine. */
void report_free(report *r);

/** The summary's axis name of a group ("all runs" for -1). */
const char *report_group_axis(const report *r, const report_group *g);

/** Writes the CSV (RFC 4180, one header line, docs/cli.md "report") to f. SERVER_EWRITE
 *  when writing failed. */
int report_write_csv(FILE *f, const report *r, char *err, size_t errlen);

/** How the HTML and PDF draw their pictures. */
typedef struct report_draw_options {
  render_view view;                /**< the view of each species' pictures */
  int width;                       /**< the pictures' width in pixels */
  void (*warn)(const char *msg);   /**< told of a damaged snapshot passed over (may be NULL) */
} report_draw_options;

/** Writes the HTML page (one file, pictures inlined as data: URIs) to f. The
 *  pictures are regrown from st (store_world_at). */
int report_write_html(FILE *f, store *st, const report *r, const report_draw_options *o,
                      char *err, size_t errlen);

/** Writes the PDF (A4 landscape pages: summary, pictures, plots, first conflicts) to f. */
int report_write_pdf(FILE *f, store *st, const report *r, const report_draw_options *o,
                     char *err, size_t errlen);

/** Formats a double so that it reads back as the same double (the shortest of %.15g,
 *  %.16g, %.17g that does); "" for NAN. */
void report_format_number(char *buf, size_t size, double v);

/** The summary cell of a measure: "6.123 (5.800–6.400)", ", k of n" appended when
 *  only k of the group's n stems have the value; "–" when none has it. */
void report_format_stat(char *buf, size_t size, const report_stat *s, int n);

/** The summary cell of a zone: "2031 (2029–2033), k of n" with the stored years, or
 *  "never, 0 of n". */
void report_format_first(char *buf, size_t size, const report_stat *s, int n);

/** The label of reported year index i: "10" or, when every run starts in one
 *  calendar year, "10 (2037)". */
void report_format_year(char *buf, size_t size, const report *r, int i);

#endif
