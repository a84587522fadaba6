/* sylva server: a prism obstacle (a footprint extruded over a z range, world.h) as a
 * closed triangle mesh, for the mesh exports (mesh.h: OBJ, PLY; gltf.h).
 *
 * The footprint's caps are triangulated by GLU's tessellator (libglu1-mesa-dev,
 * gluTess*) with the winding rule GLU_TESS_WINDING_ODD: a region is inside where a
 * ray from it crosses the rings an odd number of times, the model's own rule, so
 * holes, further parts and rings that cross themselves come out as the core reads
 * them, whatever their winding. (GEOS's constrained Delaunay triangulation wants a
 * valid polygon: holes inside their shell, rings that cross nowhere; a footprint
 * is any rings read even-odd.) Where rings cross, the tessellator adds the crossing
 * as a new point. Its triangles are counter-clockwise seen from above (the normal
 * given is +z) and name the edges of the inside's boundary; each such edge becomes
 * a wall, so a hole's walls face into the courtyard and, where rings neither cross
 * nor touch, every edge of the mesh is shared by exactly two triangles. */
#ifndef SYLVA_SERVER_PRISM_MESH_H
#define SYLVA_SERVER_PRISM_MESH_H

#include <stdbool.h>
#include <stddef.h>

#include "sylva/world.h"

/** A prism's caps and walls in the footprint's plane. */
typedef struct prism_mesh {
  bool prism;          /**< false for a box (nothing else is set then) */
  double (*xy)[2];     /**< the points the caps use: the footprint's in its order,
                            then the rings' crossings */
  size_t points;
  size_t (*tri)[3];    /**< cap triangles, indices into xy, counter-clockwise from above */
  size_t triangles;
  size_t (*wall)[2];   /**< the inside's boundary edges (from, to), the solid on the
                            left seen from above; sorted by from, then to, so a simple
                            ring's walls follow it */
  size_t walls;
  double bottom, top;  /**< the z range */
} prism_mesh;

/** The mesh of obstacle def (all zero for a box: footprint.ring_count 0). Returns
 *  0; SYLVA_ENOMEM, or SYLVA_EINVAL for a footprint the tessellator refuses (a
 *  coordinate beyond GLU_TESS_MAX_COORD, 1e150 m); *out is all zero on failure. */
int prism_mesh_build(const sylva_obstacle_def *def, prism_mesh *out);

/** Frees what m holds and zeroes it. */
void prism_mesh_free(prism_mesh *m);

/** The meshes of every obstacle of w in the order of sylva_world_obstacle_at (a
 *  box's all zero), count of them: 0 with *out set (NULL for none), or the status
 *  of prism_mesh_build (*out NULL). */
int prism_meshes_build(const sylva_world *w, prism_mesh **out, int *count);

/** Frees n meshes of prism_meshes_build and the array (NULL is fine). */
void prism_meshes_free(prism_mesh *m, int n);

#endif
