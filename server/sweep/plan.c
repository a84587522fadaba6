/* Sweep plans: parsing, checking every axis value against the scenario, and the
 * scenario of each run. */
#include "plan.h"

#include <errno.h>
#include <libgen.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "files.h"
#include "json_patch.h"
#include "measured.h"
#include "sylva/json_check.h"
#include "sylva/scenario.h"

/* A JSON pointer token for messages: '~' as "~0" and '/' as "~1" (RFC 6901). */
static void pointer_token(const char *key, char *out, size_t n) {
  size_t j = 0;
  for (const char *s = key; *s && j + 3 < n; s++) {
    if (*s == '~' || *s == '/') {
      out[j++] = '~';
      out[j++] = *s == '~' ? '0' : '1';
    } else {
      out[j++] = *s;
    }
  }
  out[j] = '\0';
}

static int failf(char *err, size_t n, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static int failf(char *err, size_t n, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err, n, fmt, ap);
  va_end(ap);
  return -1;
}

static char *dup_printf(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
static char *dup_printf(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  char *s = n >= 0 ? malloc((size_t)n + 1) : NULL;
  if (!s) return NULL;
  va_start(ap, fmt);
  vsnprintf(s, (size_t)n + 1, fmt, ap);
  va_end(ap);
  return s;
}

/* Whether a scenario object parses; with runs, also whether it would run, as `sylva
 * run` checks it before it stores anything: at least one plant, its measured trees
 * read (against base), and its world built (every root inside the world and outside
 * the obstacles). A plan is refused on what would otherwise fail in a worker, after
 * its store was created. err gets the message. */
static bool scenario_ok(const cJSON *scenario, const char *base, bool runs, char *err,
                        size_t n) {
  char *text = cJSON_PrintUnformatted(scenario);
  if (!text) {
    snprintf(err, n, "out of memory");
    return false;
  }
  sylva_scenario *s = NULL;
  sylva_world *w = NULL;
  bool ok = sylva_scenario_parse_ex(text, strlen(text), runs ? SYLVA_SCENARIO_NEED_PLANTS : 0,
                                    &s, err, n) == 0 &&
            (!runs || (sylva_import_measured(base, s, err, n) == 0 &&
                       files_build_world(base, s, &w, err, n) == 0));
  if (w) sylva_world_destroy(w);
  sylva_scenario_free(s);
  free(text);
  return ok;
}

/* Sets the species KEY of a scenario object to v: a preset's name becomes
 * {"preset": name}, an object is taken as it is. */
static bool set_species(cJSON *scenario, const char *key, const cJSON *v) {
  cJSON *species = cJSON_GetObjectItemCaseSensitive(scenario, "species");
  cJSON *def = cJSON_IsString(v) ? cJSON_CreateObject() : cJSON_Duplicate(v, true);
  if (!def || (cJSON_IsString(v) && !cJSON_AddStringToObject(def, "preset", v->valuestring))) {
    cJSON_Delete(def);
    return false;
  }
  return cJSON_ReplaceItemInObjectCaseSensitive(species, key, def) || (cJSON_Delete(def), false);
}

static bool set_seed(cJSON *scenario, const cJSON *seed) {
  cJSON *v = cJSON_CreateNumber(seed->valuedouble);
  if (!v) return false;
  if (cJSON_GetObjectItemCaseSensitive(scenario, "seed"))
    return cJSON_ReplaceItemInObjectCaseSensitive(scenario, "seed", v) || (cJSON_Delete(v), false);
  return cJSON_AddItemToObject(scenario, "seed", v) || (cJSON_Delete(v), false);
}

/* Adds a value to an axis (the json is borrowed from the plan document). */
static bool axis_add(sweep_axis *a, char *label, char *value, cJSON *json) {
  int n = a->count + 1;
  char **l = realloc(a->labels, (size_t)n * sizeof *l);
  if (l) a->labels = l;
  char **v = l ? realloc(a->values, (size_t)n * sizeof *v) : NULL;
  if (v) a->values = v;
  cJSON **j = v ? realloc(a->json, (size_t)n * sizeof *j) : NULL;
  if (j) a->json = j;
  if (!j || !label || !value) {
    free(label);
    free(value);
    return false;
  }
  a->labels[a->count] = label;
  a->values[a->count] = value;
  a->json[a->count] = json;
  a->count = n;
  return true;
}

static sweep_axis *new_axis(sweep_plan *p, sweep_axis_kind kind, char *name, char *key) {
  if (p->axis_count == SWEEP_MAX_AXES || !name) {
    free(name);
    free(key);
    return NULL;
  }
  sweep_axis *a = &p->axes[p->axis_count++];
  memset(a, 0, sizeof *a);
  a->kind = kind;
  a->name = name;
  a->key = key;
  return a;
}

/* Whether label is among the axis's labels already. */
static bool listed(const sweep_axis *a, const char *label) {
  for (int i = 0; i < a->count; i++)
    if (strcmp(a->labels[i], label) == 0) return true;
  return false;
}

/* The first member of obj whose key an earlier member has (cJSON keeps both, and
 * the second axis of one name would clash in the store), or NULL. */
static const cJSON *duplicate_key(const cJSON *obj) {
  for (const cJSON *it = obj->child; it; it = it->next)
    for (const cJSON *prev = obj->child; prev != it; prev = prev->next)
      if (strcmp(prev->string, it->string) == 0) return it;
  return NULL;
}

static int fail_duplicate(const char *at, const cJSON *dup, char *err, size_t n) {
  char tok[512];
  pointer_token(dup->string, tok, sizeof tok);
  return failf(err, n, "%s/%s: duplicate key", at, tok);
}

/* Whether value is among the axis's values already. */
static bool listed_value(const sweep_axis *a, const char *value) {
  for (int i = 0; i < a->count; i++)
    if (strcmp(a->values[i], value) == 0) return true;
  return false;
}

#define OOM(err, n) failf(err, n, "out of memory")

static int parse_species(sweep_plan *p, cJSON *axis, char *err, size_t n) {
  if (!cJSON_IsObject(axis) || !axis->child)
    return failf(err, n, "/axes/species: an object from the scenario's species keys to the "
                         "presets or species objects to try, with at least one key");
  const cJSON *dup = duplicate_key(axis);
  if (dup) return fail_duplicate("/axes/species", dup, err, n);
  cJSON *known = cJSON_GetObjectItemCaseSensitive(p->scenario, "species");
  cJSON *key;
  cJSON_ArrayForEach(key, axis) {
    char tok[512];
    pointer_token(key->string, tok, sizeof tok);
    if (!cJSON_GetObjectItemCaseSensitive(known, key->string))
      return failf(err, n, "/axes/species/%s: the scenario has no species \"%.200s\"", tok,
                   key->string);
    if (!cJSON_IsArray(key) || cJSON_GetArraySize(key) == 0)
      return failf(err, n, "/axes/species/%s: an empty axis (give a non-empty array of presets "
                           "or species objects)", tok);
    sweep_axis *a = new_axis(p, SWEEP_SPECIES, dup_printf("species/%s", key->string),
                             strdup(key->string));
    if (!a) return failf(err, n, "/axes: more than %d axes", SWEEP_MAX_AXES);
    if (!a->key) return OOM(err, n);
    int i = 0;
    cJSON *v;
    cJSON_ArrayForEach(v, key) {
      char *label, *value;
      if (cJSON_IsString(v)) {
        label = strdup(v->valuestring);
        value = strdup(v->valuestring);
      } else if (cJSON_IsObject(v)) {
        label = dup_printf("%s#%d", key->string, i + 1);
        value = cJSON_PrintUnformatted(v);
      } else {
        return failf(err, n, "/axes/species/%s/%d: a preset's name or a species object", tok, i);
      }
      /* by value: the same species object twice would be two runs of one scenario
       * under two names */
      if (value && listed_value(a, value)) {
        free(label);
        free(value);
        return failf(err, n, "/axes/species/%s/%d: %s listed twice", tok, i,
                     cJSON_IsString(v) ? "the preset is" : "the species object is");
      }
      if (!axis_add(a, label, value, v)) return OOM(err, n);
      /* the scenario with this species must be valid */
      cJSON *s = cJSON_Duplicate(p->scenario, true);
      char why[1024] = "out of memory";
      /* runnable when the base is: a species can make a measured tree or the
       * first trunk leave the world */
      bool ok = s && set_species(s, key->string, v) &&
                scenario_ok(s, p->base, p->base_runs, why, sizeof why);
      cJSON_Delete(s);
      if (!ok) return failf(err, n, "/axes/species/%s/%d: %s", tok, i, why);
      i++;
    }
  }
  return 0;
}

static int parse_seeds(sweep_plan *p, cJSON *axis, char *err, size_t n) {
  if (!cJSON_IsArray(axis) || cJSON_GetArraySize(axis) == 0)
    return failf(err, n, "/axes/seed: an empty axis (give a non-empty array of seeds)");
  sweep_axis *a = new_axis(p, SWEEP_SEED, strdup("seed"), NULL);
  if (!a) return failf(err, n, "/axes: more than %d axes", SWEEP_MAX_AXES);
  int i = 0;
  cJSON *v;
  cJSON_ArrayForEach(v, axis) {
    double d = cJSON_IsNumber(v) ? v->valuedouble : -1.0;
    if (!(d >= 0.0 && d <= SYLVA_SCENARIO_SEED_MAX && d == floor(d)))
      return failf(err, n, "/axes/seed/%d: a seed is an integer from 0 to 2^53", i);
    char *label = dup_printf("%.0f", d);
    if (label && listed(a, label)) {
      free(label);
      return failf(err, n, "/axes/seed/%d: seed %.0f is listed twice", i, d);
    }
    if (!axis_add(a, label, label ? strdup(label) : NULL, v)) return OOM(err, n);
    i++;
  }
  return 0;
}

static int parse_variants(sweep_plan *p, cJSON *axis, char *err, size_t n) {
  if (!cJSON_IsObject(axis) || !axis->child)
    return failf(err, n, "/axes/variants: an empty axis (give an object from variant names to "
                         "JSON Patch arrays)");
  sweep_axis *a = new_axis(p, SWEEP_VARIANT, strdup("variant"), NULL);
  if (!a) return failf(err, n, "/axes: more than %d axes", SWEEP_MAX_AXES);
  cJSON *v;
  cJSON_ArrayForEach(v, axis) {
    char tok[512];
    pointer_token(v->string, tok, sizeof tok);
    if (!v->string[0]) return failf(err, n, "/axes/variants/: a variant needs a name");
    if (listed(a, v->string))
      return failf(err, n, "/axes/variants/%s: the variant is named twice", tok);
    if (!cJSON_IsArray(v))
      return failf(err, n, "/axes/variants/%s: a variant is a JSON Patch (RFC 6902): an array "
                           "of operations", tok);
    if (!axis_add(a, strdup(v->string), strdup(v->string), v)) return OOM(err, n);
    cJSON *s = cJSON_Duplicate(p->scenario, true);
    if (!s) return OOM(err, n);
    char why[1024];
    if (json_patch_apply(&s, v, why, sizeof why)) {
      cJSON_Delete(s);
      return failf(err, n, "/axes/variants/%s/%s", tok, why);
    }
    bool ok = cJSON_IsObject(s) && scenario_ok(s, p->base, true, why, sizeof why);
    if (!cJSON_IsObject(s)) snprintf(why, sizeof why, "the scenario is no longer an object");
    cJSON_Delete(s);
    if (!ok) return failf(err, n, "/axes/variants/%s: the patched scenario: %s", tok, why);
  }
  return 0;
}

/* A run sets its species after its variant's patch: each variant must leave every
 * species key that a species axis varies (one that renames or removes it would
 * fail in the worker of every run with it). */
static int check_variant_species(const sweep_plan *p, char *err, size_t n) {
  for (int v = 0; v < p->axis_count; v++) {
    const sweep_axis *va = &p->axes[v];
    if (va->kind != SWEEP_VARIANT) continue;
    for (int i = 0; i < va->count; i++) {
      cJSON *s = cJSON_Duplicate(p->scenario, true);
      char why[1024];
      if (!s) return OOM(err, n);
      if (json_patch_apply(&s, va->json[i], why, sizeof why)) { /* checked before */
        cJSON_Delete(s);
        return OOM(err, n);
      }
      const cJSON *species = cJSON_GetObjectItemCaseSensitive(s, "species");
      for (int a = 0; a < p->axis_count; a++) {
        const sweep_axis *sa = &p->axes[a];
        if (sa->kind != SWEEP_SPECIES || cJSON_GetObjectItemCaseSensitive(species, sa->key))
          continue;
        char tok[512], key[512];
        pointer_token(va->labels[i], tok, sizeof tok);
        pointer_token(sa->key, key, sizeof key);
        cJSON_Delete(s);
        return failf(err, n, "/axes/variants/%s: the patched scenario has no species \"%.200s\" "
                             "(/axes/species/%s varies it)", tok, sa->key, key);
      }
      cJSON_Delete(s);
    }
  }
  return 0;
}

/* The plan's scenario: an object, or a path relative to the plan's folder. */
static int load_scenario(sweep_plan *p, const cJSON *v, const char *path, char *err, size_t n) {
  if (cJSON_IsObject(v)) {
    p->scenario = cJSON_Duplicate(v, true);
    p->base = strdup(path);
    return p->scenario && p->base ? 0 : OOM(err, n);
  }
  if (!cJSON_IsString(v) || !v->valuestring[0])
    return failf(err, n, "/scenario: a scenario object, or the path of a scenario file "
                         "relative to the plan");
  if (v->valuestring[0] == '/') {
    p->base = strdup(v->valuestring);
  } else {
    char *copy = strdup(path);
    if (!copy) return OOM(err, n);
    p->base = dup_printf("%s/%s", dirname(copy), v->valuestring);
    free(copy);
  }
  if (!p->base) return OOM(err, n);
  char *text;
  size_t len;
  int e = files_read(p->base, FILES_MAX_INPUT, &text, &len);
  if (e) return failf(err, n, "/scenario: %.300s: %s", p->base, strerror(e));
  char why[512];
  if (sylva_json_check_ex(text, len, SYLVA_SCENARIO_MAX_DEPTH,
                          SYLVA_JSON_NO_NUL_ESCAPE | SYLVA_JSON_CJSON_NUMBERS, why, sizeof why)) {
    free(text);
    return failf(err, n, "/scenario: %.300s: %s", p->base, why);
  }
  p->scenario = cJSON_ParseWithLength(text, len);
  free(text);
  if (!p->scenario) return OOM(err, n);
  if (!cJSON_IsObject(p->scenario))
    return failf(err, n, "/scenario: %.300s: a scenario is a JSON object", p->base);
  return 0;
}

/* One "HH:MM" member of the shade object into *minutes; absent leaves it. */
static int shade_time(const cJSON *shade, const char *key, int *minutes, char *err, size_t n) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(shade, key);
  if (!v) return 0;
  char why[256];
  if (!cJSON_IsString(v))
    return failf(err, n, "/shade/%s: a time \"HH:MM\" from 00:00 to 24:00", key);
  if (shade_parse_time(v->valuestring, minutes, why, sizeof why))
    return failf(err, n, "/shade/%s: %s", key, why);
  return 0;
}

int sweep_plan_shade(const cJSON *plan, bool *present, shade_day *day, char *err, size_t n) {
  const cJSON *shade = cJSON_GetObjectItemCaseSensitive(plan, "shade");
  *present = false;
  if (!shade) return 0;
  if (!cJSON_IsObject(shade))
    return failf(err, n, "/shade: an object {\"date\": \"MM-DD\", \"from\": \"HH:MM\", "
                         "\"to\": \"HH:MM\", \"step\": minutes}");
  const cJSON *dup = duplicate_key(shade);
  if (dup) return fail_duplicate("/shade", dup, err, n);
  const cJSON *v;
  cJSON_ArrayForEach(v, shade) {
    if (strcmp(v->string, "date") && strcmp(v->string, "from") && strcmp(v->string, "to") &&
        strcmp(v->string, "step")) {
      char tok[512];
      pointer_token(v->string, tok, sizeof tok);
      return failf(err, n, "/shade/%s: unknown key (shade has date, from, to and step)", tok);
    }
  }
  shade_day d = shade_default_day();
  d.year = 0;
  char why[256];
  v = cJSON_GetObjectItemCaseSensitive(shade, "date");
  if (!v) return failf(err, n, "/shade/date: missing (the day, \"MM-DD\")");
  if (!cJSON_IsString(v)) return failf(err, n, "/shade/date: a date \"MM-DD\"");
  if (shade_parse_date(v->valuestring, &d.month, &d.day, why, sizeof why))
    return failf(err, n, "/shade/date: %s", why);
  if (shade_time(shade, "from", &d.from, err, n) || shade_time(shade, "to", &d.to, err, n))
    return -1;
  v = cJSON_GetObjectItemCaseSensitive(shade, "step");
  if (v) {
    double m = cJSON_IsNumber(v) ? v->valuedouble : 0.0;
    if (!(m >= 1.0 && m <= SHADE_DAY_MINUTES && m == floor(m)))
      return failf(err, n, "/shade/step: minutes between samples, an integer from 1 to %d",
                   SHADE_DAY_MINUTES);
    d.step = (int)m;
  }
  if (d.from >= d.to)
    return failf(err, n, "/shade/from: %02d:%02d is not before /shade/to %02d:%02d", d.from / 60,
                 d.from % 60, d.to / 60, d.to % 60);
  /* the site is each run's own; any valid one lets shade_check judge the day */
  shade_site site = {.latitude = 0.0, .north = {0.0, 1.0}};
  if (shade_check(&site, &d, why, sizeof why)) return failf(err, n, "/shade: %s", why);
  *day = d;
  *present = true;
  return 0;
}

/* Refuses a plan of too many runs before its values are checked: checking builds a
 * world for each species and variant, seconds for a plan of a hundred variants,
 * and the count needs only the axes' sizes. An axis of the wrong shape counts one
 * here; parsing it names what is wrong. */
static int too_many_runs(const cJSON *axes, bool force, char *err, size_t n) {
  double runs = 1.0;
  const cJSON *v;
  cJSON_ArrayForEach(v, axes) {
    if (strcmp(v->string, "species") == 0 && cJSON_IsObject(v)) {
      const cJSON *key;
      cJSON_ArrayForEach(key, v) if (cJSON_IsArray(key)) runs *= cJSON_GetArraySize(key);
    } else if ((strcmp(v->string, "seed") == 0 && cJSON_IsArray(v)) ||
               (strcmp(v->string, "variants") == 0 && cJSON_IsObject(v))) {
      runs *= cJSON_GetArraySize(v);
    }
  }
  if (runs > SWEEP_HARD_MAX_RUNS)
    return failf(err, n, "/axes: %.0f runs, more than %d", runs, SWEEP_HARD_MAX_RUNS);
  if (runs > SWEEP_MAX_RUNS && !force)
    return failf(err, n, "/axes: %.0f runs, more than %d (give --force to run them all)", runs,
                 SWEEP_MAX_RUNS);
  return 0;
}

static int parse_plan(sweep_plan *p, cJSON *root, const char *path, bool force, char *err,
                      size_t n) {
  if (!cJSON_IsObject(root)) return failf(err, n, "a plan is a JSON object");
  const cJSON *dup = duplicate_key(root);
  if (dup) return fail_duplicate("", dup, err, n);
  cJSON *v;
  cJSON_ArrayForEach(v, root) {
    if (strcmp(v->string, "format") && strcmp(v->string, "name") &&
        strcmp(v->string, "scenario") && strcmp(v->string, "axes") &&
        strcmp(v->string, "shade")) {
      char tok[512];
      pointer_token(v->string, tok, sizeof tok);
      return failf(err, n, "/%s: unknown key (a plan has format, name, scenario, axes and "
                           "shade)", tok);
    }
  }
  v = cJSON_GetObjectItemCaseSensitive(root, "format");
  if (!cJSON_IsString(v) || strcmp(v->valuestring, SWEEP_FORMAT))
    return failf(err, n, "/format: must be \"%s\"", SWEEP_FORMAT);
  v = cJSON_GetObjectItemCaseSensitive(root, "name");
  if (!cJSON_IsString(v) || !v->valuestring[0] || strlen(v->valuestring) > 200)
    return failf(err, n, "/name: the sweep's name, a string of 1 to 200 bytes");
  if (!(p->name = strdup(v->valuestring))) return OOM(err, n);
  if (sweep_plan_shade(root, &p->shade, &p->shade_day, err, n)) return -1;
  v = cJSON_GetObjectItemCaseSensitive(root, "scenario");
  if (!v) return failf(err, n, "/scenario: missing (a scenario object or file)");
  if (load_scenario(p, v, path, err, n)) return -1;
  char why[1024], why_not_runs[1024];
  if (!scenario_ok(p->scenario, p->base, false, why, sizeof why))
    return failf(err, n, "/scenario: %s", why);
  p->base_runs = scenario_ok(p->scenario, p->base, true, why_not_runs, sizeof why_not_runs);
  cJSON *axes = cJSON_GetObjectItemCaseSensitive(root, "axes");
  if (!cJSON_IsObject(axes) || !axes->child)
    return failf(err, n, "/axes: an object with at least one axis (species, seed, variants)");
  if ((dup = duplicate_key(axes))) return fail_duplicate("/axes", dup, err, n);
  if (too_many_runs(axes, force, err, n)) return -1;
  cJSON_ArrayForEach(v, axes) {
    int rc;
    if (strcmp(v->string, "species") == 0) {
      rc = parse_species(p, v, err, n);
    } else if (strcmp(v->string, "seed") == 0) {
      rc = parse_seeds(p, v, err, n);
    } else if (strcmp(v->string, "variants") == 0) {
      rc = parse_variants(p, v, err, n);
    } else {
      char tok[512];
      pointer_token(v->string, tok, sizeof tok);
      return failf(err, n, "/axes/%s: unknown axis (species, seed, variants)", tok);
    }
    if (rc) return rc;
  }
  if (check_variant_species(p, err, n)) return -1;
  bool varied = false; /* every run's scenario is a variant's, checked to run */
  for (int a = 0; a < p->axis_count; a++) varied |= p->axes[a].kind == SWEEP_VARIANT;
  if (!p->base_runs && !varied) return failf(err, n, "/scenario: %s", why_not_runs);
  p->runs = 1; /* too_many_runs counted them */
  for (int a = 0; a < p->axis_count; a++) p->runs *= p->axes[a].count;
  /* what a store keeps: the plan with its scenario inline */
  if (!(p->plan = cJSON_Duplicate(root, true))) return OOM(err, n);
  cJSON *inline_scenario = cJSON_Duplicate(p->scenario, true);
  if (!inline_scenario ||
      !cJSON_ReplaceItemInObjectCaseSensitive(p->plan, "scenario", inline_scenario)) {
    cJSON_Delete(inline_scenario);
    return OOM(err, n);
  }
  if (!(p->canonical = cJSON_PrintUnformatted(p->plan))) return OOM(err, n);
  return 0;
}

int sweep_plan_parse(const char *text, size_t len, const char *path, bool force,
                     sweep_plan **out, char *err, size_t errlen) {
  *out = NULL;
  char why[512];
  if (sylva_json_check_ex(text, len, SYLVA_SCENARIO_MAX_DEPTH,
                          SYLVA_JSON_NO_NUL_ESCAPE | SYLVA_JSON_CJSON_NUMBERS, why, sizeof why))
    return failf(err, errlen, "%s: %s", path, why);
  sweep_plan *p = calloc(1, sizeof *p);
  cJSON *root = p ? cJSON_ParseWithLength(text, len) : NULL;
  if (!root) {
    free(p);
    return failf(err, errlen, "%s: out of memory", path);
  }
  char msg[2048];
  int rc = parse_plan(p, root, path, force, msg, sizeof msg);
  /* the axes' values point into the plan document: keep it, as p->plan's source */
  if (rc) {
    failf(err, errlen, "%s: %s", path, msg);
    cJSON_Delete(root);
    sweep_plan_free(p);
    return -1;
  }
  /* the values are borrowed from root: re-point them into p->plan, which the plan
   * owns, and let root go */
  cJSON *axes = cJSON_GetObjectItemCaseSensitive(p->plan, "axes");
  for (int a = 0; a < p->axis_count; a++) {
    sweep_axis *ax = &p->axes[a];
    cJSON *list = ax->kind == SWEEP_SPECIES
                      ? cJSON_GetObjectItemCaseSensitive(
                            cJSON_GetObjectItemCaseSensitive(axes, "species"), ax->key)
                  : ax->kind == SWEEP_SEED ? cJSON_GetObjectItemCaseSensitive(axes, "seed")
                                           : cJSON_GetObjectItemCaseSensitive(axes, "variants");
    for (int i = 0; i < ax->count; i++) ax->json[i] = cJSON_GetArrayItem(list, i);
  }
  cJSON_Delete(root);
  *out = p;
  return 0;
}

int sweep_plan_load(const char *path, bool force, sweep_plan **out, char *err, size_t errlen) {
  *out = NULL;
  char *text;
  size_t len;
  int e = files_read(path, FILES_MAX_INPUT, &text, &len);
  if (e) return failf(err, errlen, "%s: %s", path, strerror(e));
  int rc = sweep_plan_parse(text, len, path, force, out, err, errlen);
  free(text);
  return rc;
}

int sweep_plan_run(const sweep_plan *p, int position, sweep_run *out, char *err,
                   size_t errlen) {
  memset(out, 0, sizeof *out);
  out->position = position;
  int rest = position;
  for (int a = p->axis_count - 1; a >= 0; a--) {
    out->value[a] = rest % p->axes[a].count;
    rest /= p->axes[a].count;
  }
  cJSON *s = cJSON_Duplicate(p->scenario, true);
  if (!s) return failf(err, errlen, "out of memory");
  char why[1024];
  /* the variant first (its patch is written against the plan's scenario), then the
   * species and the seed */
  for (int a = 0; a < p->axis_count; a++) {
    const sweep_axis *ax = &p->axes[a];
    if (ax->kind == SWEEP_VARIANT && json_patch_apply(&s, ax->json[out->value[a]], why,
                                                      sizeof why)) {
      cJSON_Delete(s);
      return failf(err, errlen, "variant \"%s\": %s", ax->labels[out->value[a]], why);
    }
  }
  bool ok = cJSON_IsObject(s);
  for (int a = 0; a < p->axis_count && ok; a++) {
    const sweep_axis *ax = &p->axes[a];
    if (ax->kind == SWEEP_SPECIES) ok = set_species(s, ax->key, ax->json[out->value[a]]);
    if (ax->kind == SWEEP_SEED) ok = set_seed(s, ax->json[out->value[a]]);
  }
  out->scenario = ok ? cJSON_PrintUnformatted(s) : NULL;
  cJSON_Delete(s);
  /* the name: the plan's, and each axis's value */
  size_t cap = strlen(p->name) + 3;
  for (int a = 0; a < p->axis_count; a++)
    cap += strlen(p->axes[a].name) + strlen(p->axes[a].labels[out->value[a]]) + 4;
  out->name = malloc(cap);
  if (!out->scenario || !out->name) {
    sweep_run_free(out);
    return failf(err, errlen, "out of memory");
  }
  size_t len = (size_t)snprintf(out->name, cap, "%s:", p->name);
  for (int a = 0; a < p->axis_count; a++) {
    const sweep_axis *ax = &p->axes[a];
    const char *label = ax->kind == SWEEP_SPECIES ? ax->key : ax->name;
    len += (size_t)snprintf(out->name + len, cap - len, "%s %s=%s", a ? "," : "", label,
                            ax->labels[out->value[a]]);
  }
  return 0;
}

void sweep_run_free(sweep_run *r) {
  if (!r) return;
  free(r->name);
  free(r->scenario);
  r->name = r->scenario = NULL;
}

void sweep_plan_free(sweep_plan *p) {
  if (!p) return;
  for (int a = 0; a < p->axis_count; a++) {
    sweep_axis *ax = &p->axes[a];
    for (int i = 0; i < ax->count; i++) {
      free(ax->labels[i]);
      free(ax->values[i]);
    }
    free(ax->labels);
    free(ax->values);
    free(ax->json);
    free(ax->name);
    free(ax->key);
  }
  free(p->name);
  free(p->base);
  cJSON_Delete(p->scenario);
  cJSON_Delete(p->plan);
  free(p->canonical);
  free(p);
}
