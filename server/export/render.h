/* sylva server: a picture of a world, drawn with cairo as PNG, SVG or PDF: front,
 * side and top orthographic views (`sylva render`).
 *
 * Views (z is up; every view is seen from outside the world's box):
 *   front  the x-z plane looking along +y: x to the right, z up;
 *   side   the y-z plane looking along -x: y to the right, z up;
 *   top    the x-y plane seen from above (looking along -z): x to the right, y up.
 * RENDER_ALL puts front, side and top side by side, in that order.
 *
 * Each panel spans the world's box in its two axes (so walls and world sides
 * show), at one scale for both axes and for every panel of the picture. In it,
 * clipped to it and in this order:
 *   - a white background;
 *   - every obstacle as a translucent grey rectangle (its box projected,
 *     RENDER_OBSTACLE_FILL) with a darker outline; a prism from above as its
 *     footprint's rings, filled with the even-odd rule (the model's inside: a
 *     courtyard stays open), outlined ring by ring; from the front and the side as
 *     the rectangle of its extent (its footprint's bounds and its z range), which
 *     is the outline of the extruded footprint seen from there;
 *   - every internode (a node with a parent) as a straight line from its parent to
 *     the node, as wide as the node's diameter (2 * radius * scale, at least
 *     RENDER_MIN_LINE), with round caps, in its plant's colour (RENDER_PALETTE,
 *     cycled by plant id). Thin internodes are drawn first and thick ones last
 *     (by radius, then id), so trunks stay visible; branches are drawn over the
 *     obstacles, never hidden by them;
 *   - unless render_options.no_leaves, over the branches, every leaf card of every
 *     node bearing leaves (sylva_node_info.leaves, placed by foliage_place with its
 *     plant's species' leaf_size) as its blade: the ellipse inscribed in the card,
 *     projected like everything else (an ellipse with the projections of the card's
 *     along and across half-edges as conjugate semi-diameters; each semi-axis at
 *     least RENDER_MIN_LEAF / 2, so a leaf under a pixel or seen edge-on still
 *     shows), filled without an outline in the species' leaf_colour times
 *     RENDER_LEAF_SHADE + (1 - RENDER_LEAF_SHADE) * |normal . line of sight| (the
 *     normal along x across; a card facing the viewer has the full colour). The
 *     cards are drawn far to near along the line of sight (then by node id and
 *     leaf), so near leaves cover far ones;
 *   - the frame of the world's box and, in front and side, over it the ground
 *     line at z = the world's min z (the ground; 0 in the ready scenarios).
 * Around each panel: its title above, ticks and labels in metres along the bottom
 * and the left (every multiple of a 1, 2 or 5 x 10^k metre step, the smallest
 * step that leaves at least RENDER_TICK_SPACING between ticks) and the axis names
 * ("x (m)", "z (m)", ...). Above everything, a title line: the name, the
 * iteration (after its calendar year with a start year), the number of live nodes
 * and, in a world with years, the age of each plant of a species with years (the
 * first RENDER_TITLE_AGES).
 *
 * The mapping from metres to the picture (pixels for PNG; points for SVG and PDF,
 * one point per pixel), with n panels, panel k spanning [u0_k, u1_k] x
 * [v0_k, v1_k] metres and W the picture's width:
 *   scale s = (W - n * (RENDER_MARGIN_LEFT + RENDER_MARGIN_RIGHT)) / sum_k (u1_k - u0_k),
 *             lowered, if need be, until the height fits RENDER_MAX_SIZE;
 *   panel k's left edge  L_k = RENDER_MARGIN_LEFT + sum_{j<k} (RENDER_MARGIN_LEFT
 *                              + (u1_j - u0_j) * s + RENDER_MARGIN_RIGHT);
 *   panels' top edge     T   = RENDER_TITLE_HEIGHT + RENDER_PANEL_TITLE_HEIGHT;
 *   a point (u, v) is drawn at (L_k + (u - u0_k) * s, T + (v1_k - v) * s);
 *   the height is ceil(T + max_k (v1_k - v0_k) * s + RENDER_MARGIN_BOTTOM).
 * The same world and options always give the same picture. */
#ifndef SYLVA_SERVER_RENDER_H
#define SYLVA_SERVER_RENDER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "server_error.h"
#include "sylva/world.h"

/** Output formats. */
typedef enum render_format { RENDER_PNG, RENDER_SVG, RENDER_PDF } render_format;

/** What to draw. */
typedef enum render_view { RENDER_FRONT, RENDER_SIDE, RENDER_TOP, RENDER_ALL } render_view;

/** The view names, for messages. */
#define RENDER_VIEW_NAMES "front, side, top or all"
/** The format names (file extensions), for messages. */
#define RENDER_FORMAT_NAMES ".png, .svg or .pdf"

/* The layout, in pixels (points for SVG and PDF). */
#define RENDER_MARGIN_LEFT 64.0        /**< left of each panel: tick labels, axis name */
#define RENDER_MARGIN_RIGHT 24.0       /**< right of each panel */
#define RENDER_MARGIN_BOTTOM 52.0      /**< below the panels: tick labels, axis name */
#define RENDER_TITLE_HEIGHT 34.0       /**< the title line at the top */
#define RENDER_PANEL_TITLE_HEIGHT 26.0 /**< each panel's title, above it */
#define RENDER_TICK_SPACING 50.0       /**< least distance between two ticks */
#define RENDER_MIN_LINE 0.5            /**< thinnest internode */
#define RENDER_MIN_LEAF 1.0            /**< narrowest leaf blade, either axis */
#define RENDER_TITLE_AGES 8            /**< plants whose ages the title lists */

/** Widths a picture may have (and the greatest height); the least leaves room
 *  for the margins of three views. */
#define RENDER_MIN_WIDTH 400
#define RENDER_MAX_SIZE 16384
/** The default width per panel: 1500 for all three views, 500 for one. */
#define RENDER_PANEL_WIDTH 500

/** Plant colours, 0xRRGGBB, the viewer's (web/scene.mjs); plant id i gets
 *  RENDER_PALETTE[i % RENDER_PALETTE_SIZE]. */
#define RENDER_PALETTE_SIZE 12
extern const unsigned render_palette[RENDER_PALETTE_SIZE];

/** Obstacle fill: grey RENDER_OBSTACLE_GREY (0..1) at RENDER_OBSTACLE_ALPHA; over
 *  the white background it is the grey 1 - ALPHA * (1 - GREY). */
#define RENDER_OBSTACLE_GREY 0.55
#define RENDER_OBSTACLE_ALPHA 0.35
/** Clearance zone fill: amber at RENDER_ZONE_ALPHA, with a dashed outline. */
#define RENDER_ZONE_ALPHA 0.18
/** The darkest a leaf gets, as a share of its leaf_colour: a card seen edge-on. */
#define RENDER_LEAF_SHADE 0.75

/** The view called `name` (front, side, top, all); false for none. */
bool render_view_parse(const char *name, render_view *out);

/** The format of a file name by its extension (.png, .svg, .pdf; any case);
 *  false for anything else. */
bool render_format_from_path(const char *path, render_format *out);

/** How to draw. */
typedef struct render_options {
  render_format format;
  render_view view;
  int width;        /**< RENDER_MIN_WIDTH..RENDER_MAX_SIZE; 0: RENDER_PANEL_WIDTH per panel */
  const char *name; /**< the run's or scenario's name, for the title */
  int start_year;   /**< the scenario's start_year (0: none): the title's calendar year */
  bool no_leaves;   /**< the wire skeleton only (`--no-leaves`); false: leaves too */
} render_options;

/** Draws w as o asks and writes the picture to f (flushed, not closed). Returns
 *  SERVER_OK; SERVER_EINPUT for bad options, SERVER_ENOMEM, SERVER_EFAIL when cairo
 *  failed otherwise, SERVER_EWRITE when writing to f failed; err then says why in one
 *  line. */
int render_write(FILE *f, const sylva_world *w, const render_options *o, char *err,
                 size_t errlen);

#endif
