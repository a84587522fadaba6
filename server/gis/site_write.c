#include "site_write.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* v / 10^decimals written with at most `decimals` decimals, trailing zeros dropped. */
static void fixed(char *buf, size_t size, long long v, int decimals) {
  unsigned long long a = v < 0 ? 0ULL - (unsigned long long)v : (unsigned long long)v, scale = 1;
  for (int i = 0; i < decimals; i++) scale *= 10;
  unsigned long long whole = a / scale, frac = a % scale;
  int n = snprintf(buf, size, "%s%llu", v < 0 ? "-" : "", whole);
  if (frac == 0 || n < 0 || (size_t)n >= size) return;
  int digits = decimals;
  while (frac % 10 == 0) {
    frac /= 10;
    digits--;
  }
  snprintf(buf + n, size - (size_t)n, ".%0*llu", digits, frac);
}

/* A raw number item: mm as metres, or a value to 6 decimals. */
static cJSON *mm_item(long long mm) {
  char t[40];
  fixed(t, sizeof t, mm, 3);
  return cJSON_CreateRaw(t);
}

static cJSON *deg_item(double v) {
  char t[40];
  fixed(t, sizeof t, llround(v * 1e6), 6);
  return cJSON_CreateRaw(t);
}

static cJSON *int_item(long long v) {
  char t[32];
  snprintf(t, sizeof t, "%lld", v);
  return cJSON_CreateRaw(t);
}

/* Adds item to array (or to object under key); false, item freed, on failure. */
static bool put(cJSON *to, const char *key, cJSON *item) {
  bool ok = item && (key ? cJSON_AddItemToObject(to, key, item) : cJSON_AddItemToArray(to, item));
  if (!ok) cJSON_Delete(item);
  return ok;
}

/* [a, b] or [a, b, c] (c NULL: a pair) of items; NULL, every item freed, on failure. */
static cJSON *tuple(cJSON *a, cJSON *b, cJSON *c) {
  cJSON *t = cJSON_CreateArray(), *v[3] = {a, b, c};
  bool ok = t != NULL;
  for (int i = 0; i < 3; i++) {
    if (i == 2 && !c) break;
    if (ok)
      ok = put(t, NULL, v[i]);
    else
      cJSON_Delete(v[i]);
  }
  if (!ok) {
    cJSON_Delete(t);
    return NULL;
  }
  return t;
}

static cJSON *ring_item(const long long (*p)[2], int n) {
  cJSON *r = cJSON_CreateArray();
  for (int i = 0; r && i < n; i++)
    if (!put(r, NULL, tuple(mm_item(p[i][0]), mm_item(p[i][1]), NULL))) {
      cJSON_Delete(r);
      return NULL;
    }
  return r;
}

static cJSON *obstacle_item(const site_obstacle *ob) {
  cJSON *o = cJSON_CreateObject();
  bool ok = o && put(o, "id", cJSON_CreateString(ob->id)) &&
            put(o, "kind", cJSON_CreateString(ob->zone ? "zone" : "prism")) &&
            put(o, "polygon", ring_item((const long long(*)[2])ob->points, ob->ring_sizes[0]));
  if (ok && ob->ring_count > 1) {
    cJSON *holes = cJSON_CreateArray();
    ok = put(o, "holes", holes);
    int at = ob->ring_sizes[0];
    for (int r = 1; ok && r < ob->ring_count; r++) {
      ok = put(holes, NULL, ring_item((const long long(*)[2])ob->points + at, ob->ring_sizes[r]));
      at += ob->ring_sizes[r];
    }
  }
  ok = ok && put(o, "z", tuple(mm_item(0), mm_item(ob->height), NULL));
  if (!ok) {
    cJSON_Delete(o);
    return NULL;
  }
  return o;
}

static cJSON *plant_item(const site *s, const site_plant *p) {
  cJSON *o = cJSON_CreateObject(), *roots = NULL;
  bool ok = o && put(o, "id", cJSON_CreateString(p->id)) &&
            put(o, "species", cJSON_CreateString(s->lib.species[p->species].name)) &&
            put(o, "roots", roots = cJSON_CreateArray()) &&
            put(roots, NULL, tuple(mm_item(p->xy[0]), mm_item(p->xy[1]), mm_item(0))) &&
            put(o, "age", int_item(p->age));
  if (!ok) {
    cJSON_Delete(o);
    return NULL;
  }
  return o;
}

/* Prints item (compact) into f and frees it; false when it is NULL or printing fails. */
static bool emit(FILE *f, const char *before, cJSON *item) {
  char *text = item ? cJSON_PrintUnformatted(item) : NULL;
  cJSON_Delete(item);
  if (!text) return false;
  fprintf(f, "%s%s", before, text);
  free(text);
  return true;
}

/* The "site", "light" and "world" objects. */
static cJSON *site_item(const site *s) {
  cJSON *o = cJSON_CreateObject();
  if (!o || !put(o, "crs", cJSON_CreateString(s->crs)) ||
      !put(o, "origin", tuple(int_item(s->origin[0]), int_item(s->origin[1]), NULL))) {
    cJSON_Delete(o);
    return NULL;
  }
  return o;
}

static cJSON *world_item(const site *s, bool voxel) {
  cJSON *o = cJSON_CreateObject();
  char v[40];
  fixed(v, sizeof v, llround(s->voxel * 1e6), 6);
  if (!o ||
      !put(
          o, "min",
          tuple(int_item(s->world_min[0]), int_item(s->world_min[1]), int_item(s->world_min[2]))) ||
      !put(
          o, "max",
          tuple(int_item(s->world_max[0]), int_item(s->world_max[1]), int_item(s->world_max[2]))) ||
      (voxel && !put(o, "voxel", cJSON_CreateRaw(v)))) {
    cJSON_Delete(o);
    return NULL;
  }
  return o;
}

char *site_scenario_json(const site *s, const site_scenario *sc) {
  char *text = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&text, &len);
  if (!f) return NULL;
  bool ok =
      emit(f, "{\"format\": \"sylva.scenario/1\",\n \"name\": ", cJSON_CreateString(sc->name));
  fprintf(f, ",\n \"iterations\": %d", sc->iterations);
  if (sc->start_year > 0) fprintf(f, ",\n \"start_year\": %d", sc->start_year);
  ok = ok && emit(f, ",\n \"site\": ", site_item(s));
  cJSON *light = ok ? cJSON_CreateObject() : NULL;
  bool lit = light && put(light, "sky", cJSON_CreateString("site")) &&
             put(light, "latitude", deg_item(s->latitude)) &&
             put(light, "north", tuple(deg_item(s->north[0]), deg_item(s->north[1]), NULL));
  if (!lit) cJSON_Delete(light);
  ok = lit && emit(f, ",\n \"light\": ", light);
  ok = ok && emit(f, ",\n \"world\": ", world_item(s, true));
  if (ok && sc->rho > 0 && s->species_count > 0) {
    cJSON *species = cJSON_CreateObject();
    char rho[40];
    fixed(rho, sizeof rho, llround(sc->rho * 1e6), 6);
    bool all = species != NULL;
    for (int i = 0; all && i < s->species_count; i++) {
      cJSON *e = cJSON_CreateObject();
      all = put(species, s->species[i].name, e) &&
            put(e, "preset", cJSON_CreateString(s->species[i].name)) &&
            put(e, "rho", cJSON_CreateRaw(rho));
    }
    if (!all) cJSON_Delete(species);
    ok = all && emit(f, ",\n \"species\": ", species);
  }
  for (int i = 0; ok && i < s->obstacle_count; i++)
    ok = emit(f, i == 0 ? ",\n \"obstacles\": [\n  " : ",\n  ", obstacle_item(&s->obstacles[i]));
  if (ok && s->obstacle_count) fputs("\n ]", f);
  for (int i = 0; ok && i < s->plant_count; i++)
    ok = emit(f, i == 0 ? ",\n \"plants\": [\n  " : ",\n  ", plant_item(s, &s->plants[i]));
  if (ok && s->plant_count) fputs("\n ]", f);
  fputs("}\n", f);
  if (fclose(f) != 0) ok = false;
  if (!ok) {
    free(text);
    return NULL;
  }
  return text;
}

static cJSON *tallies(const site_tally *t, int n) {
  cJSON *o = cJSON_CreateObject();
  for (int i = 0; o && i < n; i++)
    if (!put(o, t[i].name, int_item(t[i].count))) {
      cJSON_Delete(o);
      return NULL;
    }
  return o;
}

char *site_summary_json(const site *s) {
  cJSON *o = cJSON_CreateObject(), *left = NULL;
  bool ok = o && put(o, "buildings", int_item(s->buildings)) &&
            put(o, "prisms", int_item(s->prisms)) && put(o, "trees", int_item(s->plant_count)) &&
            put(o, "zones", int_item(s->zones)) && put(o, "left_out", left = cJSON_CreateObject());
  for (int r = 0; ok && r < SITE_REASON_COUNT; r++)
    ok = put(left, site_reason_name((site_reason)r), int_item(s->left_out[r]));
  ok = ok && put(o, "unmatched", tallies(s->unmatched, s->unmatched_count)) &&
       put(o, "species", tallies(s->species, s->species_count)) &&
       (!s->region[0] || put(o, "region", cJSON_CreateString(s->region))) &&
       put(o, "frame", site_item(s)) && put(o, "world", world_item(s, false));
  char *text = ok ? cJSON_PrintUnformatted(o) : NULL;
  cJSON_Delete(o);
  return text;
}
