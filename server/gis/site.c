#include "site.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "frame.h"
#include "layer.h"
#include "region.h"
#include "server_error.h"

/* Room around the features of a site without --bbox, m; the least height of the
 * world, and the room above the tallest building or tree, m. */
#define SITE_MARGIN 10.0
#define SITE_MIN_TOP 40.0
#define SITE_HEADROOM 10.0
/* A region's reference city farther than this from the site is not its region. */
#define SITE_REGION_KM 400.0
/* Beyond these a value is taken for a mistake in the data. */
#define SITE_MAX_DBH_CM 300.0
#define SITE_MAX_HEIGHT_M 1000.0
/* The longest CRS name a scenario's site holds, bytes. */
#define SITE_CRS_MAX 255

const char *site_reason_name(site_reason r) {
  static const char *const names[] = {
#define SITE_REASON_NAME(name, text) text,
      SITE_REASONS(SITE_REASON_NAME)
#undef SITE_REASON_NAME
  };
  return r >= 0 && r < SITE_REASON_COUNT ? names[r] : "?";
}

/* ---- what is read ------------------------------------------------------------- */

/* A field's value read as a number: its state (gis_field_number) and its text. */
typedef struct value {
  int state;
  double v;
  char text[64];
} value;

/* A building or a zone as read. */
typedef struct footprint {
  long row;
  char id[256];
  bool has_id; /* from the id field */
  gis_polygons poly;
  double lonlat[2]; /* its centroid */
  value height, levels;
  int reason; /* a site_reason, or -1 while kept */
} footprint;

/* A tree as read. */
typedef struct tree {
  long row;
  char id[256];
  bool has_id;
  bool has_xy;
  double xy[2], lonlat[2];
  char name[SPECIES_NAME_MAX];
  value dbh;
  int reason;
  int species;
} tree;

/* One input layer and its CRSs. */
typedef struct source {
  const char *role;   /* "buildings", "trees", "zones": the layer preferred in a file */
  const char *option; /* the option that sets its CRS */
  gis_layer *layer;
  gis_crs *crs;
  bool crs_default; /* the file names none: read as EPSG:4326 */
  gis_transform *to_lonlat, *to_frame;
} source;

typedef struct build {
  const site_options *o;
  site *s;
  char *err;
  size_t errlen;
  gis_proj *proj;
  gis_crs *lonlat, *frame;
  gis_transform *frame_to_lonlat, *lonlat_to_frame;
  source src[3]; /* buildings, zones, trees */
  footprint *fp[2];
  int fp_count[2];
  tree *trees;
  int tree_count;
  gis_region regions[GIS_REGIONS];
} build;

enum { SRC_BUILDINGS, SRC_ZONES, SRC_TREES };

/* "PATH: layer NAME: row N (id X): " into buf. */
static void where(const source *src, long row, const char *id, bool has_id, char *buf, size_t n) {
  int k =
      snprintf(buf, n, "%s: layer %s: ", gis_layer_path(src->layer), gis_layer_name(src->layer));
  if (row > 0 && k >= 0 && (size_t)k < n)
    snprintf(buf + k, n - (size_t)k, has_id ? "row %ld (id %s): " : "row %ld: ", row, id);
}

static int row_fail(build *b, const source *src, long row, const char *id, bool has_id,
                    const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 6, 7)))
#endif
    ;

static int row_fail(build *b, const source *src, long row, const char *id, bool has_id,
                    const char *fmt, ...) {
  char head[512], tail[1024];
  where(src, row, id, has_id, head, sizeof head);
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(tail, sizeof tail, fmt, ap);
  va_end(ap);
  return server_fail(b->err, b->errlen, SERVER_EINPUT, "%s%s", head, tail);
}

static int no_memory(build *b) {
  return server_fail(b->err, b->errlen, SERVER_ENOMEM, "out of memory");
}

/* Opens a layer and its CRS (the option's, the file's, or EPSG:4326). */
static int open_source(build *b, source *src, const char *path, const char *crs) {
  int rc = gis_layer_open(path, src->role, NULL, crs, &src->layer, b->err, b->errlen);
  if (rc) return rc;
  size_t used = strlen(b->s->notes);
  if (gis_layer_file_layers(src->layer) > 1 && used < sizeof b->s->notes)
    snprintf(b->s->notes + used, sizeof b->s->notes - used, "%s holds %d layers: reading '%s'\n",
             path, gis_layer_file_layers(src->layer), gis_layer_name(src->layer));
  const char *text = gis_layer_crs(src->layer);
  src->crs_default = !text;
  char why[512];
  rc = gis_crs_create(b->proj, text ? text : "EPSG:4326", &src->crs, why, sizeof why);
  if (rc == SERVER_EINPUT && crs)
    return row_fail(b, src, 0, NULL, false, "%s '%s': %s", src->option, crs, why);
  if (rc == SERVER_EINPUT) return row_fail(b, src, 0, NULL, false, "its CRS: %s", why);
  return rc ? no_memory(b) : SERVER_OK;
}

static int field_of(build *b, const source *src, const char *name, int *out) {
  *out = -1;
  if (!name) return SERVER_OK;
  int i = gis_layer_field(src->layer, name, b->err, b->errlen);
  if (i < 0) return i;
  *out = i;
  return SERVER_OK;
}

static void read_value(const gis_layer *l, int field, value *v) {
  v->state = 1;
  v->text[0] = '\0';
  if (field < 0) return;
  gis_field_text(l, field, v->text, sizeof v->text);
  v->state = gis_field_number(l, field, &v->v);
}

/* Reads the buildings (k = SRC_BUILDINGS) or the zones (SRC_ZONES). */
static int read_footprints(build *b, int k) {
  const site_options *o = b->o;
  source *src = &b->src[k];
  int f_height, f_levels = -1, f_id = -1, rc;
  if ((rc = field_of(b, src, k == SRC_ZONES ? o->zone_field : o->height_field, &f_height)) ||
      (k == SRC_BUILDINGS && ((rc = field_of(b, src, o->levels_field, &f_levels)) ||
                              (rc = field_of(b, src, o->building_id_field, &f_id)))))
    return rc;
  int cap = 0;
  bool failed = false;
  while (gis_layer_next(src->layer, &failed, b->err, b->errlen)) {
    if (b->fp_count[k] == cap) {
      cap = cap ? 2 * cap : 64;
      footprint *v = realloc(b->fp[k], (size_t)cap * sizeof *v);
      if (!v) return no_memory(b);
      b->fp[k] = v;
    }
    footprint *f = &b->fp[k][b->fp_count[k]++];
    memset(f, 0, sizeof *f);
    f->row = gis_layer_row(src->layer);
    f->reason = -1;
    f->has_id = f_id >= 0 && gis_field_text(src->layer, f_id, f->id, sizeof f->id) && f->id[0];
    if (!f->has_id)
      snprintf(f->id, sizeof f->id, "%s-%ld", k == SRC_ZONES ? "zone" : "bldg", f->row);
    read_value(src->layer, f_height, &f->height);
    read_value(src->layer, f_levels, &f->levels);
    char why[512];
    rc = gis_feature_polygons(src->layer, &f->poly, why, sizeof why);
    if (rc == 1) {
      f->reason = SITE_NO_GEOMETRY;
      continue;
    }
    if (rc == SERVER_EINPUT) return row_fail(b, src, f->row, f->id, f->has_id, "%s", why);
    if (rc) return no_memory(b);
    f->lonlat[0] = f->poly.centroid[0];
    f->lonlat[1] = f->poly.centroid[1];
  }
  return failed ? SERVER_EINPUT : SERVER_OK;
}

/* Whether a tree's row passes every --keep field. */
static bool kept(const site_options *o, const gis_layer *l, const int *keep_field) {
  for (int i = 0; i < o->keep_count; i++) {
    bool first = true, any = false;
    for (int j = 0; j < i; j++)
      if (strcasecmp(o->keep[j].field, o->keep[i].field) == 0) first = false;
    if (!first) continue; /* the field's values were all tried at its first */
    char text[256];
    gis_field_text(l, keep_field[i], text, sizeof text);
    for (int j = i; j < o->keep_count && !any; j++)
      any = strcasecmp(o->keep[j].field, o->keep[i].field) == 0 &&
            strcasecmp(o->keep[j].value, text) == 0;
    if (!any) return false;
  }
  return true;
}

static int read_trees(build *b) {
  const site_options *o = b->o;
  source *src = &b->src[SRC_TREES];
  int f_species, f_dbh, f_id, f_x, f_y, rc;
  if ((rc = field_of(b, src, o->species_field, &f_species)) ||
      (rc = field_of(b, src, o->dbh_field, &f_dbh)) ||
      (rc = field_of(b, src, o->id_field, &f_id)) || (rc = field_of(b, src, o->x_field, &f_x)) ||
      (rc = field_of(b, src, o->y_field, &f_y)))
    return rc;
  int *keep_field = malloc((size_t)(o->keep_count ? o->keep_count : 1) * sizeof *keep_field);
  if (!keep_field) return no_memory(b);
  for (int i = 0; i < o->keep_count && !rc; i++)
    rc = field_of(b, src, o->keep[i].field, &keep_field[i]);
  int cap = 0;
  bool failed = false;
  while (!rc && gis_layer_next(src->layer, &failed, b->err, b->errlen)) {
    if (b->tree_count == cap) {
      cap = cap ? 2 * cap : 256;
      tree *v = realloc(b->trees, (size_t)cap * sizeof *v);
      if (!v) {
        rc = no_memory(b);
        break;
      }
      b->trees = v;
    }
    tree *t = &b->trees[b->tree_count++];
    memset(t, 0, sizeof *t);
    t->row = gis_layer_row(src->layer);
    t->reason = -1;
    t->species = -1;
    t->has_id = f_id >= 0 && gis_field_text(src->layer, f_id, t->id, sizeof t->id) && t->id[0];
    if (!t->has_id) snprintf(t->id, sizeof t->id, "%ld", t->row);
    gis_field_text(src->layer, f_species, t->name, sizeof t->name);
    read_value(src->layer, f_dbh, &t->dbh);
    if (o->x_field) {
      value x, y;
      read_value(src->layer, f_x, &x);
      read_value(src->layer, f_y, &y);
      if (x.state < 0 || y.state < 0) {
        const value *bad = x.state < 0 ? &x : &y;
        rc = row_fail(b, src, t->row, t->id, t->has_id, "field %s: '%s' is not a number",
                      x.state < 0 ? o->x_field : o->y_field, bad->text);
        break;
      }
      t->has_xy = x.state == 0 && y.state == 0;
      t->xy[0] = x.v;
      t->xy[1] = y.v;
    } else {
      char why[512];
      int g = gis_feature_point(src->layer, t->xy, why, sizeof why);
      if (g == SERVER_EINPUT) {
        rc = row_fail(b, src, t->row, t->id, t->has_id, "%s", why);
        break;
      }
      t->has_xy = g == SERVER_OK;
    }
    memcpy(t->lonlat, t->xy, sizeof t->xy);
    if (!kept(o, src->layer, keep_field))
      t->reason = SITE_FILTERED;
    else if (!t->has_xy)
      t->reason = SITE_NO_GEOMETRY;
  }
  free(keep_field);
  if (!rc && failed) rc = SERVER_EINPUT;
  return rc;
}

/* ---- where things are ------------------------------------------------------------ */

/* Transforms points of a source with t; a failure names the row (and the point, for
 * a tree). */
static int transform_rows(build *b, const source *src, const gis_transform *t, double (*xy)[2],
                          size_t n, long row, const char *id, bool has_id) {
  size_t bad;
  char why[512], point[96] = "a vertex";
  if (n == 1) snprintf(point, sizeof point, "the point (%.10g, %.10g)", xy[0][0], xy[0][1]);
  int rc = gis_transform_points(t, xy, n, &bad, why, sizeof why);
  if (rc == SERVER_EINPUT)
    return row_fail(b, src, row, id, has_id, "%s: %s%s", point, why,
                    src->crs_default ? " (the file names no CRS and is read as EPSG:4326: give "
                                       "its CRS)"
                                     : "");
  return rc;
}

static bool in_bbox(const site_options *o, const double ll[2]) {
  return ll[0] >= o->bbox[0] && ll[0] <= o->bbox[2] && ll[1] >= o->bbox[1] && ll[1] <= o->bbox[3];
}

/* Every feature's place in lon/lat (a footprint's centroid, a tree's point), and the
 * bbox's cut. *inside counts the features placed inside the bbox. */
static int place_lonlat(build *b, long *inside) {
  *inside = 0;
  char why[512];
  for (int k = 0; k < 3; k++) {
    source *src = &b->src[k];
    if (!src->layer) continue;
    int rc = gis_transform_create(b->proj, src->crs, b->lonlat, &src->to_lonlat, why, sizeof why);
    if (rc == SERVER_EINPUT)
      return row_fail(b, src, 0, NULL, false, "its CRS to EPSG:4326: %s", why);
    if (rc) return no_memory(b);
    int n = k == SRC_TREES ? b->tree_count : b->fp_count[k];
    for (int i = 0; i < n; i++) {
      bool tr = k == SRC_TREES;
      int *reason = tr ? &b->trees[i].reason : &b->fp[k][i].reason;
      if (tr ? !b->trees[i].has_xy : *reason == SITE_NO_GEOMETRY) continue;
      double *ll = tr ? b->trees[i].lonlat : b->fp[k][i].lonlat;
      rc = transform_rows(
          b, src, src->to_lonlat, (double(*)[2])ll, 1, tr ? b->trees[i].row : b->fp[k][i].row,
          tr ? b->trees[i].id : b->fp[k][i].id, tr ? b->trees[i].has_id : b->fp[k][i].has_id);
      if (rc) return rc;
      if (!(fabs(ll[0]) <= 180.0 && fabs(ll[1]) <= 90.0))
        return row_fail(
            b, src, tr ? b->trees[i].row : b->fp[k][i].row, tr ? b->trees[i].id : b->fp[k][i].id,
            tr ? b->trees[i].has_id : b->fp[k][i].has_id,
            "the point (%.10g, %.10g) has no longitude and latitude: PROJ cannot transform it to "
            "EPSG:4326%s",
            ll[0], ll[1],
            src->crs_default ? " (the file names no CRS and is read as EPSG:4326: give its CRS)"
                             : "");
      if (!b->o->has_bbox) continue;
      if (in_bbox(b->o, ll))
        ++*inside;
      else if (*reason < 0)
        *reason = SITE_OUTSIDE_BBOX;
    }
  }
  return SERVER_OK;
}

/* The frame's CRS: --crs; else the first layer's, projected in metres; else the UTM
 * zone of the centre (lon, lat). */
static int choose_frame(build *b, const double centre[2]) {
  const site_options *o = b->o;
  char why[512];
  int rc;
  if (o->crs) {
    rc = gis_crs_create(b->proj, o->crs, &b->frame, why, sizeof why);
    if (rc == SERVER_EINPUT)
      return server_fail(b->err, b->errlen, rc, "--crs '%s': %s", o->crs, why);
    if (rc) return no_memory(b);
    if (!gis_crs_projected_metric(b->frame))
      return server_fail(
          b->err, b->errlen, SERVER_EINPUT,
          "--crs '%s': not a projected CRS in metres (the frame's x and y are metres)", o->crs);
  } else {
    const source *first = NULL;
    for (int k = 0; k < 3 && !first; k++)
      if (b->src[k].layer) first = &b->src[k];
    if (first && !first->crs_default && gis_crs_projected_metric(first->crs))
      rc = gis_crs_create(b->proj, gis_layer_crs(first->layer), &b->frame, why, sizeof why);
    else
      rc = gis_crs_utm(b->proj, centre[0], centre[1], &b->frame, why, sizeof why);
    if (rc)
      return rc == SERVER_ENOMEM ? no_memory(b) : server_fail(b->err, b->errlen, rc, "%s", why);
  }
  if (!(b->s->crs = gis_crs_name(b->proj, b->frame))) return no_memory(b);
  if (strlen(b->s->crs) > SITE_CRS_MAX) { /* a scenario names its CRS in at most 255 bytes */
    if (o->crs)
      return server_fail(b->err, b->errlen, SERVER_EINPUT,
                         "--crs '%s': PROJ names it in more than %d bytes, more than a scenario "
                         "holds: give it as AUTHORITY:CODE",
                         o->crs, SITE_CRS_MAX);
    free(b->s->crs);
    b->s->crs = NULL;
    gis_crs_free(b->frame);
    b->frame = NULL;
    if ((rc = gis_crs_utm(b->proj, centre[0], centre[1], &b->frame, why, sizeof why)))
      return rc == SERVER_ENOMEM ? no_memory(b) : server_fail(b->err, b->errlen, rc, "%s", why);
    if (!(b->s->crs = gis_crs_name(b->proj, b->frame))) return no_memory(b);
  }
  if ((rc = gis_transform_create(b->proj, b->frame, b->lonlat, &b->frame_to_lonlat, why,
                                 sizeof why)) ||
      (rc = gis_transform_create(b->proj, b->lonlat, b->frame, &b->lonlat_to_frame, why,
                                 sizeof why)))
    return rc == SERVER_ENOMEM
               ? no_memory(b)
               : server_fail(b->err, b->errlen, rc, "the frame %s: %s", b->s->crs, why);
  for (int k = 0; k < 3; k++) {
    source *src = &b->src[k];
    if (!src->layer) continue;
    rc = gis_transform_create(b->proj, src->crs, b->frame, &src->to_frame, why, sizeof why);
    if (rc == SERVER_EINPUT)
      return row_fail(b, src, 0, NULL, false, "its CRS to the frame %s: %s", b->s->crs, why);
    if (rc) return no_memory(b);
  }
  return SERVER_OK;
}

static void grow(double box[4], const double p[2]) {
  box[0] = fmin(box[0], p[0]);
  box[1] = fmin(box[1], p[1]);
  box[2] = fmax(box[2], p[0]);
  box[3] = fmax(box[3], p[1]);
}

/* The centre of the site in lon/lat, for the UTM zone: the bbox's, else that of the
 * features kept so far. false when none is. */
static bool lonlat_centre(const build *b, double centre[2]) {
  const site_options *o = b->o;
  if (o->has_bbox) {
    centre[0] = (o->bbox[0] + o->bbox[2]) / 2;
    centre[1] = (o->bbox[1] + o->bbox[3]) / 2;
    return true;
  }
  double box[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};
  for (int k = 0; k < 2; k++)
    for (int i = 0; i < b->fp_count[k]; i++)
      if (b->fp[k][i].reason < 0) grow(box, b->fp[k][i].lonlat);
  for (int i = 0; i < b->tree_count; i++)
    if (b->trees[i].reason < 0) grow(box, b->trees[i].lonlat);
  centre[0] = (box[0] + box[2]) / 2;
  centre[1] = (box[1] + box[3]) / 2;
  return box[0] <= box[2];
}

/* Moves the kept features into the frame; box gets their extent there. */
static int place_frame(build *b, double box[4]) {
  for (int k = 0; k < 2; k++)
    for (int i = 0; i < b->fp_count[k]; i++) {
      footprint *f = &b->fp[k][i];
      if (f->reason >= 0) continue;
      int rc = transform_rows(b, &b->src[k], b->src[k].to_frame, f->poly.points,
                              (size_t)f->poly.point_count, f->row, f->id, f->has_id);
      if (rc) return rc;
      for (int p = 0; p < f->poly.point_count; p++) grow(box, f->poly.points[p]);
    }
  for (int i = 0; i < b->tree_count; i++) {
    tree *t = &b->trees[i];
    if (t->reason >= 0) continue;
    int rc = transform_rows(b, &b->src[SRC_TREES], b->src[SRC_TREES].to_frame, &t->xy, 1, t->row,
                            t->id, t->has_id);
    if (rc) return rc;
    grow(box, t->xy);
  }
  return SERVER_OK;
}

/* ---- rings -------------------------------------------------------------------------- */

/* Twice the signed area of a ring in mm² (positive counter-clockwise). */
static double ring_area2(const long long (*p)[2], int n) {
  double a = 0;
  for (int i = 0; i < n; i++) {
    const long long *u = p[i], *v = p[(i + 1) % n];
    a += (double)(u[0] * v[1] - v[0] * u[1]);
  }
  return a;
}

static bool lower(const long long *u, const long long *v) {
  return u[1] < v[1] || (u[1] == v[1] && u[0] < v[0]);
}

/* Rounds a ring of the frame to mm of the local frame into out, repeated points
 * dropped, turned counter-clockwise (ccw) or clockwise, starting at its lowest point:
 * its point count, 0 when fewer than 3 points or no area are left. */
static int local_ring(const double (*in)[2], int n, const long long origin[2], bool ccw,
                      long long (*out)[2], long long (*tmp)[2]) {
  int m = 0;
  for (int i = 0; i < n; i++) {
    long long q[2] = {llround((in[i][0] - (double)origin[0]) * 1000.0),
                      llround((in[i][1] - (double)origin[1]) * 1000.0)};
    if (m > 0 && tmp[m - 1][0] == q[0] && tmp[m - 1][1] == q[1]) continue;
    memcpy(tmp[m++], q, sizeof q);
  }
  while (m > 1 && tmp[m - 1][0] == tmp[0][0] && tmp[m - 1][1] == tmp[0][1]) m--;
  if (m < 3) return 0;
  double a = ring_area2((const long long(*)[2])tmp, m);
  if (a == 0) return 0;
  bool reverse = (a > 0) != ccw;
  int low = 0;
  for (int i = 1; i < m; i++)
    if (lower(tmp[i], tmp[low])) low = i;
  for (int i = 0; i < m; i++) {
    int j = reverse ? (low - i + m) % m : (low + i) % m;
    memcpy(out[i], tmp[j], sizeof out[i]);
  }
  return m;
}

/* A hole: its first point and where it sits in a buffer. */
typedef struct hole {
  long long first[2];
  int at, n;
} hole;

static int hole_order(const void *x, const void *y) {
  const hole *a = x, *b = y;
  if (lower(a->first, b->first)) return -1;
  if (lower(b->first, a->first)) return 1;
  return 0;
}

static int add_obstacle(build *b, site_obstacle **out) {
  site *s = b->s;
  if ((s->obstacle_count & (s->obstacle_count - 1)) == 0) { /* 0, 1, 2, 4, ...: grow */
    site_obstacle *v =
        realloc(s->obstacles, (size_t)(s->obstacle_count ? 2 * s->obstacle_count : 1) * sizeof *v);
    if (!v) return no_memory(b);
    s->obstacles = v;
  }
  *out = &s->obstacles[s->obstacle_count++];
  memset(*out, 0, sizeof **out);
  return SERVER_OK;
}

/* The prisms of one footprint, of height h m: one per part with an outline left at
 * 1 mm; *parts counts them. */
static int add_prisms(build *b, int k, const footprint *f, double h, int *parts) {
  *parts = 0;
  const gis_polygons *p = &f->poly;
  const source *src = &b->src[k];
  long long(*buf)[2] = malloc((size_t)(2 * p->point_count + 2) * sizeof *buf);
  hole *holes = malloc((size_t)(p->ring_count + 1) * sizeof *holes);
  int rc = buf && holes ? SERVER_OK : no_memory(b);
  long long(*tmp)[2] = buf + p->point_count + 1;
  int ring = 0, at = 0;
  for (int part = 0; part < p->part_count && !rc; part++) {
    int used = 0, nholes = 0;
    int outline = 0;
    for (int r = 0; r < p->part_rings[part]; r++, ring++) {
      int n = local_ring((const double(*)[2])p->points + at, p->ring_sizes[ring], b->s->origin,
                         r == 0, buf + used, tmp);
      at += p->ring_sizes[ring];
      if (r == 0)
        outline = n;
      else if (n > 0 && outline > 0)
        holes[nholes++] = (hole){{buf[used][0], buf[used][1]}, used, n};
      if (outline > 0) used += n;
    }
    if (outline == 0) continue;
    qsort(holes, (size_t)nholes, sizeof *holes, hole_order);
    site_obstacle *ob = NULL;
    if ((rc = add_obstacle(b, &ob))) break;
    ob->zone = k == SRC_ZONES;
    ob->height = llround(h * 1000.0);
    ob->path = gis_layer_path(src->layer);
    ob->row = f->row;
    ob->ring_count = 1 + nholes;
    ob->points = malloc((size_t)used * sizeof *ob->points);
    ob->ring_sizes = malloc((size_t)ob->ring_count * sizeof *ob->ring_sizes);
    if (!ob->points || !ob->ring_sizes) {
      rc = no_memory(b);
      break;
    }
    memcpy(ob->points, buf, (size_t)outline * sizeof *buf);
    ob->ring_sizes[0] = outline;
    int put = outline;
    for (int i = 0; i < nholes; i++) {
      memcpy(ob->points + put, buf + holes[i].at, (size_t)holes[i].n * sizeof *buf);
      ob->ring_sizes[1 + i] = holes[i].n;
      put += holes[i].n;
    }
    ++*parts;
    int len = *parts == 1 ? snprintf(ob->id, sizeof ob->id, "%s", f->id)
                          : snprintf(ob->id, sizeof ob->id, "%s/%d", f->id, *parts);
    if (len >= (int)sizeof ob->id || len < 1)
      rc = row_fail(b, src, f->row, f->id, f->has_id, "id '%s%s' is longer than %d bytes", f->id,
                    *parts == 1 ? "" : "/N", SITE_ID_MAX - 1);
  }
  free(buf);
  free(holes);
  return rc;
}

/* A footprint's height in m (NAN when it has none usable); bad text is an error. */
static int height_of(build *b, int k, const footprint *f, double *h) {
  const site_options *o = b->o;
  const source *src = &b->src[k];
  *h = NAN;
  const value *v[2] = {&f->height, &f->levels};
  const char *field[2] = {k == SRC_ZONES ? o->zone_field : o->height_field, o->levels_field};
  double scale[2] = {k == SRC_ZONES ? 1.0 : o->height_unit, o->level_height};
  for (int i = 0; i < (k == SRC_ZONES ? 1 : 2); i++) {
    if (!field[i]) continue;
    if (v[i]->state < 0)
      return row_fail(b, src, f->row, f->id, f->has_id, "field %s: '%s' is not a number", field[i],
                      v[i]->text);
    if (v[i]->state == 0 && v[i]->v > 0 && isnan(*h)) *h = v[i]->v * scale[i];
  }
  if (isnan(*h) && o->default_height > 0 && k == SRC_BUILDINGS) *h = o->default_height;
  if (*h > SITE_MAX_HEIGHT_M)
    return row_fail(b, src, f->row, f->id, f->has_id, "a height of %g m is over %g m", *h,
                    SITE_MAX_HEIGHT_M);
  return SERVER_OK;
}

static int make_obstacles(build *b, double *tallest) {
  *tallest = 0;
  for (int k = 0; k < 2; k++)
    for (int i = 0; i < b->fp_count[k]; i++) {
      footprint *f = &b->fp[k][i];
      if (f->reason >= 0) continue;
      if (f->poly.invalid[0])
        return row_fail(b, &b->src[k], f->row, f->id, f->has_id,
                        "the footprint is not a valid polygon: %s (repair it first, e.g. "
                        "ogr2ogr -makevalid)",
                        f->poly.invalid);
      double h;
      int rc = height_of(b, k, f, &h);
      if (rc) return rc;
      if (isnan(h)) {
        f->reason = SITE_NO_HEIGHT;
        continue;
      }
      int parts;
      if ((rc = add_prisms(b, k, f, h, &parts))) return rc;
      if (parts == 0) {
        f->reason = SITE_TOO_SMALL;
        continue;
      }
      if (k == SRC_ZONES) {
        b->s->zones += parts;
      } else {
        b->s->buildings++;
        b->s->prisms += parts;
        *tallest = fmax(*tallest, h);
      }
    }
  return SERVER_OK;
}

/* ---- trees -------------------------------------------------------------------------- */

static int tally(site_tally **list, int *count, const char *name) {
  for (int i = 0; i < *count; i++)
    if (strcmp((*list)[i].name, name) == 0) {
      (*list)[i].count++;
      return SERVER_OK;
    }
  site_tally *v = realloc(*list, (size_t)(*count + 1) * sizeof *v);
  if (!v) return SERVER_ENOMEM;
  *list = v;
  size_t n = strlen(name) + 1;
  if (!(v[*count].name = malloc(n))) return SERVER_ENOMEM;
  memcpy(v[*count].name, name, n);
  v[(*count)++].count = 1;
  return SERVER_OK;
}

/* The region the trees are matched in: --region, else the nearest reference city's
 * within SITE_REGION_KM of the origin (lon, lat). */
static int choose_region(build *b, const double origin[2]) {
  int rc = gis_regions_load(b->regions, b->err, b->errlen);
  if (rc) return rc;
  if (b->o->region) {
    if (!gis_region_find(b->regions, b->o->region)) {
      char list[256] = "";
      size_t used = 0;
      for (int i = 0; i < GIS_REGIONS && used < sizeof list; i++)
        used += (size_t)snprintf(list + used, sizeof list - used, "%s%s", i ? ", " : "",
                                 b->regions[i].code);
      return server_fail(b->err, b->errlen, SERVER_EINPUT,
                         "--region '%s': not a region of the Urban Tree Database (%s)",
                         b->o->region, list);
    }
    snprintf(b->s->region, sizeof b->s->region, "%s", b->o->region);
    return SERVER_OK;
  }
  double km;
  const gis_region *r = gis_region_nearest(b->regions, origin[0], origin[1], &km);
  if (km > SITE_REGION_KM)
    return server_fail(
        b->err, b->errlen, SERVER_EINPUT,
        "the site's centre (%.4f, %.4f) is %.0f km from the nearest reference city "
        "of the Urban Tree Database (%s, region %s), more than %.0f km: give --region",
        origin[0], origin[1], km, r->city, r->code, SITE_REGION_KM);
  snprintf(b->s->region, sizeof b->s->region, "%s", r->code);
  return SERVER_OK;
}

/* Reads --species-map: name,species rows into the library's map. */
static int read_map(build *b) {
  const char *path = b->o->species_map;
  if (!path) return SERVER_OK;
  const char *const csv[] = {"CSV", NULL};
  source src = {.role = NULL};
  int rc = gis_layer_open(path, NULL, csv, NULL, &src.layer, b->err, b->errlen);
  int f_name = -1, f_species = -1;
  if (!rc && !(rc = field_of(b, &src, "name", &f_name)))
    rc = field_of(b, &src, "species", &f_species);
  bool failed = false;
  while (!rc && gis_layer_next(src.layer, &failed, b->err, b->errlen)) {
    char name[SPECIES_NAME_MAX], target[SPECIES_NAME_MAX];
    gis_field_text(src.layer, f_name, name, sizeof name);
    gis_field_text(src.layer, f_species, target, sizeof target);
    long row = gis_layer_row(src.layer);
    if (!name[0]) continue;
    int k = species_find(&b->s->lib, b->s->region, target);
    if (k < 0) {
      rc = row_fail(b, &src, row, NULL, false,
                    "field species: '%s' is no library species of region %s (by name, code or "
                    "utdb:REGION:CODE; sylva species lists them)",
                    target, b->s->region);
      break;
    }
    if (species_map_add(&b->s->lib, name, k)) rc = no_memory(b);
  }
  if (!rc && failed) rc = SERVER_EINPUT;
  gis_layer_close(src.layer);
  return rc;
}

/* Species and DBH of every tree kept so far; *extra the plants' candidates. */
static int match_trees(build *b) {
  const site_options *o = b->o;
  const source *src = &b->src[SRC_TREES];
  site *s = b->s;
  for (int i = 0; i < b->tree_count; i++) {
    tree *t = &b->trees[i];
    if (t->reason >= 0) continue;
    if (t->dbh.state < 0)
      return row_fail(b, src, t->row, t->id, t->has_id, "field %s: '%s' is not a number",
                      o->dbh_field, t->dbh.text);
    if (t->dbh.state == 0) {
      double cm = t->dbh.v * o->dbh_unit;
      const char *unit = o->dbh_unit == 1.0 ? "cm" : "in";
      char shown[96];
      if (o->dbh_unit == 1.0)
        snprintf(shown, sizeof shown, "%s cm", t->dbh.text);
      else
        snprintf(shown, sizeof shown, "%s %s (%.4g cm)", t->dbh.text, unit, cm);
      if (!(t->dbh.v > 0))
        return row_fail(b, src, t->row, t->id, t->has_id, "field %s: %s is not above 0",
                        o->dbh_field, shown);
      if (cm > SITE_MAX_DBH_CM)
        return row_fail(b, src, t->row, t->id, t->has_id, "field %s: %s is over %g cm",
                        o->dbh_field, shown, SITE_MAX_DBH_CM);
      t->dbh.v = cm;
    } else if (o->default_dbh > 0) {
      t->dbh.state = 0;
      t->dbh.v = o->default_dbh;
    }
    t->species = species_match(&s->lib, s->region, t->name);
    if (t->species < 0) {
      t->reason = SITE_UNMATCHED;
      if (tally(&s->unmatched, &s->unmatched_count, t->name)) return no_memory(b);
    } else if (t->dbh.state != 0) {
      t->reason = SITE_NO_DBH;
    }
  }
  return SERVER_OK;
}

/* The voxel of a planted world: half the smallest rho of its plants' species. */
static double voxel_of(const build *b) {
  double rho = INFINITY;
  for (int i = 0; i < b->tree_count; i++)
    if (b->trees[i].reason < 0)
      rho = fmin(rho, b->o->rho > 0 ? b->o->rho : b->s->lib.species[b->trees[i].species].rho);
  if (!isfinite(rho)) rho = b->o->rho > 0 ? b->o->rho : 0.25;
  return rho / 2;
}

/* The voxel column of a local point (mm), as the core finds it: the point as a
 * float, floor((p - min) / voxel). */
static long long column_of(const site *s, long long mm, int axis) {
  double p = (double)(float)((double)mm / 1000.0);
  return (long long)floor((p - (double)s->world_min[axis]) / s->voxel);
}

typedef struct column {
  long long ix, iy;
  int tree;
} column;

static int column_order(const void *x, const void *y) {
  const column *a = x, *b = y;
  if (a->ix != b->ix) return a->ix < b->ix ? -1 : 1;
  if (a->iy != b->iy) return a->iy < b->iy ? -1 : 1;
  return (a->tree > b->tree) - (a->tree < b->tree);
}

/* Leaves out trees whose voxel column's centre lies in a building, then those in
 * the column of an earlier tree. */
static int place_trees(build *b, double *tallest) {
  site *s = b->s;
  *tallest = 0;
  gis_shape **shapes = calloc((size_t)(s->obstacle_count ? s->obstacle_count : 1), sizeof *shapes);
  double(*box)[4] = malloc((size_t)(s->obstacle_count ? s->obstacle_count : 1) * sizeof *box);
  column *cols = malloc((size_t)(b->tree_count ? b->tree_count : 1) * sizeof *cols);
  int rc = shapes && box && cols ? SERVER_OK : no_memory(b);
  for (int k = 0; k < s->obstacle_count && !rc; k++) {
    const site_obstacle *ob = &s->obstacles[k];
    double *e = box[k];
    e[0] = e[1] = INFINITY;
    e[2] = e[3] = -INFINITY;
    for (int p = 0; p < ob->ring_sizes[0]; p++) {
      double q[2] = {(double)ob->points[p][0] / 1000.0, (double)ob->points[p][1] / 1000.0};
      grow(e, q);
    }
  }
  int ncols = 0;
  for (int i = 0; i < b->tree_count && !rc; i++) {
    tree *t = &b->trees[i];
    if (t->reason >= 0) continue;
    long long mm[2] = {llround((t->xy[0] - (double)s->origin[0]) * 1000.0),
                       llround((t->xy[1] - (double)s->origin[1]) * 1000.0)};
    long long ix = column_of(s, mm[0], 0), iy = column_of(s, mm[1], 1);
    double c[2] = {(double)s->world_min[0] + ((double)ix + 0.5) * s->voxel,
                   (double)s->world_min[1] + ((double)iy + 0.5) * s->voxel};
    for (int k = 0; k < s->obstacle_count && t->reason < 0; k++) {
      const site_obstacle *ob = &s->obstacles[k];
      if (ob->zone || c[0] < box[k][0] || c[0] > box[k][2] || c[1] < box[k][1] || c[1] > box[k][3])
        continue;
      if (!shapes[k]) {
        int total = 0;
        for (int r = 0; r < ob->ring_count; r++) total += ob->ring_sizes[r];
        double(*m)[2] = malloc((size_t)total * sizeof *m);
        if (!m) {
          rc = no_memory(b);
          break;
        }
        for (int p = 0; p < total; p++) {
          m[p][0] = (double)ob->points[p][0] / 1000.0;
          m[p][1] = (double)ob->points[p][1] / 1000.0;
        }
        rc = gis_shape_create((const double(*)[2])m, ob->ring_sizes, ob->ring_count, &shapes[k]);
        free(m);
        if (rc) {
          rc = no_memory(b);
          break;
        }
      }
      if (gis_shape_covers(shapes[k], c[0], c[1])) t->reason = SITE_IN_BUILDING;
    }
    if (t->reason < 0) cols[ncols++] = (column){ix, iy, i};
  }
  if (!rc) {
    qsort(cols, (size_t)ncols, sizeof *cols, column_order);
    for (int i = 1; i < ncols; i++)
      if (cols[i].ix == cols[i - 1].ix && cols[i].iy == cols[i - 1].iy)
        b->trees[cols[i].tree].reason = SITE_TOO_CLOSE;
  }
  for (int k = 0; k < s->obstacle_count; k++) gis_shape_free(shapes ? shapes[k] : NULL);
  free(shapes);
  free(box);
  free(cols);
  if (rc) return rc;
  /* the plants, in the file's order */
  int n = 0;
  for (int i = 0; i < b->tree_count; i++) n += b->trees[i].reason < 0;
  if (!(s->plants = calloc((size_t)(n ? n : 1), sizeof *s->plants))) return no_memory(b);
  for (int i = 0; i < b->tree_count; i++) {
    tree *t = &b->trees[i];
    if (t->reason < 0) {
      site_plant *p = &s->plants[s->plant_count++];
      const species_entry *sp = &s->lib.species[t->species];
      if (strlen(t->id) >= sizeof p->id)
        return row_fail(b, &b->src[SRC_TREES], t->row, t->id, t->has_id,
                        "id '%s' is longer than %d bytes", t->id, SITE_ID_MAX - 1);
      memcpy(p->id, t->id, strlen(t->id) + 1); /* its length checked above */
      p->species = t->species;
      p->xy[0] = llround((t->xy[0] - (double)s->origin[0]) * 1000.0);
      p->xy[1] = llround((t->xy[1] - (double)s->origin[1]) * 1000.0);
      p->age = species_age(sp, t->dbh.v);
      p->row = t->row;
      *tallest = fmax(*tallest, species_height(sp, p->age + b->o->iterations));
      if (tally(&s->species, &s->species_count, sp->name)) return no_memory(b);
    }
  }
  return SERVER_OK;
}

/* ---- ids ---------------------------------------------------------------------------- */

typedef struct named {
  const char *id;
  int index;
} named;

static int named_order(const void *x, const void *y) {
  const named *a = x, *b = y;
  int c = strcmp(a->id, b->id);
  return c ? c : (a->index > b->index) - (a->index < b->index);
}

/* The first id given twice among n, or -1: *first its earlier index. */
static int duplicate(named *v, int n, int *first) {
  qsort(v, (size_t)n, sizeof *v, named_order);
  int found = -1;
  for (int i = 1; i < n; i++)
    if (strcmp(v[i].id, v[i - 1].id) == 0 && (found < 0 || v[i].index < found)) {
      found = v[i].index;
      *first = v[i - 1].index;
    }
  return found;
}

static int check_ids(build *b) {
  site *s = b->s;
  int n = s->obstacle_count > s->plant_count ? s->obstacle_count : s->plant_count;
  named *v = malloc((size_t)(n ? n : 1) * sizeof *v);
  if (!v) return no_memory(b);
  int first = 0, dup;
  for (int i = 0; i < s->obstacle_count; i++) v[i] = (named){s->obstacles[i].id, i};
  if ((dup = duplicate(v, s->obstacle_count, &first)) >= 0) {
    const site_obstacle *a = &s->obstacles[first], *d = &s->obstacles[dup];
    free(v);
    return server_fail(b->err, b->errlen, SERVER_EINPUT,
                       "%s: row %ld: obstacle id '%s' is taken by %s row %ld already (ids must be "
                       "unique)",
                       d->path, d->row, d->id, a->path, a->row);
  }
  for (int i = 0; i < s->plant_count; i++) v[i] = (named){s->plants[i].id, i};
  if ((dup = duplicate(v, s->plant_count, &first)) >= 0) {
    const site_plant *a = &s->plants[first], *d = &s->plants[dup];
    free(v);
    return row_fail(b, &b->src[SRC_TREES], d->row, d->id, true,
                    "the id is taken by row %ld already (ids must be unique)", a->row);
  }
  free(v);
  return SERVER_OK;
}

/* ---- the site ------------------------------------------------------------------------- */

static void free_build(build *b) {
  for (int k = 0; k < 3; k++) {
    gis_transform_free(b->src[k].to_lonlat);
    gis_transform_free(b->src[k].to_frame);
    gis_crs_free(b->src[k].crs);
    gis_layer_close(b->src[k].layer);
  }
  for (int k = 0; k < 2; k++) {
    for (int i = 0; i < b->fp_count[k]; i++) gis_polygons_free(&b->fp[k][i].poly);
    free(b->fp[k]);
  }
  free(b->trees);
  gis_transform_free(b->frame_to_lonlat);
  gis_transform_free(b->lonlat_to_frame);
  gis_crs_free(b->frame);
  gis_crs_free(b->lonlat);
  gis_proj_free(b->proj);
}

/* The counts of the reasons so far, for a message. */
static void reasons_text(const build *b, char *buf, size_t n) {
  long count[SITE_REASON_COUNT] = {0};
  for (int k = 0; k < 2; k++)
    for (int i = 0; i < b->fp_count[k]; i++)
      if (b->fp[k][i].reason >= 0) count[b->fp[k][i].reason]++;
  for (int i = 0; i < b->tree_count; i++)
    if (b->trees[i].reason >= 0) count[b->trees[i].reason]++;
  size_t used = 0;
  buf[0] = '\0';
  for (int r = 0; r < SITE_REASON_COUNT && used < n; r++)
    if (count[r])
      used += (size_t)snprintf(buf + used, n - used, "%s%s %ld", used ? ", " : "",
                               site_reason_name((site_reason)r), count[r]);
}

/* The origin's latitude and true north in the frame. */
static int orient(build *b) {
  site *s = b->s;
  double p[2][2] = {{(double)s->origin[0], (double)s->origin[1]}, {0, 0}};
  size_t bad;
  char why[512];
  int rc = gis_transform_points(b->frame_to_lonlat, p, 1, &bad, why, sizeof why);
  if (rc) return server_fail(b->err, b->errlen, rc, "the frame's origin to EPSG:4326: %s", why);
  s->latitude = p[0][1];
  double q[2][2] = {{p[0][0], p[0][1] - 0.0005}, {p[0][0], p[0][1] + 0.0005}};
  rc = gis_transform_points(b->lonlat_to_frame, q, 2, &bad, why, sizeof why);
  if (rc) return server_fail(b->err, b->errlen, rc, "north at the origin: %s", why);
  double dx = q[1][0] - q[0][0], dy = q[1][1] - q[0][1], len = hypot(dx, dy);
  s->north[0] = dx / len;
  s->north[1] = dy / len;
  return SERVER_OK;
}

static int build_site(build *b) {
  const site_options *o = b->o;
  site *s = b->s;
  int rc;
  if (gis_proj_create(&b->proj)) return no_memory(b);
  char why[512];
  if ((rc = gis_crs_create(b->proj, "EPSG:4326", &b->lonlat, why, sizeof why)))
    return rc == SERVER_ENOMEM
               ? no_memory(b)
               : server_fail(b->err, b->errlen, SERVER_EFAIL, "PROJ: EPSG:4326: %s", why);
  const char *path[3] = {o->buildings, o->zones, o->trees};
  const char *crs[3] = {o->buildings_crs, o->zones_crs, o->trees_crs};
  const char *role[3] = {"buildings", "zones", "trees"};
  const char *option[3] = {"--buildings-crs", "--zones-crs", "--layer-crs"};
  for (int k = 0; k < 3; k++) {
    b->src[k].role = role[k];
    b->src[k].option = option[k];
    if (path[k] && (rc = open_source(b, &b->src[k], path[k], crs[k]))) return rc;
  }
  if ((o->buildings && (rc = read_footprints(b, SRC_BUILDINGS))) ||
      (o->zones && (rc = read_footprints(b, SRC_ZONES))) || (o->trees && (rc = read_trees(b))))
    return rc;
  long inside;
  if ((rc = place_lonlat(b, &inside))) return rc;
  if (o->has_bbox && inside == 0)
    return server_fail(b->err, b->errlen, SERVER_EINPUT,
                       "--bbox %g,%g,%g,%g: no building, tree or zone lies inside it", o->bbox[0],
                       o->bbox[1], o->bbox[2], o->bbox[3]);
  double centre[2];
  if (!lonlat_centre(b, centre)) {
    char counts[256];
    reasons_text(b, counts, sizeof counts);
    return server_fail(b->err, b->errlen, SERVER_EINPUT,
                       "nothing to place: every feature was left out (%s)",
                       counts[0] ? counts : "the layers are empty");
  }
  if ((rc = choose_frame(b, centre))) return rc;
  double ext[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};
  if ((rc = place_frame(b, ext))) return rc;
  double world[4];
  if (o->has_bbox) {
    if ((rc = gis_transform_bounds(b->lonlat_to_frame, o->bbox, world, why, sizeof why)))
      return server_fail(b->err, b->errlen, rc, "--bbox to the frame %s: %s", s->crs, why);
    for (int a = 0; a < 2; a++) {
      world[a] = floor(world[a]);
      world[a + 2] = ceil(world[a + 2]);
    }
  } else {
    for (int a = 0; a < 2; a++) {
      world[a] = floor(ext[a] - SITE_MARGIN);
      world[a + 2] = ceil(ext[a + 2] + SITE_MARGIN);
    }
  }
  for (int a = 0; a < 2; a++) {
    double mid = o->has_bbox ? (world[a] + world[a + 2]) / 2 : (ext[a] + ext[a + 2]) / 2;
    s->origin[a] = llround(mid);
    s->world_min[a] = (long long)world[a] - s->origin[a];
    s->world_max[a] = (long long)world[a + 2] - s->origin[a];
  }
  if ((rc = orient(b))) return rc;
  if (o->trees) {
    double ll[2] = {(double)s->origin[0], (double)s->origin[1]};
    size_t bad;
    if ((rc = gis_transform_points(b->frame_to_lonlat, &ll, 1, &bad, why, sizeof why)))
      return server_fail(b->err, b->errlen, rc, "the frame's origin to EPSG:4326: %s", why);
    if ((rc = species_library_load(&s->lib, b->err, b->errlen)) || (rc = choose_region(b, ll)) ||
        (rc = read_map(b)) || (rc = match_trees(b)))
      return rc;
  }
  double tallest_building, tallest_tree = 0;
  if ((rc = make_obstacles(b, &tallest_building))) return rc;
  s->voxel = voxel_of(b);
  if ((rc = place_trees(b, &tallest_tree)) || (rc = check_ids(b))) return rc;
  double top = fmax(SITE_MIN_TOP, fmax(tallest_building, tallest_tree) + SITE_HEADROOM);
  s->world_min[2] = 0;
  s->world_max[2] = (long long)ceil(top);
  for (int k = 0; k < 2; k++)
    for (int i = 0; i < b->fp_count[k]; i++)
      if (b->fp[k][i].reason >= 0) s->left_out[b->fp[k][i].reason]++;
  for (int i = 0; i < b->tree_count; i++)
    if (b->trees[i].reason >= 0) s->left_out[b->trees[i].reason]++;
  return SERVER_OK;
}

int site_build(const site_options *o, site *s, char *err, size_t errlen) {
  *s = (site){0};
  gis_init();
  build b = {.o = o, .s = s, .err = err, .errlen = errlen};
  int rc = build_site(&b);
  free_build(&b);
  if (rc) site_free(s);
  return rc;
}

void site_free(site *s) {
  free(s->crs);
  for (int i = 0; i < s->obstacle_count; i++) {
    free(s->obstacles[i].points);
    free(s->obstacles[i].ring_sizes);
  }
  free(s->obstacles);
  free(s->plants);
  for (int i = 0; i < s->unmatched_count; i++) free(s->unmatched[i].name);
  free(s->unmatched);
  for (int i = 0; i < s->species_count; i++) free(s->species[i].name);
  free(s->species);
  species_library_free(&s->lib);
  *s = (site){0};
}
