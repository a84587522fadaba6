/* The species library built into the binary (sylva/library.h). The text is parsed
 * at each lookup: it is small, and a parse per scenario keeps the library free of
 * shared state between the daemon's threads. */
#include "sylva/library.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <string.h>

#include "scenario_parts.h"
#include "sylva/status.h"

extern const char sylva__library_json[];
extern const size_t sylva__library_json_len;

const char *sylva_library_text(size_t *len) {
  if (len) *len = sylva__library_json_len;
  return sylva__library_json;
}

/* The parsed library's species array, or NULL (the document in *doc). */
static const cJSON *library_species(cJSON **doc) {
  *doc = cJSON_ParseWithLength(sylva__library_json, sylva__library_json_len);
  const cJSON *list = *doc ? cJSON_GetObjectItemCaseSensitive(*doc, "species") : NULL;
  return cJSON_IsArray(list) ? list : NULL;
}

int sylva_library_find(const char *name, sylva_species_def *out) {
  cJSON *doc;
  const cJSON *list = library_species(&doc);
  if (!doc) return SYLVA_ENOMEM; /* the built-in text is checked by the test suite */
  int rc = SYLVA_ENOTFOUND;
  const cJSON *e;
  cJSON_ArrayForEach(e, list) {
    const cJSON *n = cJSON_GetObjectItemCaseSensitive(e, "name");
    if (!cJSON_IsString(n) || strcmp(n->valuestring, name) != 0) continue;
    sylva_species_def d;
    rc = sylva__species_from_json(cJSON_GetObjectItemCaseSensitive(e, "species"), &d);
    if (!rc && out) *out = d;
    break;
  }
  cJSON_Delete(doc);
  return rc;
}

void sylva_library_names(char *buf, size_t size) {
  if (!size) return;
  buf[0] = '\0';
  cJSON *doc;
  const cJSON *list = library_species(&doc);
  size_t n = 0;
  const cJSON *e;
  cJSON_ArrayForEach(e, list) {
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(e, "name");
    if (!cJSON_IsString(name) || n >= size) continue;
    int k = snprintf(buf + n, size - n, "%s%s", n ? ", " : "", name->valuestring);
    if (k > 0) n += (size_t)k;
  }
  cJSON_Delete(doc);
}
