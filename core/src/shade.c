/* Phase 5: the shade a node casts (pyramid and column), added or removed exactly. */
#include "world_impl.h"

int sylva__shade_node(sylva_world *w, int32_t slot, int sign) {
  const sylva__stem *st = &w->stems[w->nodes.stem[slot]];
  sylva__species *sp = &w->species[st->species];
  const sylva__pyramid *shade = sylva__species_shade(sp, w->nodes.birth[slot] - st->born);
  /* a node that casts shade made its pyramid's entry: taking it away cannot fail */
  SYLVA_ASSERT(shade || sign > 0);
  if (!shade) return SYLVA_ENOMEM;
  int v[3];
  sylva__node_voxel(w, slot, v);
  return sylva__grid_stamp(&w->grid, v, shade, sign);
}
