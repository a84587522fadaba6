/* Front, side and top views of a world drawn with cairo; see render.h.
 *
 * The internodes are gathered once (each with its parent's position, found by a
 * binary search over the ids: parents come first in id order), sorted by radius,
 * then stroked once per panel. The leaf cards are placed once (foliage.h) as the
 * nodes are gathered, then sorted far to near and filled once per panel. */
#include "render.h"

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "foliage.h"

#define RENDER_PI 3.14159265358979323846

const unsigned render_palette[RENDER_PALETTE_SIZE] = {
    0x2e8b3a, 0xc46a1b, 0x2f6fb3, 0xb8326e, 0x7d5bb5, 0x1a9a8f,
    0xa08a12, 0xd04a3a, 0x4f7d1f, 0x8a4b2a, 0x3d8fd1, 0xc27bb0};

static const char *const view_names[] = {
    [RENDER_FRONT] = "front", [RENDER_SIDE] = "side", [RENDER_TOP] = "top", [RENDER_ALL] = "all"};

bool render_view_parse(const char *name, render_view *out) {
  for (size_t k = 0; k < sizeof view_names / sizeof view_names[0]; k++)
    if (strcmp(name, view_names[k]) == 0) {
      *out = (render_view)k;
      return true;
    }
  return false;
}

bool render_format_from_path(const char *path, render_format *out) {
  static const char *const extensions[] = {
      [RENDER_PNG] = "png", [RENDER_SVG] = "svg", [RENDER_PDF] = "pdf"};
  const char *dot = strrchr(path, '.');
  if (!dot || strchr(dot, '/')) return false;
  for (size_t k = 0; k < sizeof extensions / sizeof extensions[0]; k++)
    if (strcasecmp(dot + 1, extensions[k]) == 0) {
      *out = (render_format)k;
      return true;
    }
  return false;
}

/* One projection: the world axes drawn to the right (u) and up (v), the line of
 * sight along axis `sight` in the direction `look` (+1 or -1), and names. */
typedef struct view_def {
  int u, v, sight;
  double look;
  const char *title, *u_label, *v_label;
} view_def;

static const view_def views[3] = {
    [RENDER_FRONT] = {0, 2, 1, 1.0, "front: x-z, looking along +y", "x (m)", "z (m)"},
    [RENDER_SIDE] = {1, 2, 0, -1.0, "side: y-z, looking along -x", "y (m)", "z (m)"},
    [RENDER_TOP] = {0, 1, 2, -1.0, "top: x-y, seen from above", "x (m)", "y (m)"},
};

/* An internode: from its parent's position to its node's. */
typedef struct segment {
  float from[3], to[3];
  float radius;
  int32_t plant, id;
} segment;

static int compare_ids(const void *a, const void *b) {
  int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
  return (x > y) - (x < y);
}

static int compare_segments(const void *a, const void *b) {
  const segment *s = a, *t = b;
  if (s->radius != t->radius) return s->radius < t->radius ? -1 : 1;
  return (s->id > t->id) - (s->id < t->id);
}

/* A leaf card to draw: where it is, its colour (the species' leaf_colour), and its
 * distance along the current panel's line of sight (farther is larger). */
typedef struct leaf_card {
  foliage_leaf f;
  double rgb[3];
  double depth;
  int32_t id, k;
} leaf_card;

/* Farthest first, then by node id and leaf: a total order, so every sort of the
 * same cards gives the same sequence. */
static int compare_leaves(const void *a, const void *b) {
  const leaf_card *s = a, *t = b;
  if (s->depth != t->depth) return s->depth > t->depth ? -1 : 1;
  if (s->id != t->id) return s->id < t->id ? -1 : 1;
  return (s->k > t->k) - (s->k < t->k);
}

/* What a world's panels draw: its internodes, thinnest first, and its leaf cards. */
typedef struct scene {
  segment *segs;
  size_t count;
  leaf_card *leaves;
  size_t leaf_count;
} scene;

static void scene_free(scene *sc) {
  free(sc->segs);
  free(sc->leaves);
}

/* The leaves of the live nodes of w, counted; false when their number overflows. */
static bool count_leaves(const sylva_world *w, size_t n, size_t *total) {
  size_t sum = 0;
  sylva_node_info info;
  for (size_t i = 0; i < n; i++) {
    sylva_world_node_at(w, i, &info);
    if (info.leaves <= 0) continue;
    if ((size_t)info.leaves > SIZE_MAX / sizeof(leaf_card) - sum) return false;
    sum += (size_t)info.leaves;
  }
  *total = sum;
  return true;
}

/* Appends the cards of a node bearing leaves; parent NULL for a root. */
static void place_leaves(const sylva_world *w, const sylva_node_info *info, const float *parent,
                         const float *node, scene *sc) {
  const sylva_species_def *def =
      sylva_world_species(w, sylva_world_plant_species(w, info->plant));
  if (!def) return;
  double p[3], q[3], rgb[3];
  for (int a = 0; a < 3; a++) {
    p[a] = parent ? parent[a] : 0.0;
    q[a] = node[a];
  }
  foliage_rgb(def->leaf_colour, rgb);
  for (int k = 0; k < info->leaves; k++) {
    leaf_card *c = &sc->leaves[sc->leaf_count++];
    foliage_place(parent ? p : NULL, q, k, info->leaves, def->leaf_size, &c->f);
    memcpy(c->rgb, rgb, sizeof c->rgb);
    c->depth = 0.0;
    c->id = info->id;
    c->k = k;
  }
}

/* The internodes of w, thinnest first, and with leaves its leaf cards; false when
 * out of memory (sc then holds nothing). */
static bool gather(const sylva_world *w, bool leaves, scene *sc) {
  memset(sc, 0, sizeof *sc);
  size_t n = sylva_world_node_count(w), total = 0;
  if (leaves && !count_leaves(w, n, &total)) return false;
  int32_t *ids = malloc((n ? n : 1) * sizeof *ids);
  float(*pos)[3] = malloc((n ? n : 1) * sizeof *pos);
  sc->segs = malloc((n ? n : 1) * sizeof *sc->segs);
  sc->leaves = malloc((total ? total : 1) * sizeof *sc->leaves);
  if (!ids || !pos || !sc->segs || !sc->leaves) {
    free(ids);
    free(pos);
    scene_free(sc);
    memset(sc, 0, sizeof *sc);
    return false;
  }
  size_t m = 0;
  sylva_node_info info;
  for (size_t i = 0; i < n; i++) {
    sylva_world_node_at(w, i, &info);
    ids[i] = info.id;
    pos[i][0] = info.x;
    pos[i][1] = info.y;
    pos[i][2] = info.z;
    /* a live node's parent is live and comes before it in id order */
    const int32_t *p =
        info.parent < 0 ? NULL : bsearch(&info.parent, ids, i, sizeof *ids, compare_ids);
    if (leaves && info.leaves > 0 && (p || info.parent < 0))
      place_leaves(w, &info, p ? pos[p - ids] : NULL, pos[i], sc);
    if (!p) continue;
    segment *s = &sc->segs[m++];
    memcpy(s->from, pos[p - ids], sizeof s->from);
    memcpy(s->to, pos[i], sizeof s->to);
    s->radius = info.radius;
    s->plant = info.plant;
    s->id = info.id;
  }
  free(ids);
  free(pos);
  qsort(sc->segs, m, sizeof *sc->segs, compare_segments);
  sc->count = m;
  return true;
}

/* The placement of the panels in the picture. */
typedef struct layout {
  int panels;
  render_view view[3];
  double lo[3][2], hi[3][2]; /* panel k spans [lo[k][0], hi[k][0]] x [lo[k][1], hi[k][1]] m */
  double left[3];            /* each panel's left edge */
  double top;                /* the panels' top edge */
  double scale;              /* pixels per metre */
  int width, height;
} layout;

static void layout_build(const sylva_world_def *def, const render_options *o, layout *l) {
  memset(l, 0, sizeof *l);
  l->panels = o->view == RENDER_ALL ? 3 : 1;
  double extent_u = 0, extent_v = 0;
  for (int k = 0; k < l->panels; k++) {
    l->view[k] = o->view == RENDER_ALL ? (render_view)k : o->view;
    const view_def *v = &views[l->view[k]];
    l->lo[k][0] = def->min[v->u];
    l->hi[k][0] = def->max[v->u];
    l->lo[k][1] = def->min[v->v];
    l->hi[k][1] = def->max[v->v];
    extent_u += l->hi[k][0] - l->lo[k][0];
    double ev = l->hi[k][1] - l->lo[k][1];
    if (ev > extent_v) extent_v = ev;
  }
  l->width = o->width ? o->width : RENDER_PANEL_WIDTH * l->panels;
  l->top = RENDER_TITLE_HEIGHT + RENDER_PANEL_TITLE_HEIGHT;
  double margins = l->panels * (RENDER_MARGIN_LEFT + RENDER_MARGIN_RIGHT);
  l->scale = (l->width - margins) / extent_u;
  double room_v = RENDER_MAX_SIZE - l->top - RENDER_MARGIN_BOTTOM;
  if (extent_v * l->scale > room_v) l->scale = room_v / extent_v;
  double x = 0;
  for (int k = 0; k < l->panels; k++) {
    l->left[k] = x + RENDER_MARGIN_LEFT;
    x = l->left[k] + (l->hi[k][0] - l->lo[k][0]) * l->scale + RENDER_MARGIN_RIGHT;
  }
  l->height = (int)ceil(l->top + extent_v * l->scale + RENDER_MARGIN_BOTTOM);
  if (l->height > RENDER_MAX_SIZE) l->height = RENDER_MAX_SIZE;
}

/* A panel's mapping from metres to the picture. */
typedef struct panel {
  const layout *l;
  const view_def *v;
  int k;
} panel;

static double panel_x(const panel *p, double u) {
  return p->l->left[p->k] + (u - p->l->lo[p->k][0]) * p->l->scale;
}

static double panel_y(const panel *p, double v) {
  return p->l->top + (p->l->hi[p->k][1] - v) * p->l->scale;
}

static void set_rgb(cairo_t *cr, unsigned rgb) {
  cairo_set_source_rgb(cr, ((rgb >> 16) & 255) / 255.0, ((rgb >> 8) & 255) / 255.0,
                       (rgb & 255) / 255.0);
}

/* Obstacle o's outline as the current path. Seen from above, a prism is its
 * footprint's rings, and true is returned: the path is to be filled even-odd, the
 * model's inside rule, so a courtyard stays open. Otherwise the rectangle of its
 * box, or of a prism's extent seen from the side (its footprint's bounds along the
 * view's axis and its z range: the outline of the extruded footprint). */
static bool obstacle_path(cairo_t *cr, const sylva_obstacle_def *o, const panel *p) {
  const sylva_footprint *fp = &o->footprint;
  if (fp->ring_count == 0 || p->v->sight != 2) {
    double x0 = panel_x(p, o->min[p->v->u]), x1 = panel_x(p, o->max[p->v->u]);
    double y0 = panel_y(p, o->max[p->v->v]), y1 = panel_y(p, o->min[p->v->v]);
    cairo_rectangle(cr, x0, y0, x1 - x0, y1 - y0);
    return false;
  }
  int k = 0;
  for (int r = 0; r < fp->ring_count; r++) {
    for (int j = 0; j < fp->ring_sizes[r]; j++, k++) {
      double x = panel_x(p, fp->points[k][p->v->u]), y = panel_y(p, fp->points[k][p->v->v]);
      if (j == 0) cairo_move_to(cr, x, y);
      else cairo_line_to(cr, x, y);
    }
    cairo_close_path(cr);
  }
  return true;
}

static void draw_obstacles(cairo_t *cr, const sylva_world *w, const panel *p) {
  int count = sylva_world_obstacle_count(w);
  for (int i = 0; i < count; i++) {
    int id;
    sylva_obstacle_def o;
    sylva_world_obstacle_at(w, i, &id, &o);
    bool even_odd = obstacle_path(cr, &o, p);
    if (even_odd) cairo_set_fill_rule(cr, CAIRO_FILL_RULE_EVEN_ODD);
    if (o.kind == SYLVA_OBSTACLE_ZONE) { /* a clearance zone: a light amber wash, dashed */
      cairo_set_source_rgba(cr, 1.0, 0.75, 0.2, RENDER_ZONE_ALPHA);
      cairo_fill_preserve(cr);
      double dash[2] = {4, 3};
      cairo_set_dash(cr, dash, 2, 0);
      cairo_set_source_rgb(cr, 0.8, 0.5, 0.0);
      cairo_set_line_width(cr, 1);
      cairo_stroke(cr);
      cairo_set_dash(cr, NULL, 0, 0);
    } else {
      cairo_set_source_rgba(cr, RENDER_OBSTACLE_GREY, RENDER_OBSTACLE_GREY,
                            RENDER_OBSTACLE_GREY, RENDER_OBSTACLE_ALPHA);
      cairo_fill_preserve(cr);
      cairo_set_source_rgb(cr, 0.35, 0.35, 0.35);
      cairo_set_line_width(cr, 1);
      cairo_stroke(cr);
    }
    if (even_odd) cairo_set_fill_rule(cr, CAIRO_FILL_RULE_WINDING);
  }
}

static void draw_segments(cairo_t *cr, const segment *segs, size_t count, const panel *p) {
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  for (size_t i = 0; i < count; i++) {
    const segment *s = &segs[i];
    double width = 2.0 * s->radius * p->l->scale;
    cairo_set_line_width(cr, width > RENDER_MIN_LINE ? width : RENDER_MIN_LINE);
    set_rgb(cr, render_palette[(uint32_t)s->plant % RENDER_PALETTE_SIZE]);
    cairo_move_to(cr, panel_x(p, s->from[p->v->u]), panel_y(p, s->from[p->v->v]));
    cairo_line_to(cr, panel_x(p, s->to[p->v->u]), panel_y(p, s->to[p->v->v]));
    cairo_stroke(cr);
  }
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
}

/* Fills one leaf's blade: the ellipse inscribed in its card, projected. The card's
 * half-edges along and across map to the picture's columns c0 and c1 of M; the
 * blade is M applied to the unit circle, whose semi-axes are the square roots of
 * the eigenvalues of M M^T, the major one at angle theta. Each semi-axis is at
 * least half of RENDER_MIN_LEAF, so a card seen edge-on or smaller than a pixel
 * still shows (and the matrix cairo gets is never singular). */
static void fill_leaf(cairo_t *cr, const leaf_card *c, const panel *p) {
  const view_def *v = p->v;
  double h = 0.5 * c->f.edge * p->l->scale;
  double c0[2] = {h * c->f.along[v->u], -h * c->f.along[v->v]};
  double c1[2] = {h * c->f.across[v->u], -h * c->f.across[v->v]};
  double a00 = c0[0] * c0[0] + c1[0] * c1[0], a11 = c0[1] * c0[1] + c1[1] * c1[1];
  double a01 = c0[0] * c0[1] + c1[0] * c1[1];
  double mean = 0.5 * (a00 + a11), spread = hypot(0.5 * (a00 - a11), a01);
  double major = sqrt(mean + spread), minor = sqrt(fmax(mean - spread, 0.0));
  double least = 0.5 * RENDER_MIN_LEAF;
  if (major < least) major = least;
  if (minor < least) minor = least;
  double theta = 0.5 * atan2(2.0 * a01, a00 - a11);
  double ct = cos(theta), st = sin(theta);
  /* the card's normal against the line of sight: cards facing the viewer are the
   * leaf colour, cards seen edge-on RENDER_LEAF_SHADE of it */
  const double *a = c->f.along, *b = c->f.across;
  double normal[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                      a[0] * b[1] - a[1] * b[0]};
  double shade = RENDER_LEAF_SHADE + (1.0 - RENDER_LEAF_SHADE) * fabs(normal[v->sight]);
  cairo_matrix_t saved, m;
  cairo_get_matrix(cr, &saved);
  cairo_matrix_init(&m, major * ct, major * st, -minor * st, minor * ct,
                    panel_x(p, c->f.centre[v->u]), panel_y(p, c->f.centre[v->v]));
  cairo_transform(cr, &m);
  cairo_new_sub_path(cr);
  cairo_arc(cr, 0.0, 0.0, 1.0, 0.0, 2.0 * RENDER_PI);
  cairo_set_matrix(cr, &saved);
  cairo_set_source_rgb(cr, shade * c->rgb[0], shade * c->rgb[1], shade * c->rgb[2]);
  cairo_fill(cr);
}

/* The leaf cards, sorted far to near along the panel's line of sight (so nearer
 * leaves cover farther ones), each filled over what is drawn already. */
static void draw_leaves(leaf_card *leaves, size_t count, cairo_t *cr, const panel *p) {
  for (size_t i = 0; i < count; i++)
    leaves[i].depth = p->v->look * leaves[i].f.centre[p->v->sight];
  qsort(leaves, count, sizeof *leaves, compare_leaves);
  for (size_t i = 0; i < count; i++) fill_leaf(cr, &leaves[i], p);
}

/* The smallest step of 1, 2 or 5 x 10^k metres at least `least` metres long. */
static double tick_step(double least) {
  double step = pow(10.0, floor(log10(least)));
  while (step < least) {
    if (step * 2 >= least) return step * 2;
    if (step * 5 >= least) return step * 5;
    step *= 10;
  }
  return step;
}

/* Text at (x, y): ax and ay (0..1) place its box's left..right and top..bottom
 * on the point. */
static void put_text(cairo_t *cr, const char *text, double x, double y, double ax, double ay) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, text, &e);
  cairo_move_to(cr, x - e.x_bearing - ax * e.width, y - e.y_bearing - ay * e.height);
  cairo_show_text(cr, text);
}

static void set_font(cairo_t *cr, double size, bool bold) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
}

/* Ticks and labels along one axis of a panel: the bottom (axis 0) or the left (1). */
static void draw_axis(cairo_t *cr, const panel *p, int axis) {
  double lo = p->l->lo[p->k][axis], hi = p->l->hi[p->k][axis];
  double step = tick_step(RENDER_TICK_SPACING / p->l->scale);
  int decimals = step >= 1 ? 0 : (int)ceil(-log10(step) - 1e-9);
  double x0 = panel_x(p, p->l->lo[p->k][0]), x1 = panel_x(p, p->l->hi[p->k][0]);
  double y0 = panel_y(p, p->l->lo[p->k][1]), y1 = panel_y(p, p->l->hi[p->k][1]);
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  set_font(cr, 11, false);
  cairo_set_line_width(cr, 1);
  for (double t = ceil(lo / step - 1e-9); t * step <= hi + step * 1e-9; t++) {
    double at = t * step;
    char label[32];
    snprintf(label, sizeof label, "%.*f", decimals, t == 0 ? 0.0 : at);
    if (axis == 0) {
      double x = panel_x(p, at);
      cairo_move_to(cr, x, y0);
      cairo_line_to(cr, x, y0 + 5);
      cairo_stroke(cr);
      put_text(cr, label, x, y0 + 8, 0.5, 0);
    } else {
      double y = panel_y(p, at);
      cairo_move_to(cr, x0, y);
      cairo_line_to(cr, x0 - 5, y);
      cairo_stroke(cr);
      put_text(cr, label, x0 - 8, y, 1, 0.5);
    }
  }
  set_font(cr, 12, false);
  if (axis == 0) {
    put_text(cr, p->v->u_label, (x0 + x1) / 2, y0 + 28, 0.5, 0);
  } else {
    cairo_save(cr);
    cairo_translate(cr, x0 - RENDER_MARGIN_LEFT + 6, (y0 + y1) / 2);
    cairo_rotate(cr, -RENDER_PI / 2);
    put_text(cr, p->v->v_label, 0, 0, 0.5, 0);
    cairo_restore(cr);
  }
}

static void draw_panel(cairo_t *cr, const sylva_world *w, scene *sc, const panel *p) {
  const sylva_world_def *def = sylva_world_get_def(w);
  double x0 = panel_x(p, p->l->lo[p->k][0]), x1 = panel_x(p, p->l->hi[p->k][0]);
  double y0 = panel_y(p, p->l->hi[p->k][1]), y1 = panel_y(p, p->l->lo[p->k][1]);
  cairo_save(cr);
  cairo_rectangle(cr, x0, y0, x1 - x0, y1 - y0);
  cairo_clip(cr);
  draw_obstacles(cr, w, p);
  draw_segments(cr, sc->segs, sc->count, p);
  draw_leaves(sc->leaves, sc->leaf_count, cr, p);
  cairo_restore(cr);

  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_set_line_width(cr, 1);
  cairo_rectangle(cr, x0, y0, x1 - x0, y1 - y0);
  cairo_stroke(cr);
  if (p->v->v == 2) {
    /* the ground, over the frame (it is usually the box's bottom) */
    double ground = panel_y(p, def->min[2]);
    cairo_set_source_rgb(cr, 0.45, 0.33, 0.2);
    cairo_set_line_width(cr, 2);
    cairo_move_to(cr, x0, ground);
    cairo_line_to(cr, x1, ground);
    cairo_stroke(cr);
  }
  draw_axis(cr, p, 0);
  draw_axis(cr, p, 1);
  set_font(cr, 13, true);
  put_text(cr, p->v->title, x0, y0 - 8, 0, 1);
}

/* Length of the valid UTF-8 sequence starting at s (1 to 4), or 0 when s does not
 * start one (cairo refuses text that is not UTF-8; a run's name may be any bytes). */
static size_t utf8_length(const unsigned char *s) {
  if (s[0] < 0x80) return 1;
  size_t n = s[0] >= 0xc2 && s[0] <= 0xdf ? 2 : s[0] >= 0xe0 && s[0] <= 0xef ? 3
           : s[0] >= 0xf0 && s[0] <= 0xf4 ? 4 : 0;
  /* the second byte's range excludes overlong forms, surrogates and > U+10FFFF */
  unsigned lo = s[0] == 0xe0 ? 0xa0 : s[0] == 0xf0 ? 0x90 : 0x80;
  unsigned hi = s[0] == 0xed ? 0x9f : s[0] == 0xf4 ? 0x8f : 0xbf;
  for (size_t k = 1; k < n; k++)
    if (s[k] < (k == 1 ? lo : 0x80) || s[k] > (k == 1 ? hi : 0xbf)) return 0;
  return n;
}

/* Copies text into out (cap bytes with the NUL; whole characters only), each byte
 * that does not start a valid UTF-8 character replaced by '?'. */
static void utf8_clean(const char *text, char *out, size_t cap) {
  const unsigned char *s = (const unsigned char *)text;
  size_t n = 0;
  while (*s) {
    size_t len = utf8_length(s);
    if (n + (len ? len : 1) >= cap) break;
    if (len) {
      memcpy(out + n, s, len);
      n += len;
      s += len;
    } else {
      out[n++] = '?';
      s++;
    }
  }
  out[n] = '\0';
}

/* The title line: the name, the iteration (after its calendar year when the run has
 * a start year), the live nodes and the ages of the first RENDER_TITLE_AGES plants
 * of species with years ("young 8, old 11", then an ellipsis). */
static void title_text(const sylva_world *w, const render_options *o, char *out, size_t cap) {
  char name[256];
  utf8_clean(o->name ? o->name : "sylva", name, sizeof name);
  int it = sylva_world_iteration(w);
  int n = o->start_year ? snprintf(out, cap, "%s \xe2\x80\x94 %d (iteration %d)", name,
                                   o->start_year + it, it)
                        : snprintf(out, cap, "%s \xe2\x80\x94 iteration %d", name, it);
  n += snprintf(out + n, cap - (size_t)n, " \xe2\x80\x94 %zu nodes", sylva_world_node_count(w));
  const char *sep = " \xe2\x80\x94 ages ";
  int listed = 0;
  for (int p = 0; p < sylva_world_plant_count(w); p++) {
    sylva_stem_stats st;
    if (sylva_world_stem_stats(w, sylva_world_stem_index(w, p, 0), &st) != 0 || st.age < 0)
      continue;
    if (listed++ == RENDER_TITLE_AGES) {
      snprintf(out + n, cap - (size_t)n, ", \xe2\x80\xa6");
      break;
    }
    char label[SYLVA_LABEL_MAX];
    utf8_clean(sylva_world_plant_label(w, p), label, sizeof label);
    n += snprintf(out + n, cap - (size_t)n, "%s%s %" PRId32, sep, label, st.age);
    sep = ", ";
  }
}

static void draw(cairo_t *cr, const sylva_world *w, const render_options *o, const layout *l,
                 scene *sc) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  for (int k = 0; k < l->panels; k++) {
    panel p = {.l = l, .v = &views[l->view[k]], .k = k};
    draw_panel(cr, w, sc, &p);
  }
  char title[1024];
  title_text(w, o, title, sizeof title);
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  set_font(cr, 15, true);
  put_text(cr, title, RENDER_MARGIN_LEFT, RENDER_TITLE_HEIGHT / 2, 0, 0.5);
}

/* Where cairo writes; the first errno of a failed write. */
typedef struct sink {
  FILE *f;
  int error;
} sink;

static cairo_status_t sink_write(void *closure, const unsigned char *data, unsigned int length) {
  sink *s = closure;
  if (s->error) return CAIRO_STATUS_WRITE_ERROR;
  errno = 0;
  if (fwrite(data, 1, length, s->f) != length) {
    s->error = errno ? errno : EIO;
    return CAIRO_STATUS_WRITE_ERROR;
  }
  return CAIRO_STATUS_SUCCESS;
}

static cairo_surface_t *create_surface(const render_options *o, const layout *l, sink *out) {
  switch (o->format) {
  case RENDER_PNG: return cairo_image_surface_create(CAIRO_FORMAT_RGB24, l->width, l->height);
  case RENDER_SVG: {
    cairo_surface_t *s = cairo_svg_surface_create_for_stream(sink_write, out, l->width, l->height);
    cairo_svg_surface_set_document_unit(s, CAIRO_SVG_UNIT_PX);
    return s;
  }
  case RENDER_PDF: return cairo_pdf_surface_create_for_stream(sink_write, out, l->width, l->height);
  }
  return NULL;
}

int render_write(FILE *f, const sylva_world *w, const render_options *o, char *err,
                 size_t errlen) {
  if ((unsigned)o->format > RENDER_PDF || (unsigned)o->view > RENDER_ALL ||
      (o->width && (o->width < RENDER_MIN_WIDTH || o->width > RENDER_MAX_SIZE))) {
    snprintf(err, errlen, "bad render options");
    return SERVER_EINPUT;
  }
  layout l;
  layout_build(sylva_world_get_def(w), o, &l);
  if (!(l.scale > 0)) {
    snprintf(err, errlen, "a width of %d leaves no room for the views", l.width);
    return SERVER_EINPUT;
  }
  scene sc;
  if (!gather(w, !o->no_leaves, &sc)) {
    snprintf(err, errlen, "out of memory");
    return SERVER_ENOMEM;
  }
  sink out = {.f = f, .error = 0};
  cairo_surface_t *surface = create_surface(o, &l, &out);
  cairo_t *cr = cairo_create(surface);
  draw(cr, w, o, &l, &sc);
  cairo_status_t status = cairo_status(cr);
  cairo_destroy(cr);
  scene_free(&sc);
  if (status == CAIRO_STATUS_SUCCESS && o->format == RENDER_PNG)
    status = cairo_surface_write_to_png_stream(surface, sink_write, &out);
  cairo_surface_finish(surface);
  if (status == CAIRO_STATUS_SUCCESS) status = cairo_surface_status(surface);
  cairo_surface_destroy(surface);
  if (!out.error && status == CAIRO_STATUS_SUCCESS && fflush(f) != 0)
    out.error = errno ? errno : EIO;
  if (out.error) {
    snprintf(err, errlen, "%s", strerror(out.error));
    return SERVER_EWRITE;
  }
  if (status != CAIRO_STATUS_SUCCESS) {
    snprintf(err, errlen, "cairo: %s", cairo_status_to_string(status));
    return status == CAIRO_STATUS_NO_MEMORY ? SERVER_ENOMEM : SERVER_EFAIL;
  }
  return SERVER_OK;
}
