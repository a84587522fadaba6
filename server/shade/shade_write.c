/* A day's shade written out (shade.h): the cells as CSV, the summary as one JSON
 * line, the ground's tree shade as a plan (cairo PNG). Fixed decimals throughout,
 * so that the same result gives the same bytes. */
#include <cairo.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "server_error.h"
#include "shade.h"

/* The status of a stream after writing: SERVER_EWRITE with errno's reason. */
static int stream_status(FILE *f, char *err, size_t errlen) {
  if (ferror(f) || fflush(f) != 0)
    return server_fail(err, errlen, SERVER_EWRITE, "%s", strerror(errno ? errno : EIO));
  return SERVER_OK;
}

int shade_write_csv(FILE *f, const shade_result *r, char *err, size_t errlen) {
  errno = 0;
  fputs("x,y,z,surface,sun_hours_open,sun_hours\n", f);
  for (size_t i = 0; i < r->cell_count && !ferror(f); i++) {
    const shade_cell *c = &r->cells[i];
    fprintf(f, "%.3f,%.3f,%.3f,%s,%.4f,%.4f\n", c->p[0], c->p[1], c->p[2],
            r->surfaces[c->surface].name, c->open, c->with);
  }
  return stream_status(f, err, errlen);
}

/* A JSON string of a label (ids are printable, but quote what must be). */
static void put_string(FILE *f, const char *s) {
  fputc('"', f);
  for (; *s; s++) {
    unsigned char ch = (unsigned char)*s;
    if (ch == '"' || ch == '\\') fprintf(f, "\\%c", ch);
    else if (ch < 0x20) fprintf(f, "\\u%04x", ch);
    else fputc(ch, f);
  }
  fputc('"', f);
}

int shade_write_summary(FILE *f, const shade_result *r, char *err, size_t errlen) {
  errno = 0;
  const shade_day *d = &r->day;
  fprintf(f,
          "{\"date\": \"%02d-%02d\", \"from\": \"%02d:%02d\", \"to\": \"%02d:%02d\", "
          "\"step\": %d, \"year\": %d, \"latitude\": %.4f, \"surfaces\": [",
          d->month, d->day, d->from / 60, d->from % 60, d->to / 60, d->to % 60, d->step, d->year,
          r->site.latitude);
  for (int s = 0; s < r->surface_count; s++) {
    const shade_surface *x = &r->surfaces[s];
    fputs(s ? ", {\"surface\": " : "{\"surface\": ", f);
    put_string(f, x->name);
    fprintf(f,
            ", \"cells\": %zu, \"sun_hours_open\": %.4f, \"sun_hours\": %.4f, "
            "\"tree_shade_hours\": %.4f, \"share_under_2h\": %.4f}",
            x->count, x->mean_open, x->mean_with, x->mean_added, x->share_dim);
  }
  fputs("]}\n", f);
  return stream_status(f, err, errlen);
}

/* The plan's layout: pixels per metre, margins, the legend's place. */
enum { PNG_MARGIN = 40, PNG_LEGEND = 110, PNG_TARGET = 900 };

/* The colour of h hours of shade out of top: white to deep blue-green. */
static void shade_colour(double h, double top, double rgb[3]) {
  double t = top > 0.0 ? h / top : 0.0;
  if (t < 0.0) t = 0.0;
  if (t > 1.0) t = 1.0;
  static const double lo[3] = {1.0, 1.0, 0.94}, hi[3] = {0.05, 0.25, 0.35};
  for (int k = 0; k < 3; k++) rgb[k] = lo[k] + t * (hi[k] - lo[k]);
}

static cairo_status_t png_sink(void *closure, const unsigned char *data, unsigned int length) {
  return fwrite(data, 1, length, closure) == length ? CAIRO_STATUS_SUCCESS
                                                     : CAIRO_STATUS_WRITE_ERROR;
}

/* The legend: a bar from 0 to top hours with ticks each `tick` hours. */
static void draw_legend(cairo_t *cr, double x, double y, double height, double top) {
  int steps = 64;
  for (int i = 0; i < steps; i++) {
    double rgb[3];
    shade_colour(top * (i + 0.5) / steps, top, rgb);
    cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
    cairo_rectangle(cr, x, y + height - height * (i + 1) / steps, 18, height / steps + 0.5);
    cairo_fill(cr);
  }
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, x, y, 18, height);
  cairo_stroke(cr);
  cairo_set_font_size(cr, 11);
  int ticks = (int)top;
  int every = ticks > 8 ? 2 : 1;
  for (int h = 0; h <= ticks; h += every) {
    double ty = y + height - height * h / top;
    cairo_move_to(cr, x + 18, ty);
    cairo_line_to(cr, x + 23, ty);
    cairo_stroke(cr);
    char label[16];
    snprintf(label, sizeof label, "%d h", h);
    cairo_move_to(cr, x + 26, ty + 4);
    cairo_show_text(cr, label);
  }
  cairo_move_to(cr, x - 4, y - 10);
  cairo_show_text(cr, "tree shade");
}

/* The plan's frame: metres, x right, y up, the plan ph pixels high at `scale`. */
static void plan_frame(cairo_t *cr, const shade_result *r, double scale, int ph) {
  cairo_translate(cr, PNG_MARGIN, PNG_MARGIN + 10 + ph);
  cairo_scale(cr, scale, -scale);
  cairo_translate(cr, -r->min[0], -r->min[1]);
}

/* Fills the path in grey and draws its outline (device units, 2 px). */
static void draw_footprint(cairo_t *cr) {
  cairo_set_source_rgb(cr, 0.78, 0.78, 0.78);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.35, 0.1, 0.1);
  cairo_set_line_width(cr, 2.0);
  cairo_stroke(cr);
}

int shade_write_png(FILE *f, const shade_result *r, const sylva_world *w, char *err,
                    size_t errlen) {
  if (r->nx <= 0 || r->surface_count < 1 || r->surfaces[0].face >= 0)
    return server_fail(err, errlen, SERVER_EINPUT, "the plan needs the ground's cells");
  double wx = r->max[0] - r->min[0], wy = r->max[1] - r->min[1];
  double scale = floor(PNG_TARGET / (wx > wy ? wx : wy));
  if (scale < 1.0) scale = 1.0;
  int pw = (int)ceil(wx * scale), ph = (int)ceil(wy * scale);
  int width = pw + 2 * PNG_MARGIN + PNG_LEGEND, height = ph + 2 * PNG_MARGIN + 20;
  double top = 0.0;
  size_t n = (size_t)r->nx * (size_t)r->ny;
  for (size_t i = 0; i < n; i++)
    if (r->cells[i].open - r->cells[i].with > top) top = r->cells[i].open - r->cells[i].with;
  top = ceil(top);
  if (top < 1.0) top = 1.0;

  cairo_surface_t *grid = cairo_image_surface_create(CAIRO_FORMAT_RGB24, r->nx, r->ny);
  cairo_surface_t *surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
  cairo_status_t status = cairo_surface_status(grid);
  if (status == CAIRO_STATUS_SUCCESS) status = cairo_surface_status(surface);
  if (status == CAIRO_STATUS_SUCCESS) {
    cairo_surface_flush(grid);
    unsigned char *px = cairo_image_surface_get_data(grid);
    int stride = cairo_image_surface_get_stride(grid);
    for (int j = 0; j < r->ny; j++) {
      /* rows from the top of the picture: north (y up) first */
      uint32_t *row = (uint32_t *)(void *)(px + (size_t)stride * (size_t)(r->ny - 1 - j));
      for (int i = 0; i < r->nx; i++) {
        const shade_cell *c = &r->cells[(size_t)j * (size_t)r->nx + (size_t)i];
        double rgb[3];
        shade_colour(c->open - c->with, top, rgb);
        row[i] = (uint32_t)lround(rgb[0] * 255) << 16 | (uint32_t)lround(rgb[1] * 255) << 8 |
                 (uint32_t)lround(rgb[2] * 255);
      }
    }
    cairo_surface_mark_dirty(grid);
    cairo_t *cr = cairo_create(surface);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_font_size(cr, 13);
    char title[160];
    snprintf(title, sizeof title, "Tree shade, hours of direct sun taken, %02d-%02d %02d:%02d-%02d:%02d",
             r->day.month, r->day.day, r->day.from / 60, r->day.from % 60, r->day.to / 60,
             r->day.to % 60);
    cairo_move_to(cr, PNG_MARGIN, 24);
    cairo_show_text(cr, title);

    cairo_save(cr);
    cairo_translate(cr, PNG_MARGIN, PNG_MARGIN + 10);
    cairo_rectangle(cr, 0, 0, pw, ph);
    cairo_clip(cr);
    cairo_scale(cr, (double)pw / r->nx, (double)ph / r->ny);
    cairo_set_source_surface(cr, grid, 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
    cairo_paint(cr);
    cairo_restore(cr);

    /* from here on, metres: x right, y up */
    cairo_save(cr);
    plan_frame(cr, r, scale, ph);
    int count = sylva_world_obstacle_count(w);
    for (int i = 0; i < count; i++) {
      int id;
      sylva_obstacle_def o;
      if (sylva_world_obstacle_at(w, i, &id, &o) != 0 || o.kind != SYLVA_OBSTACLE_SOLID ||
          o.footprint.ring_count > 0)
        continue;
      cairo_rectangle(cr, o.min[0], o.min[1], o.max[0] - o.min[0], o.max[1] - o.min[1]);
    }
    cairo_restore(cr);
    draw_footprint(cr);
    /* each prism alone: its rings even-odd, as the world reads them */
    for (int i = 0; i < count; i++) {
      int id;
      sylva_obstacle_def o;
      if (sylva_world_obstacle_at(w, i, &id, &o) != 0 || o.kind != SYLVA_OBSTACLE_SOLID ||
          o.footprint.ring_count == 0)
        continue;
      const sylva_footprint *fp = &o.footprint;
      cairo_save(cr);
      plan_frame(cr, r, scale, ph);
      for (int ring = 0, first = 0; ring < fp->ring_count; first += fp->ring_sizes[ring++]) {
        cairo_move_to(cr, fp->points[first][0], fp->points[first][1]);
        for (int k = first + 1; k < first + fp->ring_sizes[ring]; k++)
          cairo_line_to(cr, fp->points[k][0], fp->points[k][1]);
        cairo_close_path(cr);
      }
      cairo_restore(cr);
      cairo_set_fill_rule(cr, CAIRO_FILL_RULE_EVEN_ODD);
      draw_footprint(cr);
      cairo_set_fill_rule(cr, CAIRO_FILL_RULE_WINDING);
    }

    cairo_set_source_rgb(cr, 0.4, 0.2, 0.05);
    int stems = sylva_world_stem_count(w);
    for (int s = 0; s < stems; s++) {
      double root[3];
      if (sylva_world_stem_root(w, s, root) != 0) continue;
      double x = PNG_MARGIN + (root[0] - r->min[0]) * scale;
      double y = PNG_MARGIN + 10 + ph - (root[1] - r->min[1]) * scale;
      cairo_arc(cr, x, y, 4.0, 0, 2 * 3.14159265358979323846);
      cairo_fill(cr);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 1.0);
    cairo_rectangle(cr, PNG_MARGIN, PNG_MARGIN + 10, pw, ph);
    cairo_stroke(cr);
    cairo_set_font_size(cr, 11);
    char scale_text[96];
    snprintf(scale_text, sizeof scale_text, "x %.1f to %.1f m, y %.1f to %.1f m (north up in y)",
             r->min[0], r->max[0], r->min[1], r->max[1]);
    cairo_move_to(cr, PNG_MARGIN, PNG_MARGIN + 10 + ph + 18);
    cairo_show_text(cr, scale_text);
    draw_legend(cr, PNG_MARGIN + pw + 30, PNG_MARGIN + 30, ph > 120 ? ph - 40 : 80, top);
    status = cairo_status(cr);
    cairo_destroy(cr);
  }
  errno = 0;
  if (status == CAIRO_STATUS_SUCCESS) status = cairo_surface_write_to_png_stream(surface, png_sink, f);
  cairo_surface_destroy(grid);
  cairo_surface_destroy(surface);
  if (status == CAIRO_STATUS_WRITE_ERROR) return stream_status(f, err, errlen) ? SERVER_EWRITE :
      server_fail(err, errlen, SERVER_EWRITE, "write failed");
  if (status != CAIRO_STATUS_SUCCESS)
    return server_fail(err, errlen, status == CAIRO_STATUS_NO_MEMORY ? SERVER_ENOMEM : SERVER_EFAIL,
                       "cairo: %s", cairo_status_to_string(status));
  return stream_status(f, err, errlen);
}
