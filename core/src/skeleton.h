/* Nodes of every stem in one struct of arrays. Slots are in birth order, so a
 * parent's slot is always below its children's: a reverse sweep is basipetal and
 * a forward sweep acropetal. Dead slots are dropped by an order-keeping compaction. */
#ifndef SYLVA_SKELETON_H
#define SYLVA_SKELETON_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Every bit of a slot's flags byte. ALIVE, LATERAL, SCAR and BARE are the node's state and
 * are stored in snapshots; DOOMED exists only inside the shedding phase, which sets
 * it on the nodes it removes and clears the whole byte when it removes them, so no
 * node carries it between phases. */
enum {
  SYLVA__NODE_ALIVE = 1,   /* slot holds a live node */
  SYLVA__NODE_LATERAL = 2, /* first node of a lateral axis (its parent's lateral child) */
  SYLVA__NODE_SCAR = 4,    /* its lateral branch was shed: the bud does not sprout again */
  SYLVA__NODE_DOOMED = 8,  /* shedding: removed at the end of this phase */
  SYLVA__NODE_BARE = 16,   /* its stem is dead: it bears no leaves (docs/model.md, "Stands") */
  SYLVA__NODE_THICKER = 32, /* radii: its radius grew and is reported; set and cleared
                               inside the radii phase, as DOOMED inside shedding */
  /* the bits a live node carries between phases (and in a snapshot) */
  SYLVA__NODE_STATE = SYLVA__NODE_ALIVE | SYLVA__NODE_LATERAL | SYLVA__NODE_SCAR | SYLVA__NODE_BARE
};

typedef struct sylva__skeleton {
  size_t count, cap, live;
  int32_t next_id;
  int32_t *id;
  float *x, *y, *z, *radius;
  int32_t *parent, *axis_child, *lateral_child; /* slots, -1 for none */
  int32_t *birth, *stem, *depth;
  uint8_t *flags;
  uint16_t *leaves; /* the leaves last reported in a journal (not in snapshots) */
} sylva__skeleton;

/** Bytes held per slot. */
#define SYLVA__NODE_BYTES (4 * 10 + 1 + 2)

void sylva__skeleton_free(sylva__skeleton *s);
/** Makes room for n more slots. */
int sylva__skeleton_reserve(sylva__skeleton *s, size_t n);
/** Appends a node (room must be reserved); returns its slot. */
int32_t sylva__skeleton_append(sylva__skeleton *s, int32_t id, int32_t parent, float x, float y,
                               float z, float radius, int32_t birth, int32_t stem, int32_t depth,
                               uint8_t flags);
/** Drops dead slots keeping order; remap (count entries) receives each old slot's
 *  new slot or -1, and every link is translated through it. */
void sylva__skeleton_compact(sylva__skeleton *s, int32_t *remap);
/** Slot of a live node id, or -1 (ids increase with slots). */
int32_t sylva__skeleton_find(const sylva__skeleton *s, int32_t id);
size_t sylva__skeleton_bytes(const sylva__skeleton *s);
#endif
