#include "gis_export.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#include "layer.h"
#include "server_error.h"
#include "sylva/encode.h"
#include "sylva/sylva.h"

/* The four kinds of feature: GeoPackage layers, GeoJSON `layer` values. */
enum { K_TRUNKS, K_CROWNS, K_BUILDINGS, K_ZONES, K_COUNT };
static const char *const kind_names[K_COUNT] = {"trunks", "crowns", "buildings", "zones"};

/* The figures of a stem: name, type, and which kinds carry it. */
enum { F_LAYER, F_PLANT, F_STEM, F_SPECIES, F_ITERATION, F_YEAR, F_AGE, F_HEIGHT, F_DBH,
       F_CROWN_DIAMETER, F_CROWN_HEIGHT, F_LEAF_AREA, F_CROWN_AREA, F_CARBON, F_ID, F_Z_BOTTOM,
       F_Z_TOP, F_COUNT };
static const struct {
  const char *name;
  OGRFieldType type;
  bool stem, obstacle; /* on trunks and crowns; on buildings and zones */
} fields[F_COUNT] = {
    [F_LAYER] = {"layer", OFTString, false, false}, /* GeoJSON only */
    [F_PLANT] = {"plant", OFTString, true, false},
    [F_STEM] = {"stem", OFTInteger, true, false},
    [F_SPECIES] = {"species", OFTString, true, false},
    [F_ITERATION] = {"iteration", OFTInteger, true, false},
    [F_YEAR] = {"year", OFTInteger, true, false},
    [F_AGE] = {"age", OFTInteger, true, false},
    [F_HEIGHT] = {"height", OFTReal, true, false},
    [F_DBH] = {"dbh", OFTReal, true, false},
    [F_CROWN_DIAMETER] = {"crown_diameter", OFTReal, true, false},
    [F_CROWN_HEIGHT] = {"crown_height", OFTReal, true, false},
    [F_LEAF_AREA] = {"leaf_area", OFTReal, true, false},
    [F_CROWN_AREA] = {"crown_area", OFTReal, true, false},
    [F_CARBON] = {"carbon", OFTReal, true, false},
    [F_ID] = {"id", OFTString, false, true},
    [F_Z_BOTTOM] = {"z_bottom", OFTReal, false, true},
    [F_Z_TOP] = {"z_top", OFTReal, false, true},
};

/* The zones some stem entered up to the last year: one `conflict_<zone>` field each,
 * in the order first met. */
typedef struct zone_names {
  char **names;
  size_t count, cap;
  bool failed; /* out of memory */
} zone_names;

typedef struct writer {
  const gis_export_spec *spec;
  double origin[2];
  OGRSpatialReferenceH srs;
  GDALDatasetH ds;
  OGRLayerH layer[K_COUNT]; /* GeoJSON: the one layer, four times */
  int field[K_COUNT][F_COUNT]; /* index in the layer, -1 where the kind has none */
  zone_names zones;
  int *zone_field[K_COUNT];    /* per zone, index in the layer */
  char *err;
  size_t errlen;
} writer;

static int write_failed(writer *g, const char *what) {
  snprintf(g->err, g->errlen, "%s: %s: %s", g->spec->path, what, gis_gdal_reason("GDAL failed"));
  return SERVER_EWRITE;
}

/* ---- the zones met ------------------------------------------------------------------ */

static int add_zone(zone_names *z, const char *name) {
  for (size_t i = 0; i < z->count; i++)
    if (strcmp(z->names[i], name) == 0) return 0;
  if (z->count == z->cap) {
    size_t cap = z->cap ? 2 * z->cap : 8;
    char **p = realloc(z->names, cap * sizeof *p);
    if (!p) return -1;
    z->names = p;
    z->cap = cap;
  }
  size_t n = strlen(name) + 1;
  if (!(z->names[z->count] = malloc(n))) return -1;
  memcpy(z->names[z->count++], name, n);
  return 0;
}

static int collect_zones(const store_stats_row *r, void *ctx) {
  zone_names *z = ctx;
  if (!r->zones) return 0;
  cJSON *o = cJSON_Parse(r->zones);
  if (!o) {
    z->failed = true;
    return 1;
  }
  for (const cJSON *k = o->child; k; k = k->next)
    if (k->string && add_zone(z, k->string)) {
      z->failed = true;
      break;
    }
  cJSON_Delete(o);
  return z->failed;
}

/* ---- the file ------------------------------------------------------------------------ */

static int add_field(writer *g, OGRLayerH l, const char *name, OGRFieldType type, int *index) {
  OGRFieldDefnH f = OGR_Fld_Create(name, type);
  if (!f) return SERVER_ENOMEM;
  OGRErr e = OGR_L_CreateField(l, f, TRUE);
  OGR_Fld_Destroy(f);
  if (e != OGRERR_NONE) return write_failed(g, "cannot add a field");
  *index = OGR_FD_GetFieldIndex(OGR_L_GetLayerDefn(l), name);
  return SERVER_OK;
}

static int create_layer(writer *g, const char *name, OGRwkbGeometryType type, char **options,
                        const int *kinds, int nkinds) {
  OGRLayerH l = GDALDatasetCreateLayer(g->ds, name, g->srs, type, options);
  if (!l) return write_failed(g, "cannot create a layer");
  bool stem = false, obstacle = false, geojson = nkinds > 1;
  for (int i = 0; i < nkinds; i++) {
    g->layer[kinds[i]] = l;
    stem |= kinds[i] == K_TRUNKS || kinds[i] == K_CROWNS;
    obstacle |= kinds[i] == K_BUILDINGS || kinds[i] == K_ZONES;
  }
  for (int f = 0; f < F_COUNT; f++) {
    int index = -1;
    if ((f == F_LAYER && geojson) || (fields[f].stem && stem) || (fields[f].obstacle && obstacle)) {
      int rc = add_field(g, l, fields[f].name, fields[f].type, &index);
      if (rc) return rc;
    }
    for (int i = 0; i < nkinds; i++)
      g->field[kinds[i]][f] =
          f == F_LAYER || (fields[f].stem ? kinds[i] <= K_CROWNS : kinds[i] >= K_BUILDINGS) ? index
                                                                                           : -1;
  }
  if (!stem) return SERVER_OK;
  int *zf = calloc(g->zones.count ? g->zones.count : 1, sizeof *zf);
  if (!zf) return SERVER_ENOMEM;
  for (int i = 0; i < nkinds; i++)
    if (kinds[i] <= K_CROWNS && !g->zone_field[kinds[i]]) g->zone_field[kinds[i]] = zf;
  for (size_t z = 0; z < g->zones.count; z++) {
    char name[300];
    snprintf(name, sizeof name, "conflict_%s", g->zones.names[z]);
    int rc = add_field(g, l, name, OFTInteger, &zf[z]);
    if (rc) return rc;
  }
  return SERVER_OK;
}

static int open_file(writer *g) {
  const bool gpkg = g->spec->gpkg;
  GDALDriverH driver = GDALGetDriverByName(gpkg ? "GPKG" : "GeoJSON");
  if (!driver) {
    snprintf(g->err, g->errlen, "GDAL has no %s driver", gpkg ? "GPKG" : "GeoJSON");
    return SERVER_EFAIL;
  }
  CPLErrorReset();
  g->ds = GDALCreate(driver, g->spec->path, 0, 0, 0, GDT_Unknown, NULL);
  if (!g->ds) return write_failed(g, "cannot create it");
  if (gpkg) {
    static const int trunks[] = {K_TRUNKS}, crowns[] = {K_CROWNS}, buildings[] = {K_BUILDINGS},
                     zones[] = {K_ZONES};
    int rc = create_layer(g, "trunks", wkbPoint, NULL, trunks, 1);
    if (!rc) rc = create_layer(g, "crowns", wkbMultiPolygon, NULL, crowns, 1);
    if (!rc) rc = create_layer(g, "buildings", wkbMultiPolygon, NULL, buildings, 1);
    if (!rc) rc = create_layer(g, "zones", wkbMultiPolygon, NULL, zones, 1);
    if (!rc && GDALDatasetStartTransaction(g->ds, FALSE) != OGRERR_NONE)
      rc = write_failed(g, "cannot start a transaction");
    return rc;
  }
  /* RFC 7946: WGS 84 longitude and latitude, which GDAL transforms to from the
   * layer's CRS; 9 decimals of a degree are 0.1 mm or less */
  static const int all[] = {K_TRUNKS, K_CROWNS, K_BUILDINGS, K_ZONES};
  char *options[] = {"RFC7946=YES", "COORDINATE_PRECISION=9", "WRITE_NAME=NO", NULL};
  return create_layer(g, "sylva", wkbUnknown, options, all, K_COUNT);
}

static int close_file(writer *g, int rc) {
  if (!g->ds) return rc;
  if (!rc && g->spec->gpkg && GDALDatasetCommitTransaction(g->ds) != OGRERR_NONE)
    rc = write_failed(g, "cannot commit");
  CPLErrorReset();
  GDALClose(g->ds); /* GeoJSON is written out here */
  g->ds = NULL;
  if (!rc && CPLGetLastErrorType() >= CE_Failure) rc = write_failed(g, "cannot finish it");
  return rc;
}

/* ---- features -------------------------------------------------------------------------- */

/* A figure to the decimals the CSV export gives it (export/csv.c), printed as it
 * prints them (an exact half rounds to even, as printf does: 14.03125 is 14.0312) and
 * read back: the store's floats print no digits they do not hold. */
static void set_real(OGRFeatureH f, int index, double v, int decimals) {
  if (index < 0) return;
  if (isfinite(v)) {
    char buf[SYLVA_FMT_BUFSIZE];
    sylva_fmt_fixed(buf, sizeof buf, v, decimals);
    OGR_F_SetFieldDouble(f, index, strtod(buf, NULL));
  } else {
    OGR_F_SetFieldNull(f, index);
  }
}

static void set_int(OGRFeatureH f, int index, int v, bool null) {
  if (index < 0) return;
  if (null)
    OGR_F_SetFieldNull(f, index);
  else
    OGR_F_SetFieldInteger(f, index, v);
}

static void set_text(OGRFeatureH f, int index, const char *v) {
  if (index < 0) return;
  if (v)
    OGR_F_SetFieldString(f, index, v);
  else
    OGR_F_SetFieldNull(f, index);
}

/* Adds a feature of kind k with geometry geom (taken); fill sets its fields. */
static int put_feature(writer *g, int k, OGRGeometryH geom,
                       void (*fill)(writer *g, int k, OGRFeatureH f, const void *ctx),
                       const void *ctx) {
  OGRFeatureH f = OGR_F_Create(OGR_L_GetLayerDefn(g->layer[k]));
  if (!f) {
    OGR_G_DestroyGeometry(geom);
    return SERVER_ENOMEM;
  }
  set_text(f, g->field[k][F_LAYER], kind_names[k]);
  fill(g, k, f, ctx);
  OGR_F_SetGeometryDirectly(f, geom);
  OGRErr e = OGR_L_CreateFeature(g->layer[k], f);
  OGR_F_Destroy(f);
  return e == OGRERR_NONE ? SERVER_OK : write_failed(g, "cannot add a feature");
}

/* A rectangle of the world's x, y, in the site's CRS. */
static OGRGeometryH rectangle(const writer *g, double x0, double y0, double x1, double y1) {
  OGRGeometryH ring = OGR_G_CreateGeometry(wkbLinearRing);
  OGRGeometryH poly = OGR_G_CreateGeometry(wkbPolygon);
  const double xs[5] = {x0, x1, x1, x0, x0}, ys[5] = {y0, y0, y1, y1, y0};
  for (int i = 0; i < 5; i++) OGR_G_AddPoint_2D(ring, g->origin[0] + xs[i], g->origin[1] + ys[i]);
  OGR_G_AddGeometryDirectly(poly, ring);
  return poly;
}

/* A polygon or multipolygon as a multipolygon (GeoPackage layers hold one type). */
static OGRGeometryH as_multi(OGRGeometryH geom) {
  return geom ? OGR_G_ForceToMultiPolygon(geom) : NULL;
}

/* The union of a crown's cells: each row's runs of cells as rectangles, joined by
 * GEOS. NULL when out of memory or GEOS failed. */
static OGRGeometryH crown_outline(const writer *g, const sylva_world *w, const int32_t *cells,
                                  int64_t n) {
  const sylva_world_def *def = sylva_world_get_def(w);
  const double e = sylva_world_cell_edge(w);
  OGRGeometryH parts = OGR_G_CreateGeometry(wkbMultiPolygon);
  for (int64_t k = 0; k < n;) {
    int64_t end = k + 1; /* cells are in row order, then x: a run shares y, x + 1 */
    while (end < n && cells[2 * end + 1] == cells[2 * k + 1] &&
           cells[2 * end] == cells[2 * (end - 1)] + 1)
      end++;
    double x0 = def->min[0] + cells[2 * k] * e, x1 = def->min[0] + (cells[2 * (end - 1)] + 1) * e;
    double y0 = def->min[1] + cells[2 * k + 1] * e, y1 = y0 + e;
    OGR_G_AddGeometryDirectly(parts, rectangle(g, x0, y0, x1, y1));
    k = end;
  }
  OGRGeometryH u = OGR_G_UnionCascaded(parts);
  OGR_G_DestroyGeometry(parts);
  /* the union keeps a vertex at every cell corner along a straight edge: a tolerance
   * far below a cell drops those and nothing else */
  OGRGeometryH simple = u ? OGR_G_SimplifyPreserveTopology(u, 1e-6 * e) : NULL;
  OGR_G_DestroyGeometry(u);
  return as_multi(simple);
}

/* An obstacle's footprint: a box's rectangle, or a prism's rings by the even-odd
 * rule (the symmetric difference of the areas they bound). */
static OGRGeometryH footprint(const writer *g, const sylva_obstacle_def *o) {
  const sylva_footprint *fp = &o->footprint;
  if (!fp->ring_count) return as_multi(rectangle(g, o->min[0], o->min[1], o->max[0], o->max[1]));
  OGRGeometryH acc = NULL;
  int at = 0;
  for (int r = 0; r < fp->ring_count; r++) {
    OGRGeometryH ring = OGR_G_CreateGeometry(wkbLinearRing);
    for (int i = 0; i <= fp->ring_sizes[r]; i++) {
      const double *p = fp->points[at + i % fp->ring_sizes[r]];
      OGR_G_AddPoint_2D(ring, g->origin[0] + p[0], g->origin[1] + p[1]);
    }
    at += fp->ring_sizes[r];
    OGRGeometryH poly = OGR_G_CreateGeometry(wkbPolygon);
    OGR_G_AddGeometryDirectly(poly, ring);
    if (!acc) {
      acc = poly;
      continue;
    }
    OGRGeometryH x = OGR_G_SymDifference(acc, poly);
    OGR_G_DestroyGeometry(acc);
    OGR_G_DestroyGeometry(poly);
    if (!(acc = x)) return NULL;
  }
  return as_multi(acc);
}

/* A stem's fields. */
typedef struct stem_ctx {
  const sylva_world *w;
  const sylva_stem_stats *s;
  int iteration;
  int stem; /* global index */
} stem_ctx;

static void fill_stem(writer *g, int k, OGRFeatureH f, const void *ctx) {
  const stem_ctx *c = ctx;
  const sylva_stem_stats *s = c->s;
  const int *fi = g->field[k];
  const int start = g->spec->start_year;
  set_text(f, fi[F_PLANT], sylva_world_plant_label(c->w, s->plant));
  set_int(f, fi[F_STEM], s->stem, false);
  set_text(f, fi[F_SPECIES],
           sylva_world_species_label(c->w, sylva_world_plant_species(c->w, s->plant)));
  set_int(f, fi[F_ITERATION], c->iteration, false);
  set_int(f, fi[F_YEAR], start + c->iteration, start == 0);
  set_int(f, fi[F_AGE], s->age, s->age < 0);
  set_real(f, fi[F_HEIGHT], s->height, 4);
  set_real(f, fi[F_DBH], s->dbh, 4);
  set_real(f, fi[F_CROWN_DIAMETER], s->crown_width, 4);
  set_real(f, fi[F_CROWN_HEIGHT], s->crown_height, 4);
  set_real(f, fi[F_LEAF_AREA], s->leaf_area, 4);
  set_real(f, fi[F_CROWN_AREA], s->crown_area, 4);
  set_real(f, fi[F_CARBON], s->carbon, 3);
  /* each zone's conflict year: when a node of the stem was first inside it */
  for (size_t z = 0; z < g->zones.count; z++) OGR_F_SetFieldNull(f, g->zone_field[k][z]);
  sylva_conflicts cf = sylva_world_stem_conflicts(c->w, c->stem);
  for (size_t i = 0; i < cf.zone_count; i++) {
    sylva_obstacle_def o;
    if (sylva_world_obstacle(c->w, cf.zones[i].obstacle, &o) != 0 || !o.label) continue;
    for (size_t z = 0; z < g->zones.count; z++)
      if (strcmp(g->zones.names[z], o.label) == 0)
        OGR_F_SetFieldInteger(f, g->zone_field[k][z], start + cf.zones[i].first);
  }
}

static void fill_obstacle(writer *g, int k, OGRFeatureH f, const void *ctx) {
  const sylva_obstacle_def *o = ctx;
  set_text(f, g->field[k][F_ID], o->label);
  set_real(f, g->field[k][F_Z_BOTTOM], o->min[2], 4);
  set_real(f, g->field[k][F_Z_TOP], o->max[2], 4);
}

static int put_stems(writer *g, const sylva_world *w, int iteration) {
  int rc = SERVER_OK;
  for (int k = 0; k < sylva_world_stem_count(w) && !rc; k++) {
    sylva_stem_stats s;
    double root[3];
    if (sylva_world_stem_stats(w, k, &s) != 0 || sylva_world_stem_root(w, k, root) != 0) continue;
    stem_ctx c = {w, &s, iteration, k};
    OGRGeometryH pt = OGR_G_CreateGeometry(wkbPoint);
    OGR_G_SetPoint_2D(pt, 0, g->origin[0] + root[0], g->origin[1] + root[1]);
    rc = put_feature(g, K_TRUNKS, pt, fill_stem, &c);
    int32_t *cells = NULL;
    int64_t n = rc ? 0 : sylva_world_crown_cells(w, k, &cells);
    if (n < 0) rc = SERVER_ENOMEM;
    if (n > 0) {
      OGRGeometryH crown = crown_outline(g, w, cells, n);
      if (!crown) {
        snprintf(g->err, g->errlen, "GEOS could not join the cells of a crown: %s",
                 gis_gdal_reason("no reason given"));
        rc = SERVER_EFAIL;
      } else {
        rc = put_feature(g, K_CROWNS, crown, fill_stem, &c);
      }
    }
    free(cells);
  }
  return rc;
}

static int put_obstacles(writer *g, const sylva_world *w) {
  int rc = SERVER_OK;
  for (int i = 0; i < sylva_world_obstacle_count(w) && !rc; i++) {
    int id;
    sylva_obstacle_def o;
    if (sylva_world_obstacle_at(w, i, &id, &o) != 0) continue;
    OGRGeometryH geom = footprint(g, &o);
    if (!geom) {
      snprintf(g->err, g->errlen, "GEOS could not make the footprint of obstacle \"%s\": %s",
               o.label ? o.label : "", gis_gdal_reason("no reason given"));
      return SERVER_EFAIL;
    }
    rc = put_feature(g, o.kind == SYLVA_OBSTACLE_ZONE ? K_ZONES : K_BUILDINGS, geom, fill_obstacle,
                     &o);
  }
  return rc;
}

/* ---- the run --------------------------------------------------------------------------- */

/* The site's CRS and origin from the scenario. */
static int read_site(writer *g) {
  const gis_export_spec *spec = g->spec;
  cJSON *sc = cJSON_Parse(spec->scenario);
  const cJSON *site = sc ? cJSON_GetObjectItemCaseSensitive(sc, "site") : NULL;
  const cJSON *crs = cJSON_GetObjectItemCaseSensitive(site, "crs");
  const cJSON *origin = cJSON_GetObjectItemCaseSensitive(site, "origin");
  int rc = SERVER_OK;
  if (!sc) {
    snprintf(g->err, g->errlen, "run \"%s\": its stored scenario is not JSON", spec->name);
    rc = SERVER_EFAIL;
  } else if (!cJSON_IsString(crs) || cJSON_GetArraySize(origin) != 2) {
    snprintf(g->err, g->errlen,
             "run \"%s\" has no site (\"site\": {\"crs\", \"origin\"}, docs/scenario.md): "
             "geojson and gpkg place its features with it; `sylva site` writes one",
             spec->name);
    rc = SERVER_EINPUT;
  } else {
    g->origin[0] = cJSON_GetArrayItem(origin, 0)->valuedouble;
    g->origin[1] = cJSON_GetArrayItem(origin, 1)->valuedouble;
    g->srs = OSRNewSpatialReference(NULL);
    if (!g->srs) {
      rc = SERVER_ENOMEM;
    } else if (OSRSetFromUserInput(g->srs, crs->valuestring) != OGRERR_NONE) {
      snprintf(g->err, g->errlen, "run \"%s\": site.crs '%s': GDAL cannot read it (%s)",
               spec->name, crs->valuestring, gis_gdal_reason("unknown reason"));
      rc = SERVER_EINPUT;
    } else {
      OSRSetAxisMappingStrategy(g->srs, OAMS_TRADITIONAL_GIS_ORDER);
    }
  }
  cJSON_Delete(sc);
  return rc;
}

int gis_export_write(store *st, const gis_export_spec *spec, void (*warn)(const char *msg),
                     char *err, size_t errlen) {
  gis_init();
  writer g = {.spec = spec, .err = err, .errlen = errlen};
  int rc = read_site(&g);
  int last = spec->year_count ? spec->years[spec->year_count - 1] : 0;
  if (!rc && store_each_stats(st, spec->run, last, collect_zones, &g.zones)) {
    if (g.zones.failed)
      snprintf(err, errlen, "out of memory");
    else
      snprintf(err, errlen, "run \"%s\": %s", spec->name, store_error(st));
    rc = g.zones.failed ? SERVER_ENOMEM : SERVER_EFAIL;
  }
  if (!rc) rc = open_file(&g);
  for (size_t i = 0; i < spec->year_count && !rc; i++) {
    sylva_world *w = NULL;
    if (store_world_at(st, spec->run, spec->years[i], warn, &w)) {
      snprintf(err, errlen, "run \"%s\": %s", spec->name, store_error(st));
      rc = SERVER_EFAIL;
      break;
    }
    rc = put_stems(&g, w, spec->years[i]);
    if (!rc && i + 1 == spec->year_count) rc = put_obstacles(&g, w);
    sylva_world_destroy(w);
  }
  rc = close_file(&g, rc);
  if (g.zone_field[K_TRUNKS] != g.zone_field[K_CROWNS]) free(g.zone_field[K_CROWNS]);
  free(g.zone_field[K_TRUNKS]);
  for (size_t z = 0; z < g.zones.count; z++) free(g.zones.names[z]);
  free(g.zones.names);
  if (g.srs) OSRDestroySpatialReference(g.srs);
  return rc;
}
