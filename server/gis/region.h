/* sylva gis: the Urban Tree Database's climate regions placed at their reference
 * cities (data/gis/reference_cities.csv, built into the binary), and the region of a
 * site: the region whose city is nearest, within a distance. */
#ifndef SYLVA_GIS_REGION_H
#define SYLVA_GIS_REGION_H

#include <stddef.h>

/** The regions of the database. */
#define GIS_REGIONS 17

/** A region and its reference city. */
typedef struct gis_region {
  char code[16];   /**< TS6's region code, "NoEast" */
  char city[48];   /**< "Queens" */
  double lon, lat; /**< the city, WGS 84 degrees */
} gis_region;

/** Reads the built-in table into regions[GIS_REGIONS]: SERVER_OK, SERVER_EFAIL (a
 *  table that does not read, with err) or SERVER_ENOMEM. */
int gis_regions_load(gis_region *regions, char *err, size_t errlen);

/** The region whose city is nearest (lon, lat) on the WGS 84 geodesic, and its
 *  distance in *km. */
const gis_region *gis_region_nearest(const gis_region *regions, double lon, double lat, double *km);

/** The region of that code (case-sensitive), or NULL. */
const gis_region *gis_region_find(const gis_region *regions, const char *code);

#endif
