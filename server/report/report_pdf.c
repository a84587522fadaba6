/* The report as a PDF (cairo): A4 landscape pages with the summary table, each species
 * drawn at each reported year, the plots of height and crown diameter, and the
 * first-conflict chart. */
#include <cairo-pdf.h>
#include <cairo.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "report.h"
#include "report_draw.h"

#define PAGE_W 842.0 /* A4 landscape, points */
#define PAGE_H 595.0
#define MARGIN 30.0
#define TABLE_FONT 8.0
#define PICTURE_LABEL 130.0

typedef struct pdf {
  FILE *f;
  int write_errno; /* the first failed write's errno, 0 while none */
  cairo_t *cr;
} pdf;

static cairo_status_t pdf_sink(void *closure, const unsigned char *data, unsigned int length) {
  pdf *p = closure;
  if (fwrite(data, 1, length, p->f) == length) return CAIRO_STATUS_SUCCESS;
  if (!p->write_errno) p->write_errno = errno ? errno : EIO;
  return CAIRO_STATUS_WRITE_ERROR;
}

static void font(cairo_t *cr, double size, bool bold) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
}

static double text_width(cairo_t *cr, const char *s) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, s, &e);
  return e.x_advance;
}

static void text_at(cairo_t *cr, double x, double y, const char *s) {
  cairo_move_to(cr, x, y);
  cairo_show_text(cr, s);
}

/* A page's title line; returns the y below it. */
static double page_title(cairo_t *cr, const report *r, const char *what) {
  cairo_set_source_rgb(cr, 0, 0, 0);
  font(cr, 14, true);
  char title[400];
  snprintf(title, sizeof title, "sylva report: %s — %s",
           r->sweep ? r->sweep : "the runs of the store", what);
  text_at(cr, MARGIN, MARGIN + 10, title);
  return MARGIN + 26;
}

/* ---- the summary ---------------------------------------------------------------- */

enum { FIXED_COLUMNS = 5 };

/* The text of a group's first columns (c < FIXED_COLUMNS; the fifth is count). */
static void group_cell(const report *r, const report_group *g, int c, int count, char *buf,
                       size_t n) {
  switch (c) {
  case 0: snprintf(buf, n, "%s", report_group_axis(r, g)); return;
  case 1: snprintf(buf, n, "%s", g->value); return;
  case 2: snprintf(buf, n, "%s", r->species[g->species].label); return;
  case 3: report_format_year(buf, n, r, g->year); return;
  default: snprintf(buf, n, "%d", count); return;
  }
}

/* The text of column c of group g (g NULL: the header). */
static void summary_cell(const report *r, const report_group *g, int c, char *buf, size_t n) {
  static const char *const heads[FIXED_COLUMNS + REPORT_MEASURES] = {
      "axis", "value", "species", "years", "stems",
      "height (m)", "dbh (m)", "crown diameter (m)", "crown height (m)", "CO2 (kg)",
      "canopy cover", "tree shade, ground (h)"};
  int measures = report_measures_shown(r);
  if (!g) {
    if (c < FIXED_COLUMNS + measures) snprintf(buf, n, "%s", heads[c]);
    else snprintf(buf, n, "first: %s", r->zones[c - FIXED_COLUMNS - measures]);
    return;
  }
  if (c < FIXED_COLUMNS) {
    group_cell(r, g, c, g->n, buf, n);
    return;
  }
  if (c < FIXED_COLUMNS + measures) {
    report_measure m = (report_measure)(c - FIXED_COLUMNS);
    report_format_stat(buf, n, &g->measure[m], report_measure_per_run(m) ? g->runs : g->n);
  } else {
    report_format_first(buf, n, &g->first[c - FIXED_COLUMNS - measures], g->n);
  }
}

/* The text of column c of group g's stand (g NULL: the header). */
static void stand_cell(const report *r, const report_group *g, int c, char *buf, size_t n) {
  static const char *const heads[FIXED_COLUMNS] = {"axis", "value", "species", "years", "runs"};
  if (!g)
    snprintf(buf, n, "%s", c < FIXED_COLUMNS ? heads[c] : report_stand_heads[c - FIXED_COLUMNS]);
  else if (c < FIXED_COLUMNS)
    group_cell(r, g, c, g->runs, buf, n);
  else
    report_format_stat(buf, n, &g->stand[c - FIXED_COLUMNS], g->runs);
}

/* The notes under the first page's title of a table; returns the y below them. */
typedef double (*table_notes)(cairo_t *cr, const report *r, double y);

static double summary_notes(cairo_t *cr, const report *r, double y) {
  char cell[400];
  font(cr, 9, false);
  snprintf(cell, sizeof cell, "Store %s, %d run%s. Median (minimum–maximum) over the stems "
           "(canopy cover: over the runs) of each axis value, seeds pooled; first "
           "conflict: stored first years.", r->db,
           r->nruns, r->nruns == 1 ? "" : "s");
  text_at(cr, MARGIN, y + 4, cell);
  y += 18;
  if (r->shade) {
    snprintf(cell, sizeof cell, "Tree shade, ground: per run, the mean hours of sun its trees "
             "take from the ground on %02d-%02d, %02d:%02d to %02d:%02d, every %d minutes.",
             r->shade_day.month, r->shade_day.day, r->shade_day.from / 60,
             r->shade_day.from % 60, r->shade_day.to / 60, r->shade_day.to % 60,
             r->shade_day.step);
    text_at(cr, MARGIN, y + 4, cell);
    y += 14;
  }
  if (!r->ngroups) text_at(cr, MARGIN, y + 12, "No run has reached any of the reported years.");
  return y;
}

static double stand_notes(cairo_t *cr, const report *r, double y) {
  (void)r;
  font(cr, 9, false);
  text_at(cr, MARGIN, y + 4, "Each run's stand (all its stems, per hectare of its stand area) "
          "at that year: median (minimum–maximum) over the runs of each summary line.");
  text_at(cr, MARGIN, y + 18, "Died: the stems that died in iterations 1 to that year.");
  return y + 32;
}

/* Pages of a table of the groups: cols columns whose texts cell gives, the title
 * `what`, notes on the first page. */
static int table_pages(pdf *p, const report *r, int cols,
                       void (*cell_of)(const report *r, const report_group *g, int c, char *buf,
                                       size_t n),
                       const char *what, table_notes notes) {
  cairo_t *cr = p->cr;
  double *width = calloc((size_t)cols, sizeof *width);
  if (!width) return SERVER_ENOMEM;
  char cell[400];
  font(cr, TABLE_FONT, true);
  for (int c = 0; c < cols; c++) {
    cell_of(r, NULL, c, cell, sizeof cell);
    width[c] = text_width(cr, cell);
  }
  font(cr, TABLE_FONT, false);
  for (size_t i = 0; i < r->ngroups; i++)
    for (int c = 0; c < cols; c++) {
      cell_of(r, &r->groups[i], c, cell, sizeof cell);
      double w = text_width(cr, cell);
      if (w > width[c]) width[c] = w;
    }
  double total = 0;
  for (int c = 0; c < cols; c++) total += width[c] + 8;
  /* a wide table is set smaller rather than cut */
  double scale = total > PAGE_W - 2 * MARGIN ? (PAGE_W - 2 * MARGIN) / total : 1.0;
  double size = TABLE_FONT * scale, row_h = size * 1.8;
  size_t i = 0;
  do {
    double y = page_title(cr, r, what);
    if (i == 0) y = notes(cr, r, y);
    if (r->ngroups) {
      double x = MARGIN;
      font(cr, size, true);
      for (int c = 0; c < cols; c++) {
        cell_of(r, NULL, c, cell, sizeof cell);
        text_at(cr, x, y + size, cell);
        x += (width[c] + 8) * scale;
      }
      y += row_h;
      cairo_set_line_width(cr, 0.5);
      cairo_move_to(cr, MARGIN, y - size * 0.4);
      cairo_line_to(cr, PAGE_W - MARGIN, y - size * 0.4);
      cairo_stroke(cr);
      font(cr, size, false);
      for (; i < r->ngroups && y + row_h < PAGE_H - MARGIN; i++, y += row_h) {
        x = MARGIN;
        for (int c = 0; c < cols; c++) {
          cell_of(r, &r->groups[i], c, cell, sizeof cell);
          text_at(cr, x, y + size, cell);
          x += (width[c] + 8) * scale;
        }
      }
    }
    cairo_show_page(cr);
  } while (i < r->ngroups);
  free(width);
  return SERVER_OK;
}

/* ---- pictures ------------------------------------------------------------------- */

typedef struct png_reader {
  const report_png *png;
  size_t at;
} png_reader;

static cairo_status_t png_source(void *closure, unsigned char *data, unsigned int length) {
  png_reader *rd = closure;
  if (rd->png->len - rd->at < length) return CAIRO_STATUS_READ_ERROR;
  memcpy(data, rd->png->data + rd->at, length);
  rd->at += length;
  return CAIRO_STATUS_SUCCESS;
}

/* Draws a PNG scaled into the w x h box at (x, y), keeping its aspect. */
static int draw_png(cairo_t *cr, const report_png *png, double x, double y, double w, double h,
                    char *err, size_t errlen) {
  png_reader rd = {png, 0};
  cairo_surface_t *img = cairo_image_surface_create_from_png_stream(png_source, &rd);
  cairo_status_t st = cairo_surface_status(img);
  if (st != CAIRO_STATUS_SUCCESS) {
    cairo_surface_destroy(img);
    snprintf(err, errlen, "reading back a picture: %s", cairo_status_to_string(st));
    return st == CAIRO_STATUS_NO_MEMORY ? SERVER_ENOMEM : SERVER_EFAIL;
  }
  double iw = cairo_image_surface_get_width(img), ih = cairo_image_surface_get_height(img);
  double s = w / iw < h / ih ? w / iw : h / ih;
  cairo_save(cr);
  cairo_translate(cr, x, y);
  cairo_scale(cr, s, s);
  cairo_set_source_surface(cr, img, 0, 0);
  cairo_paint(cr);
  cairo_restore(cr);
  cairo_surface_destroy(img);
  return SERVER_OK;
}

/* The page header of the pictures: the title and each year above its column. */
static void picture_header(cairo_t *cr, const report *r, double cell_w) {
  double y = page_title(cr, r, "pictures");
  font(cr, 9, true);
  char cell[64], head[96];
  for (int yi = 0; yi < r->nyears; yi++) {
    report_format_year(cell, sizeof cell, r, yi);
    snprintf(head, sizeof head, "year %s", cell);
    text_at(cr, MARGIN + PICTURE_LABEL + yi * cell_w, y + 8, head);
  }
}

/* The species' label and its run's name, wrapped after its colons and commas. */
static void picture_label(cairo_t *cr, const report *r, int s, double y, double bottom) {
  cairo_set_source_rgb(cr, 0, 0, 0);
  font(cr, 9, true);
  text_at(cr, MARGIN, y + 14, r->species[s].label);
  font(cr, 6.5, false);
  char cell[300];
  double ly = y + 26;
  const char *part = r->runs[r->species[s].picture_run].name;
  while (*part && ly < bottom) {
    int len = 0;
    while (part[len] && !((part[len] == ':' || part[len] == ',') && part[len + 1] == ' ')) len++;
    if (part[len]) len++;
    snprintf(cell, sizeof cell, "%.*s", len, part);
    text_at(cr, MARGIN, ly, cell);
    ly += 9;
    part += len;
    while (*part == ' ') part++;
  }
}

/* One row per species, one column per year. A row's pictures are drawn first into
 * memory, so that its height (their widest aspect at the column's width) decides
 * whether it still fits on the page. */
static int picture_pages(pdf *p, store *st, const report *r, const report_draw_options *o,
                         char *err, size_t errlen) {
  cairo_t *cr = p->cr;
  double cell_w = (PAGE_W - 2 * MARGIN - PICTURE_LABEL) / (r->nyears ? r->nyears : 1);
  double top = MARGIN + 26 + 16, room = PAGE_H - top - MARGIN, y = PAGE_H;
  report_png *row = calloc((size_t)(r->nyears ? r->nyears : 1), sizeof *row);
  if (!row) {
    snprintf(err, errlen, "out of memory");
    return SERVER_ENOMEM;
  }
  int rc = SERVER_OK;
  for (int s = 0; s < r->nspecies && !rc; s++) {
    double h = 60; /* a row without pictures still shows its label */
    for (int yi = 0; yi < r->nyears && !rc; yi++) {
      if (!report_has_picture(r, s, yi)) continue;
      rc = report_picture(st, r, s, yi, o, &row[yi], err, errlen);
      if (!rc && row[yi].width > 0) {
        double ph = (cell_w - 4) * row[yi].height / row[yi].width;
        if (ph > h) h = ph;
      }
    }
    if (h > room) h = room;
    if (!rc && y + h > PAGE_H - MARGIN) {
      if (s) cairo_show_page(cr);
      picture_header(cr, r, cell_w);
      y = top;
    }
    if (!rc) picture_label(cr, r, s, y, y + h);
    for (int yi = 0; yi < r->nyears && !rc; yi++) {
      double x = MARGIN + PICTURE_LABEL + yi * cell_w;
      if (row[yi].data) {
        rc = draw_png(cr, &row[yi], x, y, cell_w - 4, h, err, errlen);
      } else {
        font(cr, 8, false);
        cairo_set_source_rgb(cr, 0.4, 0.4, 0.4);
        text_at(cr, x, y + 14, "not grown so far");
        cairo_set_source_rgb(cr, 0, 0, 0);
      }
    }
    for (int yi = 0; yi < r->nyears; yi++) report_png_free(&row[yi]);
    y += h + 8;
  }
  free(row);
  if (!rc && r->nspecies) cairo_show_page(cr);
  return rc;
}

/* ---- figures -------------------------------------------------------------------- */

/* One figure on a page of its own, scaled to fit. */
static int figure_page(pdf *p, const report *r, int m, const char *what) {
  cairo_t *cr = p->cr;
  double top = page_title(cr, r, what);
  double w = PAGE_W - 2 * MARGIN, h = m < 0 ? report_conflicts_height(r) : PAGE_H - top - MARGIN;
  double s = h > PAGE_H - top - MARGIN ? (PAGE_H - top - MARGIN) / h : 1.0;
  cairo_save(cr);
  cairo_translate(cr, MARGIN, top);
  cairo_scale(cr, s, s);
  int rc = m < 0 ? report_draw_conflicts(cr, w / s, h, r)
                 : report_draw_plot(cr, w, h, r, (report_measure)m);
  cairo_restore(cr);
  cairo_show_page(cr);
  return rc;
}

int report_write_pdf(FILE *f, store *st, const report *r, const report_draw_options *o,
                     char *err, size_t errlen) {
  pdf p = {.f = f};
  if (errlen) err[0] = '\0';
  cairo_surface_t *surf = cairo_pdf_surface_create_for_stream(pdf_sink, &p, PAGE_W, PAGE_H);
  p.cr = cairo_create(surf);
  char title[300];
  snprintf(title, sizeof title, "sylva report: %s", r->sweep ? r->sweep : "the runs of the store");
  cairo_pdf_surface_set_metadata(surf, CAIRO_PDF_METADATA_TITLE, title);
  cairo_pdf_surface_set_metadata(surf, CAIRO_PDF_METADATA_CREATOR, "sylva report");
  int rc = table_pages(&p, r, FIXED_COLUMNS + report_measures_shown(r) + r->nzones, summary_cell,
                       "summary", summary_notes);
  if (!rc && r->stand && r->ngroups)
    rc = table_pages(&p, r, FIXED_COLUMNS + REPORT_STAND_FIGURES, stand_cell, "stand",
                     stand_notes);
  if (!rc) rc = picture_pages(&p, st, r, o, err, errlen);
  else snprintf(err, errlen, "out of memory");
  if (!rc) rc = figure_page(&p, r, REPORT_HEIGHT, "height");
  if (!rc) rc = figure_page(&p, r, REPORT_CROWN_DIAMETER, "crown diameter");
  if (!rc) rc = figure_page(&p, r, -1, "first conflicts");
  if (rc == SERVER_ENOMEM && !err[0]) snprintf(err, errlen, "out of memory");
  cairo_status_t status = cairo_status(p.cr);
  cairo_destroy(p.cr);
  cairo_surface_finish(surf);
  if (status == CAIRO_STATUS_SUCCESS) status = cairo_surface_status(surf);
  cairo_surface_destroy(surf);
  if (rc) return rc;
  if (p.write_errno || status == CAIRO_STATUS_WRITE_ERROR) {
    snprintf(err, errlen, "%s", strerror(p.write_errno ? p.write_errno : EIO));
    return SERVER_EWRITE;
  }
  if (status != CAIRO_STATUS_SUCCESS) {
    snprintf(err, errlen, "cairo: %s", cairo_status_to_string(status));
    return status == CAIRO_STATUS_NO_MEMORY ? SERVER_ENOMEM : SERVER_EFAIL;
  }
  if (fflush(f) || ferror(f)) {
    snprintf(err, errlen, "%s", strerror(errno ? errno : EIO));
    return SERVER_EWRITE;
  }
  return SERVER_OK;
}
