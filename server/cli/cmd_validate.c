/* `sylva validate`: parse and build a scenario, report what it holds. */
#include <stdio.h>

#include "commands.h"
#include "cli_input.h"
#include "options.h"
#include "sylva/encode.h"

static const cli_option validate_options[] = {
    {"help", 'h', NULL, "show this help"},
};
#define VALIDATE_OPTION_COUNT ((int)(sizeof validate_options / sizeof validate_options[0]))

static void validate_usage(FILE *f) {
  fputs("Usage: sylva validate SCENARIO.json\n"
        "\n"
        "Checks a scenario without running it: JSON syntax, every key and value, at\n"
        "least one plant, and that each root lies inside the world and outside the\n"
        "obstacles. Prints\n"
        "  ok: NAME: P plants, S stems, O obstacles[ (Z zones)][, M pruning schedules]\n"
        "      [, site sky at latitude L][, start year Y], voxel V m, NXxNYxNZ voxels\n"
        "or the error, named by its JSON pointer, on stderr (exit status 2).\n"
        "\n"
        "Options:\n",
        f);
  cli_print_options(f, validate_options, VALIDATE_OPTION_COUNT);
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
