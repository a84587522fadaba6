/* Replays the shipped scenarios through parse -> canonical JSON -> parse, and
 * checks that both forms build the same world and grow it identically; then a
 * few fixed cases of the scenario rules and of the encoders, and the library's
 * foliage table. */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../check.h"
#include "../list_dir.h"
#include "../read_file.h"
#include "sylva/encode.h"
#include "sylva/json_check.h"
#include "sylva/library.h"
#include "sylva/scenario.h"

/* CHECK with a printf-style message. */
#define EXPECT(cond, ...)                                                   \
  do {                                                                      \
    if (cond) {                                                             \
      check_passed++;                                                       \
    } else {                                                                \
      check_failed++;                                                       \
      printf("FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);                \
      printf(__VA_ARGS__);                                                  \
      printf("\n");                                                         \
    }                                                                       \
  } while (0)


static sylva_scenario *parse_ok(const char *what, const char *text, size_t len) {
  sylva_scenario *s = NULL;
  char err[512] = "";
  int rc = sylva_scenario_parse(text, len, &s, err, sizeof err);
  EXPECT(rc == 0 && s, "%s: %s", what, err);
  return rc == 0 ? s : NULL;
}

static void roundtrip(const char *path) {
  size_t len;
  char *text = read_file(path, &len);
  EXPECT(text != NULL, "%s: cannot read", path);
  if (!text) return;
  /* a sweep plan (sylva.sweep/1, as scenarios/street-species.json) is no scenario:
   * the bad-input test validates it and the sweep suite runs it */
  if (strstr(text, "\"format\": \"sylva.sweep/1\"")) {
    free(text);
    return;
  }
  sylva_scenario *a = parse_ok(path, text, len);
  free(text);
  if (!a) return;
  char *ja = sylva_scenario_json(a);
  EXPECT(ja != NULL, "%s: canonical JSON", path);
  sylva_scenario *b = ja ? parse_ok("canonical JSON", ja, strlen(ja)) : NULL;
  char *jb = b ? sylva_scenario_json(b) : NULL;
  if (ja && jb) EXPECT(strcmp(ja, jb) == 0, "%s: canonical JSON changes on re-parse:\n%s\n%s", path, ja, jb);
  if (ja) {
    char err[256] = "";
    EXPECT(sylva_json_check(ja, strlen(ja), 64, err, sizeof err) == 0, "%s: %s", path, err);
  }

  sylva_world *wa = NULL, *wb = NULL;
  char err[512] = "";
  EXPECT(sylva_scenario_build(a, &wa, err, sizeof err) == 0, "%s: build: %s", path, err);
  if (b) EXPECT(sylva_scenario_build(b, &wb, err, sizeof err) == 0, "%s: build canonical: %s", path, err);
  if (wa && wb) {
    EXPECT(sylva_world_hash(wa) == sylva_world_hash(wb), "%s: worlds differ before growing", path);
    for (int t = 0; t < 3 && !sylva_world_finished(wa); t++) {
      const sylva_journal *j1, *j2;
      int r1 = sylva_world_step(wa, &j1), r2 = sylva_world_step(wb, &j2);
      EXPECT(r1 == 0 && r2 == 0, "%s: step %d: %d %d", path, t + 1, r1, r2);
      if (r1 || r2) break;
      char *l1 = sylva_encode_stats_line(wa, j1, 0, a->start_year),
           *l2 = sylva_encode_stats_line(wb, j2, 0, b->start_year);
      EXPECT(l1 && l2 && strcmp(l1, l2) == 0, "%s: stats lines differ:\n%s\n%s", path,
             l1 ? l1 : "(null)", l2 ? l2 : "(null)");
      if (l1) {
        char e2[256] = "";
        EXPECT(sylva_json_check(l1, strlen(l1), 64, e2, sizeof e2) == 0, "%s: stats line: %s", path, e2);
      }
      free(l1);
      free(l2);
    }
    char *k1 = sylva_encode_skeleton(wa), *k2 = sylva_encode_skeleton(wb);
    EXPECT(k1 && k2 && strcmp(k1, k2) == 0, "%s: skeletons differ", path);
    if (k1) {
      char e2[256] = "";
      EXPECT(sylva_json_check(k1, strlen(k1), 64, e2, sizeof e2) == 0, "%s: skeleton: %s", path, e2);
      EXPECT(k1[strlen(k1) - 1] == '\n', "%s: skeleton does not end with a newline", path);
    }
    free(k1);
    free(k2);
  }
  if (wa) sylva_world_destroy(wa);
  if (wb) sylva_world_destroy(wb);
  free(ja);
  free(jb);
  sylva_scenario_free(a);
  sylva_scenario_free(b);
}

static const char *scenario_dir;

/* Every shipped scenario survives parse -> canonical JSON -> parse and grows alike. */
static void test_shipped_scenarios(void) {
  size_t count;
  char **names = list_dir(scenario_dir, list_dir_json, &count);
  EXPECT(names != NULL, "cannot list %s", scenario_dir);
  if (!names) return;
  EXPECT(count > 0, "no scenarios in %s", scenario_dir);
  for (size_t i = 0; i < count; i++) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", scenario_dir, names[i]);
    roundtrip(path);
  }
  list_dir_free(names, count);
}

#define MINIMAL_WORLD "\"world\": {\"min\": [-2, -2, 0], \"max\": [2, 2, 4]}"

/* A minimal scenario gets the default name, seed, iterations and voxel. */
static void test_defaults(void) {
  const char *minimal = "{\"format\": \"sylva.scenario/1\", " MINIMAL_WORLD "}";
  sylva_scenario *s = parse_ok("minimal", minimal, strlen(minimal));
  if (!s) return;
  EXPECT(strcmp(s->name, "untitled") == 0, "name %s", s->name);
  EXPECT(s->seed == 1 && s->iterations == 40, "seed %llu iterations %d",
         (unsigned long long)s->seed, s->iterations);
  EXPECT(s->voxel == 0.05, "voxel %g", s->voxel);
  sylva_scenario_free(s);
}

/* Species resolved: the voxel, the initial trunk, growth overrides on a preset. */
static void test_species_resolution(void) {
  /* The voxel follows the smallest rho among planted species only; the initial trunk
   * follows the final growth equation; growth overrides keep the rest of a preset. */
  const char *text =
      "{\"format\": \"sylva.scenario/1\", " MINIMAL_WORLD ", \"species\": {"
      "\"tiny\": {\"rho\": 0.01},"
      "\"a\": {\"preset\": \"igm-fig15-left\", \"rho\": 0.08, \"growth\": {\"X0\": 4.6}},"
      "\"b\": {\"growth\": {\"equation\": \"weibull\", \"omega1\": 60, \"omega2\": 0.01, \"omega3\": 2}}},"
      "\"plants\": [{\"id\": \"p\", \"species\": \"a\", \"roots\": [[0, 0, 0]]},"
      "{\"id\": \"q\", \"species\": \"b\", \"roots\": [[1, 1, 0]]}]}";
  sylva_scenario *s = parse_ok("resolution", text, strlen(text));
  if (!s) return;
  EXPECT(s->voxel == 0.04, "voxel %g, want 0.04", s->voxel);
  const sylva_species_def *a = &s->species[1].def, *b = &s->species[2].def;
  EXPECT(a->growth.p[0] == 4.6 && a->growth.p[1] == 70 && a->growth.p[2] == 0.34,
         "growth %g %g %g", a->growth.p[0], a->growth.p[1], a->growth.p[2]);
  EXPECT(a->initial_nodes == 5, "initial_nodes %d, want round(4.6) = 5", a->initial_nodes);
  EXPECT(a->lambda == 0.48 && a->alpha == 3 && a->r_s == 0.20 && a->b_max == 2.5,
         "preset igm-fig15-left not applied");
  EXPECT(b->growth.kind == SYLVA_EQ_WEIBULL && b->initial_nodes == 2, "kind %d initial %d",
         (int)b->growth.kind, b->initial_nodes);
  sylva_scenario_free(s);
}

/* Every preset exists and passes the core's range check; no other name is one. */
static void test_presets(void) {
  EXPECT(sylva_preset_count() == 10, "%d presets", sylva_preset_count());
  for (int i = 0; i < sylva_preset_count(); i++) {
    sylva_species_def d;
    const char *field = NULL;
    EXPECT(sylva_preset_find(sylva_preset_name(i), &d) == 0, "%s", sylva_preset_name(i));
    EXPECT(sylva_species_check(&d, &field) == 0, "%s: %s", sylva_preset_name(i), field);
  }
  EXPECT(sylva_preset_find("nope", NULL) < 0, "unknown preset found");
  EXPECT(sylva_preset_name(-1) == NULL && sylva_preset_name(10) == NULL, "name out of range");
}

/* Errors leave *out NULL and a NUL-terminated message, even in a tiny buffer. */
static void test_parse_errors(void) {
  char small[12];
  sylva_scenario *s = (sylva_scenario *)1;
  EXPECT(sylva_scenario_parse("{", 1, &s, small, sizeof small) < 0 && s == NULL &&
             strlen(small) == sizeof small - 1,
         "tiny buffer: '%s'", small);
  EXPECT(sylva_scenario_parse("[]", 2, &s, NULL, 0) < 0 && s == NULL, "NULL buffer");
}

/* No plants: an empty site, but refused with SYLVA_SCENARIO_NEED_PLANTS. */
static void test_no_plants(void) {
  /* (the daemon plants an empty site by edits; a scenario to grow as it is needs plants) */
  static const char *const no_plants[][2] = {
      {"", "/plants: required"},
      {", \"plants\": []", "/plants: nothing to grow (the list is empty)"}};
  for (size_t i = 0; i < sizeof no_plants / sizeof no_plants[0]; i++) {
    char text[200], err[200] = "";
    snprintf(text, sizeof text,
             "{\"format\": \"sylva.scenario/1\", \"world\": {\"min\": [0, 0, 0], "
             "\"max\": [1, 1, 1]}%s}",
             no_plants[i][0]);
    sylva_scenario *s = parse_ok("no plants", text, strlen(text));
    EXPECT(s && s->plant_count == 0, "%s", text);
    sylva_scenario_free(s);
    EXPECT(sylva_scenario_parse_ex(text, strlen(text), SYLVA_SCENARIO_NEED_PLANTS, &s, err,
                                   sizeof err) < 0 &&
               s == NULL && strcmp(err, no_plants[i][1]) == 0,
           "%s: '%s'", text, err);
  }
}

/* sylva_fmt_fixed: the decimals asked at most, no trailing zero or "-0", null if not finite. */
static void test_fmt_fixed(void) {
  char buf[SYLVA_FMT_BUFSIZE];
  struct {
    double v;
    int decimals;
    const char *want;
  } fixed[] = {{1.9, 4, "1.9"},   {0.031, 4, "0.031"},  {2.0, 4, "2"},       {-0.00001, 4, "0"},
               {-0.0, 3, "0"},    {402.1, 3, "402.1"},  {12.46, 1, "12.5"},  {NAN, 4, "null"},
               {INFINITY, 4, "null"}, {-1.25, 1, "-1.2"}, {1234567.0, 0, "1234567"}};
  for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++) {
    sylva_fmt_fixed(buf, sizeof buf, fixed[i].v, fixed[i].decimals);
    EXPECT(strcmp(buf, fixed[i].want) == 0, "fixed(%g, %d) = %s, want %s", fixed[i].v,
           fixed[i].decimals, buf, fixed[i].want);
  }
}

/* sylva_fmt_shortest: the shortest text that reads back, null for NaN. */
static void test_fmt_shortest(void) {
  char buf[SYLVA_FMT_BUFSIZE];
  struct {
    double v;
    const char *want;
  } shortest[] = {{100, "100"}, {0.1, "0.1"}, {0.021, "0.021"}, {1e-7, "1e-07"},
                  {-0.0, "0"},  {2e6, "2000000"}, {1e17, "1e+17"}, {NAN, "null"}};
  for (size_t i = 0; i < sizeof shortest / sizeof shortest[0]; i++) {
    sylva_fmt_shortest(buf, sizeof buf, shortest[i].v);
    EXPECT(strcmp(buf, shortest[i].want) == 0, "shortest(%g) = %s, want %s", shortest[i].v, buf,
           shortest[i].want);
  }
}

/* The done line names the iterations and the reason. */
static void test_done_line(void) {
  char *done = sylva_encode_done_line(24, "finished");
  EXPECT(done && strcmp(done, "{\"done\": true, \"iterations\": 24, \"reason\": \"finished\"}") == 0,
         "%s", done ? done : "(null)");
  free(done);
}

/* The stats line of the first iteration of s's world (malloc'd; NULL when the world
 * does not build or step), with its first stem's measures in *first. */
static char *first_stats_line(sylva_scenario *s, double elapsed_ms, sylva_stem_stats *first) {
  sylva_world *w = NULL;
  char err[256] = "";
  EXPECT(sylva_scenario_build(s, &w, err, sizeof err) == 0, "%s", err);
  if (!w) return NULL;
  const sylva_journal *j;
  char *line = NULL;
  int rc = sylva_world_step(w, &j);
  EXPECT(rc == 0, "step: %d", rc);
  if (rc == 0) {
    line = sylva_encode_stats_line(w, j, elapsed_ms, s->start_year);
    if (j->stem_count) *first = j->stats[0];
  }
  sylva_world_destroy(w);
  return line;
}

/* A label with quotes, a backslash and a newline is escaped in the stats line. */
static void test_odd_label(void) {
  const char *odd = "{\"format\": \"sylva.scenario/1\", " MINIMAL_WORLD
                    ", \"species\": {\"s\": {}}, \"plants\": [{\"id\": \"a\\\"b\\\\c\\nd\", "
                    "\"species\": \"s\", \"roots\": [[0, 0, 0]]}]}";
  sylva_scenario *s = parse_ok("odd label", odd, strlen(odd));
  if (!s) return;
  sylva_stem_stats first;
  char *line = first_stats_line(s, 12.46, &first);
  EXPECT(line && strstr(line, "{\"iteration\": 1, \"elapsed_ms\": 12.5, \"stems\": [{\"plant\": "
                              "\"a\\\"b\\\\c\\nd\", \"stem\": 0, \"height\": ") == line,
         "%s", line ? line : "(null)");
  free(line);
  sylva_scenario_free(s);
}

/* The light key: a site's defaults, its canonical form parsed back to the same
 * sky; the zenith sky written out as no key at all. */
static void test_light(void) {
  const char *site = "{\"format\": \"sylva.scenario/1\", " MINIMAL_WORLD
                     ", \"light\": {\"sky\": \"site\", \"latitude\": -33.9}}";
  sylva_scenario *a = parse_ok("site", site, strlen(site));
  if (!a) return;
  const sylva_sky_def *d = &a->light.sky;
  EXPECT(a->light.site && d->latitude == -33.9 && d->north[0] == 0 && d->north[1] == 1 &&
             d->first_day == 1 && d->last_day == 365 && d->diffuse == 0.5 && d->samples == 64,
         "site defaults: %g [%g, %g] [%d, %d] %g %d", d->latitude, d->north[0], d->north[1],
         d->first_day, d->last_day, d->diffuse, d->samples);
  char *json = sylva_scenario_json(a);
  EXPECT(json && strstr(json, "\"light\": {\"sky\": \"site\", \"latitude\": -33.9, \"north\": [0, 1], "
                              "\"season\": [1, 365], \"diffuse\": 0.5, \"samples\": 64}"),
         "canonical: %s", json ? json : "(null)");
  sylva_scenario *b = json ? parse_ok("canonical site", json, strlen(json)) : NULL;
  if (b) EXPECT(b->light.site && memcmp(&a->light.sky, &b->light.sky, sizeof a->light.sky) == 0,
                "the canonical form's sky differs");
  free(json);
  sylva_scenario_free(a);
  sylva_scenario_free(b);
  const char *zenith = "{\"format\": \"sylva.scenario/1\", " MINIMAL_WORLD
                       ", \"light\": {\"sky\": \"zenith\"}}";
  sylva_scenario *z = parse_ok("zenith", zenith, strlen(zenith));
  if (!z) return;
  json = sylva_scenario_json(z);
  EXPECT(!z->light.site && json && !strstr(json, "light"), "zenith: %s", json ? json : "(null)");
  free(json);
  sylva_scenario_free(z);
}

/* Years (tests/scenario/years.json, beside the shipped scenarios): the round trip;
 * start_year and a plant's age in the canonical form and read back; the IGM
 * species' canonical form without the keys of real species; the stats line's year,
 * ages (null for the IGM tree) and crown diameter. */
static void test_years(void) {
  char path[4096];
  snprintf(path, sizeof path, "%s/../tests/scenario/years.json", scenario_dir);
  roundtrip(path);
  size_t len;
  char *text = read_file(path, &len);
  EXPECT(text != NULL, "%s: cannot read", path);
  sylva_scenario *s = text ? parse_ok(path, text, len) : NULL;
  free(text);
  if (!s) return;
  EXPECT(s->start_year == 2027, "start_year %d", s->start_year);
  EXPECT(s->plant_count == 3 && s->plants[0].age == 0 && s->plants[1].age == 3 &&
             s->plants[2].age == 0,
         "ages");
  EXPECT(s->species[0].def.years == 1 && s->species[1].def.years == 0, "years");
  char *json = sylva_scenario_json(s);
  EXPECT(json && strstr(json, "\"iterations\": 8,\n  \"start_year\": 2027,\n  \"world\": "),
         "canonical start_year: %s", json ? json : "(null)");
  EXPECT(json && strstr(json, "\"roots\": [[1.5, 0, 0]], \"age\": 3}") &&
             strstr(json, "\"roots\": [[-1.5, 0, 0]]}"),
         "canonical ages: %s", json ? json : "(null)");
  /* the years species says so; the other keys of real species are at their
   * defaults, and the IGM species carries none of them */
  const char *oak = json ? strstr(json, "\"oak\": {") : NULL;
  EXPECT(json && strstr(json, "\"years\": 1") && !strstr(json, "\"nursery\"") &&
             !strstr(json, "\"ref_rho\"") && !strstr(json, "\"acclimation\"") &&
             !strstr(json, "\"shade_weight\"") && !strstr(json, "\"lift\"") && oak &&
             !strstr(oak, "\"years\""),
         "canonical species: %s", json ? json : "(null)");
  free(json);
  sylva_stem_stats first;
  char *line = first_stats_line(s, 0, &first);
  EXPECT(line && strstr(line, "{\"iteration\": 1, \"year\": 2028, \"elapsed_ms\": 0, ") == line &&
             strstr(line, "\"plant\": \"young\", \"stem\": 0, \"age\": 1, \"height\": ") &&
             strstr(line, "\"plant\": \"old\", \"stem\": 0, \"age\": 4, \"height\": ") &&
             strstr(line, "\"plant\": \"igm\", \"stem\": 0, \"age\": null, \"height\": "),
         "%s", line ? line : "(null)");
  if (line) {
    char width[SYLVA_FMT_BUFSIZE], want[2 * SYLVA_FMT_BUFSIZE + 64];
    sylva_fmt_fixed(width, sizeof width, first.crown_width, 4);
    snprintf(want, sizeof want, "\"crown_width\": %s, \"crown_diameter\": %s, ", width, width);
    EXPECT(strstr(line, want), "%s in %s", want, line);
  }
  free(line);
  sylva_scenario_free(s);
}

/* Foliage keys: a species' non-default leaf_size, leaf_density and leaf_colour in
 * its canonical form and read back; a species at the defaults writes none of them;
 * the stats line's leaf_area is the stem's, with 4 decimals. */
static void test_foliage(void) {
  const char *text = "{\"format\": \"sylva.scenario/1\", " MINIMAL_WORLD
                     ", \"species\": {\"leafy\": {\"preset\": \"igm-fig11\", \"leaf_size\": 0.25,"
                     " \"leaf_density\": 12, \"leaf_colour\": \"#1A2b3c\"}, \"plain\": {}},"
                     " \"plants\": [{\"id\": \"t\", \"species\": \"leafy\", \"roots\": [[0, 0, 0]]}]}";
  sylva_scenario *a = parse_ok("foliage", text, strlen(text));
  if (!a) return;
  const sylva_species_def *d = &a->species[0].def;
  EXPECT(d->leaf_size == 0.25 && d->leaf_density == 12 && d->leaf_colour == 0x1a2b3c,
         "parsed: %g %d %06x", d->leaf_size, d->leaf_density, (unsigned)d->leaf_colour);
  char *json = sylva_scenario_json(a);
  const char *plain = json ? strstr(json, "\"plain\": {") : NULL;
  EXPECT(json && strstr(json, "\"leaf_size\": 0.25") && strstr(json, "\"leaf_density\": 12") &&
             strstr(json, "\"leaf_colour\": \"#1a2b3c\"") && plain &&
             !strstr(plain, "\"leaf_size\"") && !strstr(plain, "\"leaf_density\"") &&
             !strstr(plain, "\"leaf_colour\""),
         "canonical: %s", json ? json : "(null)");
  sylva_scenario *b = json ? parse_ok("canonical foliage", json, strlen(json)) : NULL;
  char *again = b ? sylva_scenario_json(b) : NULL;
  if (b) {
    const sylva_species_def *e = &b->species[0].def;
    EXPECT(e->leaf_size == d->leaf_size && e->leaf_density == d->leaf_density &&
               e->leaf_colour == d->leaf_colour && again && strcmp(json, again) == 0,
           "read back: %g %d %06x", e->leaf_size, e->leaf_density, (unsigned)e->leaf_colour);
  }
  free(again);
  free(json);
  sylva_scenario_free(b);
  sylva_stem_stats first;
  char *line = first_stats_line(a, 0, &first);
  if (line) {
    char area[SYLVA_FMT_BUFSIZE], want[SYLVA_FMT_BUFSIZE + 64];
    sylva_fmt_fixed(area, sizeof area, first.leaf_area, 4);
    snprintf(want, sizeof want, "\"leaf_area\": %s, \"crown_area\": ", area);
    EXPECT(first.leaf_area > 0 && strstr(line, want), "%s in %s", want, line);
  }
  free(line);
  sylva_scenario_free(a);
}

/* The library's foliage (data/species/foliage.csv, docs/species.md "Foliage"): one
 * row per species code of the library and none other, each row's kind broadleaf or
 * needle (Pinus strobus the needle one), and every library species resolved with
 * its code's leaf_size, leaf_density and leaf_colour. */
static void test_library_foliage(void) {
  const char *csv = sylva_library_foliage_text(NULL);
  EXPECT(strncmp(csv, "code,kind,leaf_size,leaf_density,leaf_colour,source\n", 52) == 0,
         "header: %.60s", csv);
  cJSON *doc = cJSON_Parse(sylva_library_text(NULL));
  const cJSON *list = cJSON_GetObjectItemCaseSensitive(doc, "species");
  EXPECT(cJSON_GetArraySize(list) > 0, "the library");
  int rows = 0, matched = 0;
  for (const char *line = strchr(csv, '\n'); line && line[1]; line = strchr(line + 1, '\n')) {
    char code[16], kind[16], colour[8];
    double size;
    int density, n = 0;
    EXPECT(sscanf(line + 1, "%15[^,],%15[^,],%lf,%d,%7[^,],%n", code, kind, &size, &density,
                  colour, &n) == 5 && n > 0 && line[1 + n] != '\n',
           "row %.60s", line + 1);
    if (n == 0) continue;
    rows++;
    EXPECT(strcmp(kind, strcmp(code, "PIST") == 0 ? "needle" : "broadleaf") == 0, "%s: %s", code,
           kind);
    const cJSON *e;
    int found = 0;
    cJSON_ArrayForEach(e, list) {
      const cJSON *c = cJSON_GetObjectItemCaseSensitive(e, "code");
      const cJSON *name = cJSON_GetObjectItemCaseSensitive(e, "name");
      if (!cJSON_IsString(c) || strcmp(c->valuestring, code) != 0) continue;
      found++;
      sylva_species_def d;
      EXPECT(cJSON_IsString(name) && sylva_library_find(name->valuestring, &d) == 0, "%s", code);
      EXPECT(d.leaf_size == size && d.leaf_density == density &&
                 d.leaf_colour == (int)strtol(colour + 1, NULL, 16),
             "%s: %g %d %06x, the table %g %d %s", code, d.leaf_size, d.leaf_density,
             (unsigned)d.leaf_colour, size, density, colour);
    }
    EXPECT(found > 0, "%s: not a library code", code);
    matched += found;
  }
  EXPECT(rows > 0 && matched == cJSON_GetArraySize(list), "%d rows cover %d of %d library species",
         rows, matched, cJSON_GetArraySize(list));
  cJSON_Delete(doc);
}

/* A plant names a library species directly (docs/scenario.md, "Plants"): it is held
 * as a species of that name with the library's def, once however many plants name
 * it, after the species given; an entry of the map of the same name wins; an
 * unknown library name is refused with its pointer. */
static void test_library_plants(void) {
  static const char head[] = "{\"format\": \"sylva.scenario/1\", \"iterations\": 2, "
                             "\"world\": {\"min\": [-10, -10, 0], \"max\": [10, 10, 20]}, ";
  char text[1024];
  snprintf(text, sizeof text, "%s\"species\": {\"bush\": {\"preset\": \"igm-fig11\"}}, \"plants\": ["
           "{\"id\": \"a\", \"species\": \"utdb:NoEast:ACPL\", \"roots\": [[0, 0, 0]], \"age\": 5}, "
           "{\"id\": \"b\", \"species\": \"bush\", \"roots\": [[5, 0, 0]]}, "
           "{\"id\": \"c\", \"species\": \"utdb:NoEast:ACPL\", \"roots\": [[-5, 0, 0]]}]}", head);
  sylva_scenario *s = parse_ok("library plants", text, strlen(text));
  sylva_species_def lib;
  EXPECT(sylva_library_find("utdb:NoEast:ACPL", &lib) == 0, "in the library");
  if (s) {
    EXPECT(s->species_count == 2 && strcmp(s->species[1].name, "utdb:NoEast:ACPL") == 0,
           "%d species", s->species_count);
    EXPECT(s->plants[0].species == 1 && s->plants[1].species == 0 && s->plants[2].species == 1,
           "plants' species %d %d %d", s->plants[0].species, s->plants[1].species,
           s->plants[2].species);
    EXPECT(s->species_count == 2 && s->species[1].def.lambda == lib.lambda &&
               s->species[1].def.growth.p[1] == lib.growth.p[1] && s->species[1].def.rho == lib.rho,
           "the library's def");
    /* its stored form writes the species out, as for the entry {"preset": name} */
    char *canon = sylva_scenario_json(s);
    char spelt[1024];
    snprintf(spelt, sizeof spelt, "%s\"species\": {\"bush\": {\"preset\": \"igm-fig11\"}, "
             "\"utdb:NoEast:ACPL\": {\"preset\": \"utdb:NoEast:ACPL\"}}, \"plants\": ["
             "{\"id\": \"a\", \"species\": \"utdb:NoEast:ACPL\", \"roots\": [[0, 0, 0]], \"age\": 5}, "
             "{\"id\": \"b\", \"species\": \"bush\", \"roots\": [[5, 0, 0]]}, "
             "{\"id\": \"c\", \"species\": \"utdb:NoEast:ACPL\", \"roots\": [[-5, 0, 0]]}]}", head);
    sylva_scenario *entry = parse_ok("spelt out", spelt, strlen(spelt));
    char *entry_json = entry ? sylva_scenario_json(entry) : NULL;
    EXPECT(canon && entry_json && strcmp(canon, entry_json) == 0, "as if the map held it");
    free(entry_json);
    sylva_scenario_free(entry);
    sylva_scenario *back = canon ? parse_ok("stored form", canon, strlen(canon)) : NULL;
    char *again = back ? sylva_scenario_json(back) : NULL;
    EXPECT(again && strcmp(canon, again) == 0, "the stored form round-trips");
    free(again);
    free(canon);
    sylva_scenario_free(back);
    sylva_scenario_free(s);
  }
  /* the map's own entry of that name wins */
  snprintf(text, sizeof text, "%s\"species\": {\"utdb:NoEast:ACPL\": {\"preset\": "
           "\"utdb:NoEast:ACPL\", \"lambda\": 0.6}}, \"plants\": [{\"id\": \"a\", \"species\": "
           "\"utdb:NoEast:ACPL\", \"roots\": [[0, 0, 0]]}]}", head);
  s = parse_ok("the map's entry", text, strlen(text));
  EXPECT(s && s->species_count == 1 && s->species[0].def.lambda == 0.6, "overrides kept");
  sylva_scenario_free(s);
  /* an unknown library name */
  snprintf(text, sizeof text, "%s\"plants\": [{\"id\": \"a\", \"species\": \"utdb:NoEast:NOPE\", "
           "\"roots\": [[0, 0, 0]]}]}", head);
  char err[512] = "";
  s = NULL;
  EXPECT(sylva_scenario_parse(text, strlen(text), &s, err, sizeof err) < 0 && !s &&
             strstr(err, "/plants/0/species: unknown species \"utdb:NoEast:NOPE\"") &&
             strstr(err, "library"),
         "%s", err);
}

/* Prisms (a building with a courtyard, a zone along a street at an angle) and the site's
 * frame: read, written in the stored form and read back to the same bytes; built, the
 * world holds the footprints as given. A GeoJSON-closed ring loses its last point. */
static void test_prisms_and_site(void) {
  static const char text[] =
      "{\"format\": \"sylva.scenario/1\", \"iterations\": 2, "
      "\"world\": {\"min\": [-20, -20, 0], \"max\": [20, 20, 20]}, "
      "\"species\": {\"bush\": {\"preset\": \"igm-fig11\"}}, "
      "\"plants\": [{\"id\": \"a\", \"species\": \"bush\", \"roots\": [[0, 0, 0]]}], "
      "\"obstacles\": [{\"id\": \"house\", \"kind\": \"prism\", "
      "\"polygon\": [[2, 2], [12, 2], [12, 10], [2, 10], [2, 2]], "
      "\"holes\": [[[5, 5], [5, 7], [8, 7], [8, 5]]], \"z\": [0, 9.5]}, "
      "{\"id\": \"street\", \"kind\": \"zone\", \"polygon\": [[-20, -8], [20, -2], [20, 1], [-20, -5]], "
      "\"z\": [0, 4.5]}, {\"id\": \"wall\", \"kind\": \"box\", \"min\": [-5, 5, 0], \"max\": [-4.8, 9, 2]}], "
      "\"site\": {\"crs\": \"EPSG:32618\", \"origin\": [583960, 4507523]}}";
  sylva_scenario *s = parse_ok("prisms", text, strlen(text));
  if (!s) return;
  EXPECT(s->obstacle_count == 3 && s->obstacles[0].ring_count == 2 && s->obstacles[0].point_count == 8 &&
             s->obstacles[1].kind == SYLVA_OBSTACLE_ZONE && s->obstacles[1].ring_count == 1 &&
             s->obstacles[2].ring_count == 0,
         "obstacles as given");
  EXPECT(s->obstacles[0].min[0] == 2 && s->obstacles[0].max[1] == 10 && s->obstacles[0].max[2] == 9.5,
         "bounds");
  EXPECT(strcmp(s->site_crs, "EPSG:32618") == 0 && s->site_origin[0] == 583960 &&
             s->site_origin[1] == 4507523, "the site");
  char *canon = sylva_scenario_json(s);
  EXPECT(canon && strstr(canon, "{\"id\": \"house\", \"kind\": \"prism\", \"polygon\": [[2, 2], [12, 2], "
                                "[12, 10], [2, 10]], \"holes\": [[[5, 5], [5, 7], [8, 7], [8, 5]]], \"z\": [0, 9.5]}") &&
             strstr(canon, "\"site\": {\"crs\": \"EPSG:32618\", \"origin\": [583960, 4507523]}"),
         "%s", canon ? canon : "(null)");
  sylva_scenario *back = canon ? parse_ok("stored form", canon, strlen(canon)) : NULL;
  char *again = back ? sylva_scenario_json(back) : NULL;
  EXPECT(again && strcmp(canon, again) == 0, "the stored form round-trips");
  sylva_world *w = NULL;
  char err[256] = "";
  EXPECT(sylva_scenario_build(s, &w, err, sizeof err) == 0, "%s", err);
  sylva_obstacle_def d;
  EXPECT(w && sylva_world_obstacle_at(w, 0, NULL, &d) == 0 && d.footprint.ring_count == 2 &&
             d.footprint.points[4][0] == 5 && d.footprint.ring_sizes[1] == 4,
         "the world's footprint");
  sylva_world_destroy(w);
  free(again);
  free(canon);
  sylva_scenario_free(back);
  sylva_scenario_free(s);
}

int main(int argc, char **argv) {
  if (argc != 2 && argc != 3) {
    fprintf(stderr, "usage: %s SCENARIO_DIR [TEST]\n", argv[0]);
    return 2;
  }
  scenario_dir = argv[1];
  static const check_test tests[] = {
      CHECK_TEST(defaults), CHECK_TEST(species_resolution), CHECK_TEST(presets),
      CHECK_TEST(parse_errors), CHECK_TEST(no_plants), CHECK_TEST(fmt_fixed),
      CHECK_TEST(fmt_shortest), CHECK_TEST(done_line), CHECK_TEST(odd_label), CHECK_TEST(light),
      CHECK_TEST(shipped_scenarios), CHECK_TEST(years), CHECK_TEST(foliage),
      CHECK_TEST(library_foliage), CHECK_TEST(library_plants),
      CHECK_TEST(prisms_and_site)};
  CHECK_RUN(argc, argv, 2, tests);
  return check_summary("scenario-roundtrip");
}
