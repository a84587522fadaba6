/* sylva server: the texture of a leaf card in the glTF export, drawn with cairo at
 * run time and encoded as PNG.
 *
 * LEAF_TEXTURE_SIZE pixels square, RGBA (premultiplied by cairo, written straight
 * by its PNG writer): a transparent background; the blade, the ellipse inscribed in
 * the card (as docs/model.md, "Foliage", counts a leaf's area and `sylva render`
 * draws it) in near-white; a grey midrib from the base (the bottom edge, v = 1)
 * to near the tip (the top edge, v = 0). White, so a material's base colour factor
 * gives the leaf its species' colour; the blade's alpha (1 inside, 0 outside, the
 * antialiased edge between) makes the cut-out of alphaMode MASK. The same bytes on
 * every call with the same cairo. */
#ifndef SYLVA_SERVER_LEAF_TEXTURE_H
#define SYLVA_SERVER_LEAF_TEXTURE_H

#include <stddef.h>

/** Edge of the texture in pixels. */
#define LEAF_TEXTURE_SIZE 64

/** Draws the texture and encodes it as PNG into a new buffer *png of *len bytes
 *  (the caller frees it). Returns 0, or SYLVA_ENOMEM (*png NULL, *len 0) when cairo
 *  or memory failed. */
int leaf_texture_png(unsigned char **png, size_t *len);

#endif
