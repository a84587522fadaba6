#include "frame.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <geodesic.h>
#include <proj.h>

#include "server_error.h"

struct gis_proj {
  PJ_CONTEXT *ctx;
  char said[256]; /* PROJ's last logged error: it says more than its error code */
};

struct gis_crs {
  gis_proj *proj;
  PJ *pj;
};

struct gis_transform {
  gis_proj *proj;
  PJ *pj;
};

static void keep_log(void *data, int level, const char *msg) {
  gis_proj *p = data;
  if (level == PJ_LOG_ERROR && msg) snprintf(p->said, sizeof p->said, "%s", msg);
}

int gis_proj_create(gis_proj **out) {
  gis_proj *p = calloc(1, sizeof *p);
  if (!p || !(p->ctx = proj_context_create())) {
    free(p);
    *out = NULL;
    return SERVER_ENOMEM;
  }
  /* PROJ's own logging would go to stderr: its reasons are reported through err. */
  proj_log_func(p->ctx, p, keep_log);
  proj_log_level(p->ctx, PJ_LOG_ERROR);
  *out = p;
  return SERVER_OK;
}

void gis_proj_free(gis_proj *p) {
  if (!p) return;
  proj_context_destroy(p->ctx);
  free(p);
}

/* PROJ's reason for the context's last failure: what it logged, else its code's. */
static const char *proj_reason(gis_proj *p) {
  if (p->said[0]) return p->said;
  int e = proj_context_errno(p->ctx);
  const char *m = e ? proj_context_errno_string(p->ctx, e) : NULL;
  return m && m[0] ? m : "unknown reason";
}

static bool is_crs(const PJ *pj) {
  switch (proj_get_type(pj)) {
    case PJ_TYPE_GEOGRAPHIC_2D_CRS:
    case PJ_TYPE_GEOGRAPHIC_3D_CRS:
    case PJ_TYPE_GEOCENTRIC_CRS:
    case PJ_TYPE_PROJECTED_CRS:
    case PJ_TYPE_COMPOUND_CRS:
    case PJ_TYPE_BOUND_CRS:
    case PJ_TYPE_ENGINEERING_CRS:
    case PJ_TYPE_OTHER_CRS: return true;
    default: return false;
  }
}

int gis_crs_create(gis_proj *p, const char *text, gis_crs **out, char *err, size_t errlen) {
  *out = NULL;
  p->said[0] = '\0';
  PJ *pj = proj_create(p->ctx, text);
  if (!pj)
    return server_fail(err, errlen, SERVER_EINPUT, "PROJ cannot read it (%s)", proj_reason(p));
  if (!is_crs(pj)) {
    proj_destroy(pj);
    return server_fail(err, errlen, SERVER_EINPUT, "PROJ reads it, but not as a CRS");
  }
  gis_crs *c = malloc(sizeof *c);
  if (!c) {
    proj_destroy(pj);
    return server_fail(err, errlen, SERVER_ENOMEM, "out of memory");
  }
  *c = (gis_crs){.proj = p, .pj = pj};
  *out = c;
  return SERVER_OK;
}

int gis_crs_utm(gis_proj *p, double lon, double lat, gis_crs **out, char *err, size_t errlen) {
  int zone = (int)floor((lon + 180.0) / 6.0) + 1;
  if (zone < 1) zone = 1;
  if (zone > 60) zone = 60;
  char name[32];
  snprintf(name, sizeof name, "EPSG:%d", (lat >= 0 ? 32600 : 32700) + zone);
  return gis_crs_create(p, name, out, err, errlen);
}

void gis_crs_free(gis_crs *c) {
  if (!c) return;
  proj_destroy(c->pj);
  free(c);
}

bool gis_crs_projected_metric(const gis_crs *c) {
  PJ_CONTEXT *ctx = c->proj->ctx;
  /* a CRS bound to WGS 84 (WKT1's TOWGS84) is judged by the CRS it binds */
  PJ *base = proj_get_type(c->pj) == PJ_TYPE_BOUND_CRS ? proj_get_source_crs(ctx, c->pj) : NULL;
  const PJ *crs = base ? base : c->pj;
  bool metric = false;
  if (proj_get_type(crs) == PJ_TYPE_PROJECTED_CRS) {
    PJ *cs = proj_crs_get_coordinate_system(ctx, crs);
    int n = cs ? proj_cs_get_axis_count(ctx, cs) : 0;
    metric = n == 2;
    for (int i = 0; i < n && metric; i++) {
      double factor = 0;
      if (!proj_cs_get_axis_info(ctx, cs, i, NULL, NULL, NULL, &factor, NULL, NULL, NULL) ||
          factor != 1.0)
        metric = false;
    }
    proj_destroy(cs);
  }
  proj_destroy(base);
  return metric;
}

static char *joined(const char *auth, const char *code) {
  size_t n = strlen(auth) + strlen(code) + 2;
  char *s = malloc(n);
  if (s) snprintf(s, n, "%s:%s", auth, code);
  return s;
}

char *gis_crs_name(gis_proj *p, const gis_crs *c) {
  const char *auth = proj_get_id_auth_name(c->pj, 0), *code = proj_get_id_code(c->pj, 0);
  if (auth && code) return joined(auth, code);
  int *confidence = NULL;
  PJ_OBJ_LIST *list = proj_identify(p->ctx, c->pj, "EPSG", NULL, &confidence);
  char *name = NULL;
  int best = -1, n = list ? proj_list_get_count(list) : 0;
  for (int i = 0; i < n; i++)
    if (confidence[i] >= 70 && (best < 0 || confidence[i] > confidence[best])) best = i;
  if (best >= 0) {
    PJ *match = proj_list_get(p->ctx, list, best);
    auth = match ? proj_get_id_auth_name(match, 0) : NULL;
    code = match ? proj_get_id_code(match, 0) : NULL;
    if (auth && code) name = joined(auth, code);
    proj_destroy(match);
  }
  proj_int_list_destroy(confidence);
  proj_list_destroy(list);
  if (name) return name;
  const char *options[] = {"MULTILINE=NO", NULL};
  const char *text = proj_as_proj_string(p->ctx, c->pj, PJ_PROJ_5, NULL);
  if (!text) text = proj_as_wkt(p->ctx, c->pj, PJ_WKT2_2019, options);
  if (!text) return NULL;
  size_t len = strlen(text) + 1;
  if ((name = malloc(len))) memcpy(name, text, len);
  return name;
}

int gis_transform_create(gis_proj *p, const gis_crs *from, const gis_crs *to, gis_transform **out,
                         char *err, size_t errlen) {
  *out = NULL;
  p->said[0] = '\0';
  PJ *raw = proj_create_crs_to_crs_from_pj(p->ctx, from->pj, to->pj, NULL, NULL);
  PJ *pj = raw ? proj_normalize_for_visualization(p->ctx, raw) : NULL;
  proj_destroy(raw);
  if (!pj)
    return server_fail(err, errlen, SERVER_EINPUT, "PROJ has no transformation between them (%s)",
                       proj_reason(p));
  gis_transform *t = malloc(sizeof *t);
  if (!t) {
    proj_destroy(pj);
    return server_fail(err, errlen, SERVER_ENOMEM, "out of memory");
  }
  *t = (gis_transform){.proj = p, .pj = pj};
  *out = t;
  return SERVER_OK;
}

void gis_transform_free(gis_transform *t) {
  if (!t) return;
  proj_destroy(t->pj);
  free(t);
}

int gis_transform_points(const gis_transform *t, double (*xy)[2], size_t n, size_t *bad, char *err,
                         size_t errlen) {
  *bad = 0;
  if (n == 0) return SERVER_OK;
  proj_errno_reset(t->pj);
  t->proj->said[0] = '\0';
  size_t stride = sizeof xy[0];
  proj_trans_generic(t->pj, PJ_FWD, &xy[0][0], stride, n, &xy[0][1], stride, n, NULL, 0, 0, NULL, 0,
                     0);
  for (size_t i = 0; i < n; i++)
    if (!isfinite(xy[i][0]) || !isfinite(xy[i][1]) || xy[i][0] == HUGE_VAL) {
      *bad = i;
      int e = proj_errno(t->pj);
      const char *m = t->proj->said[0] ? t->proj->said
                      : e              ? proj_context_errno_string(t->proj->ctx, e)
                                       : NULL;
      return server_fail(err, errlen, SERVER_EINPUT, "PROJ cannot transform it (%s)",
                         m && m[0] ? m : "no finite result");
    }
  return SERVER_OK;
}

int gis_transform_bounds(const gis_transform *t, const double box[4], double out[4], char *err,
                         size_t errlen) {
  if (!proj_trans_bounds(t->proj->ctx, t->pj, PJ_FWD, box[0], box[1], box[2], box[3], &out[0],
                         &out[1], &out[2], &out[3], 21) ||
      !isfinite(out[0]) || !isfinite(out[1]) || !isfinite(out[2]) || !isfinite(out[3]))
    return server_fail(err, errlen, SERVER_EINPUT, "PROJ cannot transform it (%s)",
                       proj_reason(t->proj));
  return SERVER_OK;
}

double gis_geodesic_m(double lon1, double lat1, double lon2, double lat2) {
  struct geod_geodesic g;
  geod_init(&g, 6378137.0, 1.0 / 298.257223563);
  double s12 = 0;
  geod_inverse(&g, lat1, lon1, lat2, lon2, &s12, NULL, NULL);
  return s12;
}
