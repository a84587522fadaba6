/* sylva server: the sun's hours on a site's ground and on the vertical faces of
 * its solid obstacles over one day, without the plants and with them
 * (docs/model.md, "Shade on the site"; `sylva shade` in docs/cli.md).
 *
 * A cell is a voxel-sized square: the floor's voxel squares (the ground), the
 * voxel squares of each vertical face of each solid box, and about a voxel wide
 * and a voxel high on each wall of each solid prism (one wall per edge of its
 * footprint), those whose centres lie inside the world's box. From each cell's
 * centre a ray towards the sun is stopped by solid obstacles (exact ray-box and
 * ray-prism tests) and keeps exp(-k LAD path) through the leaves
 * (Beer-Lambert, k = SHADE_K), the leaf area density per voxel coming from the
 * leaves the world reports, placed as foliage_place() places them.
 *
 *   shade_site site = {.latitude = 40, .north = {0, 1}};
 *   shade_day day = shade_default_day();  day.month = 6; day.day = 21;
 *   shade_result r;
 *   char err[256];
 *   if (shade_compute(w, &site, &day, NULL, &r, err, sizeof err) == 0) {
 *     ... r.cells, r.surfaces ...
 *     shade_result_free(&r);
 *   }
 *
 * Pure computation: no I/O, no globals, no clock; the same world and options give
 * the same result, bit for bit. Safe to call from several threads on worlds that
 * none of them changes. Errors are negative server_error statuses (server_error.h)
 * with the reason in err. */
#ifndef SYLVA_SERVER_SHADE_H
#define SYLVA_SERVER_SHADE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "server_error.h"
#include "sylva/scenario.h"
#include "sylva/world.h"

/** Extinction coefficient of a spherical leaf angle distribution (Campbell and
 *  Norman 1998, An Introduction to Environmental Biophysics, ch. 15): the shadow a
 *  leaf of unit one-sided area casts on a plane normal to the beam, averaged over
 *  leaf angles, for any sun elevation. */
#define SHADE_K 0.5

/** Hours of sun with trees below which a cell counts as shaded in the summary. */
#define SHADE_DIM_HOURS 2.0

/** Minutes in a day: the latest `to`. */
#define SHADE_DAY_MINUTES 1440

/** The four vertical faces of a box obstacle, by outward normal. A prism's faces
 *  are its footprint's edges instead, numbered 0, 1, ... in ring order (the
 *  outline's, then each hole's), edge i running from point i to the next point of
 *  its ring, and named "e0", "e1", ... */
typedef enum shade_face {
  SHADE_FACE_PX = 0, /**< "+x" */
  SHADE_FACE_MX = 1, /**< "-x" */
  SHADE_FACE_PY = 2, /**< "+y" */
  SHADE_FACE_MY = 3, /**< "-y" */
  SHADE_FACE_COUNT = 4
} shade_face;

/** Where the site is and how its clock runs. */
typedef struct shade_site {
  double latitude; /**< degrees, north positive, -90 to 90 */
  double north[2]; /**< the direction of north in the x-y plane (not zero) */
  /** With clock: times are clock times at longitude (degrees, east positive) in a
   *  zone utc_offset hours ahead of UTC (solar time = clock time + longitude / 15 -
   *  utc_offset + the equation of time). Without: times are local solar time
   *  (12:00 the sun's transit). */
  bool clock;
  double longitude, utc_offset;
} shade_site;

/** The site of a scenario's light (its latitude, north and clock); false when the
 *  light is not a site's (the paper's zenith sky has no latitude): *site untouched. */
bool shade_site_of(const sylva_scenario *s, shade_site *site);

/** The day and the times sampled: from, from + step, ... < to (minutes after
 *  midnight), each sample standing for `step` minutes. */
typedef struct shade_day {
  int month, day; /**< a valid date of a common year (no 29 February) */
  int year;       /**< the calendar year, only carried into the summary (the sun is
                       that of proto's fixed common year, sylva/sun.h) */
  int from, to;   /**< 0 <= from < to <= SHADE_DAY_MINUTES */
  int step;       /**< minutes, 1 to SHADE_DAY_MINUTES */
} shade_day;

/** Which cells to compute (NULL for all): the result holds only these surfaces. */
typedef struct shade_filter {
  bool ground;   /**< the ground's cells */
  bool faces;    /**< the obstacles' faces (all of them when obstacle < 0) */
  int obstacle;  /**< only this obstacle's faces (id), or -1 */
  int face;      /**< only this face of it (a box's shade_face, a prism's edge
                      number), or -1 for all its faces */
} shade_filter;

/** One cell: its centre, its surface and its hours of direct sun. */
typedef struct shade_cell {
  double p[3];
  int surface; /**< index into shade_result.surfaces */
  double open; /**< hours of sun without the plants (sun_hours_open) */
  double with; /**< hours of sun with them, leaves passing part of it (sun_hours) */
} shade_cell;

/** Longest face name with its NUL: "e99999", a prism's last edge. */
#define SHADE_FACE_NAME_MAX 8

/** A surface: the ground, or one face of one solid obstacle, with its summary. */
typedef struct shade_surface {
  char name[SYLVA_LABEL_MAX + SHADE_FACE_NAME_MAX]; /**< "ground" or "OBSTACLE_ID:FACE" */
  char face_name[SHADE_FACE_NAME_MAX]; /**< FACE: "+x", ... for a box, "e0", ... for a
                                            prism; "" for the ground */
  int obstacle;                   /**< obstacle id, -1 for the ground */
  int face;                       /**< a box's shade_face or a prism's edge number, -1
                                       for the ground */
  double normal[3];               /**< outward unit normal: (0, 0, 1) for the ground; a
                                       prism wall's points to the side of its edge
                                       outside the footprint (even-odd) */
  double along[2];                /**< a face's cells run along it this way (unit,
                                       x-y), fastest, then up; 0 for the ground */
  double width;                   /**< a face's cells' width along it, metres (the
                                       voxel for a box's; a prism edge's length over
                                       its cell count) */
  size_t first, count;            /**< its cells: cells[first .. first + count) */
  double mean_open, mean_with;    /**< mean hours of sun (0 without cells) */
  double mean_added;              /**< mean hours of shade the plants add: open - with */
  double share_dim;               /**< share of cells with under SHADE_DIM_HOURS of sun
                                       with the plants */
} shade_surface;

/** A day's shade. The ground's cells come first (when computed), x fastest, then
 *  each face's, surfaces in obstacle order and face order; a face's cells along
 *  it fastest (surface.along), then up. */
typedef struct shade_result {
  shade_cell *cells;
  size_t cell_count;
  shade_surface *surfaces;
  int surface_count;
  int nx, ny;         /**< the ground's grid (the world's voxels in x and y); 0 when
                           the ground was not computed */
  double voxel;       /**< the cells' edge, metres */
  double min[3], max[3]; /**< the world's box */
  shade_site site;
  shade_day day;
  int samples;        /**< time samples taken (those with the sun up included) */
  double leaf_area;   /**< m^2 of leaves put in the voxels (one-sided) */
} shade_result;

/** Defaults: 01-01 of 2025, the whole day (00:00 to 24:00) at 10-minute steps. */
shade_day shade_default_day(void);

/** Checks a site and a day; SERVER_EINPUT with the reason in err. */
int shade_check(const shade_site *site, const shade_day *day, char *err, size_t errlen);

/** The day of the year (1 to 365) of month-day in a common year, or 0 when there is
 *  no such date (02-30, 13-01, 02-29). */
int shade_day_of_year(int month, int day);

/** Parses "MM-DD" (a valid date of a common year); SERVER_EINPUT with the reason. */
int shade_parse_date(const char *text, int *month, int *day, char *err, size_t errlen);

/** Parses "HH:MM" (00:00 to 24:00) into minutes after midnight; SERVER_EINPUT. */
int shade_parse_time(const char *text, int *minutes, char *err, size_t errlen);

/** Parses a surface name, "ground" or "OBSTACLE_ID:FACE" (the id a solid obstacle
 *  of w; FACE +x, -x, +y or -y of a box, e0 to e(N-1) of a prism of N footprint
 *  points), into a filter; SERVER_EINPUT naming what is unknown. */
int shade_parse_surface(const sylva_world *w, const char *text, shade_filter *out, char *err,
                        size_t errlen);

/** The name of a box's face: "+x", "-x", "+y" or "-y". */
const char *shade_face_name(shade_face f);

/** Computes the day's shade of world w (as it stands: its live nodes and their
 *  leaves, its solid obstacles) into *out, which the caller frees with
 *  shade_result_free (also after a failure). filter NULL computes every cell.
 *  Returns 0, SERVER_EINPUT (bad site or day) or SERVER_ENOMEM. */
int shade_compute(const sylva_world *w, const shade_site *site, const shade_day *day,
                  const shade_filter *filter, shade_result *out, char *err, size_t errlen);
/** shade_compute on `threads` threads (0: the machine's cores), each taking a run of
 *  the cells: the same result, bit for bit, for any number of threads. w must not
 *  change meanwhile. */
int shade_compute_threads(const sylva_world *w, const shade_site *site, const shade_day *day,
                          const shade_filter *filter, int threads, shade_result *out, char *err,
                          size_t errlen);

/** Frees what shade_compute allocated and zeroes *r. */
void shade_result_free(shade_result *r);

/** The ground's hours of shade the plants add (open - with) as a flat array of
 *  r->nx * r->ny values, x fastest (index i + nx * j is the cell whose centre is
 *  min + (i + 0.5, j + 0.5) voxels), into out (the caller's, of that size).
 *  SERVER_EINPUT when r holds no ground. */
int shade_ground_added(const shade_result *r, double *out);

/** The same summary for all faces of one obstacle together (cells, means and
 *  share as in shade_surface); 0 cells when it has none in r. */
void shade_obstacle_summary(const shade_result *r, int obstacle, shade_surface *out);

/* Writing (shade_write.c). Each returns 0, SERVER_EWRITE (err says why) or
 * SERVER_ENOMEM. */

/** Cells as CSV: header x,y,z,surface,sun_hours_open,sun_hours; one row per cell,
 *  coordinates with 3 decimals, hours with 4. */
int shade_write_csv(FILE *f, const shade_result *r, char *err, size_t errlen);

/** The day's summary as one JSON object on one line, with a newline: date, from,
 *  to, step, year, latitude, and per surface its cells and means. */
int shade_write_summary(FILE *f, const shade_result *r, char *err, size_t errlen);

/** The plan as a PNG: the ground's added shade hours as colours with a legend, solid
 *  obstacles' outlines and the stems' roots of w as dots. SERVER_EINPUT when r
 *  holds no ground. */
int shade_write_png(FILE *f, const shade_result *r, const sylva_world *w, char *err,
                    size_t errlen);

#endif
