/* The report's pictures, shared by its HTML and PDF: each species drawn at a reported
 * year (render.h), the plots of height and crown diameter over the years with the
 * database's open-grown curves, and the first-conflict chart, all with cairo.
 * Private to server/report. */
#ifndef SYLVA_SERVER_REPORT_DRAW_H
#define SYLVA_SERVER_REPORT_DRAW_H

#include <cairo.h>
#include <stddef.h>

#include "report.h"

/** A PNG in memory (malloc'd data). */
typedef struct report_png {
  unsigned char *data;
  size_t len;
  int width, height;
} report_png;

/** Frees the data of a PNG (not the struct). */
void report_png_free(report_png *p);

/** Whether species s has a picture at reported year index y: its picture run reached
 *  that iteration. */
bool report_has_picture(const report *r, int s, int y);

/** Species s's picture run regrown to reported year y (store_world_at) and drawn
 *  (render_write, PNG, o's view and width, titled with the species). */
int report_picture(store *st, const report *r, int s, int y, const report_draw_options *o,
                   report_png *out, char *err, size_t errlen);

/** Draws the plot of a measure (REPORT_HEIGHT or REPORT_CROWN_DIAMETER) over the
 *  years into the w x h box at the origin of cr: per species its median over every
 *  stem, the range shaded, and the database's open-grown curve dashed. SERVER_OK or
 *  SERVER_ENOMEM (nothing drawn). */
int report_draw_plot(cairo_t *cr, double w, double h, const report *r, report_measure m);

/** The height the first-conflict chart wants. */
double report_conflicts_height(const report *r);

/** Draws the first-conflict chart (species by zone, in years after the start: median
 *  bar, range whisker, how many stems met the zone by their last stored iteration).
 *  SERVER_OK or SERVER_ENOMEM (nothing drawn). */
int report_draw_conflicts(cairo_t *cr, double w, double h, const report *r);

/** Draws a figure (report_draw_plot with m, or report_draw_conflicts when m < 0) into a
 *  w x h PNG in memory. */
int report_figure_png(const report *r, int m, int w, int h, report_png *out, char *err,
                      size_t errlen);

/** The colour of species s, 0xRRGGBB (the render palette, cycled). */
unsigned report_species_colour(int s);

#endif
