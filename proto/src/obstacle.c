/* Obstacles as JSON (docs/scenario.md, "Obstacles"): boxes, prisms and zones of
 * either shape, read for scenarios and protocol edits and written for scenarios,
 * snapshots and the store's command log, in one place. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/scenario.h"
#include "encode_parts.h"
#include "scenario_parts.h"
#include "strbuf.h"

sylva_obstacle_def sylva_scenario_obstacle_def(const sylva_scenario_obstacle *o) {
  sylva_obstacle_def d = {.label = o->id, .kind = o->kind};
  memcpy(d.min, o->min, sizeof d.min);
  memcpy(d.max, o->max, sizeof d.max);
  if (o->ring_count)
    d.footprint = (sylva_footprint){(const double(*)[2])o->points, o->point_count, o->ring_sizes,
                                    o->ring_count};
  return d;
}

void sylva_scenario_obstacle_clear(sylva_scenario_obstacle *o) {
  free(o->points);
  free(o->ring_sizes);
  o->points = NULL;
  o->ring_sizes = NULL;
  o->point_count = o->ring_count = 0;
}

static const cJSON *member(const cJSON *obj, const char *key) {
  return cJSON_GetObjectItemCaseSensitive(obj, key);
}

/* ---- writing --------------------------------------------------------------------- */

static void put_pair(sylva__strbuf *b, double x, double y, const char *sep) {
  sylva__strbuf_putc(b, '[');
  sylva__strbuf_shortest(b, x);
  sylva__strbuf_puts(b, sep);
  sylva__strbuf_shortest(b, y);
  sylva__strbuf_putc(b, ']');
}

static void put_ring(sylva__strbuf *b, const double (*pt)[2], int n, const char *sep) {
  sylva__strbuf_putc(b, '[');
  for (int i = 0; i < n; i++) {
    if (i) sylva__strbuf_puts(b, sep);
    put_pair(b, pt[i][0], pt[i][1], sep);
  }
  sylva__strbuf_putc(b, ']');
}

void sylva__put_obstacle(sylva__strbuf *b, const sylva_obstacle_def *o, bool compact) {
  const char *sep = compact ? "," : ", ", *colon = compact ? ":" : ": ";
  const sylva_footprint *f = &o->footprint;
  sylva__strbuf_printf(b, "{\"id\"%s", colon);
  sylva__strbuf_json_string(b, o->label ? o->label : "");
  sylva__strbuf_printf(b, "%s\"kind\"%s\"%s\"", sep, colon,
                       o->kind == SYLVA_OBSTACLE_ZONE ? "zone" : f->ring_count ? "prism" : "box");
  if (!f->ring_count) {
    for (int k = 0; k < 2; k++) {
      const double *v = k ? o->max : o->min;
      sylva__strbuf_printf(b, "%s\"%s\"%s[", sep, k ? "max" : "min", colon);
      for (int a = 0; a < 3; a++) {
        if (a) sylva__strbuf_puts(b, sep);
        sylva__strbuf_shortest(b, v[a]);
      }
      sylva__strbuf_putc(b, ']');
    }
  } else {
    sylva__strbuf_printf(b, "%s\"polygon\"%s", sep, colon);
    put_ring(b, f->points, f->ring_sizes[0], sep);
    if (f->ring_count > 1) {
      sylva__strbuf_printf(b, "%s\"holes\"%s[", sep, colon);
      for (int r = 1, first = f->ring_sizes[0]; r < f->ring_count; first += f->ring_sizes[r++]) {
        if (r > 1) sylva__strbuf_puts(b, sep);
        put_ring(b, f->points + first, f->ring_sizes[r], sep);
      }
      sylva__strbuf_putc(b, ']');
    }
    sylva__strbuf_printf(b, "%s\"z\"%s", sep, colon);
    put_pair(b, o->min[2], o->max[2], sep);
  }
  sylva__strbuf_putc(b, '}');
}

char *sylva_obstacle_json(const sylva_obstacle_def *o, bool compact) {
  sylva__strbuf b = {0};
  sylva__put_obstacle(&b, o, compact);
  return sylva__strbuf_finish(&b);
}

/* ---- reading --------------------------------------------------------------------- */

/* Twice the signed area of a ring (shoelace). */
static double ring_area2(const double (*pt)[2], int n) {
  double a = 0.0;
  for (int i = 0; i < n; i++) a += pt[i][0] * pt[(i + 1) % n][1] - pt[(i + 1) % n][0] * pt[i][1];
  return a;
}

/* Reads a ring, an array of at least 3 [x, y] (a last point equal to the first, as
 * GeoJSON closes its rings, is dropped), appending it to o's footprint. */
static int read_ring(sylva__parser *p, const cJSON *ring, sylva_scenario_obstacle *o) {
  int n = cJSON_IsArray(ring) ? cJSON_GetArraySize(ring) : 0;
  if (!cJSON_IsArray(ring))
    return sylva__fail(p, "expected an array of [x, y], got %s", sylva__type_name(ring));
  if (n > SYLVA_FOOTPRINT_MAX_POINTS - o->point_count)
    return sylva__fail(p, "%d points; a footprint may have at most %d in all", o->point_count + n,
                       SYLVA_FOOTPRINT_MAX_POINTS);
  double(*pts)[2] = realloc(o->points, ((size_t)o->point_count + (size_t)n + 1) * sizeof *pts);
  if (!pts) return sylva__fail_nomem(p);
  o->points = pts;
  int *sizes = realloc(o->ring_sizes, ((size_t)o->ring_count + 1) * sizeof *sizes);
  if (!sizes) return sylva__fail_nomem(p);
  o->ring_sizes = sizes;
  double(*at)[2] = pts + o->point_count;
  int i = 0;
  for (const cJSON *pt = ring->child; pt; pt = pt->next, i++) {
    size_t old = sylva__ptr_push_index(p, (size_t)i);
    int rc = 0;
    if (!cJSON_IsArray(pt) || cJSON_GetArraySize(pt) != 2 || !cJSON_IsNumber(pt->child) ||
        !cJSON_IsNumber(pt->child->next))
      rc = sylva__fail(p, "expected [x, y], got %s", sylva__type_name(pt));
    else if (!isfinite(pt->child->valuedouble) || !isfinite(pt->child->next->valuedouble))
      rc = sylva__fail(p, "coordinates must be finite");
    sylva__ptr_pop(p, old);
    if (rc) return rc;
    at[i][0] = pt->child->valuedouble;
    at[i][1] = pt->child->next->valuedouble;
  }
  if (n > 3 && at[n - 1][0] == at[0][0] && at[n - 1][1] == at[0][1]) n--; /* closed */
  if (n < 3) return sylva__fail(p, "a ring needs at least 3 points, got %d", n);
  if (ring_area2((const double(*)[2])at, n) == 0.0) return sylva__fail(p, "the ring has no area");
  o->ring_sizes[o->ring_count++] = n;
  o->point_count += n;
  return 0;
}

/* A prism's "polygon", "holes" and "z" into o. */
static int read_prism(sylva__parser *p, const cJSON *obj, sylva_scenario_obstacle *o) {
  size_t old = sylva__ptr_push(p, "polygon");
  int rc = read_ring(p, member(obj, "polygon"), o);
  sylva__ptr_pop(p, old);
  const cJSON *holes = member(obj, "holes");
  if (!rc && holes) {
    old = sylva__ptr_push(p, "holes");
    if (!cJSON_IsArray(holes)) rc = sylva__fail(p, "expected an array of rings, got %s", sylva__type_name(holes));
    int i = 0;
    for (const cJSON *h = rc ? NULL : holes->child; h && !rc; h = h->next, i++) {
      size_t o2 = sylva__ptr_push_index(p, (size_t)i);
      rc = read_ring(p, h, o);
      sylva__ptr_pop(p, o2);
    }
    sylva__ptr_pop(p, old);
  }
  if (rc) return rc;
  old = sylva__ptr_push(p, "z");
  const cJSON *z = member(obj, "z");
  if (!cJSON_IsArray(z) || cJSON_GetArraySize(z) != 2 || !cJSON_IsNumber(z->child) ||
      !cJSON_IsNumber(z->child->next))
    rc = sylva__fail(p, "expected [from, to] in metres, got %s", sylva__type_name(z));
  else if (!isfinite(z->child->valuedouble) || !isfinite(z->child->next->valuedouble))
    rc = sylva__fail(p, "must be finite");
  else if (!(z->child->next->valuedouble > z->child->valuedouble)) {
    char a[SYLVA_FMT_BUFSIZE], b[SYLVA_FMT_BUFSIZE];
    rc = sylva__fail(p, "to must be greater than from (%s <= %s)",
                     sylva__num(a, z->child->next->valuedouble), sylva__num(b, z->child->valuedouble));
  }
  sylva__ptr_pop(p, old);
  if (rc) return rc;
  o->min[2] = z->child->valuedouble;
  o->max[2] = z->child->next->valuedouble;
  o->min[0] = o->min[1] = INFINITY;
  o->max[0] = o->max[1] = -INFINITY;
  for (int i = 0; i < o->point_count; i++)
    for (int a = 0; a < 2; a++) {
      o->min[a] = fmin(o->min[a], o->points[i][a]);
      o->max[a] = fmax(o->max[a], o->points[i][a]);
    }
  return 0;
}

int sylva__parse_obstacle(sylva__parser *p, const cJSON *obj, sylva_scenario_obstacle *o) {
  static const char *const keys[] = {"id", "kind", "min", "max", "polygon", "holes", "z"};
  int rc = sylva__want_object(p, obj);
  if (!rc) rc = sylva__check_keys(p, obj, keys, sizeof keys / sizeof keys[0]);
  if (rc) return rc;
  for (int i = 0; i < 2; i++)
    if (!member(obj, keys[i])) return sylva__fail_at_key(p, keys[i], "required");
  size_t old = sylva__ptr_push(p, "id");
  rc = sylva__want_label(p, member(obj, "id"), o->id);
  sylva__ptr_pop(p, old);
  if (rc) return rc;
  old = sylva__ptr_push(p, "kind");
  const char *kind = "";
  rc = sylva__want_string(p, member(obj, "kind"), &kind);
  o->kind = strcmp(kind, "zone") == 0 ? SYLVA_OBSTACLE_ZONE : SYLVA_OBSTACLE_SOLID;
  bool prism = strcmp(kind, "prism") == 0 || (o->kind == SYLVA_OBSTACLE_ZONE && member(obj, "polygon"));
  if (!rc && strcmp(kind, "box") != 0 && strcmp(kind, "zone") != 0 && strcmp(kind, "prism") != 0) {
    char q[80];
    rc = sylva__fail(p, "unknown obstacle kind %s (known: box, prism, zone)", sylva__quote(q, kind));
  }
  sylva__ptr_pop(p, old);
  if (rc) return rc;
  /* the keys of the shape: a box's min and max, a prism's polygon, holes and z */
  static const char *const box_keys[] = {"min", "max"}, *const prism_keys[] = {"polygon", "z"};
  const char *const *need = prism ? prism_keys : box_keys, *const *other = prism ? box_keys : prism_keys;
  for (int i = 0; i < 2; i++)
    if (!member(obj, need[i])) return sylva__fail_at_key(p, need[i], "required for a %s", prism ? "prism" : "box");
  for (int i = 0; i < 2; i++)
    if (member(obj, other[i]))
      return sylva__fail_at_key(p, other[i], "a %s has %s", prism ? "prism" : "box",
                                prism ? "polygon, holes and z, no min or max" : "min and max, no polygon or z");
  if (!prism && member(obj, "holes")) return sylva__fail_at_key(p, "holes", "a box has min and max, no holes");
  if (prism) return read_prism(p, obj, o);
  old = sylva__ptr_push(p, "min");
  rc = sylva__want_vec3(p, member(obj, "min"), o->min);
  sylva__ptr_pop(p, old);
  if (rc) return rc;
  old = sylva__ptr_push(p, "max");
  rc = sylva__want_vec3(p, member(obj, "max"), o->max);
  for (int i = 0; !rc && i < 3; i++)
    if (!(o->max[i] > o->min[i])) {
      char a[SYLVA_FMT_BUFSIZE], b[SYLVA_FMT_BUFSIZE];
      rc = sylva__fail(p, "must be greater than min on every axis (%c: %s <= %s)", "xyz"[i],
                       sylva__num(a, o->max[i]), sylva__num(b, o->min[i]));
    }
  sylva__ptr_pop(p, old);
  return rc;
}

int sylva_obstacle_read(const cJSON *obj, const char *at, sylva_scenario_obstacle *out,
                        char *err, size_t errlen) {
  memset(out, 0, sizeof *out);
  sylva__parser p = {.err = err, .errlen = errlen};
  size_t n = strlen(at);
  if (n >= sizeof p.ptr) n = sizeof p.ptr - 1;
  memcpy(p.ptr, at, n);
  p.plen = n;
  int rc = sylva__parse_obstacle(&p, obj, out);
  if (rc) sylva_scenario_obstacle_clear(out);
  return rc;
}
