/* sylva server: mesh export (Wavefront OBJ, ASCII PLY) of a world's branches.
 *
 * Every internode (a node with a parent) is a generalized cylinder segment from
 * its parent's position to its own. Each node that ends or starts an internode
 * gets one ring of `sides` vertices of its own radius, perpendicular to its
 * internode (a root: towards its first child). The first ring of a stem gets a
 * fixed frame; every other ring carries its parent's frame by parallel transport
 * (rotation-minimizing), so rings do not twist. A node with several children
 * shares its ring with all of them. Every face is a triangle:
 *   - each internode: 2 * sides triangles joining the parent's ring to the node's;
 *   - each tip (a node with a parent and no children) and each root with children
 *     is closed by a fan of sides - 2 triangles over its ring;
 *   - an obstacle (when requested): a box, 8 vertices and 12 triangles; a prism
 *     (prism_mesh.h), the P points of its triangulated footprint at its bottom,
 *     then at its top (2 P vertices), two triangles per wall (W of them, one per
 *     edge of the footprint's boundary, a hole's facing into it), then the C
 *     triangles of the bottom cap and of the top cap (2 W + 2 C triangles). Rings
 *     that cross nowhere, n points in all, h of them holes: P = W = n,
 *     C = n + 2 h - 2; every edge of the mesh is then shared by exactly two of its
 *     triangles (it is closed).
 * A root without children has no internode and no geometry. So, with I internodes,
 * T tips, R roots that have children, B boxes and the prisms as above:
 *   vertices = sides * (I + R) + 8 * B + the prisms' 2 P
 *   faces    = 2 * sides * I + (sides - 2) * (T + R) + 12 * B + the prisms' 2 W + 2 C
 * Faces are wound counter-clockwise seen from outside (normals point outwards).
 *
 * Layout, the same in both formats: stems in global stem order (plants in id
 * order, their stems in order), within a stem the nodes with geometry in id
 * order, one ring each (vertex k of a ring at angle 2 pi k / sides); then the
 * obstacles in the order of sylva_world_obstacle_at. Faces follow the same order
 * (a node's internode, then its caps). Positions are world metres, z up, written
 * with "%.5f"; the same world and options always give the same bytes.
 *
 * OBJ: one object `o <plant label>_<stem index>` per stem with geometry, holding
 * its vertices then its faces (1-based global indices); obstacles as objects
 * `o obstacle_<label>`. Whitespace and control bytes in labels become '_'.
 * PLY: `format ascii 1.0`; vertices `float x y z`; faces
 * `list uchar int vertex_indices` plus `int stem`: the global stem index of a
 * branch face, or -1 - i for the faces of the i-th obstacle. Header comments name
 * every stem and obstacle. */
#ifndef SYLVA_SERVER_MESH_H
#define SYLVA_SERVER_MESH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "sylva/world.h"

/** File formats of sylva_mesh_write. */
typedef enum sylva_mesh_format {
  SYLVA_MESH_OBJ, /**< Wavefront OBJ, one object per stem */
  SYLVA_MESH_PLY  /**< ASCII PLY 1.0 with a per-face stem index */
} sylva_mesh_format;

/** What to export. */
typedef struct sylva_mesh_options {
  int sides;      /**< vertices per ring, SYLVA_MESH_MIN_SIDES..SYLVA_MESH_MAX_SIDES */
  bool obstacles; /**< also write the obstacles (boxes and prisms, zones too) */
} sylva_mesh_options;

/** Fewest vertices per ring. */
#define SYLVA_MESH_MIN_SIDES 3
/** Most vertices per ring. */
#define SYLVA_MESH_MAX_SIDES 64
/** Returned by sylva_mesh_write when writing to the stream failed (errno says
 *  why). Not a sylva_status: report it with strerror(errno). */
#define SYLVA_MESH_EWRITE (-1)

/** Default options: 8 sides, no obstacles. */
sylva_mesh_options sylva_mesh_default_options(void);

/** Writes the branches of w (and, if asked, its obstacles) to out. opt NULL means
 *  the defaults. Returns 0; SYLVA_EINVAL for a bad format or options or a prism
 *  the tessellator refuses (prism_mesh.h) and SYLVA_ENOMEM (nothing written);
 *  SYLVA_ETOOBIG for a PLY with more than INT32_MAX vertices (nothing written);
 *  SYLVA_MESH_EWRITE when a write to out failed (errno set; out is left as far as
 *  it got). out is flushed, not closed. */
int sylva_mesh_write(FILE *out, const sylva_world *w, sylva_mesh_format format,
                     const sylva_mesh_options *opt);

/** Counts the vertices and faces sylva_mesh_write would write (the formula above;
 *  the same for both formats; prisms are triangulated to count them). Returns 0,
 *  SYLVA_EINVAL as sylva_mesh_write, or SYLVA_ENOMEM; on failure both counts are 0. */
int sylva_mesh_count(const sylva_world *w, sylva_mesh_format format,
                     const sylva_mesh_options *opt, size_t *vertices, size_t *faces);

/** The branch geometry of a world as sylva_mesh_write lays it out, stem by stem,
 *  for writers of other formats (the glTF export): the rings and triangles above,
 *  with the outward unit normal of each ring vertex (from its ring's frame: the
 *  radial direction, so a tapered cylinder shades smoothly). Holds the world
 *  (const) and one frame per node; the world must not change while it lives. */
typedef struct sylva_mesh_branches sylva_mesh_branches;

/** Plans the branches of w with `sides` vertices per ring. Returns 0 with *out
 *  set; SYLVA_EINVAL for sides outside SYLVA_MESH_MIN_SIDES..SYLVA_MESH_MAX_SIDES,
 *  SYLVA_ENOMEM (*out NULL). */
int sylva_mesh_branches_create(const sylva_world *w, int sides, sylva_mesh_branches **out);

/** Frees b (NULL is fine). */
void sylva_mesh_branches_destroy(sylva_mesh_branches *b);

/** Stem s's share of the layout: its first vertex (global index), its vertices and
 *  its triangles; a stem without geometry has 0 of both. */
void sylva_mesh_branches_stem(const sylva_mesh_branches *b, int s, size_t *first,
                              size_t *vertices, size_t *triangles);

/** The node indices (for sylva_world_node_at) of stem s in id order, *count of
 *  them, and the node index of node i's parent (-1 for a root). */
const int32_t *sylva_mesh_branches_stem_nodes(const sylva_mesh_branches *b, int s,
                                              size_t *count);
int32_t sylva_mesh_branches_parent(const sylva_mesh_branches *b, size_t i);

/** Calls vertex(ctx, position, normal) for each vertex of stem s in layout order
 *  (world metres, z up; the normal is a unit vector). Stops at the first false
 *  from vertex and returns false; true when all were given. */
bool sylva_mesh_branches_vertices(sylva_mesh_branches *b, int s,
                                  bool (*vertex)(void *ctx, const double pos[3],
                                                 const double normal[3]),
                                  void *ctx);

/** Calls triangle(ctx, a, b, c) for each triangle of stem s in layout order, with
 *  vertex indices relative to the stem's first vertex, counter-clockwise seen from
 *  outside. Stops at the first false and returns false; true when all were given. */
bool sylva_mesh_branches_triangles(const sylva_mesh_branches *b, int s,
                                   bool (*triangle)(void *ctx, size_t a, size_t b, size_t c),
                                   void *ctx);

/** Corner v (0..7) of an obstacle's box: bit 0 picks max x, bit 1 max y, bit 2 max z. */
void sylva_mesh_box_corner(const sylva_obstacle_def *o, int v, double q[3]);

/** The six sides of a box as quads of corners, counter-clockwise seen from outside,
 *  in the order -x, +x, -y, +y, -z, +z. */
extern const int sylva_mesh_box_quads[6][4];

#endif
