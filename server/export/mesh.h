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
 *   - an obstacle box (when requested): 8 vertices and 12 triangles.
 * A root without children has no internode and no geometry. So, with I internodes,
 * T tips, R roots that have children and B obstacles:
 *   vertices = sides * (I + R) + 8 * B
 *   faces    = 2 * sides * I + (sides - 2) * (T + R) + 12 * B
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
  bool obstacles; /**< also write the obstacle boxes */
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
 *  the defaults. Returns 0; SYLVA_EINVAL for a bad format or options and
 *  SYLVA_ENOMEM (nothing written); SYLVA_ETOOBIG for a PLY with more than
 *  INT32_MAX vertices (nothing written); SYLVA_MESH_EWRITE when a write to out
 *  failed (errno set; out is left as far as it got). out is flushed, not closed. */
int sylva_mesh_write(FILE *out, const sylva_world *w, sylva_mesh_format format,
                     const sylva_mesh_options *opt);

/** Counts the vertices and faces sylva_mesh_write would write (the formula above;
 *  the same for both formats). Returns 0, SYLVA_EINVAL for a bad format or
 *  options, or SYLVA_ENOMEM; on failure both counts are 0. */
int sylva_mesh_count(const sylva_world *w, sylva_mesh_format format,
                     const sylva_mesh_options *opt, size_t *vertices, size_t *faces);

#endif
