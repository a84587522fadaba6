/* `sylva species`: the species library, and any species of the Urban Tree Database
 * (docs/cli.md, "species"). */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "options.h"
#include "sylva/library.h"
#include "utdb.h"

enum { OPT_REGION, OPT_UTDB, OPT_JSON, OPT_HELP, OPT_COUNT };

static const cli_option species_options[OPT_COUNT] = {
    [OPT_REGION] = {"region", 0, "R", "only the library's species of region R (NoEast, InlVal)"},
    [OPT_UTDB] = {"utdb", 0, "REGION:CODE", "a species of the Urban Tree Database, library or not"},
    [OPT_JSON] = {"json", 0, NULL, "one JSON object a line instead of a table"},
    [OPT_HELP] = {"help", 'h', NULL, "show this help"},
};

static const char citation[] =
    "Source: McPherson, van Doorn and Peper 2016, Urban tree database, USDA Forest Service, "
    "https://doi.org/10.2737/RDS-2016-0005 (updated 21 January 2020).";

static void species_usage(FILE *f) {
  fputs("Usage: sylva species [--region R] [--json]\n"
        "       sylva species --utdb REGION:CODE [--json]\n"
        "\n"
        "Lists the species library: species in years calibrated to the USDA Urban Tree\n"
        "Database, used as presets (\"preset\": \"utdb:NoEast:PLAC\"). Per species: its\n"
        "name, scientific and common name, region, the database's number of trees n and\n"
        "the adjusted R2 of its height curve, and the calibration's largest error over\n"
        "the decades of height, dbh, crown diameter and crown height.\n"
        "With --utdb, shows one species of the database (library or not; `sylva fit\n"
        "--utdb` calibrates any of them): names, n and R2 of each curve, age range.\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, species_options, OPT_COUNT);
}

static double num(const cJSON *obj, const char *key) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
  return cJSON_IsNumber(v) ? v->valuedouble : NAN;
}

static const char *str(const cJSON *obj, const char *key) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
  return cJSON_IsString(v) ? v->valuestring : "";
}

static int list_library(const char *region, bool json) {
  size_t len;
  const char *text = sylva_library_text(&len);
  cJSON *doc = cJSON_ParseWithLength(text, len);
  const cJSON *list = doc ? cJSON_GetObjectItemCaseSensitive(doc, "species") : NULL;
  if (!cJSON_IsArray(list)) {
    cJSON_Delete(doc);
    fprintf(stderr, "sylva species: the built-in library could not be read\n");
    return CLI_EXIT_FAILURE;
  }
  if (!json)
    printf("%-20s %-28s %-24s %-7s %4s %5s  %s\n", "NAME", "SCIENTIFIC", "COMMON", "REGION", "N",
           "R2", "ERROR: HEIGHT DBH CROWN-DIA CROWN-HT");
  const cJSON *e;
  int shown = 0;
  cJSON_ArrayForEach(e, list) {
    if (region && strcmp(str(e, "region"), region) != 0) continue;
    shown++;
    const cJSON *err = cJSON_GetObjectItemCaseSensitive(e, "error");
    const cJSON *r2 = cJSON_GetObjectItemCaseSensitive(e, "r2");
    if (json) {
      cJSON *line = cJSON_CreateObject();
      const char *keys[] = {"name", "scientific", "common", "region", "code"};
      for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++)
        cJSON_AddStringToObject(line, keys[i], str(e, keys[i]));
      cJSON_AddNumberToObject(line, "n", num(e, "n"));
      cJSON_AddItemToObject(line, "r2", cJSON_Duplicate(r2, true));
      cJSON_AddItemToObject(line, "error", cJSON_Duplicate(err, true));
      char *s = cJSON_PrintUnformatted(line);
      if (s) puts(s);
      free(s);
      cJSON_Delete(line);
    } else {
      printf("%-20s %-28.28s %-24.24s %-7s %4.0f %5.2f  %5.0f%% %4.0f%% %6.0f%% %8.0f%%\n",
             str(e, "name"), str(e, "scientific"), str(e, "common"), str(e, "region"), num(e, "n"),
             num(r2, "height"), 100 * num(err, "height"), 100 * num(err, "dbh"),
             100 * num(err, "crown_diameter"), 100 * num(err, "crown_height"));
    }
  }
  cJSON_Delete(doc);
  if (region && !shown) return cli_usage_error("species", "--region: no library species in %s", region);
  if (!json) printf("%s\n", citation);
  return fflush(stdout) == 0 ? CLI_EXIT_OK : CLI_EXIT_FAILURE;
}

static const char *const curve_keys[SYLVA_UTDB_MEASURES] = {"dbh", "height", "crown_diameter",
                                                              "crown_height", "leaf_area", "age"};

static int show_utdb(const char *key, bool json) {
  sylva_utdb *u;
  if (sylva_utdb_builtin(&u)) {
    fprintf(stderr, "sylva species: the built-in Urban Tree Database could not be read\n");
    return CLI_EXIT_FAILURE;
  }
  const char *colon = strchr(key, ':');
  char region[32] = "";
  if (colon && (size_t)(colon - key) < sizeof region) memcpy(region, key, (size_t)(colon - key));
  const sylva_utdb_species *s = colon ? sylva_utdb_find(u, region, colon + 1) : NULL;
  if (!s) {
    sylva_utdb_free(u);
    return cli_usage_error("species", "--utdb: no species '%s' in the Urban Tree Database "
                           "(REGION:CODE, for example NoEast:PLAC)", key);
  }
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "region", s->region);
  cJSON_AddStringToObject(o, "code", s->code);
  cJSON_AddStringToObject(o, "scientific", s->scientific);
  cJSON_AddStringToObject(o, "common", s->common);
  cJSON_AddStringToObject(o, "type", s->type);
  cJSON_AddNumberToObject(o, "n", s->curve[SYLVA_UTDB_HEIGHT].n);
  cJSON *r2 = cJSON_AddObjectToObject(o, "r2");
  for (int m = 0; m < SYLVA_UTDB_MEASURES; m++)
    if (s->curve[m].present && isfinite(s->curve[m].r2))
      cJSON_AddNumberToObject(r2, curve_keys[m], s->curve[m].r2);
  cJSON *ages = cJSON_AddArrayToObject(o, "ages");
  cJSON_AddItemToArray(ages, cJSON_CreateNumber(isfinite(s->age_min) ? s->age_min : 0));
  cJSON_AddItemToArray(ages, cJSON_CreateNumber(isfinite(s->age_max) ? s->age_max : 0));
  cJSON_AddBoolToObject(o, "complete", sylva_utdb_complete(s));
  /* the chained curves, clamped to where they apply, at every decade of the ages */
  cJSON *at = cJSON_AddObjectToObject(o, "decades");
  for (int a = 0; sylva_utdb_complete(s) && a <= (isfinite(s->age_max) ? s->age_max : 0); a += 10) {
    sylva_utdb_sizes z;
    if (sylva_utdb_chain(s, a, true, &z)) continue;
    char key[16];
    snprintf(key, sizeof key, "%d", a);
    cJSON *d = cJSON_AddObjectToObject(at, key);
    cJSON_AddNumberToObject(d, "height", z.height_m);
    cJSON_AddNumberToObject(d, "dbh", z.dbh_cm / 100.0);
    cJSON_AddNumberToObject(d, "crown_diameter", z.crown_dia_m);
    cJSON_AddNumberToObject(d, "crown_height", z.crown_ht_m);
    if (isfinite(z.leaf_area_m2)) cJSON_AddNumberToObject(d, "leaf_area", z.leaf_area_m2);
  }
  char *text = json ? cJSON_PrintUnformatted(o) : NULL;
  if (json) {
    if (text) puts(text);
  } else {
    printf("%s:%s  %s (%s), type %s\n", s->region, s->code, s->scientific, s->common, s->type);
    printf("ages %g to %g years\n", s->age_min, s->age_max);
    for (int m = 0; m < SYLVA_UTDB_MEASURES; m++)
      if (s->curve[m].present)
        printf("  %-15s %-9s n %4d  R2 %.3f\n", curve_keys[m], s->curve[m].form, s->curve[m].n,
               s->curve[m].r2);
    printf("%s\n", citation);
  }
  free(text);
  cJSON_Delete(o);
  sylva_utdb_free(u);
  return fflush(stdout) == 0 ? CLI_EXIT_OK : CLI_EXIT_FAILURE;
}

int cmd_species(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "species", species_options, OPT_COUNT, argc, argv);
  const char *region = NULL, *utdb = NULL, *arg;
  bool json = false;
  int first = argc, opt;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    if (opt == OPT_REGION) {
      region = arg;
    } else if (opt == OPT_UTDB) {
      utdb = arg;
    } else if (opt == OPT_JSON) {
      json = true;
    } else {
      species_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (first != argc) return cli_usage_error("species", "unexpected argument '%s'", argv[first]);
  if (utdb && region) return cli_usage_error("species", "--utdb and --region do not go together");
  return utdb ? show_utdb(utdb, json) : list_library(region, json);
}
