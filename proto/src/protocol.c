/* The messages of `sylva.v1`: strict parsing of client messages (errors name the
 * JSON pointer of the offending value) and deterministic encoders of the server's. */
#include "sylva/protocol.h"

#include <cjson/cJSON.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "encode_parts.h"
#include "scenario_parts.h"
#include "strbuf.h"
#include "sylva/json_check.h"
#include "sylva/status.h"

/* Longest "id" a client may send, bytes of its JSON text; it is echoed in replies. */
#define REF_MAX 256

/* ---- message types and their keys ---- */

typedef struct msg_kind {
  const char *name;
  const char *const *keys; /* every key the type allows, "type" and "id" included */
  size_t key_count;
} msg_kind;

static const char *const bare_keys[] = {"type", "id"};

#define KEYS(...) (const char *const[]){"type", "id", __VA_ARGS__}
#define KIND(name, ...)                                                                       \
  { name, KEYS(__VA_ARGS__), sizeof KEYS(__VA_ARGS__) / sizeof(const char *) }

/* Indexed by sylva_msg_type. */
static const msg_kind kinds[] = {
    [SYLVA_MSG_HELLO] = KIND("hello", "token"),
    [SYLVA_MSG_LIST] = {"list", bare_keys, 2},
    [SYLVA_MSG_CREATE] = KIND("create", "scenario", "name", "start"),
    [SYLVA_MSG_SUBSCRIBE] = KIND("subscribe", "run", "since", "detail"),
    [SYLVA_MSG_UNSUBSCRIBE] = KIND("unsubscribe", "run"),
    [SYLVA_MSG_CONTROL] = KIND("control", "run", "action", "count"),
    [SYLVA_MSG_EDIT] = KIND("edit", "run", "add_plants", "add_obstacles", "remove_obstacles", "prune"),
    [SYLVA_MSG_FORK] = KIND("fork", "run", "iteration", "name"),
    [SYLVA_MSG_GET] = KIND("get", "run", "iteration"),
    [SYLVA_MSG_LIGHT] = KIND("light", "run", "z"),
    [SYLVA_MSG_SCENARIOS] = {"scenarios", bare_keys, 2},
};

#undef KIND
#undef KEYS

#define KIND_COUNT (sizeof kinds / sizeof kinds[0])

static const char *const type_list =
    "hello, list, create, subscribe, unsubscribe, control, edit, fork, get, light, scenarios";

const char *sylva_msg_type_name(sylva_msg_type type) {
  return (size_t)type < KIND_COUNT ? kinds[type].name : NULL;
}

static const char *const action_names[] = {
    [SYLVA_CONTROL_START] = "start",
    [SYLVA_CONTROL_PAUSE] = "pause",
    [SYLVA_CONTROL_STEP] = "step",
    [SYLVA_CONTROL_STOP] = "stop",
};

static const char *const detail_names[] = {
    [SYLVA_DETAIL_NODES] = "nodes",
    [SYLVA_DETAIL_STEMS] = "stems",
};

/* ---- field readers ---- */

static const cJSON *member(const cJSON *obj, const char *key) {
  return cJSON_GetObjectItemCaseSensitive(obj, key);
}

/* The client's "id" as compact JSON: a string or a finite number. */
static int read_ref(sylva__parser *p, const cJSON *item, char **out) {
  size_t old = sylva__ptr_push(p, "id");
  int rc = 0;
  sylva__strbuf b = {0};
  if (cJSON_IsString(item)) {
    sylva__strbuf_json_string(&b, item->valuestring);
  } else if (cJSON_IsNumber(item)) {
    double v = 0;
    rc = sylva__want_number(p, item, &v);
    if (!rc) sylva__strbuf_shortest(&b, v);
  } else {
    rc = sylva__fail(p, "expected a string or a number, got %s", sylva__type_name(item));
  }
  if (!rc && !b.failed && b.len > REF_MAX)
    rc = sylva__fail(p, "%zu bytes of JSON; at most %d are allowed", b.len, REF_MAX);
  if (rc) {
    sylva__strbuf_free(&b);
  } else if (!(*out = sylva__strbuf_finish(&b))) {
    rc = sylva__fail_nomem(p);
  }
  sylva__ptr_pop(p, old);
  return rc;
}

/* item, the value of key, as one of names (count of them, listed in `known` for the
 * error): its index in *out. */
static int read_choice(sylva__parser *p, const cJSON *item, const char *key,
                       const char *const *names, size_t count, const char *known, size_t *out) {
  size_t old = sylva__ptr_push(p, key);
  const char *s = "";
  int rc = sylva__want_string(p, item, &s);
  size_t k = 0;
  while (!rc && k < count && strcmp(s, names[k]) != 0) k++;
  if (!rc && k == count) {
    char q[80];
    rc = sylva__fail(p, "unknown %s %s (known: %s)", key, sylva__quote(q, s), known);
  }
  sylva__ptr_pop(p, old);
  if (!rc) *out = k;
  return rc;
}

/* The run id: an integer in [1, 2^53 - 1]. */
static int read_run(sylva__parser *p, const cJSON *obj, int64_t *out) {
  const cJSON *item = member(obj, "run");
  if (!item) return sylva__fail_at_key(p, "run", "required (the run id, an integer >= 1)");
  size_t old = sylva__ptr_push(p, "run");
  char a[SYLVA_FMT_BUFSIZE];
  int rc = 0;
  if (!cJSON_IsNumber(item))
    rc = sylva__fail(p, "expected an integer >= 1, got %s", sylva__type_name(item));
  else if (!isfinite(item->valuedouble))
    rc = sylva__fail(p, "expected an integer >= 1, got a number out of range");
  else if (item->valuedouble != floor(item->valuedouble) || item->valuedouble < 1)
    rc = sylva__fail(p, "expected an integer >= 1, got %s", sylva__num(a, item->valuedouble));
  else if (item->valuedouble > SYLVA_MSG_ID_MAX)
    rc = sylva__fail(p, "expected an integer >= 1 and <= 9007199254740991 (2^53 - 1), got %s",
                     sylva__num(a, item->valuedouble));
  else
    *out = (int64_t)item->valuedouble;
  sylva__ptr_pop(p, old);
  return rc;
}

/* A run name: 1 to SYLVA_MSG_NAME_MAX bytes without control characters (C0, DEL, C1). */
static int read_name(sylva__parser *p, const cJSON *item, char **out) {
  size_t old = sylva__ptr_push(p, "name");
  const char *s = "";
  int rc = sylva__want_string(p, item, &s);
  size_t n = rc ? 0 : strlen(s);
  if (!rc && (n == 0 || n > SYLVA_MSG_NAME_MAX))
    rc = sylva__fail(p, "must be 1 to %d bytes long, got %zu", SYLVA_MSG_NAME_MAX, n);
  for (size_t i = 0; !rc && i < n; i++) {
    unsigned char c = (unsigned char)s[i];
    bool c1 = c == 0xC2 && i + 1 < n && (unsigned char)s[i + 1] >= 0x80 &&
              (unsigned char)s[i + 1] <= 0x9F;
    if (c < 0x20 || c == 0x7F || c1)
      rc = sylva__fail(p, "must not contain control characters (byte %zu)", i);
  }
  if (!rc && !(*out = strdup(s))) rc = sylva__fail_nomem(p);
  sylva__ptr_pop(p, old);
  return rc;
}

/* An optional array member of at most SYLVA_MSG_MAX_EDIT elements. */
static int read_edit_array(sylva__parser *p, const cJSON *obj, const char *key,
                           const cJSON **arr, int *count) {
  *arr = member(obj, key);
  *count = 0;
  if (!*arr) return 0;
  if (!cJSON_IsArray(*arr))
    return sylva__fail_at_key(p, key, "expected an array, got %s", sylva__type_name(*arr));
  *count = cJSON_GetArraySize(*arr);
  if (*count > SYLVA_MSG_MAX_EDIT)
    return sylva__fail_at_key(p, key, "%d elements; at most %d are allowed per edit", *count,
                              SYLVA_MSG_MAX_EDIT);
  return 0;
}

/* Names the first repeated id of refs (count > 1): "/<key>/<i><tail>: duplicate ...". */
static int check_unique(sylva__parser *p, const char *key, const char *what, const char *tail,
                        sylva__id_ref *refs, int count) {
  int first = 0, second = 0;
  if (!sylva__find_duplicate(refs, count, &first, &second)) return 0;
  const char *id = "";
  for (int k = 0; k < count; k++)
    if (refs[k].index == second) id = refs[k].id;
  char q[80];
  size_t old = sylva__ptr_push(p, key);
  sylva__ptr_push_index(p, (size_t)second);
  if (*tail) sylva__ptr_push(p, tail);
  int rc = sylva__fail(p, "duplicate %s %s (also /%s/%d%s%s)", what, sylva__quote(q, id), key,
                       first, *tail ? "/" : "", tail);
  sylva__ptr_pop(p, old);
  return rc;
}

/* "prune": {"zone": ID} or {"min": [x, y, z], "max": [x, y, z]}. */
static int parse_prune(sylva__parser *p, const cJSON *item, sylva_msg *m) {
  static const char *const keys[] = {"zone", "min", "max"};
  size_t old = sylva__ptr_push(p, "prune");
  int rc = sylva__want_object(p, item);
  if (!rc) rc = sylva__check_keys(p, item, keys, 3);
  const cJSON *zone = rc ? NULL : member(item, "zone");
  m->prune = true;
  if (!rc && zone) {
    if (member(item, "min") || member(item, "max"))
      rc = sylva__fail(p, "a zone or a box (min and max), not both");
    size_t o2 = sylva__ptr_push(p, "zone");
    if (!rc) rc = sylva__want_label(p, zone, m->prune_zone);
    sylva__ptr_pop(p, o2);
  } else if (!rc) {
    if (!member(item, "min") || !member(item, "max"))
      rc = sylva__fail(p, "expected {\"zone\": ID} or {\"min\": [x, y, z], \"max\": [x, y, z]}");
    size_t o2 = sylva__ptr_push(p, "min");
    if (!rc) rc = sylva__want_vec3(p, member(item, "min"), m->prune_min);
    sylva__ptr_pop(p, o2);
    o2 = sylva__ptr_push(p, "max");
    if (!rc) rc = sylva__want_vec3(p, member(item, "max"), m->prune_max);
    for (int a = 0; !rc && a < 3; a++)
      if (m->prune_max[a] < m->prune_min[a])
        rc = sylva__fail(p, "must not be below min (%c)", "xyz"[a]);
    sylva__ptr_pop(p, o2);
  }
  sylva__ptr_pop(p, old);
  return rc;
}

static int parse_edit(sylva__parser *p, const cJSON *root, sylva_msg *m) {
  const cJSON *plants, *obstacles, *removals;
  int plant_count, obstacle_count, removal_count;
  int rc = read_edit_array(p, root, "add_plants", &plants, &plant_count);
  if (!rc) rc = read_edit_array(p, root, "add_obstacles", &obstacles, &obstacle_count);
  if (!rc) rc = read_edit_array(p, root, "remove_obstacles", &removals, &removal_count);
  const cJSON *prune = member(root, "prune");
  if (!rc && prune) rc = parse_prune(p, prune, m);
  if (rc) return rc;
  int most = plant_count > obstacle_count ? plant_count : obstacle_count;
  if (removal_count > most) most = removal_count;
  sylva__id_ref *refs = malloc(((size_t)most + 1) * sizeof *refs);
  if (!refs) return sylva__fail_nomem(p);

  if (plant_count) {
    m->add_plants = calloc((size_t)plant_count, sizeof *m->add_plants);
    m->add_plant_species = calloc((size_t)plant_count, sizeof *m->add_plant_species);
    if (!m->add_plants || !m->add_plant_species) rc = sylva__fail_nomem(p);
    size_t old = sylva__ptr_push(p, "add_plants");
    int i = 0, stems = 0;
    for (const cJSON *e = rc ? NULL : plants->child; e && !rc; e = e->next, i++) {
      size_t o2 = sylva__ptr_push_index(p, (size_t)i);
      m->add_plant_count = i + 1; /* so that a partial plant is freed */
      const char *species = NULL;
      rc = sylva__parse_plant(p, e, NULL, 0, &stems, &m->add_plants[i], &species);
      if (!rc && !(m->add_plant_species[i] = strdup(species))) rc = sylva__fail_nomem(p);
      refs[i] = (sylva__id_ref){m->add_plants[i].id, i};
      sylva__ptr_pop(p, o2);
    }
    sylva__ptr_pop(p, old);
    if (!rc) rc = check_unique(p, "add_plants", "plant id", "id", refs, plant_count);
  }

  if (!rc && obstacle_count) {
    m->add_obstacles = calloc((size_t)obstacle_count, sizeof *m->add_obstacles);
    if (!m->add_obstacles) rc = sylva__fail_nomem(p);
    size_t old = sylva__ptr_push(p, "add_obstacles");
    int i = 0;
    for (const cJSON *e = rc ? NULL : obstacles->child; e && !rc; e = e->next, i++) {
      size_t o2 = sylva__ptr_push_index(p, (size_t)i);
      rc = sylva__parse_obstacle(p, e, &m->add_obstacles[i]);
      m->add_obstacle_count = i + 1;
      refs[i] = (sylva__id_ref){m->add_obstacles[i].id, i};
      sylva__ptr_pop(p, o2);
    }
    sylva__ptr_pop(p, old);
    if (!rc) rc = check_unique(p, "add_obstacles", "obstacle id", "id", refs, obstacle_count);
  }

  if (!rc && removal_count) {
    m->remove_obstacles = calloc((size_t)removal_count, sizeof *m->remove_obstacles);
    if (!m->remove_obstacles) rc = sylva__fail_nomem(p);
    size_t old = sylva__ptr_push(p, "remove_obstacles");
    int i = 0;
    for (const cJSON *e = rc ? NULL : removals->child; e && !rc; e = e->next, i++) {
      size_t o2 = sylva__ptr_push_index(p, (size_t)i);
      char label[SYLVA_LABEL_MAX];
      rc = sylva__want_label(p, e, label);
      if (!rc && !(m->remove_obstacles[i] = strdup(label))) rc = sylva__fail_nomem(p);
      m->remove_obstacle_count = i + 1;
      if (!rc) refs[i] = (sylva__id_ref){m->remove_obstacles[i], i};
      sylva__ptr_pop(p, o2);
    }
    sylva__ptr_pop(p, old);
    if (!rc) rc = check_unique(p, "remove_obstacles", "obstacle id", "", refs, removal_count);
  }
  free(refs);
  return rc;
}

static int parse_fields(sylva__parser *p, const cJSON *root, sylva_msg *m) {
  const cJSON *item;
  double v = 0;
  bool present = false;
  int rc = 0;
  switch (m->type) {
  case SYLVA_MSG_HELLO:
    if ((item = member(root, "token"))) {
      size_t old = sylva__ptr_push(p, "token");
      const char *s = "";
      rc = sylva__want_string(p, item, &s);
      if (!rc && !(m->token = strdup(s))) rc = sylva__fail_nomem(p);
      sylva__ptr_pop(p, old);
    }
    return rc;
  case SYLVA_MSG_LIST:
  case SYLVA_MSG_SCENARIOS:
    return 0;
  case SYLVA_MSG_CREATE: {
    if (!(item = member(root, "scenario")))
      return sylva__fail_at_key(p, "scenario",
                                "required (a scenario object, as in a scenario file)");
    size_t old = sylva__ptr_push(p, "scenario");
    rc = sylva__want_object(p, item);
    if (!rc) {
      p->base = p->plen;
      /* no SYLVA_SCENARIO_NEED_PLANTS: a site without plants is planted by edits */
      rc = sylva__scenario_from_json(p, item, 0, &m->scenario);
      p->base = 0;
    }
    sylva__ptr_pop(p, old);
    if (rc == SYLVA_ETOOBIG) rc = SYLVA_EINVAL;
    if (!rc && (item = member(root, "name"))) rc = read_name(p, item, &m->name);
    if (!rc && (item = member(root, "start"))) {
      if (cJSON_IsBool(item)) m->start = cJSON_IsTrue(item);
      else
        rc = sylva__fail_at_key(p, "start", "expected a boolean, got %s", sylva__type_name(item));
    }
    return rc;
  }
  case SYLVA_MSG_SUBSCRIBE:
    rc = read_run(p, root, &m->run);
    if (!rc) rc = sylva__read_integer(p, root, "since", 0, SYLVA_MSG_ID_MAX, &present, &v);
    if (!rc && present) {
      m->has_since = true;
      m->since = (int64_t)v;
    }
    if (!rc && (item = member(root, "detail"))) {
      size_t k = 0;
      rc = read_choice(p, item, "detail", detail_names, SYLVA_DETAIL_COUNT, "nodes, stems", &k);
      if (!rc) m->detail = (sylva_detail)k;
    }
    return rc;
  case SYLVA_MSG_UNSUBSCRIBE:
    return read_run(p, root, &m->run);
  case SYLVA_MSG_CONTROL: {
    rc = read_run(p, root, &m->run);
    if (rc) return rc;
    if (!(item = member(root, "action")))
      return sylva__fail_at_key(p, "action",
                                "required: \"start\", \"pause\", \"step\" or \"stop\"");
    size_t k = 0;
    rc = read_choice(p, item, "action", action_names, sizeof action_names / sizeof action_names[0],
                     "start, pause, step, stop", &k);
    if (rc) return rc;
    m->action = (sylva_control_action)k;
    m->count = 1;
    if (member(root, "count") && m->action != SYLVA_CONTROL_STEP)
      return sylva__fail_at_key(p, "count", "only allowed with \"action\": \"step\"");
    rc = sylva__read_integer(p, root, "count", 1, SYLVA_MSG_MAX_STEP, &present, &v);
    if (!rc && present) m->count = (int)v;
    return rc;
  }
  case SYLVA_MSG_EDIT:
    rc = read_run(p, root, &m->run);
    return rc ? rc : parse_edit(p, root, m);
  case SYLVA_MSG_FORK:
    rc = read_run(p, root, &m->run);
    if (!rc) rc = sylva__read_integer(p, root, "iteration", 0, INT_MAX, NULL, &v);
    if (!rc) m->iteration = (int)v;
    if (!rc) {
      if ((item = member(root, "name"))) rc = read_name(p, item, &m->name);
      else rc = sylva__fail_at_key(p, "name", "required (the new run's name)");
    }
    return rc;
  case SYLVA_MSG_GET:
    rc = read_run(p, root, &m->run);
    if (!rc) rc = sylva__read_integer(p, root, "iteration", 0, INT_MAX, NULL, &v);
    if (!rc) m->iteration = (int)v;
    return rc;
  case SYLVA_MSG_LIGHT: {
    rc = read_run(p, root, &m->run);
    if (rc) return rc;
    if (!(item = member(root, "z"))) return sylva__fail_at_key(p, "z", "required (height, metres)");
    size_t old = sylva__ptr_push(p, "z");
    rc = sylva__want_number(p, item, &m->z);
    sylva__ptr_pop(p, old);
    return rc;
  }
  }
  return sylva__fail(p, "internal error: unhandled message type");
}

static int parse_root(sylva__parser *p, const cJSON *root, sylva_msg *m) {
  int rc = sylva__want_object(p, root);
  if (rc) return rc;
  const cJSON *item = member(root, "id");
  /* The id first, so that an error about anything else can still be matched. */
  if (item && (rc = read_ref(p, item, &m->ref))) return rc;
  if (!(item = member(root, "type")))
    return sylva__fail_at_key(p, "type", "required (one of %s)", type_list);
  size_t old = sylva__ptr_push(p, "type");
  const char *name = "";
  rc = sylva__want_string(p, item, &name);
  size_t k = 0;
  while (!rc && k < KIND_COUNT && strcmp(kinds[k].name, name) != 0) k++;
  if (!rc && k == KIND_COUNT) {
    char q[80];
    rc = sylva__fail(p, "unknown message type %s (known: %s)", sylva__quote(q, name), type_list);
  }
  sylva__ptr_pop(p, old);
  if (rc) return rc;
  m->type = (sylva_msg_type)k;
  if ((rc = sylva__check_keys(p, root, kinds[k].keys, kinds[k].key_count))) return rc;
  return parse_fields(p, root, m);
}

int sylva_msg_parse(const char *text, size_t len, sylva_msg *out, char *err, size_t errlen) {
  memset(out, 0, sizeof *out);
  if (err && errlen) err[0] = '\0';
  char syntax[400];
  if (sylva_json_check_ex(text, len, SYLVA_MSG_MAX_DEPTH,
                          SYLVA_JSON_NO_NUL_ESCAPE | SYLVA_JSON_CJSON_NUMBERS, syntax,
                          sizeof syntax) != 0) {
    if (err && errlen) snprintf(err, errlen, "(syntax) %s", syntax);
    return SYLVA_EINVAL;
  }
  cJSON *root = cJSON_ParseWithLength(text, len);
  if (!root) {
    /* The text passed the strict check (numbers short enough for cJSON), so this
     * is memory. */
    if (err && errlen) snprintf(err, errlen, "out of memory while parsing the message");
    return SYLVA_ENOMEM;
  }
  sylva__parser p = {.ptr = "", .plen = 0, .base = 0, .err = err, .errlen = errlen};
  int rc = parse_root(&p, root, out);
  cJSON_Delete(root);
  if (rc) {
    char *ref = out->ref;
    out->ref = NULL;
    sylva_msg_free(out);
    out->ref = ref;
    if (rc != SYLVA_ENOMEM) rc = SYLVA_EINVAL;
  }
  return rc;
}

void sylva_msg_free(sylva_msg *m) {
  if (!m) return;
  free(m->ref);
  free(m->token);
  free(m->name);
  sylva_scenario_free(m->scenario);
  for (int i = 0; m->add_plants && i < m->add_plant_count; i++) free(m->add_plants[i].roots);
  for (int i = 0; m->add_plant_species && i < m->add_plant_count; i++)
    free(m->add_plant_species[i]);
  free(m->add_plants);
  free(m->add_plant_species);
  for (int i = 0; m->add_obstacles && i < m->add_obstacle_count; i++)
    sylva_scenario_obstacle_clear(&m->add_obstacles[i]);
  free(m->add_obstacles);
  for (int i = 0; m->remove_obstacles && i < m->remove_obstacle_count; i++)
    free(m->remove_obstacles[i]);
  free(m->remove_obstacles);
  memset(m, 0, sizeof *m);
}

/* ---- encoders ---- */

static void put_ref_and_close(sylva__strbuf *b, const char *ref) {
  if (ref) {
    sylva__strbuf_puts(b, ",\"ref\":");
    sylva__strbuf_puts(b, ref);
  }
  sylva__strbuf_putc(b, '}');
}

static void put_string(sylva__strbuf *b, const char *s) {
  sylva__strbuf_json_string(b, s ? s : "");
}

char *sylva_msg_welcome(const char *server_version, sylva_auth auth, const char *ref) {
  sylva__strbuf b = {0};
  sylva__strbuf_printf(
      &b, "{\"type\":\"welcome\",\"protocol\":%d,\"server\":{\"name\":\"sylva\",\"version\":",
      SYLVA_PROTOCOL_VERSION);
  put_string(&b, server_version);
  sylva__strbuf_printf(&b, "},\"auth\":%s,\"public_read\":%s",
                       auth != SYLVA_AUTH_NONE ? "true" : "false",
                       auth != SYLVA_AUTH_ALL ? "true" : "false");
  put_ref_and_close(&b, ref);
  return sylva__strbuf_finish(&b);
}

char *sylva_msg_error(const char *code, const char *message, const char *ref) {
  sylva__strbuf b = {0};
  sylva__strbuf_puts(&b, "{\"type\":\"error\",\"code\":");
  put_string(&b, code);
  sylva__strbuf_puts(&b, ",\"message\":");
  put_string(&b, message);
  put_ref_and_close(&b, ref);
  return sylva__strbuf_finish(&b);
}

char *sylva_msg_created(int64_t run, const char *name, const char *ref) {
  sylva__strbuf b = {0};
  sylva__strbuf_printf(&b, "{\"type\":\"created\",\"run\":%" PRId64 ",\"name\":", run);
  put_string(&b, name);
  put_ref_and_close(&b, ref);
  return sylva__strbuf_finish(&b);
}

/* ,"start_year":Y for a run whose scenario gives one. */
static void put_start_year(sylva__strbuf *b, int start_year) {
  if (start_year) sylva__strbuf_printf(b, ",\"start_year\":%d", start_year);
}

char *sylva_msg_status(int64_t run, sylva_run_status status, int iteration, int start_year,
                       const char *ref) {
  sylva__strbuf b = {0};
  sylva__strbuf_printf(&b, "{\"type\":\"status\",\"run\":%" PRId64 ",\"status\":", run);
  put_string(&b, sylva_run_status_name(status));
  sylva__strbuf_printf(&b, ",\"iteration\":%d", iteration);
  put_start_year(&b, start_year);
  put_ref_and_close(&b, ref);
  return sylva__strbuf_finish(&b);
}

/* ,"axes":{...} from the store's text of a run's axes. The text is parsed and each
 * string member written again, so that whatever the store holds, the message stays
 * valid JSON of the documented shape (a member that is not a string is left out). */
static void put_axes(sylva__strbuf *b, const char *axes) {
  cJSON *j = axes ? cJSON_Parse(axes) : NULL;
  if (cJSON_IsObject(j)) {
    sylva__strbuf_puts(b, ",\"axes\":{");
    bool first = true;
    for (const cJSON *m = j->child; m; m = m->next) {
      if (!cJSON_IsString(m) || !m->string) continue;
      if (!first) sylva__strbuf_putc(b, ',');
      first = false;
      put_string(b, m->string);
      sylva__strbuf_putc(b, ':');
      put_string(b, m->valuestring);
    }
    sylva__strbuf_putc(b, '}');
  }
  cJSON_Delete(j);
}

static void put_runs(sylva__strbuf *b, const sylva_run_summary *runs, size_t n) {
  sylva__strbuf_putc(b, '[');
  for (size_t i = 0; i < n; i++) {
    const sylva_run_summary *r = &runs[i];
    sylva__strbuf_printf(b, "%s{\"run\":%" PRId64 ",\"name\":", i ? "," : "", r->run);
    put_string(b, r->name);
    sylva__strbuf_puts(b, ",\"status\":");
    put_string(b, sylva_run_status_name(r->status));
    sylva__strbuf_printf(b, ",\"iteration\":%d,\"stems\":%d,\"nodes\":%" PRId64 "%s",
                         r->iteration, r->stems, r->nodes, r->loading ? ",\"loading\":true" : "");
    if (r->sweep) {
      sylva__strbuf_puts(b, ",\"sweep\":");
      put_string(b, r->sweep);
      sylva__strbuf_printf(b, ",\"position\":%d", r->position);
      put_axes(b, r->axes);
    }
    sylva__strbuf_putc(b, '}');
  }
  sylva__strbuf_putc(b, ']');
}

char *sylva_msg_runs(const sylva_run_summary *runs, size_t n, const char *ref) {
  sylva__strbuf b = {0};
  sylva__strbuf_puts(&b, "{\"type\":\"runs\",\"runs\":");
  put_runs(&b, runs, n);
  put_ref_and_close(&b, ref);
  return sylva__strbuf_finish(&b);
}

char *sylva_runs_json(const sylva_run_summary *runs, size_t n) {
  sylva__strbuf b = {0};
  put_runs(&b, runs, n);
  return sylva__strbuf_finish(&b);
}

/* ,"foliage":[{"species":..,"leaf_size":..,"leaf_density":..,"leaf_colour":"#rrggbb"},..],
 * "plant_species":[k,..]: what the viewer draws each species' leaves with, in the
 * world's species order, and each plant's species (an index into it). */
static void put_foliage(sylva__strbuf *b, const sylva_world *w) {
  sylva__strbuf_puts(b, ",\"foliage\":[");
  int species = sylva_world_species_count(w);
  for (int k = 0; k < species; k++) {
    const sylva_species_def *d = sylva_world_species(w, k);
    sylva__strbuf_puts(b, k ? ",{\"species\":" : "{\"species\":");
    put_string(b, sylva_world_species_label(w, k));
    sylva__strbuf_puts(b, ",\"leaf_size\":");
    sylva__strbuf_shortest(b, d->leaf_size);
    sylva__strbuf_printf(b, ",\"leaf_density\":%d,\"leaf_colour\":\"#%06x\"}", d->leaf_density,
                         (unsigned)d->leaf_colour & 0xffffffu);
  }
  sylva__strbuf_puts(b, "],\"plant_species\":[");
  int plants = sylva_world_plant_count(w);
  for (int p = 0; p < plants; p++)
    sylva__strbuf_printf(b, "%s%d", p ? "," : "", sylva_world_plant_species(w, p));
  sylva__strbuf_putc(b, ']');
}

/* ,"leaves":[[id,n],..]: every node bearing leaves now (sylva_node_info.leaves), in
 * id order. */
static void put_node_leaves(sylva__strbuf *b, const sylva_world *w) {
  sylva__strbuf_puts(b, ",\"leaves\":[");
  size_t count = sylva_world_node_count(w);
  bool first = true;
  for (size_t i = 0; i < count; i++) {
    sylva_node_info n;
    if (sylva_world_node_at(w, i, &n) != 0 || n.leaves <= 0) continue;
    sylva__strbuf_printf(b, "%s[%" PRId32 ",%" PRId32 "]", first ? "" : ",", n.id, n.leaves);
    first = false;
  }
  sylva__strbuf_putc(b, ']');
}

/* The stand's figures after canopy_cover where the run's lines give them (docs/model.md,
 * "Stands"). */
static void put_stand(sylva__strbuf *b, const sylva__stats_form *form, const sylva_stand_stats *s) {
  if (!form->stand) return;
  sylva__strbuf_puts(b, ",\"stand\":");
  sylva__put_stand(b, s, true);
}

/* ,"detail":"stems" of the messages of a stems subscriber (nothing for nodes). */
static void put_detail(sylva__strbuf *b, sylva_detail detail) {
  if (detail == SYLVA_DETAIL_STEMS) sylva__strbuf_puts(b, ",\"detail\":\"stems\"");
}

char *sylva_msg_snapshot(int64_t run, int64_t seq, const sylva_world *w, int start_year,
                         const char *ref) {
  return sylva_msg_snapshot_detail(run, seq, w, start_year, SYLVA_DETAIL_NODES, ref);
}

char *sylva_msg_snapshot_detail(int64_t run, int64_t seq, const sylva_world *w, int start_year,
                                sylva_detail detail, const char *ref) {
  sylva__strbuf b = {0};
  sylva__stats_form form = sylva__stats_form_of(w, start_year);
  bool nodes = detail != SYLVA_DETAIL_STEMS;
  sylva__strbuf_printf(&b, "{\"type\":\"snapshot\",\"run\":%" PRId64 ",\"seq\":%" PRId64
                           ",\"iteration\":%d",
                       run, seq, sylva_world_iteration(w));
  put_detail(&b, detail);
  sylva__strbuf_putc(&b, ',');
  sylva__put_world_body(&b, w, nodes);
  sylva__strbuf_puts(&b, ",\"stats\":[");
  int stems = sylva_world_stem_count(w);
  for (int s = 0; s < stems; s++) {
    sylva_stem_stats st;
    sylva_world_stem_stats(w, s, &st);
    if (s) sylva__strbuf_putc(&b, ',');
    sylva__put_stem_stats(&b, w, &st, &form, true);
  }
  sylva__strbuf_puts(&b, "],\"species\":[");
  int species = sylva_world_species_count(w);
  for (int k = 0; k < species; k++) {
    if (k) sylva__strbuf_putc(&b, ',');
    put_string(&b, sylva_world_species_label(w, k));
  }
  /* the sky that lights the run (scenario.md, "Light") */
  sylva__strbuf_puts(&b, sylva_world_get_def(w)->sky_count ? "],\"sky\":\"site\"" : "],\"sky\":\"zenith\"");
  put_start_year(&b, start_year);
  put_foliage(&b, w);
  if (nodes) put_node_leaves(&b, w);
  sylva__strbuf_puts(&b, ",\"canopy_cover\":"); /* docs/model.md, "Canopy cover" */
  sylva__strbuf_fixed(&b, sylva_world_canopy_cover(w), 4);
  sylva_stand_stats stand;
  sylva_world_stand(w, &stand);
  put_stand(&b, &form, &stand);
  put_ref_and_close(&b, ref);
  return sylva__strbuf_finish(&b);
}

/* "stats":[..],"canopy_cover":..,"stand":..} of a delta, at either detail. */
static void put_delta_stats(sylva__strbuf *b, const sylva_world *w, const sylva_journal *j,
                            int start_year) {
  sylva__stats_form form = sylva__stats_form_of(w, start_year);
  sylva__strbuf_puts(b, "\"stats\":[");
  for (size_t i = 0; i < j->stem_count; i++) {
    if (i) sylva__strbuf_putc(b, ',');
    sylva__put_stem_stats(b, w, &j->stats[i], &form, true);
  }
  sylva__strbuf_puts(b, "],\"canopy_cover\":");
  sylva__strbuf_fixed(b, j->canopy_cover, 4);
  put_stand(b, &form, &j->stand);
  sylva__strbuf_putc(b, '}');
}

char *sylva_msg_delta_detail(int64_t run, int64_t seq, const sylva_world *w,
                             const sylva_journal *j, int start_year, sylva_detail detail) {
  if (detail != SYLVA_DETAIL_STEMS) return sylva_msg_delta(run, seq, w, j, start_year);
  sylva__strbuf b = {0};
  if (!sylva__strbuf_reserve(&b, j->stem_count * 200 + 256)) return sylva__strbuf_finish(&b);
  sylva__strbuf_printf(&b, "{\"type\":\"delta\",\"run\":%" PRId64 ",\"seq\":%" PRId64
                           ",\"iteration\":%d",
                       run, seq, j->iteration);
  put_detail(&b, detail);
  sylva__strbuf_putc(&b, ',');
  put_delta_stats(&b, w, j, start_year);
  return sylva__strbuf_finish(&b);
}

char *sylva_msg_delta(int64_t run, int64_t seq, const sylva_world *w, const sylva_journal *j,
                      int start_year) {
  sylva__strbuf b = {0};
  if (!sylva__strbuf_reserve(&b, j->added_count * 64 + j->radii_count * 24 + j->shed_count * 12 +
                                     j->leaves_count * 20 + j->stem_count * 200 + 256))
    return sylva__strbuf_finish(&b);
  sylva__strbuf_printf(&b, "{\"type\":\"delta\",\"run\":%" PRId64 ",\"seq\":%" PRId64
                           ",\"iteration\":%d,\"added\":[",
                       run, seq, j->iteration);
  for (size_t i = 0; i < j->added_count; i++) {
    const sylva_node_info *n = &j->added[i];
    sylva__strbuf_printf(&b, "%s[%" PRId32 ",%" PRId32 ",%" PRId32 ",%" PRId32 ",", i ? "," : "",
                         n->id, n->parent, n->plant, n->stem);
    sylva__put_node_geometry(&b, n);
    sylva__strbuf_putc(&b, ']');
  }
  sylva__strbuf_puts(&b, "],\"radii\":[");
  for (size_t i = 0; i < j->radii_count; i++) {
    sylva__strbuf_printf(&b, "%s[%" PRId32 ",", i ? "," : "", j->radii[i].id);
    sylva__put_radius(&b, j->radii[i].radius);
    sylva__strbuf_putc(&b, ']');
  }
  sylva__strbuf_puts(&b, "],\"shed\":[");
  for (size_t i = 0; i < j->shed_count; i++)
    sylva__strbuf_printf(&b, "%s%" PRId32, i ? "," : "", j->shed[i]);
  sylva__strbuf_puts(&b, "],\"leaves\":[");
  for (size_t i = 0; i < j->leaves_count; i++)
    sylva__strbuf_printf(&b, "%s[%" PRId32 ",%" PRId32 "]", i ? "," : "", j->leaves[i].id,
                         j->leaves[i].leaves);
  sylva__strbuf_puts(&b, "],");
  put_delta_stats(&b, w, j, start_year);
  return sylva__strbuf_finish(&b);
}

/* Standard base64 (RFC 4648) with padding. */
static void put_base64(sylva__strbuf *b, const unsigned char *data, size_t n) {
  static const char alphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  if (!sylva__strbuf_reserve(b, (n + 2) / 3 * 4)) return;
  char *out = b->data + b->len;
  size_t i = 0, k = 0;
  for (; i + 2 < n; i += 3) {
    uint32_t v = (uint32_t)data[i] << 16 | (uint32_t)data[i + 1] << 8 | data[i + 2];
    out[k++] = alphabet[v >> 18];
    out[k++] = alphabet[(v >> 12) & 63];
    out[k++] = alphabet[(v >> 6) & 63];
    out[k++] = alphabet[v & 63];
  }
  if (i < n) {
    uint32_t v = (uint32_t)data[i] << 16 | (i + 1 < n ? (uint32_t)data[i + 1] << 8 : 0);
    out[k++] = alphabet[v >> 18];
    out[k++] = alphabet[(v >> 12) & 63];
    out[k++] = i + 1 < n ? alphabet[(v >> 6) & 63] : '=';
    out[k++] = '=';
  }
  b->len += k;
  b->data[b->len] = '\0';
}

char *sylva_msg_light_slice(int64_t run, const sylva_world *w, double z, const char *ref) {
  const sylva_world_def *def = sylva_world_get_def(w);
  int dims[3];
  sylva_world_dims(w, dims);
  double voxel = def->voxel;
  /* The layer holding z, with z clamped into the world (NaN takes the ground). */
  double zc = z >= def->min[2] ? z : def->min[2];
  if (zc > def->max[2]) zc = def->max[2];
  double layer = floor((zc - def->min[2]) / voxel);
  if (layer > dims[2] - 1) layer = dims[2] - 1;
  if (!(layer >= 0)) layer = 0;
  double centre_z = def->min[2] + (layer + 0.5) * voxel;

  size_t nx = (size_t)dims[0], ny = (size_t)dims[1];
  if (ny && nx > SIZE_MAX / 4 / ny) return NULL;
  size_t cells = nx * ny;
  unsigned char *values = malloc(cells ? cells : 1);
  if (!values) return NULL;
  for (size_t j = 0; j < ny; j++)
    for (size_t i = 0; i < nx; i++) {
      double p[3] = {def->min[0] + ((double)i + 0.5) * voxel,
                     def->min[1] + ((double)j + 0.5) * voxel, centre_z};
      double light = sylva_world_light_at(w, p);
      if (!(light > 0)) light = 0;
      if (light > 1) light = 1;
      values[j * nx + i] = (unsigned char)lround(light * 255);
    }

  sylva__strbuf b = {0};
  sylva__strbuf_printf(&b, "{\"type\":\"light_slice\",\"run\":%" PRId64 ",\"iteration\":%d,\"z\":",
                       run, sylva_world_iteration(w));
  sylva__strbuf_fixed(&b, centre_z, 6);
  sylva__strbuf_puts(&b, ",\"origin\":[");
  sylva__strbuf_shortest(&b, def->min[0]);
  sylva__strbuf_putc(&b, ',');
  sylva__strbuf_shortest(&b, def->min[1]);
  sylva__strbuf_puts(&b, "],\"voxel\":");
  sylva__strbuf_shortest(&b, voxel);
  sylva__strbuf_printf(&b, ",\"nx\":%zu,\"ny\":%zu,\"values\":\"", nx, ny);
  put_base64(&b, values, cells);
  free(values);
  sylva__strbuf_putc(&b, '"');
  put_ref_and_close(&b, ref);
  return sylva__strbuf_finish(&b);
}

char *sylva_msg_scenarios(const char *const *names, const char *const *titles, size_t n,
                          const char *ref) {
  sylva__strbuf b = {0};
  sylva__strbuf_puts(&b, "{\"type\":\"scenarios\",\"scenarios\":[");
  for (size_t i = 0; i < n; i++) {
    const char *title = titles && titles[i] ? titles[i] : names[i];
    sylva__strbuf_puts(&b, i ? ",{\"name\":" : "{\"name\":");
    put_string(&b, names[i]);
    sylva__strbuf_puts(&b, ",\"title\":");
    put_string(&b, title);
    sylva__strbuf_putc(&b, '}');
  }
  sylva__strbuf_putc(&b, ']');
  put_ref_and_close(&b, ref);
  return sylva__strbuf_finish(&b);
}
