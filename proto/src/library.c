/* The species library built into the binary (sylva/library.h), with the foliage of
 * data/species/foliage.csv added to its species (docs/species.md, "Foliage") and
 * the wood and carbon of data/species/carbon.csv (docs/model.md, "Wood and carbon") and
 * the stand keys of data/species/stand.csv (docs/model.md, "Stands"). The text is parsed
 * at each lookup: it is small, and a parse per scenario keeps the library free of
 * shared state between the daemon's threads. */
#include "sylva/library.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scenario_parts.h"
#include "sylva/status.h"

extern const char sylva__library_json[];
extern const size_t sylva__library_json_len;
extern const char sylva__foliage_csv[];
extern const size_t sylva__foliage_csv_len;
extern const char sylva__carbon_csv[];
extern const size_t sylva__carbon_csv_len;
extern const char sylva__stand_csv[];
extern const size_t sylva__stand_csv_len;

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

const char *sylva_library_foliage_text(size_t *len) {
  if (len) *len = sylva__foliage_csv_len;
  return sylva__foliage_csv;
}

/* Adds the foliage table's row for `code` to a library species object as its
 * leaf_size, leaf_density and leaf_colour, to be checked as any scenario's keys are
 * (docs/species.md, "Foliage"). A code without a row keeps the defaults. The
 * table's rows are `code,kind,leaf_size,leaf_density,leaf_colour,source`; no field
 * before the source holds a comma or a quote. 0, or SYLVA_ENOMEM. */
static int add_foliage(cJSON *species, const char *code) {
  const char *line = strchr(sylva__foliage_csv, '\n'); /* past the header */
  size_t code_len = strlen(code);
  for (; line; line = strchr(line, '\n')) {
    line++;
    if (strncmp(line, code, code_len) != 0 || line[code_len] != ',') continue;
    const char *f[5]; /* the starts of code, kind, size, density, colour */
    f[0] = line;
    for (int i = 1; i < 5; i++) {
      size_t k = strcspn(f[i - 1], ",\n");
      if (f[i - 1][k] != ',') return SYLVA_OK; /* a short row: the test suite catches it */
      f[i] = f[i - 1] + k + 1;
    }
    char colour[8] = "";
    size_t colour_len = strcspn(f[4], ",\n");
    if (colour_len < sizeof colour) memcpy(colour, f[4], colour_len), colour[colour_len] = '\0';
    cJSON_DeleteItemFromObjectCaseSensitive(species, "leaf_size");
    cJSON_DeleteItemFromObjectCaseSensitive(species, "leaf_density");
    cJSON_DeleteItemFromObjectCaseSensitive(species, "leaf_colour");
    if (!cJSON_AddNumberToObject(species, "leaf_size", strtod(f[2], NULL)) ||
        !cJSON_AddNumberToObject(species, "leaf_density", strtod(f[3], NULL)) ||
        !cJSON_AddStringToObject(species, "leaf_colour", colour))
      return SYLVA_ENOMEM;
    return SYLVA_OK;
  }
  return SYLVA_OK;
}

const char *sylva_library_carbon_text(size_t *len) {
  if (len) *len = sylva__carbon_csv_len;
  return sylva__carbon_csv;
}

/* The carbon table's columns that are species keys, in its order after the code. */
static const char *const carbon_keys[] = {"wood_density", "biomass_form", "biomass_a",
                                          "biomass_b",    "biomass_c",    "biomass_p",
                                          "biomass_q",    "biomass_factor"};
enum { CARBON_KEYS = sizeof carbon_keys / sizeof *carbon_keys };

/* Sets a library species object's numeric `keys` from the row of `table` (a CSV
 * text whose first column names the species) that starts with `name`, to be checked
 * as any scenario's keys are. A name without a row keeps the defaults. No field
 * before the row's last ones holds a comma or a quote. 0, or SYLVA_ENOMEM. */
static int add_row(cJSON *species, const char *table, const char *name,
                   const char *const *keys, int nkeys) {
  const char *line = strchr(table, '\n'); /* past the header */
  size_t name_len = strlen(name);
  for (; line; line = strchr(line, '\n')) {
    line++;
    if (strncmp(line, name, name_len) != 0 || line[name_len] != ',') continue;
    const char *f = line + name_len + 1;
    for (int i = 0; i < nkeys; i++) {
      cJSON_DeleteItemFromObjectCaseSensitive(species, keys[i]);
      if (!cJSON_AddNumberToObject(species, keys[i], strtod(f, NULL))) return SYLVA_ENOMEM;
      size_t k = strcspn(f, ",\n");
      if (f[k] != ',') return SYLVA_OK; /* a short row: the test suite catches it */
      f += k + 1;
    }
    return SYLVA_OK;
  }
  return SYLVA_OK;
}

/* The carbon table's row for `code` (data/species/carbon.csv, written by
 * scripts/carbon-table): the species' wood density and biomass allometry
 * (docs/model.md, "Wood and carbon"); a code without a row has no carbon. */
static int add_carbon(cJSON *species, const char *code) {
  return add_row(species, sylva__carbon_csv, code, carbon_keys, CARBON_KEYS);
}

const char *sylva_library_stand_text(size_t *len) {
  if (len) *len = sylva__stand_csv_len;
  return sylva__stand_csv;
}

/* The stand table's columns that are species keys, in its order after the name. */
static const char *const stand_keys[] = {"stock_spread",    "vigour_spread",   "height_light",
                                         "mortality_light", "mortality_years", "snag_years"};

/* The stand table's row for the species REGION:CODE (data/species/stand.csv, written
 * by scripts/stand-table): how its plants differ and die (docs/model.md, "Stands"). */
static int add_stand(cJSON *species, const char *region, const char *code) {
  char name[64];
  if (snprintf(name, sizeof name, "%s:%s", region, code) >= (int)sizeof name) return SYLVA_OK;
  return add_row(species, sylva__stand_csv, name, stand_keys,
                 (int)(sizeof stand_keys / sizeof *stand_keys));
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
    const cJSON *code = cJSON_GetObjectItemCaseSensitive(e, "code");
    cJSON *species = cJSON_GetObjectItemCaseSensitive(e, "species");
    rc = cJSON_IsString(code) && cJSON_IsObject(species) ? add_foliage(species, code->valuestring)
                                                          : SYLVA_OK;
    if (!rc && cJSON_IsString(code) && cJSON_IsObject(species))
      rc = add_carbon(species, code->valuestring);
    const cJSON *region = cJSON_GetObjectItemCaseSensitive(e, "region");
    if (!rc && cJSON_IsString(code) && cJSON_IsString(region) && cJSON_IsObject(species))
      rc = add_stand(species, region->valuestring, code->valuestring);
    if (rc) break;
    sylva_species_def d;
    rc = sylva__species_from_json(species, &d);
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
