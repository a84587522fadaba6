#include "layer.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#include "server_error.h"

struct gis_layer {
  GDALDatasetH ds;
  OGRLayerH layer;
  OGRFeatureH feature; /* the current feature, NULL before the first and at the end */
  long row;
  char *path, *name, *crs;
  char *memory; /* /vsimem/ file to unlink at close, or NULL */
};

void gis_init(void) {
  static bool ready;
  if (ready) return;
  GDALAllRegister();
  /* Messages are reported through err by whoever called: none on stderr. */
  CPLSetErrorHandler(CPLQuietErrorHandler);
  ready = true;
}

static char *dup_text(const char *s) {
  size_t n = strlen(s) + 1;
  char *d = malloc(n);
  if (d) memcpy(d, s, n);
  return d;
}

const char *gis_gdal_reason(const char *fallback) {
  const char *m = CPLGetLastErrorMsg();
  return m && m[0] ? m : fallback;
}

static int open_dataset(const char *path, const char *shown, const char *prefer,
                        const char *const *drivers, const char *crs, gis_layer **out, char *err,
                        size_t errlen) {
  *out = NULL;
  CPLErrorReset();
  GDALDatasetH ds = GDALOpenEx(path, GDAL_OF_VECTOR | GDAL_OF_READONLY | GDAL_OF_VERBOSE_ERROR,
                               drivers, NULL, NULL);
  if (!ds)
    return server_fail(err, errlen, SERVER_EINPUT, "%s: GDAL cannot open it as a vector layer: %s",
                       shown, gis_gdal_reason("no driver reads it"));
  int n = GDALDatasetGetLayerCount(ds);
  OGRLayerH layer = NULL;
  for (int i = 0; i < n && prefer && !layer; i++) {
    OGRLayerH li = GDALDatasetGetLayer(ds, i);
    if (li && strcasecmp(OGR_L_GetName(li), prefer) == 0) layer = li;
  }
  if (!layer && n > 0) layer = GDALDatasetGetLayer(ds, 0);
  if (!layer) {
    GDALClose(ds);
    return server_fail(err, errlen, SERVER_EINPUT, "%s: the file holds no layer", shown);
  }
  gis_layer *l = calloc(1, sizeof *l);
  if (!l) {
    GDALClose(ds);
    return server_fail(err, errlen, SERVER_ENOMEM, "out of memory");
  }
  l->ds = ds;
  l->layer = layer;
  l->path = dup_text(shown);
  l->name = dup_text(OGR_L_GetName(layer));
  if (crs) {
    l->crs = dup_text(crs);
  } else {
    OGRSpatialReferenceH srs = OGR_L_GetSpatialRef(layer);
    char *wkt = NULL;
    const char *options[] = {"FORMAT=WKT2_2019", "MULTILINE=NO", NULL};
    if (srs && OSRExportToWktEx(srs, &wkt, options) == OGRERR_NONE && wkt) {
      l->crs = dup_text(wkt);
      if (!l->crs) crs = ""; /* any non-NULL: flags the failure below */
    }
    CPLFree(wkt);
  }
  if (!l->path || !l->name || (crs && !l->crs)) {
    gis_layer_close(l);
    return server_fail(err, errlen, SERVER_ENOMEM, "out of memory");
  }
  OGR_L_ResetReading(layer);
  *out = l;
  return SERVER_OK;
}

int gis_layer_open(const char *path, const char *prefer, const char *const *drivers,
                   const char *crs, gis_layer **out, char *err, size_t errlen) {
  return open_dataset(path, path, prefer, drivers, crs, out, err, errlen);
}

int gis_layer_open_text(const char *name, const char *data, size_t len, gis_layer **out, char *err,
                        size_t errlen) {
  *out = NULL;
  char path[256];
  snprintf(path, sizeof path, "/vsimem/sylva/%s.csv", name);
  VSILFILE *f = VSIFileFromMemBuffer(path, (GByte *)(uintptr_t)data, (vsi_l_offset)len, FALSE);
  if (!f) return server_fail(err, errlen, SERVER_ENOMEM, "out of memory");
  VSIFCloseL(f);
  const char *const csv[] = {"CSV", NULL};
  int rc = open_dataset(path, name, NULL, csv, NULL, out, err, errlen);
  if (rc == SERVER_OK && !((*out)->memory = dup_text(path))) rc = SERVER_ENOMEM;
  if (rc) {
    gis_layer_close(*out);
    *out = NULL;
    VSIUnlink(path);
    if (rc == SERVER_ENOMEM) server_fail(err, errlen, rc, "out of memory");
  }
  return rc;
}

void gis_layer_close(gis_layer *l) {
  if (!l) return;
  if (l->feature) OGR_F_Destroy(l->feature);
  if (l->ds) GDALClose(l->ds);
  if (l->memory) VSIUnlink(l->memory);
  free(l->memory);
  free(l->path);
  free(l->name);
  free(l->crs);
  free(l);
}

const char *gis_layer_path(const gis_layer *l) { return l->path; }
const char *gis_layer_name(const gis_layer *l) { return l->name; }
const char *gis_layer_crs(const gis_layer *l) { return l->crs; }
int gis_layer_file_layers(const gis_layer *l) { return GDALDatasetGetLayerCount(l->ds); }
long gis_layer_row(const gis_layer *l) { return l->row; }

int gis_layer_field(const gis_layer *l, const char *name, char *err, size_t errlen) {
  OGRFeatureDefnH defn = OGR_L_GetLayerDefn(l->layer);
  int i = OGR_FD_GetFieldIndex(defn, name);
  if (i >= 0) return i;
  char list[1024] = "";
  size_t used = 0;
  int n = OGR_FD_GetFieldCount(defn);
  for (int k = 0; k < n && used < sizeof list; k++)
    used += (size_t)snprintf(list + used, sizeof list - used, "%s%s", k ? ", " : "",
                             OGR_Fld_GetNameRef(OGR_FD_GetFieldDefn(defn, k)));
  return server_fail(err, errlen, SERVER_EINPUT, "%s: layer %s: no field '%s' (fields: %s)",
                     l->path, l->name, name, n ? list : "none");
}

bool gis_layer_next(gis_layer *l, bool *failed, char *err, size_t errlen) {
  *failed = false;
  if (l->feature) OGR_F_Destroy(l->feature);
  CPLErrorReset();
  l->feature = OGR_L_GetNextFeature(l->layer);
  if (!l->feature) {
    if (CPLGetLastErrorType() >= CE_Failure) {
      *failed = true;
      server_fail(err, errlen, SERVER_EINPUT, "%s: layer %s: after row %ld: %s", l->path, l->name,
                  l->row, gis_gdal_reason("read error"));
    }
    return false;
  }
  l->row++;
  return true;
}

static void trim_into(const char *s, char *buf, size_t size) {
  while (isspace((unsigned char)*s)) s++;
  size_t n = strlen(s);
  while (n > 0 && isspace((unsigned char)s[n - 1])) n--;
  if (n >= size) n = size - 1;
  memcpy(buf, s, n);
  buf[n] = '\0';
}

bool gis_field_text(const gis_layer *l, int field, char *buf, size_t size) {
  buf[0] = '\0';
  if (!l->feature || !OGR_F_IsFieldSetAndNotNull(l->feature, field)) return false;
  OGRFieldType t = OGR_Fld_GetType(OGR_F_GetFieldDefnRef(l->feature, field));
  /* Numbers written alike whatever the format stores: a Shapefile's 12.5 reads
   * back as "12.500000000000000" in GDAL's own text. */
  if (t == OFTInteger || t == OFTInteger64)
    snprintf(buf, size, "%lld", (long long)OGR_F_GetFieldAsInteger64(l->feature, field));
  else if (t == OFTReal)
    snprintf(buf, size, "%.15g", OGR_F_GetFieldAsDouble(l->feature, field));
  else
    trim_into(OGR_F_GetFieldAsString(l->feature, field), buf, size);
  return true;
}

int gis_field_number(const gis_layer *l, int field, double *out) {
  if (!l->feature || !OGR_F_IsFieldSetAndNotNull(l->feature, field)) return 1;
  OGRFieldType t = OGR_Fld_GetType(OGR_F_GetFieldDefnRef(l->feature, field));
  if (t == OFTInteger || t == OFTInteger64 || t == OFTReal) {
    *out = OGR_F_GetFieldAsDouble(l->feature, field);
    return isfinite(*out) ? 0 : -1;
  }
  char text[128];
  trim_into(OGR_F_GetFieldAsString(l->feature, field), text, sizeof text);
  if (!text[0]) return 1;
  char *end;
  errno = 0;
  double v = strtod(text, &end);
  if (end == text || *end || errno || !isfinite(v)) return -1;
  *out = v;
  return 0;
}

void gis_polygons_free(gis_polygons *p) {
  free(p->points);
  free(p->ring_sizes);
  free(p->part_rings);
  *p = (gis_polygons){0};
}

/* Appends the ring's points, the closing point dropped. */
static int add_ring(gis_polygons *p, OGRGeometryH ring, int *capacity) {
  int n = OGR_G_GetPointCount(ring);
  if (n > 1 && OGR_G_GetX(ring, 0) == OGR_G_GetX(ring, n - 1) &&
      OGR_G_GetY(ring, 0) == OGR_G_GetY(ring, n - 1))
    n--;
  if (p->point_count + n > *capacity) {
    int c = (p->point_count + n) * 2;
    double(*v)[2] = realloc(p->points, (size_t)c * sizeof *v);
    if (!v) return SERVER_ENOMEM;
    p->points = v;
    *capacity = c;
  }
  for (int i = 0; i < n; i++) {
    p->points[p->point_count + i][0] = OGR_G_GetX(ring, i);
    p->points[p->point_count + i][1] = OGR_G_GetY(ring, i);
  }
  p->point_count += n;
  p->ring_sizes[p->ring_count++] = n;
  return SERVER_OK;
}

/* Part k of a polygon (itself) or a multipolygon. */
static OGRGeometryH part_of(OGRGeometryH g, int k) {
  return wkbFlatten(OGR_G_GetGeometryType(g)) == wkbPolygon ? g : OGR_G_GetGeometryRef(g, k);
}

static int polygons_of(OGRGeometryH g, gis_polygons *p) {
  int parts = wkbFlatten(OGR_G_GetGeometryType(g)) == wkbPolygon ? 1 : OGR_G_GetGeometryCount(g);
  int rings = 0;
  for (int k = 0; k < parts; k++) rings += OGR_G_GetGeometryCount(part_of(g, k));
  p->ring_sizes = malloc((size_t)(rings ? rings : 1) * sizeof *p->ring_sizes);
  p->part_rings = malloc((size_t)(parts ? parts : 1) * sizeof *p->part_rings);
  if (!p->ring_sizes || !p->part_rings) return SERVER_ENOMEM;
  int capacity = 0;
  for (int k = 0; k < parts; k++) {
    OGRGeometryH poly = part_of(g, k);
    int n = OGR_G_GetGeometryCount(poly);
    if (n == 0) continue; /* an empty part */
    for (int r = 0; r < n; r++)
      if (add_ring(p, OGR_G_GetGeometryRef(poly, r), &capacity)) return SERVER_ENOMEM;
    p->part_rings[p->part_count++] = n;
  }
  return SERVER_OK;
}

int gis_feature_polygons(const gis_layer *l, gis_polygons *out, char *err, size_t errlen) {
  *out = (gis_polygons){0};
  OGRGeometryH g = l->feature ? OGR_F_GetGeometryRef(l->feature) : NULL;
  if (!g || OGR_G_IsEmpty(g)) return 1;
  OGRwkbGeometryType t = wkbFlatten(OGR_G_GetGeometryType(g));
  OGRGeometryH linear = NULL;
  if (t == wkbCurvePolygon || t == wkbMultiSurface) {
    if (!(linear = OGR_G_GetLinearGeometry(g, 0, NULL)))
      return server_fail(err, errlen, SERVER_ENOMEM, "out of memory");
    g = linear;
    t = wkbFlatten(OGR_G_GetGeometryType(g));
  }
  int rc = SERVER_OK;
  if (t != wkbPolygon && t != wkbMultiPolygon) {
    rc = server_fail(err, errlen, SERVER_EINPUT, "the geometry is a %s, not a polygon",
                     OGRGeometryTypeToName(t));
    goto done;
  }
  CPLErrorReset();
  if (!OGR_G_IsValid(g))
    snprintf(out->invalid, sizeof out->invalid, "%s", gis_gdal_reason("GEOS finds it invalid"));
  OGRGeometryH c = OGR_G_CreateGeometry(wkbPoint);
  if (!c || OGR_G_Centroid(g, c) != OGRERR_NONE || (rc = polygons_of(g, out))) {
    rc = server_fail(err, errlen, SERVER_ENOMEM, "out of memory");
    gis_polygons_free(out);
  } else {
    out->centroid[0] = OGR_G_GetX(c, 0);
    out->centroid[1] = OGR_G_GetY(c, 0);
  }
  if (c) OGR_G_DestroyGeometry(c);
done:
  if (linear) OGR_G_DestroyGeometry(linear);
  return rc;
}

int gis_feature_point(const gis_layer *l, double xy[2], char *err, size_t errlen) {
  OGRGeometryH g = l->feature ? OGR_F_GetGeometryRef(l->feature) : NULL;
  if (!g || OGR_G_IsEmpty(g)) return 1;
  OGRwkbGeometryType t = wkbFlatten(OGR_G_GetGeometryType(g));
  if (t == wkbMultiPoint && OGR_G_GetGeometryCount(g) == 1) {
    g = OGR_G_GetGeometryRef(g, 0);
    t = wkbFlatten(OGR_G_GetGeometryType(g));
  }
  if (t != wkbPoint)
    return server_fail(err, errlen, SERVER_EINPUT, "the geometry is a %s, not a point",
                       OGRGeometryTypeToName(t));
  xy[0] = OGR_G_GetX(g, 0);
  xy[1] = OGR_G_GetY(g, 0);
  return SERVER_OK;
}

struct gis_shape {
  OGRGeometryH polygon;
};

int gis_shape_create(const double (*points)[2], const int *ring_sizes, int ring_count,
                     gis_shape **out) {
  *out = NULL;
  gis_shape *s = calloc(1, sizeof *s);
  if (!s || !(s->polygon = OGR_G_CreateGeometry(wkbPolygon))) {
    free(s);
    return SERVER_ENOMEM;
  }
  int at = 0;
  for (int r = 0; r < ring_count; r++) {
    OGRGeometryH ring = OGR_G_CreateGeometry(wkbLinearRing);
    if (!ring) {
      gis_shape_free(s);
      return SERVER_ENOMEM;
    }
    for (int i = 0; i <= ring_sizes[r]; i++) { /* closed again */
      const double *p = points[at + i % ring_sizes[r]];
      OGR_G_AddPoint_2D(ring, p[0], p[1]);
    }
    at += ring_sizes[r];
    OGR_G_AddGeometryDirectly(s->polygon, ring);
  }
  *out = s;
  return SERVER_OK;
}

void gis_shape_free(gis_shape *s) {
  if (!s) return;
  if (s->polygon) OGR_G_DestroyGeometry(s->polygon);
  free(s);
}

bool gis_shape_covers(const gis_shape *s, double x, double y) {
  OGRGeometryH p = OGR_G_CreateGeometry(wkbPoint);
  if (!p) return false;
  OGR_G_SetPoint_2D(p, 0, x, y);
  bool in = OGR_G_Intersects(s->polygon, p);
  OGR_G_DestroyGeometry(p);
  return in;
}
