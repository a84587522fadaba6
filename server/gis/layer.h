/* sylva gis: vector layers read with GDAL/OGR (any format GDAL reads: GeoJSON,
 * GeoPackage, Shapefile, FlatGeobuf, CSV, ...). A layer is opened, its fields are
 * looked up by name, and its features are walked in the file's order, each with its
 * row number (1 for the first feature read, whatever the format numbers its FIDs),
 * its field values and its geometry in the layer's own coordinates (x east or
 * longitude first, as GDAL's vector drivers give them). GDAL stays inside
 * server/gis/: nothing here names a GDAL type.
 *
 * Functions that can fail return SERVER_OK (0) or a negative server_error
 * (server_error.h) and write why into err: SERVER_EINPUT for bad input (a file
 * GDAL cannot open, a missing field, a bad geometry), SERVER_ENOMEM. */
#ifndef SYLVA_GIS_LAYER_H
#define SYLVA_GIS_LAYER_H

#include <stdbool.h>
#include <stddef.h>

/** An open layer and the feature it is at. */
typedef struct gis_layer gis_layer;

/** Readies GDAL (its drivers registered once, its messages kept from stderr:
 *  every failure is reported through err). Call before any other function. */
void gis_init(void);

/** GDAL's last message (CPLGetLastErrorMsg), or `fallback` when it said nothing. */
const char *gis_gdal_reason(const char *fallback);

/** Opens the layer of path that is named `prefer` (case-insensitive) when the file
 *  has one, else its first layer; drivers (NULL: any) restricts the formats tried
 *  ({"CSV", NULL}). crs, when not NULL, replaces the layer's own CRS (any text PROJ
 *  reads: "EPSG:4326", WKT, PROJJSON). SERVER_EINPUT names the file and GDAL's
 *  reason when GDAL cannot open it or it has no layer. */
int gis_layer_open(const char *path, const char *prefer, const char *const *drivers,
                   const char *crs, gis_layer **out, char *err, size_t errlen);

/** Opens the CSV text data[0..len) (kept by the caller while the layer is open) as
 *  a layer named `name`, as gis_layer_open() opens a file. */
int gis_layer_open_text(const char *name, const char *data, size_t len, gis_layer **out, char *err,
                        size_t errlen);

/** Closes a layer; NULL is allowed. */
void gis_layer_close(gis_layer *l);

/** The path the layer was opened from, and the layer's name. */
const char *gis_layer_path(const gis_layer *l);
const char *gis_layer_name(const gis_layer *l);

/** The number of layers of the layer's file (a note when it is more than one). */
int gis_layer_file_layers(const gis_layer *l);

/** The layer's CRS: the text given to gis_layer_open(), else the file's own as WKT2,
 *  else NULL (a CSV, a Shapefile without .prj). */
const char *gis_layer_crs(const gis_layer *l);

/** The index of the field called name (case-insensitive, as GDAL matches names):
 *  >= 0, or SERVER_EINPUT with "PATH: layer NAME: no field 'F' (fields: a, b)". */
int gis_layer_field(const gis_layer *l, const char *name, char *err, size_t errlen);

/** Moves to the next feature in the file's order: true, or false at the end (and
 *  on a read error, which *failed then reports with err). Restarts nowhere: a layer
 *  is walked once. */
bool gis_layer_next(gis_layer *l, bool *failed, char *err, size_t errlen);

/** The current feature's row: 1 for the first read, 2 for the next, ... */
long gis_layer_row(const gis_layer *l);

/** The current feature's value of a field as text into buf (truncated to size):
 *  a string as stored, trimmed of surrounding spaces; an integer in decimal; a real
 *  number as the shortest of %.15g; a date or other as GDAL writes it. false (buf
 *  "") when the value is unset or null. */
bool gis_field_text(const gis_layer *l, int field, char *buf, size_t size);

/** The current feature's value of a field as a number: 0 and *out for a number
 *  (a numeric field, or a text field holding a whole decimal number, surrounding
 *  spaces allowed), 1 when unset, null or empty text, -1 when text that is not a
 *  number (buf given to gis_field_text() shows it). */
int gis_field_number(const gis_layer *l, int field, double *out);

/** A feature's polygons: parts, each an outer ring and its holes, rings not closed
 *  (the last point is not the first again), in the layer's coordinates (2D; a z is
 *  dropped). */
typedef struct gis_polygons {
  double (*points)[2]; /**< every ring's points, ring after ring */
  int point_count;
  int *ring_sizes; /**< points of each ring */
  int ring_count;
  int *part_rings; /**< rings of each part: its outer ring first, then its holes */
  int part_count;
  double centroid[2]; /**< the whole footprint's centroid (GEOS), layer coordinates */
  char invalid[160];  /**< "" for a valid polygon, else GEOS's reason ("Self-intersection
                           at or near point 5 5") */
} gis_polygons;

/** Frees what gis_feature_polygons() gave; the struct is zeroed. */
void gis_polygons_free(gis_polygons *p);

/** The current feature's geometry as polygons: SERVER_OK (out->invalid says whether
 *  GEOS finds it valid); 1 when it has none (null or empty); SERVER_EINPUT when it is
 *  not a polygon or multipolygon ("the geometry is a LineString, not a polygon").
 *  Curved polygons are made linear. */
int gis_feature_polygons(const gis_layer *l, gis_polygons *out, char *err, size_t errlen);

/** The current feature's point: SERVER_OK and xy; 1 when it has no geometry (null or
 *  empty); SERVER_EINPUT when it is not a point (a multipoint of one point is one). */
int gis_feature_point(const gis_layer *l, double xy[2], char *err, size_t errlen);

/** A polygon held for point tests (GEOS). */
typedef struct gis_shape gis_shape;

/** A polygon of rings (ring_sizes[] points each, not closed; the first the outline,
 *  the others its holes): SERVER_OK and *out, or SERVER_ENOMEM. */
int gis_shape_create(const double (*points)[2], const int *ring_sizes, int ring_count,
                     gis_shape **out);

/** Frees a shape; NULL is allowed. */
void gis_shape_free(gis_shape *s);

/** Whether (x, y) lies inside the shape or on its outline. */
bool gis_shape_covers(const gis_shape *s, double x, double y);

#endif
