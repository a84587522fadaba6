#include "command_log.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server_error.h"
#include "sylva/status.h"
#include "sylva/scenario.h"
#include "sylva/world.h"

/* ---- writing ---------------------------------------------------------------------- */

static cJSON *vec3(const double v[3]) { return cJSON_CreateDoubleArray(v, 3); }

static cJSON *encode_obstacle(const edit_obstacle *o) {
  if (o->ring_count) { /* a prism: as a scenario writes it (format 4) */
    sylva_obstacle_def def = {o->id, {o->min[0], o->min[1], o->min[2]},
                              {o->max[0], o->max[1], o->max[2]}, o->kind,
                              {(const double(*)[2])o->points, o->point_count, o->ring_sizes, o->ring_count}};
    char *text = sylva_obstacle_json(&def, true);
    cJSON *obj = text ? cJSON_Parse(text) : NULL;
    free(text);
    return obj;
  }
  cJSON *obj = cJSON_CreateObject();
  if (obj && cJSON_AddStringToObject(obj, "id", o->id) &&
      cJSON_AddStringToObject(obj, "kind", o->kind == SYLVA_OBSTACLE_ZONE ? "zone" : "box") &&
      cJSON_AddItemToObject(obj, "min", vec3(o->min)) &&
      cJSON_AddItemToObject(obj, "max", vec3(o->max)))
    return obj;
  cJSON_Delete(obj);
  return NULL;
}

static cJSON *encode_plant(const edit_plant *p) {
  cJSON *obj = cJSON_CreateObject(), *roots = NULL;
  bool ok = obj && cJSON_AddStringToObject(obj, "id", p->id) &&
            cJSON_AddStringToObject(obj, "species", p->species) &&
            (roots = cJSON_AddArrayToObject(obj, "roots"));
  for (int i = 0; ok && i < p->root_count; i++) ok = cJSON_AddItemToArray(roots, vec3(p->roots[i]));
  if (ok && p->age) ok = cJSON_AddNumberToObject(obj, "age", p->age) != NULL;
  if (ok) return obj;
  cJSON_Delete(obj);
  return NULL;
}

char *command_log_encode(const edit *e) {
  /* the oldest format that holds the edit: stores without ages keep their bytes, and
   * older builds still read them */
  int format = 2;
  for (int i = 0; i < e->plant_count; i++)
    if (e->plants[i].age) format = 3;
  for (int i = 0; i < e->obstacle_count; i++)
    if (e->obstacles[i].ring_count) format = 4;
  cJSON *root = cJSON_CreateObject();
  cJSON *removals = NULL, *obstacles = NULL, *plants = NULL;
  bool ok = root && cJSON_AddNumberToObject(root, "format", format) &&
            cJSON_AddStringToObject(root, "command", "edit") &&
            (removals = cJSON_AddArrayToObject(root, "remove_obstacles")) &&
            (obstacles = cJSON_AddArrayToObject(root, "add_obstacles")) &&
            (plants = cJSON_AddArrayToObject(root, "add_plants"));
  for (int i = 0; ok && i < e->removal_count; i++)
    ok = cJSON_AddItemToArray(removals, cJSON_CreateString(e->removals[i]));
  for (int i = 0; ok && i < e->obstacle_count; i++)
    ok = cJSON_AddItemToArray(obstacles, encode_obstacle(&e->obstacles[i]));
  for (int i = 0; ok && i < e->plant_count; i++)
    ok = cJSON_AddItemToArray(plants, encode_plant(&e->plants[i]));
  if (ok && e->prune.set) {
    cJSON *prune = cJSON_AddObjectToObject(root, "prune");
    ok = prune && (e->prune.zone ? cJSON_AddStringToObject(prune, "zone", e->prune.zone) != NULL
                                 : cJSON_AddItemToObject(prune, "min", vec3(e->prune.min)) &&
                                       cJSON_AddItemToObject(prune, "max", vec3(e->prune.max)));
  }
  char *text = ok ? cJSON_PrintUnformatted(root) : NULL;
  cJSON_Delete(root);
  return text;
}

/* ---- reading ---------------------------------------------------------------------- */

/* Where a problem is: the JSON pointer of the value being read; the format read. */
typedef struct reader {
  char ptr[160];
  char *err;
  size_t errlen;
  int format;
} reader;

static int bad(reader *r, const char *fmt, ...) {
  char msg[256];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  snprintf(r->err, r->errlen, "%s: %s", r->ptr[0] ? r->ptr : "(root)", msg);
  return SERVER_EINPUT;
}

/* Points r at member `key` (or index i when key is NULL) below `base`. */
static void at(reader *r, const char *base, const char *key, int i) {
  char tmp[2 * sizeof r->ptr + 16];
  if (key) snprintf(tmp, sizeof tmp, "%s/%s", base, key);
  else snprintf(tmp, sizeof tmp, "%s/%d", base, i);
  snprintf(r->ptr, sizeof r->ptr, "%.*s", (int)sizeof r->ptr - 1, tmp);
}

/* Only keys of known[] (each once). */
static int check_keys(reader *r, const cJSON *obj, const char *const *known, size_t n) {
  char base[sizeof r->ptr];
  memcpy(base, r->ptr, sizeof base);
  for (const cJSON *m = obj->child; m; m = m->next) {
    size_t k = 0;
    while (k < n && strcmp(m->string, known[k]) != 0) k++;
    at(r, base, m->string, 0);
    if (k == n) return bad(r, "unknown key");
    for (const cJSON *o = obj->child; o != m; o = o->next)
      if (strcmp(o->string, m->string) == 0) return bad(r, "duplicate key");
  }
  memcpy(r->ptr, base, sizeof base);
  return SERVER_OK;
}

/* A label (1 to SYLVA_LABEL_MAX - 1 bytes), copied to *out. */
static int read_label(reader *r, const cJSON *item, char **out) {
  if (!cJSON_IsString(item)) return bad(r, "expected a string");
  size_t n = strlen(item->valuestring);
  if (n == 0 || n >= SYLVA_LABEL_MAX)
    return bad(r, "must be 1 to %d bytes long, got %zu", SYLVA_LABEL_MAX - 1, n);
  return (*out = strdup(item->valuestring)) ? SERVER_OK : SERVER_ENOMEM;
}

static int read_vec3(reader *r, const cJSON *item, double out[3]) {
  if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 3) return bad(r, "expected [x, y, z]");
  int i = 0;
  for (const cJSON *c = item->child; c; c = c->next, i++) {
    if (!cJSON_IsNumber(c) || !isfinite(c->valuedouble)) return bad(r, "expected [x, y, z]");
    out[i] = c->valuedouble;
  }
  return SERVER_OK;
}

/* An optional array member; *count its length (0 when absent). */
static int read_array(reader *r, const cJSON *root, const char *key, const cJSON **arr,
                      int *count) {
  *arr = cJSON_GetObjectItemCaseSensitive(root, key);
  *count = 0;
  if (!*arr) return SERVER_OK;
  at(r, "", key, 0);
  if (!cJSON_IsArray(*arr)) return bad(r, "expected an array");
  *count = cJSON_GetArraySize(*arr);
  return SERVER_OK;
}

/* A format-4 obstacle, a box or a prism, read as a scenario's are. */
static int read_obstacle_4(reader *r, const cJSON *item, edit_obstacle *o) {
  sylva_scenario_obstacle so;
  int rc = sylva_obstacle_read(item, r->ptr, &so, r->err, r->errlen);
  if (rc) return rc == SYLVA_ENOMEM ? SERVER_ENOMEM : SERVER_EINPUT;
  if (!(o->id = strdup(so.id))) {
    sylva_scenario_obstacle_clear(&so);
    return SERVER_ENOMEM;
  }
  memcpy(o->min, so.min, sizeof o->min);
  memcpy(o->max, so.max, sizeof o->max);
  o->kind = so.kind;
  o->points = so.points; /* the footprint, handed over */
  o->ring_sizes = so.ring_sizes;
  o->point_count = so.point_count;
  o->ring_count = so.ring_count;
  return SERVER_OK;
}

static int read_obstacle(reader *r, const cJSON *item, edit_obstacle *o) {
  static const char *const keys[] = {"id", "kind", "min", "max"};
  char base[sizeof r->ptr];
  memcpy(base, r->ptr, sizeof base);
  if (!cJSON_IsObject(item)) return bad(r, "expected an object");
  if (r->format >= 4) return read_obstacle_4(r, item, o);
  int rc = check_keys(r, item, keys, 4);
  const cJSON *kind = cJSON_GetObjectItemCaseSensitive(item, "kind");
  at(r, base, "kind", 0);
  bool zone = r->format >= 2 && cJSON_IsString(kind) && strcmp(kind->valuestring, "zone") == 0;
  if (!rc && !zone && !(cJSON_IsString(kind) && strcmp(kind->valuestring, "box") == 0))
    rc = bad(r, r->format >= 2 ? "expected \"box\" or \"zone\"" : "expected \"box\"");
  o->kind = zone ? SYLVA_OBSTACLE_ZONE : SYLVA_OBSTACLE_SOLID;
  at(r, base, "id", 0);
  if (!rc) rc = read_label(r, cJSON_GetObjectItemCaseSensitive(item, "id"), &o->id);
  at(r, base, "min", 0);
  if (!rc) rc = read_vec3(r, cJSON_GetObjectItemCaseSensitive(item, "min"), o->min);
  at(r, base, "max", 0);
  if (!rc) rc = read_vec3(r, cJSON_GetObjectItemCaseSensitive(item, "max"), o->max);
  return rc;
}

static int read_plant(reader *r, const cJSON *item, edit_plant *p) {
  static const char *const keys[] = {"id", "species", "roots", "age"};
  char base[sizeof r->ptr];
  memcpy(base, r->ptr, sizeof base);
  if (!cJSON_IsObject(item)) return bad(r, "expected an object");
  int rc = check_keys(r, item, keys, r->format >= 3 ? 4 : 3); /* age: format 3 on */
  const cJSON *age = cJSON_GetObjectItemCaseSensitive(item, "age");
  at(r, base, "age", 0);
  if (!rc && age) {
    double v = cJSON_IsNumber(age) ? age->valuedouble : -1;
    if (v != floor(v) || v < 0 || v > SYLVA_MAX_AGE)
      rc = bad(r, "expected an integer from 0 to %d", SYLVA_MAX_AGE);
    else
      p->age = (int)v;
  }
  at(r, base, "id", 0);
  if (!rc) rc = read_label(r, cJSON_GetObjectItemCaseSensitive(item, "id"), &p->id);
  at(r, base, "species", 0);
  if (!rc) rc = read_label(r, cJSON_GetObjectItemCaseSensitive(item, "species"), &p->species);
  const cJSON *roots = cJSON_GetObjectItemCaseSensitive(item, "roots");
  at(r, base, "roots", 0);
  if (!rc && (!cJSON_IsArray(roots) || cJSON_GetArraySize(roots) == 0))
    rc = bad(r, "expected a non-empty array of [x, y, z]");
  if (rc) return rc;
  int n = cJSON_GetArraySize(roots);
  if (!(p->roots = calloc((size_t)n, sizeof *p->roots))) return SERVER_ENOMEM;
  p->root_count = n;
  char list[sizeof r->ptr];
  memcpy(list, r->ptr, sizeof list);
  int i = 0;
  for (const cJSON *c = roots->child; c && !rc; c = c->next, i++) {
    at(r, list, NULL, i);
    rc = read_vec3(r, c, p->roots[i]);
  }
  return rc;
}

/* The prune of a format-2 edit: {"zone": ID} or {"min": [..], "max": [..]}. */
static int read_prune(reader *r, const cJSON *item, edit_prune *p) {
  static const char *const keys[] = {"zone", "min", "max"};
  r->ptr[0] = 0;
  at(r, "", "prune", 0);
  if (!cJSON_IsObject(item)) return bad(r, "expected an object");
  int rc = check_keys(r, item, keys, 3);
  if (rc) return rc;
  p->set = true;
  const cJSON *zone = cJSON_GetObjectItemCaseSensitive(item, "zone");
  if (zone) {
    at(r, "/prune", "zone", 0);
    if (cJSON_GetObjectItemCaseSensitive(item, "min") || cJSON_GetObjectItemCaseSensitive(item, "max"))
      return bad(r, "a zone or a box (min, max), not both");
    return read_label(r, zone, &p->zone);
  }
  at(r, "/prune", "min", 0);
  rc = read_vec3(r, cJSON_GetObjectItemCaseSensitive(item, "min"), p->min);
  at(r, "/prune", "max", 0);
  if (!rc) rc = read_vec3(r, cJSON_GetObjectItemCaseSensitive(item, "max"), p->max);
  return rc;
}

/* The three arrays of an edit, at the top level of the record, and its prune. */
static int read_edit(reader *r, const cJSON *root, edit *out) {
  const cJSON *removals = NULL, *obstacles = NULL, *plants = NULL;
  int nr = 0, no = 0, np = 0;
  int rc = read_array(r, root, "remove_obstacles", &removals, &nr);
  if (!rc) rc = read_array(r, root, "add_obstacles", &obstacles, &no);
  if (!rc) rc = read_array(r, root, "add_plants", &plants, &np);
  if (!rc && edit_reserve(out, nr, no, np)) rc = SERVER_ENOMEM;
  int i = 0;
  for (const cJSON *c = removals ? removals->child : NULL; c && !rc; c = c->next, i++) {
    at(r, "/remove_obstacles", NULL, i);
    rc = read_label(r, c, &out->removals[i]);
  }
  i = 0;
  for (const cJSON *c = obstacles ? obstacles->child : NULL; c && !rc; c = c->next, i++) {
    at(r, "/add_obstacles", NULL, i);
    rc = read_obstacle(r, c, &out->obstacles[i]);
  }
  i = 0;
  for (const cJSON *c = plants ? plants->child : NULL; c && !rc; c = c->next, i++) {
    at(r, "/add_plants", NULL, i);
    rc = read_plant(r, c, &out->plants[i]);
  }
  const cJSON *prune = cJSON_GetObjectItemCaseSensitive(root, "prune");
  if (!rc && prune) rc = read_prune(r, prune, &out->prune);
  return rc;
}

static int read_record(reader *r, const cJSON *root, edit *out) {
  static const char *const keys[] = {"format",        "command",    "remove_obstacles",
                                     "add_obstacles", "add_plants", "prune"};
  static const char *const keys0[] = {"type", "run", "id", "remove_obstacles", "add_obstacles",
                                      "add_plants"};
  if (!cJSON_IsObject(root)) return bad(r, "expected an object");
  const cJSON *format = cJSON_GetObjectItemCaseSensitive(root, "format");
  if (!format) { /* format 0: a protocol-1 edit message */
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(root, "type");
    at(r, "", "type", 0);
    if (!cJSON_IsString(type) || strcmp(type->valuestring, "edit") != 0)
      return bad(r, "expected \"edit\" (a record without \"format\" is a protocol-1 edit)");
    r->ptr[0] = 0;
    int rc = check_keys(r, root, keys0, 6);
    return rc ? rc : read_edit(r, root, out);
  }
  at(r, "", "format", 0);
  double v = cJSON_IsNumber(format) ? format->valuedouble : -1;
  if (v != floor(v) || v < 1) return bad(r, "expected an integer >= 1");
  if (v > COMMAND_LOG_FORMAT)
    return bad(r, "format %.0f is newer than this sylva reads (up to %d)", v, COMMAND_LOG_FORMAT);
  const cJSON *command = cJSON_GetObjectItemCaseSensitive(root, "command");
  at(r, "", "command", 0);
  if (!cJSON_IsString(command) || strcmp(command->valuestring, "edit") != 0)
    return bad(r, "expected \"edit\" (the only command of format %d)", COMMAND_LOG_FORMAT);
  r->ptr[0] = 0;
  r->format = (int)v;
  int rc = check_keys(r, root, keys, r->format >= 2 ? 6 : 5); /* prune: format 2 on */
  return rc ? rc : read_edit(r, root, out);
}

int command_log_decode(const char *json, edit *out, char *err, size_t errlen) {
  *out = (edit){0};
  reader r = {"", err, errlen, 0};
  cJSON *root = cJSON_Parse(json);
  if (!root) return bad(&r, "not JSON");
  int rc = read_record(&r, root, out);
  cJSON_Delete(root);
  if (rc == SERVER_ENOMEM) snprintf(err, errlen, "out of memory");
  return rc;
}
