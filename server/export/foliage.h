/* sylva server: where a leaf-bearing node's leaves are (docs/model.md, "Foliage").
 * One placement for every output that draws leaves: `sylva render`, the glTF
 * export, and the viewer (web/foliage.mjs follows the same rule).
 *
 * A node bearing leaves (sylva_node_info.leaves = n > 0) carries n square leaf cards
 * of edge leaf_size along its internode, from its parent's position p to its own q:
 * leaf k (0 <= k < n) sits at t = (k + 0.5) / n of the way, turned around the
 * internode by the golden angle k * 137.5 degrees from a frame fixed by the
 * internode alone, its card's base on the axis and its blade pointing outwards and
 * forwards (45 degrees between the internode and the outward direction), so that
 * its centre is leaf_size / 2 from the base along the blade. A root (no parent)
 * takes the internode as vertical, of length leaf_size. Pure arithmetic in doubles
 * in a fixed order: the same node always gives the same leaves. */
#ifndef SYLVA_SERVER_FOLIAGE_H
#define SYLVA_SERVER_FOLIAGE_H

/** One leaf card: its centre, the unit direction of its blade (base to tip) and the
 *  unit direction across it, and its edge, in world metres (z up). The card's
 *  corners are centre +- edge/2 * along +- edge/2 * across; its normal is
 *  along x across. */
typedef struct foliage_leaf {
  double centre[3];
  double along[3];
  double across[3];
  double edge;
} foliage_leaf;

/** Leaf k of n of a node at q whose parent is at p (NULL for a root), with leaves
 *  of edge size. */
void foliage_place(const double p[3], const double q[3], int k, int n, double size,
                   foliage_leaf *out);

/** The colour 0xRRGGBB as three components in 0..1. */
void foliage_rgb(int colour, double rgb[3]);

#endif
