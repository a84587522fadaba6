/* sylva gis: a stored run's results written back to GIS files with GDAL/OGR, for a
 * run whose scenario has a site (its CRS and origin, docs/scenario.md "Site"):
 *
 * - per stem and chosen year, its trunk (a point: the stem's root) and its crown
 *   (a polygon: the union of the floor cells under its leaves, those its
 *   crown_area counts, docs/model.md "Canopy cover"), each with the stem's
 *   figures of that year and each zone's conflict year;
 * - the obstacles of the last chosen year: the solid ones (buildings, walls) and
 *   the clearance zones, as polygons with their heights.
 *
 * GeoPackage: four layers (trunks, crowns, buildings, zones) in the site's CRS.
 * GeoJSON (RFC 7946): one FeatureCollection in WGS 84 (lon, lat), each feature's
 * `layer` naming which of the four it belongs to (docs/cli.md, "export"). */
#ifndef SYLVA_GIS_EXPORT_H
#define SYLVA_GIS_EXPORT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "store.h"

/** What to write. */
typedef struct gis_export_spec {
  int64_t run;          /**< the store's run id */
  const char *name;     /**< the run's name, for messages */
  const char *scenario; /**< its scenario, canonical JSON (store_run.scenario) */
  int start_year;       /**< its start year, 0 when none (store_run.start_year) */
  const int *years;     /**< the stored iterations to write (years since planting),
                             ascending */
  size_t year_count;
  bool gpkg;            /**< GeoPackage; else GeoJSON */
  const char *path;     /**< the file to create (it must not exist); "/vsistdout/"
                             for GeoJSON on stdout */
} gis_export_spec;

/** Writes spec. SERVER_OK; SERVER_EINPUT when the run has no site or its CRS is one
 *  PROJ cannot read; SERVER_EFAIL when the store failed; SERVER_EWRITE when GDAL
 *  could not write the file; SERVER_ENOMEM. err then says why in one line. warn
 *  (may be NULL) hears of damaged snapshots passed over. */
int gis_export_write(store *st, const gis_export_spec *spec, void (*warn)(const char *msg),
                     char *err, size_t errlen);

#endif
