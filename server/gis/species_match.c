#include "species_match.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "server_error.h"
#include "sylva/library.h"

static const char *text_of(const cJSON *obj, const char *key) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
  return cJSON_IsString(v) ? v->valuestring : "";
}

static void copy(char *dst, size_t size, const char *src) { snprintf(dst, size, "%s", src); }

int species_library_load(species_library *lib, char *err, size_t errlen) {
  *lib = (species_library){0};
  size_t len;
  const char *text = sylva_library_text(&len);
  cJSON *doc = cJSON_ParseWithLength(text, len);
  const cJSON *list = doc ? cJSON_GetObjectItemCaseSensitive(doc, "species") : NULL;
  if (!cJSON_IsArray(list)) {
    cJSON_Delete(doc);
    return doc ? server_fail(err, errlen, SERVER_EFAIL,
                             "the built-in species library does not read")
               : server_fail(err, errlen, SERVER_ENOMEM, "out of memory");
  }
  int n = cJSON_GetArraySize(list);
  int rc = sylva_utdb_builtin(&lib->utdb);
  if (rc == SYLVA_OK && !(lib->species = calloc((size_t)(n ? n : 1), sizeof *lib->species)))
    rc = SYLVA_ENOMEM;
  if (rc) {
    cJSON_Delete(doc);
    species_library_free(lib);
    return server_fail(err, errlen, SERVER_ENOMEM, "out of memory");
  }
  const cJSON *e;
  cJSON_ArrayForEach(e, list) {
    species_entry *s = &lib->species[lib->count];
    copy(s->name, sizeof s->name, text_of(e, "name"));
    copy(s->region, sizeof s->region, text_of(e, "region"));
    copy(s->code, sizeof s->code, text_of(e, "code"));
    species_normalise(text_of(e, "scientific"), s->scientific, sizeof s->scientific);
    species_normalise(text_of(e, "common"), s->common, sizeof s->common);
    const cJSON *ages = cJSON_GetObjectItemCaseSensitive(e, "ages");
    const cJSON *def = cJSON_GetObjectItemCaseSensitive(e, "species");
    const cJSON *rho = def ? cJSON_GetObjectItemCaseSensitive(def, "rho") : NULL;
    s->utdb = sylva_utdb_find(lib->utdb, s->region, s->code);
    if (cJSON_GetArraySize(ages) != 2 || !cJSON_IsNumber(rho) || !s->utdb ||
        !s->utdb->curve[SYLVA_UTDB_AGE].present) {
      cJSON_Delete(doc);
      species_library_free(lib);
      return server_fail(err, errlen, SERVER_EFAIL,
                         "the built-in species library's %s lacks its ages, rho or UTDB equations",
                         text_of(e, "name"));
    }
    s->age_min = cJSON_GetArrayItem(ages, 0)->valueint;
    s->age_max = cJSON_GetArrayItem(ages, 1)->valueint;
    s->rho = rho->valuedouble;
    lib->count++;
  }
  cJSON_Delete(doc);
  return SERVER_OK;
}

void species_library_free(species_library *lib) {
  free(lib->species);
  free(lib->map);
  sylva_utdb_free(lib->utdb);
  *lib = (species_library){0};
}

void species_normalise(const char *name, char *out, size_t size) {
  size_t n = 0;
  bool space = false;
  for (const unsigned char *p = (const unsigned char *)name; *p && n + 4 < size; p++) {
    const char *put = NULL;
    char one[2] = {0, 0};
    if (p[0] == 0xc3 && p[1] == 0x97) { /* U+00D7 multiplication sign: a hybrid */
      put = " x ";
      p++;
    } else if (p[0] == 0xe2 && p[1] == 0x80 && p[2] >= 0x98 && p[2] <= 0x9f) {
      put = p[2] <= 0x9b ? "'" : "\""; /* curly quotes */
      p += 2;
    } else if (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r' || *p == '\f' || *p == '\v') {
      put = " ";
    } else {
      one[0] = (char)(*p >= 'A' && *p <= 'Z' ? *p - 'A' + 'a' : *p);
      put = one;
    }
    for (; *put; put++) {
      if (*put == ' ') {
        space = n > 0;
        continue;
      }
      if (space) out[n++] = ' ';
      space = false;
      out[n++] = *put;
    }
  }
  out[n] = '\0';
}

bool species_region_has(const species_library *lib, const char *region) {
  for (int i = 0; i < lib->count; i++)
    if (strcmp(lib->species[i].region, region) == 0) return true;
  return false;
}

/* Step 2 on a normalised name: a code, scientific or common name of the region, or
 * a full library name. */
static int direct(const species_library *lib, const char *region, const char *n) {
  for (int i = 0; i < lib->count; i++) {
    const species_entry *s = &lib->species[i];
    if (strcasecmp(n, s->name) == 0) return i;
    if (strcmp(s->region, region) != 0) continue;
    if (strcasecmp(n, s->code) == 0 || strcmp(n, s->scientific) == 0 || strcmp(n, s->common) == 0)
      return i;
  }
  return -1;
}

int species_find(const species_library *lib, const char *region, const char *target) {
  char n[SPECIES_NAME_MAX];
  species_normalise(target, n, sizeof n);
  return n[0] ? direct(lib, region, n) : -1;
}

int species_map_add(species_library *lib, const char *name, int species) {
  char n[SPECIES_NAME_MAX];
  species_normalise(name, n, sizeof n);
  for (int i = 0; i < lib->map_count; i++)
    if (strcmp(lib->map[i].name, n) == 0) return SERVER_OK;
  struct species_map_entry *m = realloc(lib->map, (size_t)(lib->map_count + 1) * sizeof *m);
  if (!m) return SERVER_ENOMEM;
  lib->map = m;
  copy(m[lib->map_count].name, sizeof m->name, n);
  m[lib->map_count++].species = species;
  return SERVER_OK;
}

/* The words of a normalised name: their starts and lengths, at most max. */
static int words_of(const char *n, const char **start, size_t *len, int max) {
  int k = 0;
  while (*n && k < max) {
    size_t w = strcspn(n, " ");
    start[k] = n;
    len[k++] = w;
    n += w;
    if (*n == ' ') n++;
  }
  return k;
}

static bool word_is(const char *w, size_t len, const char *what) {
  return strlen(what) == len && strncmp(w, what, len) == 0;
}

/* Whether a word ends a species' name: a cultivar's quote, or a rank. */
static bool rank_word(const char *w, size_t len) {
  static const char *const ranks[] = {"var.",  "var", "ssp.", "ssp", "subsp.",
                                      "subsp", "f.",  "f",    "cv.", "cv"};
  if (w[0] == '\'' || w[0] == '"') return true;
  for (size_t i = 0; i < sizeof ranks / sizeof ranks[0]; i++)
    if (word_is(w, len, ranks[i])) return true;
  return false;
}

/* The name without a hybrid's x as its second word, into out. */
static void without_x(const char *n, char *out, size_t size) {
  const char *w[3];
  size_t l[3];
  if (words_of(n, w, l, 3) == 3 && word_is(w[1], l[1], "x"))
    snprintf(out, size, "%.*s %s", (int)l[0], w[0], w[2]);
  else
    copy(out, size, n);
}

int species_match(const species_library *lib, const char *region, const char *name) {
  char n[SPECIES_NAME_MAX];
  species_normalise(name, n, sizeof n);
  if (!n[0]) return -1;
  for (int i = 0; i < lib->map_count; i++) /* 1 */
    if (strcmp(lib->map[i].name, n) == 0) return lib->map[i].species;
  int found = direct(lib, region, n); /* 2 */
  if (found >= 0) return found;
  const char *w[4];
  size_t l[4];
  int words = words_of(n, w, l, 4);
  int base = words >= 3 && word_is(w[1], l[1], "x") ? 3 : 2;
  char species[SPECIES_NAME_MAX];
  copy(species, sizeof species, n);
  if (words > base && rank_word(w[base], l[base])) { /* 3 */
    species[w[base] - n - 1] = '\0';
    if ((found = direct(lib, region, species)) >= 0) return found;
  }
  char plain[SPECIES_NAME_MAX], other[SPECIES_NAME_MAX];
  without_x(species, plain, sizeof plain); /* 4 */
  for (int i = 0; i < lib->count; i++) {
    if (strcmp(lib->species[i].region, region) != 0) continue;
    without_x(lib->species[i].scientific, other, sizeof other);
    if (strcmp(plain, other) == 0) return i;
  }
  /* 5: a genus alone, or with sp., spp. or a cultivar */
  if (words == 1 || (words >= 2 && (word_is(w[1], l[1], "sp.") || word_is(w[1], l[1], "spp.") ||
                                    word_is(w[1], l[1], "sp") || word_is(w[1], l[1], "spp") ||
                                    w[1][0] == '\'' || w[1][0] == '"'))) {
    char sp[SPECIES_NAME_MAX], spp[SPECIES_NAME_MAX];
    snprintf(sp, sizeof sp, "%.*s sp.", (int)l[0], w[0]);
    snprintf(spp, sizeof spp, "%.*s spp.", (int)l[0], w[0]);
    for (int i = 0; i < lib->count; i++) {
      const species_entry *s = &lib->species[i];
      if (strcmp(s->region, region) == 0 &&
          (strcmp(s->scientific, sp) == 0 || strcmp(s->scientific, spp) == 0))
        return i;
    }
  }
  return -1;
}

int species_age(const species_entry *s, double dbh_cm) {
  double a = sylva_utdb_eval_clamped(&s->utdb->curve[SYLVA_UTDB_AGE], dbh_cm);
  double r = isfinite(a) ? round(a) : s->age_min;
  if (r < s->age_min) r = s->age_min;
  if (r > s->age_max) r = s->age_max;
  if (r < 0) r = 0;
  if (r > 500) r = 500;
  return (int)r;
}

double species_height(const species_entry *s, int age) {
  sylva_utdb_sizes z;
  if (sylva_utdb_chain(s->utdb, age, true, &z)) return NAN;
  return z.height_m;
}
