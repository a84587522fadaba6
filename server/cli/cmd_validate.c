/* `sylva validate`: parse and build a scenario, or check a sweep plan, and report
 * what it holds. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "commands.h"
#include "cli_input.h"
#include "files.h"
#include "options.h"
#include "plan.h"
#include "sylva/encode.h"

static const cli_option validate_options[] = {
    {"help", 'h', NULL, "show this help"},
};
#define VALIDATE_OPTION_COUNT ((int)(sizeof validate_options / sizeof validate_options[0]))

static void validate_usage(FILE *f) {
  fputs("Usage: sylva validate SCENARIO.json | PLAN.json\n"
        "\n"
        "Checks a scenario without running it: JSON syntax, every key and value, at\n"
        "least one plant, and that each root lies inside the world and outside the\n"
        "obstacles. Prints\n"
        "  ok: NAME: P plants, S stems, O obstacles[ (Z zones)][, M pruning schedules]\n"
        "      [, site sky at latitude L][, start year Y], voxel V m, NXxNYxNZ voxels\n"
        "or the error, named by its JSON pointer, on stderr (exit status 2).\n"
        "A sweep plan (sylva.sweep/1) is checked as `sylva sweep` checks it, every\n"
        "run's scenario too; it prints\n"
        "  ok: sweep NAME: R runs (AXIS N x AXIS N ...)\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, validate_options, VALIDATE_OPTION_COUNT);
}

/* Whether the text is a sweep plan: a JSON object whose "format" is the plan's. A
 * malformed text is not; the scenario's reader then names what is wrong with it. */
static bool is_plan(const char *data, size_t len) {
  cJSON *root = cJSON_ParseWithLength(data, len);
  const cJSON *format = cJSON_GetObjectItemCaseSensitive(root, "format");
  bool plan = cJSON_IsString(format) && strcmp(format->valuestring, SWEEP_FORMAT) == 0;
  cJSON_Delete(root);
  return plan;
}

/* A sweep plan: the plan as `sylva sweep` reads it (--force: a plan of more runs than
 * the default limit is still valid), then every run's scenario. */
static int validate_plan(const char *path, const char *data, size_t len) {
  sweep_plan *p;
  char err[1200];
  if (sweep_plan_parse(data, len, path, true, &p, err, sizeof err)) {
    fprintf(stderr, "sylva: %s\n", err);
    return CLI_EXIT_USAGE;
  }
  int rc = CLI_EXIT_OK;
  for (int i = 0; i < p->runs && rc == CLI_EXIT_OK; i++) {
    sweep_run r;
    if (sweep_plan_run(p, i, &r, err, sizeof err)) {
      fprintf(stderr, "sylva: %s: run %d: %s\n", path, i, err);
      rc = CLI_EXIT_USAGE;
      break;
    }
    sylva_scenario *s = NULL;
    if (sylva_scenario_parse(r.scenario, strlen(r.scenario), &s, err, sizeof err)) {
      fprintf(stderr, "sylva: %s: run \"%s\": %s\n", path, r.name, err);
      rc = CLI_EXIT_USAGE;
    }
    sylva_scenario_free(s);
    sweep_run_free(&r);
  }
  if (rc == CLI_EXIT_OK) {
    printf("ok: sweep %s: %d runs (", p->name, p->runs);
    for (int a = 0; a < p->axis_count; a++)
      printf("%s%s %d", a ? " x " : "", p->axes[a].name, p->axes[a].count);
    printf(")%s\n", p->runs > SWEEP_MAX_RUNS ? ", more than sylva sweep runs without --force" : "");
  }
  sweep_plan_free(p);
  if (rc == CLI_EXIT_OK && fflush(stdout) != 0) rc = CLI_EXIT_FAILURE;
  return rc;
}

int cmd_validate(int argc, char **argv) {
  cli_parser p;
  cli_parser_init(&p, "validate", validate_options, VALIDATE_OPTION_COUNT, argc, argv);
  int first = argc, opt;
  const char *arg;
  while ((opt = cli_next(&p, &arg, &first)) >= 0) {
    if (opt == 0) {
      validate_usage(stdout);
      return CLI_EXIT_OK;
    }
  }
  if (opt == -2) return CLI_EXIT_USAGE;
  if (argc - first != 1)
    return cli_usage_error("validate", argc - first == 0 ? "missing SCENARIO.json"
                                                         : "expected one SCENARIO.json");
  const char *path = argv[first];
  /* a plan is told by its content; anything else (an unreadable file too) is read
   * as a scenario, whose reader names what is wrong */
  char *data = NULL;
  size_t len = 0;
  if (files_read(path, FILES_MAX_INPUT, &data, &len) == 0 && is_plan(data, len)) {
    int rc = validate_plan(path, data, len);
    free(data);
    return rc;
  }
  free(data);

  sylva_scenario *s;
  int rc = cli_input_scenario(path, SYLVA_SCENARIO_NEED_PLANTS, &s);
  if (rc) return rc;
  sylva_world *w;
  rc = cli_input_world(path, s, &w);
  if (rc) {
    sylva_scenario_free(s);
    return rc;
  }
  int dims[3];
  sylva_world_dims(w, dims);
  char voxel[SYLVA_FMT_BUFSIZE];
  sylva_fmt_shortest(voxel, sizeof voxel, s->voxel);
  int zones = 0;
  for (int i = 0; i < s->obstacle_count; i++) zones += s->obstacles[i].kind == SYLVA_OBSTACLE_ZONE;
  printf("ok: %s: %d plants, %d stems, %d obstacles", s->name, sylva_world_plant_count(w),
         sylva_world_stem_count(w), sylva_world_obstacle_count(w));
  if (zones) printf(" (%d zones)", zones);
  if (s->management_count) printf(", %d pruning schedules", s->management_count);
  if (s->light.site) printf(", site sky at latitude %g", s->light.sky.latitude);
  if (s->start_year) printf(", start year %d", s->start_year);
  printf(", voxel %s m, %dx%dx%d voxels\n", voxel, dims[0], dims[1], dims[2]);
  sylva_world_destroy(w);
  sylva_scenario_free(s);
  if (fflush(stdout) != 0) return CLI_EXIT_FAILURE;
  return CLI_EXIT_OK;
}
