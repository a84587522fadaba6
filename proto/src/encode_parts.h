/* Private to libsylva-proto: the writers shared by the skeleton (encode.c) and the
 * protocol messages (protocol.c), so that both print the same bytes for the same
 * world. Each appends to a sylva__strbuf; an allocation failure sets b->failed. */
#ifndef SYLVA_PROTO_ENCODE_PARTS_H
#define SYLVA_PROTO_ENCODE_PARTS_H

#include <stdbool.h>

#include "strbuf.h"
#include "sylva/world.h"

/** Decimals of positions (x, y, z) in skeletons, snapshots and deltas. */
#define SYLVA__POSITION_DECIMALS 4
/** Decimals of radii. */
#define SYLVA__RADIUS_DECIMALS 5

/** Appends an obstacle's JSON (sylva_obstacle_json(), obstacle.c). */
void sylva__put_obstacle(sylva__strbuf *b, const sylva_obstacle_def *o, bool compact);
/** [x,y,z] with the shortest exact numbers. */
void sylva__put_vec3(sylva__strbuf *b, const double v[3]);
/** "x,y,z,radius" of a node (positions with 4 decimals, the radius with 5, trimmed). */
void sylva__put_node_geometry(sylva__strbuf *b, const sylva_node_info *n);
/** A radius with 5 decimals, trimmed. */
void sylva__put_radius(sylva__strbuf *b, float radius);
/** "voxel":V,"world":{"min":[..],"max":[..]},"obstacles":[..],"plants":[..] of the
 *  skeleton format (without braces around it); without with_nodes each stem is only
 *  {"root":[x,y,z]} (and the nodes are not read). */
void sylva__put_world_body(sylva__strbuf *b, const sylva_world *w, bool with_nodes);
/** Which optional fields the stats of a world carry (cli.md, "Output"). */
typedef struct sylva__stats_form {
  bool conflicts; /**< pruned, zones, clearance (sylva_world_reports_conflicts) */
  bool years;     /**< age, crown_diameter, crown_height (sylva_encode_years) */
  int start_year; /**< 0, or the calendar year of iteration 0: zones' "first" in years */
  bool stand;     /**< alive, died, vigour and the stand's figures (sylva_encode_stand) */
} sylva__stats_form;

/** The stand's figures as a JSON object {"area": ..., "alive": ..., ...}
 *  (docs/model.md, "Stands"); null figures as null. */
void sylva__put_stand(sylva__strbuf *b, const sylva_stand_stats *s, bool compact);

/** The form of w's stats. */
sylva__stats_form sylva__stats_form_of(const sylva_world *w, int start_year);

/** One stem's measures as in the stats line of `sylva run`: {"plant": "t1", "stem": 0,
 *  ...}; compact drops the spaces after ',' and ':'. */
void sylva__put_stem_stats(sylva__strbuf *b, const sylva_world *w, const sylva_stem_stats *s,
                           const sylva__stats_form *form, bool compact);

#endif
