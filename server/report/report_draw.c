/* The report's pictures (report_draw.h): species drawn by the render code, plots of
 * height and crown diameter over the years, the first-conflict chart. */
#include "report_draw.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render.h"

/* ---- PNGs in memory --------------------------------------------------------------- */

void report_png_free(report_png *p) {
  free(p->data);
  *p = (report_png){0};
}

/* A PNG's size from its IHDR chunk (what every PNG starts with). */
static void png_size(report_png *p) {
  const unsigned char *d = p->data;
  if (p->len < 24) return;
  p->width = (int)((unsigned)d[16] << 24 | (unsigned)d[17] << 16 | (unsigned)d[18] << 8 | d[19]);
  p->height = (int)((unsigned)d[20] << 24 | (unsigned)d[21] << 16 | (unsigned)d[22] << 8 | d[23]);
}

bool report_has_picture(const report *r, int s, int y) {
  int run = r->species[s].picture_run;
  return run >= 0 && run < r->nruns && r->runs[run].last_iteration >= r->years[y];
}

int report_picture(store *st, const report *r, int s, int y, const report_draw_options *o,
                   report_png *out, char *err, size_t errlen) {
  *out = (report_png){0};
  const report_run *run = &r->runs[r->species[s].picture_run];
  sylva_world *w = NULL;
  if (store_world_at(st, run->id, r->years[y], o->warn, &w)) {
    snprintf(err, errlen, "run \"%s\" at iteration %d: %s", run->name, r->years[y],
             store_error(st));
    return SERVER_EFAIL;
  }
  char *buf = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&buf, &len);
  if (!f) {
    sylva_world_destroy(w);
    snprintf(err, errlen, "out of memory");
    return SERVER_ENOMEM;
  }
  render_options ro = {.format = RENDER_PNG, .view = o->view, .width = o->width,
                       .name = r->species[s].label, .start_year = run->start_year};
  char why[256];
  int rc = render_write(f, w, &ro, why, sizeof why);
  sylva_world_destroy(w);
  if (fclose(f) && !rc) {
    snprintf(why, sizeof why, "%s", strerror(errno));
    rc = SERVER_ENOMEM;
  }
  if (rc) {
    free(buf);
    snprintf(err, errlen, "drawing %s at year %d: %s", r->species[s].label, r->years[y], why);
    return rc == SERVER_EWRITE ? SERVER_ENOMEM : rc;
  }
  out->data = (unsigned char *)buf;
  out->len = len;
  png_size(out);
  return SERVER_OK;
}

/* ---- drawing helpers ------------------------------------------------------------ */

unsigned report_species_colour(int s) {
  return render_palette[(unsigned)s % RENDER_PALETTE_SIZE];
}

static void set_colour(cairo_t *cr, unsigned rgb, double alpha) {
  cairo_set_source_rgba(cr, ((rgb >> 16) & 255) / 255.0, ((rgb >> 8) & 255) / 255.0,
                        (rgb & 255) / 255.0, alpha);
}

/* Text with its baseline at y, aligned at x by `align` of its width (0 left, 0.5
 * centre, 1 right). */
static void text_at(cairo_t *cr, double x, double y, const char *s, double align) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, s, &e);
  cairo_move_to(cr, x - align * e.x_advance, y);
  cairo_show_text(cr, s);
}

/* A tick step of 1, 2 or 5 x 10^k that leaves at least `space` units of the axis
 * between two ticks. */
static double tick_step(double space) {
  double p = pow(10.0, floor(log10(space > 0 ? space : 1)));
  for (int i = 0; i < 3; i++) {
    double s = (double[]){1, 2, 5}[i] * p;
    if (s >= space) return s;
  }
  return 10 * p;
}

/* A plot's frame, ticks and axis names: x from 0 to xmax, y from 0 to ymax (no y
 * scale when yname is ""), in the box (x0, y0)-(x1, y1). */
static void frame_axes(cairo_t *cr, double x0, double y0, double x1, double y1, double xmax,
                       double ymax, const char *xname, const char *yname) {
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1);
  cairo_rectangle(cr, x0, y0, x1 - x0, y1 - y0);
  cairo_stroke(cr);
  cairo_set_font_size(cr, 11);
  char buf[32];
  double xs = tick_step(xmax * 50.0 / (x1 - x0)), ys = tick_step(ymax * 35.0 / (y1 - y0));
  for (double v = 0; v <= xmax + 1e-9; v += xs) {
    double x = x0 + v / xmax * (x1 - x0);
    cairo_move_to(cr, x, y1);
    cairo_line_to(cr, x, y1 + 4);
    cairo_stroke(cr);
    snprintf(buf, sizeof buf, "%g", v);
    text_at(cr, x, y1 + 16, buf, 0.5);
  }
  /* a chart without a y scale (yname "") has bars, not values, up the side */
  for (double v = 0; yname[0] && v <= ymax + 1e-9; v += ys) {
    double y = y1 - v / ymax * (y1 - y0);
    cairo_set_source_rgba(cr, 0, 0, 0, 0.12);
    cairo_move_to(cr, x0, y);
    cairo_line_to(cr, x1, y);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, x0 - 4, y);
    cairo_line_to(cr, x0, y);
    cairo_stroke(cr);
    snprintf(buf, sizeof buf, "%g", v);
    text_at(cr, x0 - 7, y + 4, buf, 1.0);
  }
  text_at(cr, (x0 + x1) / 2, y1 + 34, xname, 0.5);
  cairo_save(cr);
  cairo_translate(cr, x0 - 40, (y0 + y1) / 2);
  cairo_rotate(cr, -2.0 * atan(1.0)); /* a quarter turn back */
  text_at(cr, 0, 0, yname, 0.5);
  cairo_restore(cr);
}

/* ---- plots over the years ------------------------------------------------------- */

typedef struct point {
  int species, iteration;
  double v;
} point;

static int compare_points(const void *a, const void *b) {
  const point *x = a, *y = b;
  if (x->species != y->species) return x->species - y->species;
  if (x->iteration != y->iteration) return x->iteration - y->iteration;
  return (x->v > y->v) - (x->v < y->v);
}

/* The database's value of a measure at year x of species s (NAN beyond its ages). */
static double utdb_at(const report_species *s, report_measure m, int x) {
  int age = x + s->age0;
  if (!s->utdb || age < 0 || age > s->utdb->years) return NAN;
  return m == REPORT_HEIGHT ? s->utdb->at[age].height : s->utdb->at[age].crown_dia;
}

/* A figure's start: the state saved (the figure restores it), a white page, and the
 * title's font: bold 14 in black. */
static void figure_begin(cairo_t *cr, double w, double h) {
  cairo_save(cr);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_rectangle(cr, 0, 0, w, h);
  cairo_fill(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
  cairo_set_font_size(cr, 14);
  cairo_set_source_rgb(cr, 0, 0, 0);
}

int report_draw_plot(cairo_t *cr, double w, double h, const report *r, report_measure m) {
  point *pts = malloc((r->nsamples ? r->nsamples : 1) * sizeof *pts);
  if (!pts) return SERVER_ENOMEM;
  figure_begin(cr, w, h);
  const char *name = m == REPORT_HEIGHT ? "Height" : "Crown diameter";
  char title[128];
  snprintf(title, sizeof title, "%s over the years: median of every stem, range shaded", name);
  text_at(cr, 16, 22, title, 0);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);

  double x0 = 70, y0 = 40, x1 = w - 230, y1 = h - 50;
  size_t n = 0;
  double ymax = 0;
  int xmax = r->max_iteration > 0 ? r->max_iteration : 1;
  for (size_t i = 0; i < r->nsamples; i++) {
    double v = m == REPORT_HEIGHT ? r->samples[i].height : r->samples[i].crown_diameter;
    if (isnan(v)) continue;
    pts[n++] = (point){r->samples[i].species, r->samples[i].iteration, v};
    if (v > ymax) ymax = v;
  }
  for (int s = 0; s < r->nspecies; s++)
    for (int x = 0; x <= xmax; x++) {
      double v = utdb_at(&r->species[s], m, x);
      if (v > ymax) ymax = v;
    }
  ymax = ymax > 0 ? ymax * 1.05 : 1;
  qsort(pts, n, sizeof *pts, compare_points);
  frame_axes(cr, x0, y0, x1, y1, xmax, ymax, "years since planting (iteration)",
             m == REPORT_HEIGHT ? "height (m)" : "crown diameter (m)");
  cairo_rectangle(cr, x0, y0, x1 - x0, y1 - y0);
  cairo_save(cr);
  cairo_clip(cr);
#define PX(x) (x0 + (double)(x) / xmax * (x1 - x0))
#define PY(v) (y1 - (v) / ymax * (y1 - y0))
  /* per species: runs of points of one iteration give min, median and max */
  for (size_t i = 0; i < n;) {
    int s = pts[i].species;
    size_t end = i;
    while (end < n && pts[end].species == s) end++;
    unsigned c = report_species_colour(s);
    for (int pass = 0; pass < 3; pass++) {
      /* pass 0: the band's upper edge forward, 1: its lower edge back; 2: the median */
      bool started = false;
      if (pass == 1) {
        for (size_t j = end; j > i;) {
          size_t k = j;
          while (k > i && pts[k - 1].iteration == pts[j - 1].iteration) k--;
          cairo_line_to(cr, PX(pts[k].iteration), PY(pts[k].v));
          j = k;
        }
        cairo_close_path(cr);
        set_colour(cr, c, 0.18);
        cairo_fill(cr);
        continue;
      }
      for (size_t j = i; j < end;) {
        size_t k = j;
        while (k < end && pts[k].iteration == pts[j].iteration) k++;
        size_t cnt = k - j;
        double v = pass == 0 ? pts[k - 1].v
                             : cnt % 2 ? pts[j + cnt / 2].v
                                       : (pts[j + cnt / 2 - 1].v + pts[j + cnt / 2].v) / 2;
        if (!started) cairo_move_to(cr, PX(pts[j].iteration), PY(v));
        else cairo_line_to(cr, PX(pts[j].iteration), PY(v));
        started = true;
        j = k;
      }
      if (pass == 2) {
        set_colour(cr, c, 1);
        cairo_set_line_width(cr, 2);
        cairo_stroke(cr);
      }
    }
    i = end;
  }
  /* the database's open-grown curves, dashed */
  const double dash[] = {7, 4};
  for (int s = 0; s < r->nspecies; s++) {
    bool started = false;
    for (int x = 0; x <= xmax; x++) {
      double v = utdb_at(&r->species[s], m, x);
      if (isnan(v)) continue;
      if (!started) cairo_move_to(cr, PX(x), PY(v));
      else cairo_line_to(cr, PX(x), PY(v));
      started = true;
    }
    if (!started) continue;
    set_colour(cr, report_species_colour(s), 1);
    cairo_set_line_width(cr, 1.5);
    cairo_set_dash(cr, dash, 2, 0);
    cairo_stroke(cr);
    cairo_set_dash(cr, NULL, 0, 0);
  }
#undef PX
#undef PY
  cairo_restore(cr);
  /* the legend, right of the plot */
  cairo_set_font_size(cr, 11);
  double ly = y0 + 8;
  for (int s = 0; s < r->nspecies; s++, ly += 18) {
    set_colour(cr, report_species_colour(s), 1);
    cairo_set_line_width(cr, 2);
    cairo_move_to(cr, x1 + 14, ly);
    cairo_line_to(cr, x1 + 38, ly);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    text_at(cr, x1 + 44, ly + 4, r->species[s].label, 0);
  }
  ly += 10;
  cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
  cairo_set_line_width(cr, 1.5);
  cairo_set_dash(cr, dash, 2, 0);
  cairo_move_to(cr, x1 + 14, ly);
  cairo_line_to(cr, x1 + 38, ly);
  cairo_stroke(cr);
  cairo_set_dash(cr, NULL, 0, 0);
  cairo_set_source_rgb(cr, 0, 0, 0);
  text_at(cr, x1 + 44, ly + 4, "Urban Tree Database,", 0);
  text_at(cr, x1 + 44, ly + 18, "open-grown (library species)", 0);
  free(pts);
  cairo_restore(cr);
  return SERVER_OK;
}

/* ---- first conflicts ------------------------------------------------------------ */

#define CONFLICT_BAR 16.0
#define CONFLICT_GAP 14.0
#define CONFLICT_TOP 44.0
#define CONFLICT_BOTTOM 56.0

double report_conflicts_height(const report *r) {
  int zones = r->nzones ? r->nzones : 1;
  return CONFLICT_TOP + r->nspecies * (zones * CONFLICT_BAR + CONFLICT_GAP) + CONFLICT_BOTTOM;
}

/* Zone colours: distinct from one another, drawn for every species alike. */
static const unsigned zone_palette[] = {0xd95f02, 0x7570b3, 0x1b9e77, 0xe7298a, 0x66a61e,
                                        0xe6ab02, 0xa6761d, 0x666666};

static int compare_doubles(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int report_draw_conflicts(cairo_t *cr, double w, double h, const report *r) {
  double *v = malloc((r->nfinals ? r->nfinals : 1) * sizeof *v);
  if (!v) return SERVER_ENOMEM;
  figure_begin(cr, w, h);
  text_at(cr, 16, 22, "First conflict with each clearance zone, years after planting", 0);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 11);
  if (!r->nzones) {
    text_at(cr, 16, CONFLICT_TOP + 12, "The runs have no clearance zones.", 0);
    cairo_restore(cr);
    free(v);
    return SERVER_OK;
  }
  double x0 = 170, x1 = w - 250, y1 = h - CONFLICT_BOTTOM;
  double xmax = r->max_iteration > 0 ? r->max_iteration : 1;
  frame_axes(cr, x0, CONFLICT_TOP, x1, y1, xmax, 1, "years after planting (by each run's last "
             "stored iteration)", "");
  double y = CONFLICT_TOP + CONFLICT_GAP / 2;
  for (int s = 0; s < r->nspecies; s++) {
    cairo_set_source_rgb(cr, 0, 0, 0);
    text_at(cr, x0 - 8, y + r->nzones * CONFLICT_BAR / 2 + 4, r->species[s].label, 1.0);
    for (int z = 0; z < r->nzones; z++, y += CONFLICT_BAR) {
      int n = 0, k = 0;
      for (size_t i = 0; i < r->nfinals; i++) {
        const report_row *f = &r->finals[i];
        if (f->species != s) continue;
        n++;
        for (int j = 0; j < f->nfirst; j++)
          if (f->first[j].index == z)
            v[k++] = f->first[j].value - r->runs[f->run].start_year;
      }
      char label[160];
      unsigned c = zone_palette[z % (sizeof zone_palette / sizeof *zone_palette)];
      if (k) {
        qsort(v, (size_t)k, sizeof *v, compare_doubles);
        double med = k % 2 ? v[k / 2] : (v[k / 2 - 1] + v[k / 2]) / 2;
        set_colour(cr, c, 0.85);
        cairo_rectangle(cr, x0, y + 2, med / xmax * (x1 - x0), CONFLICT_BAR - 4);
        cairo_fill(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_set_line_width(cr, 1);
        double a = x0 + v[0] / xmax * (x1 - x0), b = x0 + v[k - 1] / xmax * (x1 - x0);
        cairo_move_to(cr, a, y + CONFLICT_BAR / 2);
        cairo_line_to(cr, b, y + CONFLICT_BAR / 2);
        cairo_move_to(cr, a, y + 4);
        cairo_line_to(cr, a, y + CONFLICT_BAR - 4);
        cairo_move_to(cr, b, y + 4);
        cairo_line_to(cr, b, y + CONFLICT_BAR - 4);
        cairo_stroke(cr);
        snprintf(label, sizeof label, "%s: %g y (%g–%g), %d of %d", r->zones[z], med, v[0],
                 v[k - 1], k, n);
      } else {
        snprintf(label, sizeof label, "%s: never, 0 of %d", r->zones[z], n);
      }
      set_colour(cr, c, 1);
      text_at(cr, x1 + 8, y + CONFLICT_BAR - 4, label, 0);
    }
    y += CONFLICT_GAP;
  }
  free(v);
  cairo_restore(cr);
  return SERVER_OK;
}

/* ---- figures as PNG ------------------------------------------------------------- */

static cairo_status_t png_sink(void *closure, const unsigned char *data, unsigned int length) {
  FILE *f = closure;
  return fwrite(data, 1, length, f) == length ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_WRITE_ERROR;
}

int report_figure_png(const report *r, int m, int w, int h, report_png *out, char *err,
                      size_t errlen) {
  *out = (report_png){0};
  cairo_surface_t *surf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
  cairo_t *cr = cairo_create(surf);
  int drawn = m < 0 ? report_draw_conflicts(cr, w, h, r)
                    : report_draw_plot(cr, w, h, r, (report_measure)m);
  cairo_status_t status = drawn ? CAIRO_STATUS_NO_MEMORY : cairo_status(cr);
  cairo_destroy(cr);
  char *buf = NULL;
  size_t len = 0;
  FILE *f = status == CAIRO_STATUS_SUCCESS ? open_memstream(&buf, &len) : NULL;
  if (f) status = cairo_surface_write_to_png_stream(surf, png_sink, f);
  else if (status == CAIRO_STATUS_SUCCESS) status = CAIRO_STATUS_NO_MEMORY;
  cairo_surface_destroy(surf);
  if (f && fclose(f) && status == CAIRO_STATUS_SUCCESS) status = CAIRO_STATUS_NO_MEMORY;
  if (status != CAIRO_STATUS_SUCCESS) {
    free(buf);
    snprintf(err, errlen, "drawing a figure: %s", cairo_status_to_string(status));
    return status == CAIRO_STATUS_NO_MEMORY ? SERVER_ENOMEM : SERVER_EFAIL;
  }
  out->data = (unsigned char *)buf;
  out->len = len;
  png_size(out);
  return SERVER_OK;
}
