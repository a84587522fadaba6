/* The scenario's `management` key (docs/scenario.md, "Management"): what the
 * planner does to the plants on a schedule. One action so far, pruning a clearance
 * zone: every node inside it goes with its subtree. */
#include <stdlib.h>
#include <string.h>

#include "scenario_parts.h"
#include "strbuf.h"

static const char *const action_keys[] = {"action", "zone", "every", "from"};

/* The index of the zone this label names among s's obstacles, or -1. */
static int zone_index(const sylva_scenario *s, const char *label) {
  for (int i = 0; i < s->obstacle_count; i++)
    if (s->obstacles[i].kind == SYLVA_OBSTACLE_ZONE && strcmp(s->obstacles[i].id, label) == 0)
      return i;
  return -1;
}

static int parse_action(sylva__parser *p, const cJSON *obj, const sylva_scenario *s,
                        sylva_scenario_prune *out) {
  int rc = sylva__want_object(p, obj);
  if (!rc) rc = sylva__check_keys(p, obj, action_keys, 4);
  if (rc) return rc;
  const cJSON *v;
  char q[80];
  if (!(v = cJSON_GetObjectItemCaseSensitive(obj, "action")))
    return sylva__fail_at_key(p, "action", "required: \"prune\"");
  size_t old = sylva__ptr_push(p, "action");
  const char *action = "";
  rc = sylva__want_string(p, v, &action);
  if (!rc && strcmp(action, "prune") != 0)
    rc = sylva__fail(p, "unknown action %s (known: prune)", sylva__quote(q, action));
  sylva__ptr_pop(p, old);
  if (rc) return rc;
  if (!(v = cJSON_GetObjectItemCaseSensitive(obj, "zone")))
    return sylva__fail_at_key(p, "zone", "required: the id of a zone among the obstacles");
  old = sylva__ptr_push(p, "zone");
  char label[SYLVA_LABEL_MAX];
  rc = sylva__want_label(p, v, label);
  if (!rc && (out->zone = zone_index(s, label)) < 0) {
    bool solid = false;
    for (int i = 0; i < s->obstacle_count; i++) solid |= strcmp(s->obstacles[i].id, label) == 0;
    rc = solid ? sylva__fail(p, "obstacle %s is a box, not a zone", sylva__quote(q, label))
               : sylva__fail(p, "no zone %s among the obstacles", sylva__quote(q, label));
  }
  sylva__ptr_pop(p, old);
  if (rc) return rc;
  double n = 0;
  out->every = 0;
  if ((v = cJSON_GetObjectItemCaseSensitive(obj, "every"))) {
    old = sylva__ptr_push(p, "every");
    rc = sylva__want_integer(p, v, 1, SYLVA_SCENARIO_MAX_ITERATIONS, &n);
    out->every = (int)n;
    sylva__ptr_pop(p, old);
    if (rc) return rc;
  }
  out->from = 1;
  if ((v = cJSON_GetObjectItemCaseSensitive(obj, "from"))) {
    old = sylva__ptr_push(p, "from");
    rc = sylva__want_integer(p, v, 1, SYLVA_SCENARIO_MAX_ITERATIONS, &n);
    out->from = (int)n;
    sylva__ptr_pop(p, old);
  }
  return rc;
}

int sylva__parse_management(sylva__parser *p, const cJSON *item, sylva_scenario *s) {
  size_t old = sylva__ptr_push(p, "management");
  int rc = 0;
  int count = cJSON_IsArray(item) ? cJSON_GetArraySize(item) : -1;
  if (count < 0)
    rc = sylva__fail(p, "expected an array of actions, got %s", sylva__type_name(item));
  else if (count > SYLVA_SCENARIO_MAX_MANAGEMENT)
    rc = sylva__fail(p, "%d actions; at most %d are allowed", count, SYLVA_SCENARIO_MAX_MANAGEMENT);
  else if (count && !(s->management = calloc((size_t)count, sizeof *s->management)))
    rc = sylva__fail_nomem(p);
  for (int i = 0; !rc && i < count; i++) {
    size_t o2 = sylva__ptr_push_index(p, (size_t)i);
    rc = parse_action(p, cJSON_GetArrayItem(item, i), s, &s->management[i]);
    if (!rc) s->management_count = i + 1;
    sylva__ptr_pop(p, o2);
  }
  sylva__ptr_pop(p, old);
  return rc;
}

void sylva__put_management(sylva__strbuf *b, const sylva_scenario *s) {
  sylva__strbuf_putc(b, '[');
  for (int i = 0; i < s->management_count; i++) {
    const sylva_scenario_prune *m = &s->management[i];
    sylva__strbuf_puts(b, i ? ",\n    {\"action\": \"prune\", \"zone\": "
                            : "\n    {\"action\": \"prune\", \"zone\": ");
    sylva__strbuf_json_string(b, s->obstacles[m->zone].id);
    if (m->every) sylva__strbuf_printf(b, ", \"every\": %d", m->every);
    sylva__strbuf_printf(b, ", \"from\": %d}", m->from);
  }
  sylva__strbuf_puts(b, s->management_count ? "\n  ]" : "]");
}

int sylva__build_management(sylva__parser *p, const sylva_scenario *s, sylva_world *w) {
  for (int i = 0; i < s->management_count; i++) {
    const sylva_scenario_prune *m = &s->management[i];
    sylva_prune_def d = {sylva_world_find_obstacle(w, s->obstacles[m->zone].id), m->every,
                         m->from};
    int rc = sylva_world_add_prune(w, &d);
    if (rc == SYLVA_ENOMEM) return sylva__fail_nomem(p);
    if (rc) { /* parsing checked the zone: never expected */
      size_t old = sylva__ptr_push(p, "management");
      sylva__ptr_push_index(p, (size_t)i);
      rc = sylva__fail(p, "%s", sylva_strerror(rc));
      sylva__ptr_pop(p, old);
      return rc;
    }
  }
  return 0;
}
