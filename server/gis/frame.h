/* sylva gis: coordinate reference systems and transformations with PROJ (proj.h).
 * Every transformation takes and gives x east (or longitude) first and y north (or
 * latitude), whatever order the CRS's definition gives its axes
 * (proj_normalize_for_visualization); geographic coordinates are degrees. PROJ stays
 * inside server/gis/: nothing here names a PROJ type.
 *
 * Functions that can fail return SERVER_OK (0) or a negative server_error and write
 * why into err: SERVER_EINPUT for a CRS PROJ cannot read or a point it cannot
 * transform, SERVER_ENOMEM. */
#ifndef SYLVA_GIS_FRAME_H
#define SYLVA_GIS_FRAME_H

#include <stdbool.h>
#include <stddef.h>

/** PROJ's context: one per thread that uses the CRSs made with it. */
typedef struct gis_proj gis_proj;

/** A new context: SERVER_OK and *out, or SERVER_ENOMEM. */
int gis_proj_create(gis_proj **out);

/** Frees a context; free its CRSs and transformations first. NULL is allowed. */
void gis_proj_free(gis_proj *p);

/** A coordinate reference system. */
typedef struct gis_crs gis_crs;

/** The CRS given as text PROJ reads ("EPSG:32618", WKT, PROJJSON, a PROJ string):
 *  SERVER_EINPUT with "PROJ cannot read it (REASON)" when it is none. */
int gis_crs_create(gis_proj *p, const char *text, gis_crs **out, char *err, size_t errlen);

/** WGS 84's UTM zone (EPSG:326ZZ north of the equator, 327ZZ south) of a place,
 *  lon/lat in degrees: zone floor((lon + 180) / 6) + 1, within 1..60; Norway's and
 *  Svalbard's exceptions are not made. */
int gis_crs_utm(gis_proj *p, double lon, double lat, gis_crs **out, char *err, size_t errlen);

/** Frees a CRS; NULL is allowed. */
void gis_crs_free(gis_crs *c);

/** Whether the CRS is projected with both axes in metres (the CRS a local frame in
 *  metres can be taken from as it is). */
bool gis_crs_projected_metric(const gis_crs *c);

/** The CRS as one string PROJ reads back: "AUTHORITY:CODE" when it has an
 *  identifier, or when PROJ identifies it as equivalent to one of the EPSG
 *  registry (the best match of confidence 70 or more); else its PROJ string, else
 *  its WKT2 (2019) on one line. malloc()ed; NULL when out of memory. */
char *gis_crs_name(gis_proj *p, const gis_crs *c);

/** A transformation from one CRS to another. */
typedef struct gis_transform gis_transform;

/** The transformation from `from` to `to` (proj_create_crs_to_crs): SERVER_EINPUT
 *  with PROJ's reason when there is none. */
int gis_transform_create(gis_proj *p, const gis_crs *from, const gis_crs *to, gis_transform **out,
                         char *err, size_t errlen);

/** Frees a transformation; NULL is allowed. */
void gis_transform_free(gis_transform *t);

/** Transforms n points in place. SERVER_EINPUT when a point cannot be transformed
 *  (PROJ gives no finite result): *bad is its index and err PROJ's reason; the
 *  points are then partly transformed. */
int gis_transform_points(const gis_transform *t, double (*xy)[2], size_t n, size_t *bad, char *err,
                         size_t errlen);

/** The extent in `to` of the rectangle box = {xmin, ymin, xmax, ymax} of `from`,
 *  its outline densified (proj_trans_bounds, 21 points a side) into out. */
int gis_transform_bounds(const gis_transform *t, const double box[4], double out[4], char *err,
                         size_t errlen);

/** The geodesic distance on WGS 84 between two places (lon/lat, degrees), metres
 *  (PROJ's geodesic.h, Karney's algorithm). */
double gis_geodesic_m(double lon1, double lat1, double lon2, double lat2);

#endif
