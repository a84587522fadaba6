/* The report of a calibration: a table of the model against the data at each decade,
 * and a picture of the curves with the measured trees (cairo). */
#include "fit_report.h"

#include <cairo.h>
#include <math.h>
#include <stdio.h>

static const char *const measure_names[4] = {"height (m)", "dbh (cm)", "crown diameter (m)",
                                              "crown height (m)"};

static double measure_at(const sylva_fit_sizes *s, int m) {
  const double v[4] = {s->height, s->dbh_cm, s->crown_dia, s->crown_ht};
  return v[m];
}

static double tree_measure(const sylva_fit_tree *t, int m) {
  const double v[4] = {t->height, t->dbh_cm, t->crown_dia, t->crown_ht};
  return v[m];
}

void sylva_fit_report_table(FILE *f, const sylva_fit_targets *t, const sylva_fit_result *r) {
  fputs("| age | height m (data / model) | dbh cm | crown diameter m | crown height m |\n"
        "|---|---|---|---|---|\n",
        f);
  for (int a = 10; a <= r->grown.years; a += 10) {
    if (a < t->first) continue;
    fprintf(f, "| %d |", a);
    for (int m = 0; m < 4; m++) {
      double want = measure_at(&t->at[a], m), got = measure_at(&r->grown.at[a], m);
      double e = sylva_fit_error(got, want);
      if (isfinite(e))
        fprintf(f, " %.2f / %.2f (%+.0f%%) |", want, got, 100.0 * e);
      else
        fprintf(f, " %.2f / %.2f |", want, got);
    }
    fputc('\n', f);
  }
}

static double nice_top(double v) {
  double p = pow(10.0, floor(log10(v > 0 ? v : 1)));
  for (double s = 1; s <= 10; s += (s < 2 ? 1 : s < 5 ? 3 : 5))
    if (s * p >= v) return s * p;
  return 10 * p;
}

int sylva_fit_report_png(const char *path, const char *title, const sylva_fit_targets *t,
                         const sylva_fit_result *r, const sylva_fit_tree *trees, int count) {
  const int W = 1000, H = 760, pw = 440, ph = 300;
  cairo_surface_t *surf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, W, H);
  cairo_t *cr = cairo_create(surf);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, 16);
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_move_to(cr, 30, 28);
  cairo_show_text(cr, title);
  int years = r->grown.years;
  for (int m = 0; m < 4; m++) {
    double x0 = 60 + (m % 2) * (pw + 60), y0 = 60 + (m / 2) * (ph + 60);
    double top = 0;
    for (int a = 0; a <= years; a++) {
      double v = measure_at(&t->at[a], m), g = measure_at(&r->grown.at[a], m);
      if (isfinite(v) && v > top) top = v;
      if (isfinite(g) && g > top) top = g;
    }
    for (int i = 0; i < count; i++) {
      double v = tree_measure(&trees[i], m);
      if (isfinite(v) && v > top && trees[i].age <= years) top = v;
    }
    top = nice_top(top);
    /* axes, ticks every 10 years and every fifth of the top */
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    cairo_set_line_width(cr, 1);
    cairo_rectangle(cr, x0, y0, pw, ph);
    cairo_stroke(cr);
    cairo_set_font_size(cr, 11);
    for (int a = 0; a <= years; a += 10) {
      double x = x0 + pw * a / (double)years;
      char s[16];
      snprintf(s, sizeof s, "%d", a);
      cairo_move_to(cr, x - 6, y0 + ph + 14);
      cairo_show_text(cr, s);
    }
    for (int k = 0; k <= 5; k++) {
      double y = y0 + ph - ph * k / 5.0;
      char s[16];
      snprintf(s, sizeof s, "%g", top * k / 5.0);
      cairo_move_to(cr, x0 - 36, y + 4);
      cairo_show_text(cr, s);
    }
    cairo_set_font_size(cr, 13);
    cairo_move_to(cr, x0 + 6, y0 + 16);
    cairo_show_text(cr, measure_names[m]);
    /* the data's curve (grey), the model's median (green), the trees (dots) */
    for (int pass = 0; pass < 2; pass++) {
      const sylva_fit_targets *c = pass ? &r->grown : t;
      if (pass)
        cairo_set_source_rgb(cr, 0.1, 0.55, 0.2);
      else
        cairo_set_source_rgb(cr, 0.45, 0.45, 0.45);
      cairo_set_line_width(cr, pass ? 2.5 : 2);
      bool open = false;
      for (int a = pass ? 0 : t->first; a <= years; a++) {
        double v = measure_at(&c->at[a], m);
        if (!isfinite(v)) {
          open = false;
          continue;
        }
        double x = x0 + pw * a / (double)years, y = y0 + ph - ph * v / top;
        if (open)
          cairo_line_to(cr, x, y);
        else
          cairo_move_to(cr, x, y);
        open = true;
      }
      cairo_stroke(cr);
    }
    cairo_set_source_rgba(cr, 0.2, 0.3, 0.8, 0.7);
    for (int i = 0; i < count; i++) {
      double v = tree_measure(&trees[i], m);
      if (!isfinite(v) || trees[i].age > years) continue;
      cairo_arc(cr, x0 + pw * trees[i].age / years, y0 + ph - ph * v / top, 3, 0, 6.283185307179586);
      cairo_fill(cr);
    }
  }
  cairo_set_font_size(cr, 12);
  cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
  cairo_move_to(cr, 30, H - 14);
  cairo_show_text(cr, "age (years since planting); grey: the data's curve, green: the model "
                      "(median of the seeds), dots: measured trees");
  cairo_destroy(cr);
  cairo_status_t st = cairo_surface_write_to_png(surf, path);
  cairo_surface_destroy(surf);
  return st == CAIRO_STATUS_SUCCESS ? 0 : -1;
}
