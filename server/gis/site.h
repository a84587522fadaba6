/* sylva gis: a site from GIS layers (`sylva site`, docs/cli.md "site"): buildings
 * become solid prisms, clearance zones prisms of kind zone, trees plants of library
 * species with their ages, all in one local frame in metres (x east, y north, the
 * origin at the site's centre), ready to be written as a scenario (site_write.h).
 * The layers are read with GDAL (layer.h), transformed with PROJ (frame.h), their
 * species matched to the library (species_match.h). Nothing here writes a file. */
#ifndef SYLVA_GIS_SITE_H
#define SYLVA_GIS_SITE_H

#include <stdbool.h>
#include <stddef.h>

#include "species_match.h"

/** Longest id of a plant or an obstacle, bytes with the NUL (scenario.md's labels). */
#define SITE_ID_MAX 64

/** Why a feature was left out; the order is the order rows are checked in. */
#define SITE_REASONS(X)                                                                      \
  X(SITE_FILTERED, "filtered")         /* a tree whose --keep fields do not match */         \
  X(SITE_NO_GEOMETRY, "no_position")   /* no geometry (or no coordinates in --xy-fields) */  \
  X(SITE_OUTSIDE_BBOX, "outside_bbox") /* its point or footprint centroid outside */         \
  X(SITE_UNMATCHED, "unmatched")       /* a tree whose species matches no library species */ \
  X(SITE_NO_DBH, "no_dbh")             /* a tree without a DBH, and no --default-dbh */      \
  X(SITE_NO_HEIGHT, "no_height")       /* a footprint or zone without a usable height */     \
  X(SITE_TOO_SMALL, "too_small")       /* a footprint of no area at 1 mm */                  \
  X(SITE_IN_BUILDING, "in_building")   /* a tree whose trunk stands in a building */         \
  X(SITE_TOO_CLOSE, "too_close")       /* a tree in the voxel column of an earlier tree */

typedef enum site_reason {
#define SITE_REASON_ENUM(name, text) name,
  SITE_REASONS(SITE_REASON_ENUM)
#undef SITE_REASON_ENUM
      SITE_REASON_COUNT
} site_reason;

/** The summary's name of a reason ("no_dbh"). */
const char *site_reason_name(site_reason r);

/** One --keep FIELD=VALUE. */
typedef struct site_keep {
  const char *field, *value;
} site_keep;

/** What to read and how (the options of `sylva site`). Units: height_unit metres
 *  per unit of the height field, dbh_unit centimetres per unit of the DBH field. */
typedef struct site_options {
  const char *buildings, *buildings_crs, *height_field, *levels_field, *building_id_field;
  double height_unit, level_height, default_height; /**< default_height 0: none */
  const char *trees, *trees_crs, *x_field, *y_field, *species_field, *dbh_field, *id_field;
  const char *species_map;
  double dbh_unit, default_dbh; /**< default_dbh 0: none */
  const site_keep *keep;
  int keep_count;
  const char *zones, *zones_crs, *zone_field;
  bool has_bbox;
  double bbox[4]; /**< west, south, east, north, degrees */
  const char *crs, *region;
  int iterations;
  double rho; /**< the plants' internode length; 0: each species' own */
} site_options;

/** An obstacle: a prism or a zone, rings in millimetres of the local frame. */
typedef struct site_obstacle {
  char id[SITE_ID_MAX];
  bool zone;
  long long (*points)[2]; /**< rings, the outline (counter-clockwise) then the holes
                               (clockwise), each starting at its lowest (y, then x)
                               point, the holes in the order of their first point */
  int *ring_sizes;
  int ring_count;
  long long height; /**< mm */
  const char *path; /**< the file it came from */
  long row;         /**< its feature's row there */
} site_obstacle;

/** A plant: one root on the ground. */
typedef struct site_plant {
  char id[SITE_ID_MAX];
  int species;     /**< index into the site's library */
  long long xy[2]; /**< mm */
  int age;
  long row; /**< its row in the trees' file */
} site_plant;

/** A name and how many rows had it. */
typedef struct site_tally {
  char *name;
  long count;
} site_tally;

/** A site. */
typedef struct site {
  char *crs;           /**< the frame's CRS, as PROJ reads it back */
  long long origin[2]; /**< the frame's coordinates of the local (0, 0), m */
  double latitude;     /**< of the origin, degrees */
  double north[2];     /**< true north in the local frame, a unit vector */
  char region[16];     /**< the UTDB region the trees were matched in ("" without trees) */
  long long world_min[3], world_max[3]; /**< m */
  double voxel;                         /**< m */
  site_obstacle *obstacles;
  int obstacle_count;
  site_plant *plants;
  int plant_count;
  long buildings, prisms, zones; /**< features kept, prisms of buildings, zone prisms */
  long left_out[SITE_REASON_COUNT];
  site_tally *unmatched; /**< in the order first met */
  int unmatched_count;
  site_tally *species; /**< plants per library name, in the order first planted */
  int species_count;
  species_library lib;
  char notes[1024]; /**< lines for stderr: which layer of a file of several was read */
} site;

/** Builds the site: SERVER_OK and *s; SERVER_EINPUT for bad input, with err naming
 *  the file, the layer, the row and the field; SERVER_EFAIL, SERVER_ENOMEM. *s is
 *  freed on failure. */
int site_build(const site_options *o, site *s, char *err, size_t errlen);

/** Frees a site; the struct is zeroed. */
void site_free(site *s);

#endif
