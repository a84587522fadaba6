/* sylva server: a world as binary glTF 2.0 (GLB): its branches as the tapered
 * generalized cylinders of mesh.h, its leaves as textured cards (foliage.h) and,
 * on request, its obstacles as boxes and prisms. `sylva export --format glb` and the daemon's
 * export route write it; docs/cli.md ("export") describes the file for its users.
 *
 * Units are metres. glTF's +Y is up, so a world point (x, y, z), z up, is written
 * as (x, z, -y): a rotation, right-handed as before, that keeps every winding.
 *
 * The scene has one root node "sylva" (extras: {"iteration": T}); its children are,
 * in order, one node per stem with any geometry (plants in id order, their stems in
 * order), named "<plant label>/<stem index>", then, with obstacles, one node per
 * obstacle (the order of sylva_world_obstacle_at), named "obstacle/<label>" for a
 * solid box or prism and "zone/<label>" for a clearance zone. No node has a transform: the
 * vertices are in world coordinates. Each node has a mesh of its own, named as the
 * node, whose primitives are (triangles, indices UNSIGNED_INT):
 *   - a stem's bark, when it has an internode: the rings and triangles of mesh.h
 *     (POSITION, NORMAL: the ring's outward radial direction, so the cylinders
 *     shade smoothly), material "bark";
 *   - a stem's leaves, when it bears any: per leaf card (foliage_place, the cards
 *     in node id order, then leaf order) four vertices, base-left, base-right,
 *     tip-right, tip-left (left and right along -across and +across), with
 *     POSITION, NORMAL (along x across) and TEXCOORD_0 (u 0..1 across the card, v 1
 *     at the base and 0 at the tip), and two triangles; material "leaves", or
 *     "leaves-<species label>" (one per species bearing leaves) when those species
 *     differ in leaf_colour;
 *   - an obstacle's box: 24 vertices (four per side, flat normals) and 12 triangles;
 *     a prism's mesh (the walls and caps of mesh.h, from prism_mesh.h): four
 *     vertices per wall (the bottom of its edge's start and end, then their tops)
 *     with the wall's outward normal and two triangles, then the bottom cap's
 *     points (normal down) with its triangles, the top cap's (normal up) with its
 *     triangles: 4 W + 2 P vertices, 2 W + 2 C triangles (a prism on a rectangle:
 *     24 and 12, as its box); closed once its vertices are joined by position;
 *     material "obstacle" (solid) or "zone" (clearance zone).
 * Materials (metallic-roughness, metallic 0): "bark" brown, roughness 0.9;
 * "leaves..." base colour factor the species' leaf_colour with the leaf texture
 * (leaf_texture.h, a PNG in the buffer) as base colour texture, alphaMode MASK,
 * alphaCutoff 0.5, double-sided; "obstacle" grey, opaque; "zone" amber, alpha 0.35,
 * alphaMode BLEND, double-sided. Only the materials in use are written; the
 * texture, its image and sampler only with leaves.
 *
 * Binary layout: one buffer (the GLB's BIN chunk) of bufferViews, in order: every
 * VEC3 attribute (byteStride 12; per primitive its positions then its normals),
 * every TEXCOORD_0 (byteStride 8), every index, the PNG; each accessor of a
 * primitive in that primitive's order; POSITION accessors carry min and max. A world
 * with no geometry has no buffer and no BIN chunk. The JSON chunk is written by
 * cJSON and padded with spaces, the BIN chunk with zeros, both to 4 bytes. The same
 * world and options always give the same bytes. */
#ifndef SYLVA_SERVER_GLTF_H
#define SYLVA_SERVER_GLTF_H

#include <stdio.h>

#include "mesh.h"
#include "sylva/world.h"

/** Writes w to out as GLB with the options of mesh.h (sides of the branch rings,
 *  obstacles or not; NULL: the defaults). Returns 0; SYLVA_EINVAL for bad options
 *  or a prism the tessellator refuses (prism_mesh.h),
 *  SYLVA_ENOMEM, SYLVA_ETOOBIG for a file past the 4 GiB GLB holds (nothing written
 *  then); SYLVA_MESH_EWRITE when a write to out failed (errno set). out is flushed,
 *  not closed. */
int gltf_write(FILE *out, const sylva_world *w, const sylva_mesh_options *opt);

#endif
