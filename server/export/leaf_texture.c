/* The leaf texture (leaf_texture.h). */
#include "leaf_texture.h"

#include <cairo.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/status.h"

#define LEAF_PI 3.14159265358979323846

/* A growing byte block that cairo's PNG writer appends to. */
typedef struct png_sink {
  unsigned char *data;
  size_t len, cap;
} png_sink;

static cairo_status_t sink_write(void *closure, const unsigned char *bytes, unsigned int length) {
  png_sink *s = closure;
  if (length > s->cap - s->len) {
    size_t cap = s->cap ? s->cap : 1024;
    while (length > cap - s->len) {
      if (cap > SIZE_MAX / 2) return CAIRO_STATUS_NO_MEMORY;
      cap *= 2;
    }
    unsigned char *data = realloc(s->data, cap);
    if (!data) return CAIRO_STATUS_NO_MEMORY;
    s->data = data;
    s->cap = cap;
  }
  memcpy(s->data + s->len, bytes, length);
  s->len += length;
  return CAIRO_STATUS_SUCCESS;
}

/* The blade and its midrib on a transparent surface of side n pixels. */
static void draw_leaf(cairo_t *cr, double n) {
  cairo_set_operator(cr, CAIRO_OPERATOR_SOURCE);
  cairo_set_source_rgba(cr, 0.0, 0.0, 0.0, 0.0);
  cairo_paint(cr);
  cairo_set_operator(cr, CAIRO_OPERATOR_OVER);
  /* the inscribed ellipse, half a pixel inside the edge so that its antialiased
   * rim stays on the card */
  double r = 0.5 * n - 0.5;
  cairo_save(cr);
  cairo_translate(cr, 0.5 * n, 0.5 * n);
  cairo_scale(cr, r, r);
  cairo_arc(cr, 0.0, 0.0, 1.0, 0.0, 2.0 * LEAF_PI);
  cairo_restore(cr);
  cairo_set_source_rgba(cr, 0.95, 0.95, 0.95, 1.0);
  cairo_fill(cr);
  /* the midrib: from the base (bottom) to a tenth short of the tip (top), as the
   * card's `along` runs from v = 1 to v = 0 */
  cairo_set_line_width(cr, n / 32.0);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_move_to(cr, 0.5 * n, n - 1.0);
  cairo_line_to(cr, 0.5 * n, 0.1 * n);
  cairo_set_source_rgba(cr, 0.6, 0.6, 0.6, 1.0);
  cairo_stroke(cr);
}

int leaf_texture_png(unsigned char **png, size_t *len) {
  *png = NULL;
  *len = 0;
  cairo_surface_t *surface =
      cairo_image_surface_create(CAIRO_FORMAT_ARGB32, LEAF_TEXTURE_SIZE, LEAF_TEXTURE_SIZE);
  cairo_t *cr = cairo_create(surface);
  draw_leaf(cr, LEAF_TEXTURE_SIZE);
  cairo_status_t status = cairo_status(cr);
  cairo_destroy(cr);
  cairo_surface_flush(surface);
  png_sink sink = {0};
  if (status == CAIRO_STATUS_SUCCESS)
    status = cairo_surface_write_to_png_stream(surface, sink_write, &sink);
  cairo_surface_destroy(surface);
  if (status != CAIRO_STATUS_SUCCESS) {
    free(sink.data);
    return SYLVA_ENOMEM;
  }
  *png = sink.data;
  *len = sink.len;
  return 0;
}
